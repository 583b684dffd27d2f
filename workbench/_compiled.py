"""Numba compilation with one signature per kernel: the decorators of the kernels.

Numba compiles a function once per distinct tuple of argument types, and
array types differ in mutability and layout as well as in dtype and
dimension; a constant argument (``f(x, 3)``, ``g(..., True)``) even has a type
of its own per value. Each such compile of a kernel costs seconds on a first
run (empty cache), and the kernels used to collect several: one with a
read-only array and one with a writable one, one called from Python and one
called from another kernel, one per constant joint index. Hence
:func:`entry_point`, for the kernels that Python calls, and :func:`helper`,
for those only other kernels call.

An entry point has exactly one signature, built from the argument types of its
first use, whether a call from Python or from another kernel:

* arrays named in ``outputs`` (written to) keep their type;
* the other arrays become read-only, with layout ``"A"`` (any strides) unless
  named in ``contiguous`` (layout ``"C"``, for the hot arrays of a loop whose
  callers always pass C-contiguous arrays);
* scalars lose their constant types (``Literal[int](3)`` is int64), and one
  annotated ``float``, ``int`` or ``bool`` gets that type (float64, int64,
  boolean) whatever the value of the first call (an int for a float
  parameter would otherwise fix an integer type).

Compilation is then disabled, so Numba converts the arguments of every later
call to that signature: a writable array passes as read-only, a C or
F-contiguous one as layout "A", an int as a float, at no cost per call (no
copy, no new compile). Arguments it cannot convert (another dtype or number
of dimensions, a read-only array for an output, a strided array where
``contiguous`` says "C" — the call that compiles included, whose arguments
Numba would otherwise pass on unconverted) raise ``TypeError``. Entry
points take no default arguments: an omitted argument has a type of its own
(``omitted(default=...)``) that no signature accepts once compilation is
disabled, so callers pass every argument.

The signature is built lazily, on first use, so that a command compiles (or
loads from Numba's disk cache, ``cache=True``) only the kernels it runs, not
every kernel of the modules it imports. The decorated function is a Numba
dispatcher like ``numba.njit``'s: calling it from Python or from compiled code
costs nothing more, and ``signatures`` lists its one signature.

Processes that share the disk cache compile an entry point once: the compile
holds a file lock next to the cache entries (``<module>.<name>.lock``, left in
place), and a process that waited for it loads the result from the cache.
That is what lets ``workbench demo`` run the fish cutting in a second process
while the first compiles the closed form both need (Linux and macOS; elsewhere
each process compiles its own).

A helper keeps the array types of its callers (it is usually inlined into
them, and a contiguous array compiles to faster code) and only drops the
constant types of scalars. It is compiled without the wrappers that a call
from Python needs (they would lengthen every first compile): called from
Python, it runs its Python source, as within :func:`interpreted`.

Both compile with the options of every kernel of the project: ``cache=True``,
``nogil=True``, ``error_model="numpy"`` (a division by zero gives inf or nan,
as in numpy, rather than raising).

Numba's disk cache alone would run stale code: it keys an entry on the
kernel's own bytecode and checks only the timestamp of the kernel's own file,
so a helper inlined from another file, or a constant imported from one, stays
as it was when the entry was written (Numba issue #1833). Here the key of
every entry point and helper also holds :func:`source_digest` of its module:
a hash of the source of that module and of every module of its package it
imports, transitively (read from the files, by their ``import`` statements).
An edit anywhere in what a kernel can reach makes a new entry, compiled once;
a helper may live in any module, once.

The first compile of a process (a cache miss: the first use on a machine, or
after an edit or an upgrade) says so in one line on stderr, :data:`COMPILING`,
naming the kernel; ``WORKBENCH_PROGRESS=0`` in the environment silences it
(the command line sets it while a command runs, and says so in its own
progress line).

An entry point declared with ``vectorize=True`` holds a loop written for
LLVM's loop vectoriser (no branches but selects, no library calls, flat
arrays indexed by unsigned integers: a signed index carries Python's
negative-index test, which hides the address pattern). While it compiles,
two of LLVM's options are set, and restored after: such a loop has one
address per slot it writes, and proving that they do not overlap takes LLVM
one assumption each, more than its default budget
(``-vectorize-scev-check-threshold``, 16, raised to
:data:`VECTORIZE_ASSUMPTIONS`); and its cost model, which counts each
strided store as a scalar one, declines loops that run twice as fast
vectorised (measured on the UR closed form), so the width is set
(``-force-vector-width``, :data:`VECTOR_WIDTH` doubles: AVX2's; other
machines split or join registers).

Within :func:`interpreted`, a kernel that this process has not compiled yet
runs its Python source instead: a command that solves one pose (``workbench
ik``) answers in milliseconds where compiling, on a first run, takes seconds,
and loading the compiled code from the cache takes longer than interpreting one
call. The source is the same, so are the results (tested); record fields are
read as attributes (``geo.d1``) through :class:`numpy.recarray` views, and
numpy's floating-point errors are silenced as in the compiled code. The mode
is per thread.

:func:`compile_in_background` does the same for a process's first calls that
solve one problem (``ik.analytic``, in a notebook or a script): the first one
starts a thread that compiles (or loads) the kernels the call needs, and the
calls run as Python meanwhile, up to :data:`PYTHON_CALLS` of them; the next
waits for the thread. A first answer takes milliseconds instead of the
seconds of a compile (a calibrated arm's: 18 s), and a loop of calls waits no
longer than before. The Python source gives the compiled answers to the bit at
random poses (300 per family, measured) and within 1e-12 rad at singular ones
(the tests' ``ATOL_INTERPRETED``).

Numba itself is imported only when a kernel is first compiled: the decorators
return a kernel (:class:`_Kernel`) whose dispatcher, of
:mod:`workbench._dispatchers`, is built on first need (a call outside
:func:`interpreted`, or one of its attributes: ``signatures``, ...).
Building one builds every kernel's and puts each dispatcher in place of its
kernel in the modules that hold it, so compiled code sees only dispatchers;
kernels decorated later get theirs at once. Until then a call runs the Python
source, as a dispatcher would within :func:`interpreted`: ``workbench ik`` of
one pose of a six-axis arm imports neither Numba nor LLVM (a few tenths of a
second of a command's start).
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import inspect
import os
import re
import sys
import threading
from collections.abc import Callable, Hashable, Iterable, Iterator
from pathlib import Path
from typing import Any, TypeVar, cast

import numpy as np

F = TypeVar("F", bound=Callable[..., Any])

#: Per thread: ``interpreting`` (within :func:`interpreted`) and ``warming``
#: (the thread of :func:`compile_in_background`).
_thread = threading.local()

#: Options of every kernel (``njit`` implies ``nopython=True``).
OPTIONS = {"nopython": True, "nogil": True, "error_model": "numpy"}

#: LLVM's options while a ``vectorize=True`` entry point compiles (module
#: docstring): the budget of runtime assumptions and the vector width.
VECTORIZE_ASSUMPTIONS = 1000
VECTOR_WIDTH = 4
#: Their LLVM defaults, restored after (0: the cost model chooses the width).
LLVM_DEFAULTS = {"vectorize-scev-check-threshold": 16, "force-vector-width": 0}

#: The line said on stderr when this process first compiles a kernel (module
#: docstring), unless the environment sets ``WORKBENCH_PROGRESS=0``.
COMPILING = (
    "compiling the Numba kernels on first use (a few seconds, cached for later "
    "runs): {what}…"
)
#: Added to it when the compile runs in the thread of
#: :func:`compile_in_background`.
IN_BACKGROUND = " (in the background; until it is done, calls run as Python)"

#: Kernels whose compile this process has announced (at most one).
_announced: list[str] = []
_announce_lock = threading.Lock()


@contextlib.contextmanager
def interpreted() -> Iterator[None]:
    """Run the kernels not compiled yet in this process as Python (module docstring).

    For commands that call the kernels a few times: no compile, no cache load.
    """
    before = getattr(_thread, "interpreting", False)
    _thread.interpreting = True
    try:
        yield
    finally:
        _thread.interpreting = before


def is_interpreting() -> bool:
    """Whether this thread's code runs within :func:`interpreted`."""
    return getattr(_thread, "interpreting", False)


