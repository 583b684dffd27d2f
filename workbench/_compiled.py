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
numpy's floating-point errors are silenced as in the compiled code.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import inspect
import os
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, Any, TypeVar, cast

import numpy as np
from llvmlite import binding as llvm
from numba.core import config, registry, sigutils, types
from numba.core.caching import FunctionCache
from numba.core.compiler_lock import global_compiler_lock

try:
    import fcntl
except ImportError:  # Windows: no file locks, each process compiles its own
    fcntl = None  # type: ignore[assignment]

F = TypeVar("F", bound=Callable[..., Any])

#: True within :func:`interpreted`.
_interpreting = False

# Numba sets the attributes of its dispatchers and of its config at run time.
_CPUDispatcher: Any = registry.CPUDispatcher
_config: Any = config

#: Options of every kernel (``njit`` implies ``nopython=True``).
_OPTIONS = {"nopython": True, "nogil": True, "error_model": "numpy"}

#: LLVM's options while a ``vectorize=True`` entry point compiles (module
#: docstring): the budget of runtime assumptions and the vector width.
VECTORIZE_ASSUMPTIONS = 1000
VECTOR_WIDTH = 4
#: Their LLVM defaults, restored after (0: the cost model chooses the width).
_LLVM_DEFAULTS = {"vectorize-scev-check-threshold": 16, "force-vector-width": 0}

#: Scalar types fixed by a parameter's annotation.
_ANNOTATED = {"float": types.float64, "int": types.int64, "bool": types.boolean}

#: The line said on stderr when this process first compiles a kernel (module
#: docstring), unless the environment sets ``WORKBENCH_PROGRESS=0``.
COMPILING = (
    "compiling the Numba kernels on first use (a few seconds, cached for later "
    "runs): {what}…"
)

#: Kernels whose compile this process has announced (at most one).
_announced: list[str] = []
_announce_lock = threading.Lock()


@contextlib.contextmanager
def interpreted() -> Iterator[None]:
    """Run the kernels not compiled yet in this process as Python (module docstring).

    For commands that call the kernels a few times: no compile, no cache load.
    """
    global _interpreting
    before, _interpreting = _interpreting, True
    try:
        yield
    finally:
        _interpreting = before


def _as_attributes(arg: Any) -> Any:
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


def _imported_modules(name: str, source: bytes) -> set[str]:
    """Modules of ``name``'s own top package that ``source`` imports.

    ``from package import name`` counts as ``package.name`` when that is a
    module, else as ``package`` (its ``__init__`` defines the name).
    """
    top = name.split(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
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


class _SourceKeyedCache(FunctionCache):
    """Numba's disk cache of a kernel, keyed on the source it can reach too.

    Numba keys a cache entry on the kernel's own bytecode and checks only the
    timestamp of the kernel's own file, so code compiled in from another
    module (an inlined helper, a kernel it calls, a constant it reads) would
    stay as it was when first cached. The key here also holds
    :func:`source_digest` of the kernel's module: an edit of any module it
    imports, directly or not, makes a new entry.
    """

    def _index_key(self, sig: Any, codegen: Any) -> tuple[Any, ...]:
        key = super()._index_key(sig, codegen)
        return (*key, source_digest(self._py_func.__module__))

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        loaded = super().load_overload(sig, target_context)
        if loaded is None and self._enabled:
            _announce_compile(self._py_func)
        return loaded


def _announce_compile(func: Callable[..., Any]) -> None:
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
    try:
        sys.stderr.write(f"workbench: {COMPILING.format(what=what)}\n")
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):  # no stderr: the line is optional
        pass


class _Interpretable(_CPUDispatcher):
    """A dispatcher that runs its Python function within :func:`interpreted`."""

    def _compile_for_args(self, *args: Any, **kws: Any) -> Any:
        # Numba's C dispatcher calls this on a call no compiled code matches,
        # then calls what it returns with the arguments.
        if _interpreting:
            return self._interpret
        return super()._compile_for_args(*args, **kws)

    def _interpret(self, *args: Any) -> Any:
        with np.errstate(all="ignore"):
            return self.py_func(*(_as_attributes(arg) for arg in args))


class _Helper(_Interpretable):
    """A dispatcher for kernels only: constant scalars compile as plain types.

    Compiled without the wrappers that a call from Python needs (module
    docstring), so a call from Python runs the Python source, as within
    :func:`interpreted`.
    """

    def __call__(self, *args: Any) -> Any:
        return self._interpret(*args)

    def compile(self, sig: Any) -> Any:
        args, return_type = sigutils.normalize_signature(sig)
        args = tuple(types.unliteral(a) for a in args)
        return super().compile(args if return_type is None else return_type(*args))


