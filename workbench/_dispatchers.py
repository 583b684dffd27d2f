"""Numba's dispatchers of the kernels, imported when a kernel is first compiled.

:mod:`workbench._compiled` says what they do (its module docstring) and builds
them, handing itself over as ``runtime`` (the interpreted mode, the source
digest, the compile notice, the options); this module holds the parts that
need Numba, so that a process that only runs kernels interpreted (``workbench
ik``) or none (``workbench fk``) never imports it.
"""

from __future__ import annotations

import contextlib
import inspect
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np
from llvmlite import binding as llvm
from numba.core import config, registry, sigutils, types
from numba.core.caching import FunctionCache
from numba.core.compiler_lock import global_compiler_lock
from numba.core.runtime import rtsys

try:
    import fcntl
except ImportError:  # Windows: no file locks, each process compiles its own
    fcntl = None  # type: ignore[assignment]

# Numba sets the attributes of its dispatchers and of its config at run time.
_CPUDispatcher: Any = registry.CPUDispatcher
_config: Any = config

#: Scalar types fixed by a parameter's annotation.
_ANNOTATED = {"float": types.float64, "int": types.int64, "bool": types.boolean}


def build_entry_point(
    runtime: Any,
    func: Any,
    outputs: frozenset[str],
    contiguous: frozenset[str],
    vectorize: bool,
) -> Any:
    """The dispatcher of :func:`workbench._compiled.entry_point`'s kernel ``func``."""
    if _config.DISABLE_JIT:  # NUMBA_DISABLE_JIT=1: plain Python, as njit
        return func
    dispatcher = _EntryPoint(func, targetoptions=dict(runtime.OPTIONS))
    dispatcher._runtime = runtime
    dispatcher._outputs, dispatcher._contiguous = outputs, contiguous
    dispatcher._vectorize = vectorize
    dispatcher._cache = _SourceKeyedCache(func, runtime)
    return dispatcher


def build_helper(runtime: Any, func: Any, options: dict[str, Any]) -> Any:
    """The dispatcher of :func:`workbench._compiled.helper`'s kernel ``func``."""
    if _config.DISABLE_JIT:
        return func
    dispatcher = _Helper(func, targetoptions=dict(runtime.OPTIONS, **options))
    dispatcher._runtime = runtime
    dispatcher._cache = _SourceKeyedCache(func, runtime)
    return dispatcher


class _SourceKeyedCache(FunctionCache):
    """Numba's disk cache of a kernel, keyed on the source it can reach too.

    Numba keys a cache entry on the kernel's own bytecode and checks only the
    timestamp of the kernel's own file, so code compiled in from another
    module (an inlined helper, a kernel it calls, a constant it reads) would
    stay as it was when first cached. The key here also holds
    ``source_digest`` of the kernel's module: an edit of any module it
    imports, directly or not, makes a new entry.
    """

    def __init__(self, func: Any, runtime: Any) -> None:
        super().__init__(func)
        self._runtime = runtime

    def _index_key(self, sig: Any, codegen: Any) -> tuple[Any, ...]:
        key = super()._index_key(sig, codegen)
        return (*key, self._runtime.source_digest(self._py_func.__module__))

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        # Numba refreshes the whole target context first (every registry of
        # implementations, SciPy's BLAS among them: half a second), which only
        # a compile needs (its pipeline refreshes it again); running compiled
        # code needs Numba's runtime only.
        rtsys.initialize(target_context)
        loaded = self._load_overload(sig, target_context)
        if loaded is None and self._enabled:
            self._runtime.announce_compile(self._py_func)
        return loaded


class _Interpretable(_CPUDispatcher):
    """A dispatcher that runs its Python function within :func:`interpreted`."""

    _runtime: Any = None  # workbench._compiled, set by the build functions

    def _compile_for_args(self, *args: Any, **kws: Any) -> Any:
        # Numba's C dispatcher calls this on a call no compiled code matches,
        # then calls what it returns with the arguments.
        if self._runtime.is_interpreting():
            return self._interpret
        return super()._compile_for_args(*args, **kws)

    def _interpret(self, *args: Any) -> Any:
        with np.errstate(all="ignore"):
            return self.py_func(*(self._runtime.as_attributes(arg) for arg in args))


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
        llvm.set_option(
            "", f"-vectorize-scev-check-threshold={self._runtime.VECTORIZE_ASSUMPTIONS}"
        )
        llvm.set_option("", f"-force-vector-width={self._runtime.VECTOR_WIDTH}")
        try:
            yield
        finally:
            for name, value in self._runtime.LLVM_DEFAULTS.items():
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