def is_compiled(kernel: Any) -> bool:
    """Whether this process has compiled (or loaded) code for ``kernel``."""
    return bool(getattr(get_built(kernel), "signatures", None))


#: The threads of :func:`compile_in_background`, by key, and how many calls
#: of each ran as Python meanwhile.
_background: dict[Hashable, threading.Thread] = {}
_python_calls: dict[Hashable, int] = {}
_background_lock = threading.Lock()
#: Calls that run as Python while a key's kernels compile; the next one waits
#: for the compile. A caller that solves a few poses gets its answers at once
#: (under a millisecond each), one that loops waits no longer than it would
#: have (the Python calls take the GIL from the compile: a loop of them would
#: slow it to a crawl).
PYTHON_CALLS = 50


def compile_in_background(key: Hashable, warm_up: Callable[[], object]) -> bool:
    """Whether a call should run as Python while its kernels compile in a thread.

    For calls that solve one problem (``ik.analytic``): the first such call
    with ``key`` starts a thread that runs ``warm_up`` outside
    :func:`interpreted` (it calls the kernels once, so that they compile, or
    load from the cache), and this call and the next ones run as Python, in
    milliseconds, until the thread has finished or :data:`PYTHON_CALLS` have
    run (the next waits for the thread); then the compiled code. The thread
    is not a daemon (an exit waits for it, so the cache is written) and a fork
    waits for it too (a child would inherit its locks).

    Returns:
        True while ``key``'s thread runs (the call then runs as Python);
        False once it has finished, within :func:`interpreted` (the call runs
        as Python anyway) and in the thread itself.
    """
    if is_interpreting() or getattr(_thread, "warming", False):
        return False
    with _background_lock:
        thread = _background.get(key)
        if thread is None:
            thread = threading.Thread(
                target=_warm_up, args=(warm_up,), name=f"workbench compile {key}"
            )
            _background[key], _python_calls[key] = thread, 0
            thread.start()
        _python_calls[key] += 1
        python = _python_calls[key] <= PYTHON_CALLS
    if python and thread.is_alive():
        return True
    thread.join()
    return False