class _EntryPoint(_Interpretable):
    """A dispatcher with one signature, built on first use (module docstring)."""

    _outputs: frozenset[str] = frozenset()
    _contiguous: frozenset[str] = frozenset()
    _vectorize = False

    def compile(self, sig: Any) -> Any:
        args, _ = sigutils.normalize_signature(sig)
        with global_compiler_lock:  # one thread builds the signature
            if self._can_compile:
                with self._one_process_at_a_time(), self._vectorizer_options():
                    entry = super().compile(self._signature(args))  # or load it
                self.disable_compile()
            else:  # another thread built it meanwhile
                entry = next(iter(self.overloads.values())).entry_point
        # Numba runs the entry it gets here on the arguments of the call that
        # compiled it, unconverted: a strided array where the one signature
        # takes layout "C" would be read as if it were contiguous.
        self._refuse_strided(args)
        return entry

    def _refuse_strided(self, args: Iterable[Any]) -> None:
        """Raise ``TypeError`` if an array named in ``contiguous`` is strided."""
        parameters = inspect.signature(self.py_func).parameters
        strided = [
            name
            for name, arg in zip(parameters, args, strict=True)
            if name in self._contiguous
            and isinstance(arg, types.Array)
            and arg.layout != "C"
        ]
        if strided:
            raise TypeError(
                f"{self.py_func.__qualname__}: {', '.join(strided)} must be "
                "C-contiguous arrays"
            )

    def _signature(self, args: Iterable[Any]) -> tuple[Any, ...]:
        """The one signature, from the argument types of the first use."""
        parameters = inspect.signature(self.py_func).parameters.values()
        result = []
        for parameter, arg in zip(parameters, args, strict=True):
            name = parameter.name
            if isinstance(arg, types.Array) and name not in self._outputs:
                contiguous = name in self._contiguous
                arg = arg.copy(layout="C" if contiguous else "A", readonly=True)
            elif isinstance(arg, types.Number | types.Boolean | types.Literal):
                annotation = getattr(parameter.annotation, "__name__", None)
                annotation = annotation or parameter.annotation  # a string
                arg = _ANNOTATED.get(annotation, types.unliteral(arg))
            result.append(arg)
        return tuple(result)

    @contextlib.contextmanager
    def _vectorizer_options(self) -> Iterator[None]:
        """LLVM's options set while a ``vectorize`` kernel compiles (module doc)."""
        if not self._vectorize:
            yield
            return
        llvm.set_option("", f"-vectorize-scev-check-threshold={VECTORIZE_ASSUMPTIONS}")
        llvm.set_option("", f"-force-vector-width={VECTOR_WIDTH}")
        try:
            yield
        finally:
            for name, value in _LLVM_DEFAULTS.items():
                llvm.set_option("", f"-{name}={value}")

    @contextlib.contextmanager
    def _one_process_at_a_time(self) -> Iterator[None]:
        """Hold this kernel's file lock in the cache folder (module docstring)."""
        func = self.py_func
        folder = Path(self._cache.cache_path)
        lock: IO[str] | None = None
        if fcntl is not None:
            try:
                folder.mkdir(parents=True, exist_ok=True)
                name = f"{func.__module__}.{func.__qualname__}.lock"
                lock = (folder / name).open("a")
            except OSError:  # a read-only cache: Numba compiles without saving
                pass
        if lock is None:
            yield
            return
        with lock:  # closing the file releases the lock (so does an exit)
            fcntl.flock(lock, fcntl.LOCK_EX)
            yield


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
        if _config.DISABLE_JIT:  # NUMBA_DISABLE_JIT=1: plain Python, as njit
            return func
        dispatcher = _EntryPoint(func, targetoptions=dict(_OPTIONS))
        dispatcher._outputs, dispatcher._contiguous = outputs, contiguous
        dispatcher._vectorize = vectorize
        dispatcher._cache = _SourceKeyedCache(func)
        return cast(F, dispatcher)

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
        if _config.DISABLE_JIT:
            return func
        options = dict(_OPTIONS, no_cpython_wrapper=True, no_cfunc_wrapper=True)
        if forceinline:
            options["forceinline"] = True
        if inline_source:
            options["inline"] = "always"
        dispatcher = _Helper(func, targetoptions=options)
        dispatcher._cache = _SourceKeyedCache(func)
        return cast(F, dispatcher)

    return decorate