def _warm_up(warm_up: Callable[[], object]) -> None:
    """Run ``warm_up`` as the background thread of :func:`compile_in_background`."""
    _thread.warming = True
    try:
        warm_up()
    except Exception:  # the caller's own compiled call raises it again
        pass


def wait_for_background() -> None:
    """Wait until every thread of :func:`compile_in_background` has finished."""
    with _background_lock:
        threads = list(_background.values())
    for thread in threads:
        if thread is not threading.current_thread():
            thread.join()


if hasattr(os, "register_at_fork"):  # a child would inherit the compile's locks
    os.register_at_fork(before=wait_for_background)


def as_attributes(arg: Any) -> Any:
    """A record or record array whose fields read as attributes, else ``arg``."""
    if isinstance(arg, np.void):
        return np.asarray(arg).view(np.recarray)[()]
    if isinstance(arg, np.ndarray) and arg.dtype.names is not None:
        return arg.view(np.recarray)
    return arg


@functools.cache
def _module_file(name: str) -> Path | None:
    """The source file of module ``name``, found from its top package's folder.

    Without importing anything (a package's ``__init__`` would run): ``None``
    for a module that is not a ``.py`` file of an imported top-level package.
    """
    top, _, rest = name.partition(".")
    package = sys.modules.get(top)
    if package is None:
        return None
    folders = getattr(package, "__path__", None)
    if not folders:  # a top-level module
        file = getattr(package, "__file__", None)
        return Path(file) if not rest and file and file.endswith(".py") else None
    base = Path(folders[0]).joinpath(*rest.split(".")) if rest else Path(folders[0])
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


#: The start of a line that may begin an import statement (``import x``,
#: ``from x import y``, at any indentation).
_IMPORT_LINE = re.compile(rb"^[ \t]*(?:from[ \t]+[\w.]+[ \t]+import|import)\b", re.M)


def _import_statements(source: bytes) -> list[ast.Import | ast.ImportFrom]:
    """The import statements of ``source``, without parsing the whole of it.

    Each line that may start one (:data:`_IMPORT_LINE`) is parsed alone, with
    the lines its parentheses or backslashes continue it on: a few
    milliseconds where parsing the whole modules takes tenths of a second, in
    every process that loads a kernel. One in a docstring only adds a module
    to the closure; if a line does not parse alone (prose that starts with
    "import"), the whole source is parsed instead, so none is missed.
    """
    found: list[ast.Import | ast.ImportFrom] = []
    for match in _IMPORT_LINE.finditer(source):
        start = end = match.start()
        while True:
            end = source.find(b"\n", end + 1)
            end = len(source) if end < 0 else end
            text = source[start:end].lstrip()
            if end == len(source) or not (
                text.rstrip().endswith(b"\\") or text.count(b"(") > text.count(b")")
            ):
                break
        try:
            tree = ast.parse(text)
        except SyntaxError:
            tree = ast.parse(source)
            return [
                node
                for node in ast.walk(tree)
                if isinstance(node, ast.Import | ast.ImportFrom)
            ]
        found.extend(
            node for node in tree.body if isinstance(node, ast.Import | ast.ImportFrom)
        )
    return found


def _imported_modules(name: str, source: bytes) -> set[str]:
    """Modules of ``name``'s own top package that ``source`` imports.

    ``from package import name`` counts as ``package.name`` when that is a
    module, else as ``package`` (its ``__init__`` defines the name).
    """
    top = name.split(".")[0]
    found: set[str] = set()
    for node in _import_statements(source):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        else:
            if node.level:  # relative: from the package of this module
                parts = name.split(".")[: -node.level]
                origin = ".".join([*parts, node.module] if node.module else parts)
            else:
                origin = node.module or ""
            for alias in node.names:
                submodule = f"{origin}.{alias.name}"
                found.add(submodule if _module_file(submodule) else origin)
    return {m for m in found if m.split(".")[0] == top}


def _closure(name: str) -> dict[str, bytes]:
    """Source of module ``name`` and of the modules it imports, transitively.

    Within its own top package (:func:`_imported_modules`), by module name.
    """
    seen: dict[str, bytes] = {}
    todo = [name]
    while todo:
        module = todo.pop()
        if module in seen:
            continue
        read = _read_module(module)
        if read is not None:
            seen[module], imported = read
            todo.extend(imported)
    return seen


@functools.cache
def _read_module(name: str) -> tuple[bytes, frozenset[str]] | None:
    """Source of module ``name`` and the modules it imports; None if no file."""
    file = _module_file(name)
    if file is None:
        return None
    source = file.read_bytes()
    return source, frozenset(_imported_modules(name, source))


@functools.cache
def source_digest(name: str) -> str:
    """SHA-256 of the source of module ``name`` and of every module it imports.

    Transitively, within its own top package (for ``workbench.ik._puma_kernel``:
    every ``workbench`` module its compiled code can reach, with the constants
    they define). Computed once per process.
    """
    closure = _closure(name)
    digest = hashlib.sha256()
    for module in sorted(closure):
        digest.update(f"{module}\0{len(closure[module])}\0".encode())
        digest.update(closure[module])
    return digest.hexdigest()


def announce_compile(func: Callable[..., Any]) -> None:
    """Say once per process, on stderr, that a kernel is being compiled.

    The line (:data:`COMPILING`) names the kernel and what its module
    computes (its docstring's first line, up to a colon). Silenced by
    ``WORKBENCH_PROGRESS=0``, as the command line's progress lines (a command
    sets it while it runs: it says so itself).
    """
    with _announce_lock:
        if _announced or os.environ.get("WORKBENCH_PROGRESS", "1") == "0":
            return
        _announced.append(f"{func.__module__}.{func.__qualname__}")
    module = sys.modules.get(func.__module__)
    lines = ((module.__doc__ if module else None) or "").strip().splitlines()
    summary = lines[0].split(":")[0].rstrip(".").replace("``", "") if lines else ""
    what = _announced[0] + (f", {summary[:1].lower()}{summary[1:]}" if summary else "")
    where = IN_BACKGROUND if getattr(_thread, "warming", False) else ""
    try:
        sys.stderr.write(f"workbench: {COMPILING.format(what=what)}{where}\n")
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):  # no stderr: the line is optional
        pass


def entry_point(
    *,
    outputs: Iterable[str] = (),
    contiguous: Iterable[str] = (),
    vectorize: bool = False,
) -> Callable[[F], F]:
    """Compile a kernel that Python calls, with one signature (module docstring).

    Args:
        outputs: Names of the array parameters the kernel writes to.
        contiguous: Names of input arrays compiled as C-contiguous (faster
            loops); every caller must pass C-contiguous arrays there.
        vectorize: The kernel's loop is written for LLVM's loop vectoriser,
            which gets the assumption budget and vector width it needs
            (module docstring).

    Raises:
        TypeError: If the function has default arguments, or ``outputs`` or
            ``contiguous`` names no parameter of it.
    """
    outputs, contiguous = frozenset(outputs), frozenset(contiguous)

    def decorate(func: F) -> F:
        names = set(inspect.signature(func).parameters)
        if func.__defaults__ or func.__kwdefaults__:
            raise TypeError(f"{func.__qualname__}: an entry point takes no defaults")
        if not (outputs | contiguous) <= names:
            unknown = sorted((outputs | contiguous) - names)
            raise TypeError(f"{func.__qualname__}: no parameters {unknown}")
        return cast(
            F,
            _Kernel(
                func,
                "entry point",
                functools.partial(
                    _build_entry_point, func, outputs, contiguous, vectorize
                ),
            ),
        )

    return decorate


def helper(
    *, forceinline: bool = False, inline_source: bool = False
) -> Callable[[F], F]:
    """Compile a kernel that only other kernels call (module docstring).

    Args:
        forceinline: Have LLVM inline it into every caller (its
            ``alwaysinline`` attribute): for the small functions called per
            angle or per pose in the loops. Numba's own ``inline="always"``
            (inlining before type inference) compiles several times slower
            when used for many small functions.
        inline_source: Have Numba inline it into each caller before type
            inference (``inline="always"``): for a large body called once
            per entry point, which then gets no compile and no LLVM
            optimisation of its own (every level of linked libraries is
            optimised again in its caller).
    """

    def decorate(func: F) -> F:
        options: dict[str, Any] = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}
        if forceinline:
            options["forceinline"] = True
        if inline_source:
            options["inline"] = "always"
        return cast(
            F, _Kernel(func, "helper", functools.partial(_build_helper, func, options))
        )

    return decorate


def _build_entry_point(
    func: Any, outputs: frozenset[str], contiguous: frozenset[str], vectorize: bool
) -> Any:
    from workbench._dispatchers import build_entry_point

    return build_entry_point(
        sys.modules[__name__], func, outputs, contiguous, vectorize
    )


def _build_helper(func: Any, options: dict[str, Any]) -> Any:
    from workbench._dispatchers import build_helper

    return build_helper(sys.modules[__name__], func, options)


class _Kernel:
    """A kernel whose Numba dispatcher is built when first needed (module docs).

    Until then (no call outside :func:`interpreted`, no attribute of the
    dispatcher asked for), a call runs the Python source, as a dispatcher
    would within :func:`interpreted` (a helper's call from Python always
    does). Building one kernel's dispatcher builds every kernel's and puts
    each dispatcher in place of its kernel in the modules that hold it, so
    that compiled code sees only dispatchers.
    """

    def __init__(self, func: Any, kind: str, build: Callable[[], Any]) -> None:
        self.py_func = func
        self.kind = kind  # "entry point" or "helper"
        self._build = build
        self._dispatcher: Any = None
        functools.update_wrapper(self, func)
        with _kernels_lock:
            if _built:
                self._dispatcher = build()
            else:
                _kernels.append(self)

    def __call__(self, *args: Any) -> Any:
        dispatcher = self._dispatcher
        if dispatcher is None:
            if self.kind == "helper" or is_interpreting():
                with np.errstate(all="ignore"):
                    return self.py_func(*(as_attributes(arg) for arg in args))
            dispatcher = self.dispatcher
        return dispatcher(*args)

    @property
    def dispatcher(self) -> Any:
        """The Numba dispatcher (built on first use, every kernel's with it)."""
        if self._dispatcher is None:
            _build_every_kernel()
        return self._dispatcher

    def __getattr__(self, name: str) -> Any:  # signatures, overloads, ...
        if name.startswith("__") or name in ("_dispatcher", "_build", "py_func"):
            raise AttributeError(name)
        return getattr(self.dispatcher, name)

    def __repr__(self) -> str:
        return f"<kernel {self.py_func.__module__}.{self.py_func.__qualname__}>"


def get_built(kernel: Any) -> Any:
    """The Numba dispatcher of ``kernel`` if built, else None (no Numba import).

    Anything else (a dispatcher, a plain function) is returned as it is.
    """
    return kernel._dispatcher if isinstance(kernel, _Kernel) else kernel


#: Kernels whose dispatcher is not built yet, and whether every one is.
_kernels: list[_Kernel] = []
_built = False
_kernels_lock = threading.RLock()


def _build_every_kernel() -> None:
    """Build every kernel's dispatcher; put each in place of its kernel."""
    global _built
    with _kernels_lock:
        if _built:
            return
        dispatchers = {id(kernel): kernel._build() for kernel in _kernels}
        for kernel in _kernels:
            kernel._dispatcher = dispatchers[id(kernel)]
        packages = {kernel.py_func.__module__.split(".")[0] for kernel in _kernels}
        for name, module in list(sys.modules.items()):
            if module is None or name.split(".")[0] not in packages:
                continue
            namespace = vars(module)
            for key, value in list(namespace.items()):
                if isinstance(value, _Kernel) and value._dispatcher is not None:
                    namespace[key] = value._dispatcher
        _kernels.clear()
        _built = True
