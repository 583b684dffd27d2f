"""Package front doors that import their modules on first use (PEP 562).

A package's ``__init__`` re-exports the public names of its modules; importing
them all at once makes ``import workbench.workspace.grid`` (or a constant of
one module) pay for every module of the package and what they import (Zarr,
Dask, SciPy, Numba). A lazy package writes its re-exports once, as usual, but
inside ``if TYPE_CHECKING:`` (for mypy and readers), and ends with::

    __getattr__, __dir__ = attach(__name__, __file__, __all__)

:func:`attach` reads those ``from workbench.x.y import name`` lines from the
package's own source, and the package then imports a module when one of its
names is first asked for (``workbench.workspace.build_map``, ``from
workbench.workspace import build_map``); a submodule asked for as an
attribute is imported too.

:func:`call_when_imported` serves what listens to a heavy package (the
progress line and the command line's Ctrl-C guard listen to Numba's compile
events): it waits for that package's import instead of importing it, so a
command that never compiles never imports Numba.
"""

from __future__ import annotations

import ast
import importlib
import importlib.abc
import importlib.machinery
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any


def _type_checking_imports(source: str) -> dict[str, str]:
    """Name -> module of the ``from M import name`` lines under ``if TYPE_CHECKING``."""
    found: dict[str, str] = {}
    for node in ast.parse(source).body:
        if not (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"):
            continue
        for line in node.body:
            if isinstance(line, ast.ImportFrom) and line.module and not line.level:
                for alias in line.names:
                    found[alias.asname or alias.name] = line.module
    return found


def attach(
    package: str, init_file: str, public: Sequence[str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of a lazy package (module docstring).

    Args:
        package: The package's ``__name__``.
        init_file: The package's ``__file__`` (its ``__init__.py``).
        public: The package's ``__all__``; each name must come from one of
            the ``TYPE_CHECKING`` imports.

    Raises:
        ImportError: If a name of ``public`` has no ``TYPE_CHECKING`` import
            (a package whose front door would miss a name).
    """
    origins = _type_checking_imports(Path(init_file).read_text(encoding="utf-8"))
    missing = sorted(set(public) - set(origins))
    if missing:
        raise ImportError(f"{package}: no lazy import for {', '.join(missing)}")

    def __getattr__(name: str) -> Any:
        module = origins.get(name)
        if module is not None:
            value = getattr(importlib.import_module(module), name)
            setattr(sys.modules[package], name, value)  # the next access is direct
            return value
        if name.startswith("__"):  # dunders are never submodules or names here
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        try:
            return importlib.import_module(f"{package}.{name}")
        except ModuleNotFoundError as err:
            if err.name != f"{package}.{name}":
                raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(public))

    sys.modules[package].__class__ = _shadowing(origins)
    return __getattr__, __dir__


def _shadowing(origins: dict[str, str]) -> type[ModuleType]:
    """A module class whose names shadow submodules of the same name.

    ``workbench.trajectory.pick_and_place`` is a function of the module
    ``workbench.trajectory.pick_and_place``: importing that module sets the
    package's attribute to the module, and an eager ``__init__`` would then
    have set it back to the function. This class does the latter at once.
    """

    class _LazyPackage(ModuleType):
        def __setattr__(self, name: str, value: Any) -> None:
            if isinstance(value, ModuleType) and origins.get(name) == value.__name__:
                value = getattr(value, name)
            super().__setattr__(name, value)

    return _LazyPackage


def call_when_imported(name: str, callback: Callable[[], None]) -> Callable[[], None]:
    """Call ``callback`` now if module ``name`` is imported, else right after.

    Args:
        name: A top-level module (``"numba"``).
        callback: Called once, with no arguments, in the thread that imports
            the module, once its code has run.

    Returns:
        A function that cancels the wait (if the module was not imported yet).
    """
    if name in sys.modules:
        callback()
        return lambda: None
    finder = _AfterImport(name, callback)
    sys.meta_path.insert(0, finder)

    def cancel() -> None:
        if finder in sys.meta_path:
            sys.meta_path.remove(finder)

    return cancel


class _AfterImport(importlib.abc.MetaPathFinder):
    """Calls ``then`` once module ``name`` has been imported (then steps aside)."""

    def __init__(self, name: str, then: Callable[[], None]) -> None:
        self._name, self._then = name, then

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: Any = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname != self._name:
            return None
        if self in sys.meta_path:
            sys.meta_path.remove(self)  # the other finders find the module
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None:
            return spec
        spec.loader = _Loader(spec.loader, self._then)
        return spec


class _Loader(importlib.abc.Loader):
    """A module's own loader, then ``then`` (the module keeps its own loader)."""

    def __init__(self, wrapped: Any, then: Callable[[], None]) -> None:
        self._wrapped, self._then = wrapped, then

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> Any:
        return self._wrapped.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        module.__loader__ = self._wrapped
        if module.__spec__ is not None:
            module.__spec__.loader = self._wrapped
        self._wrapped.exec_module(module)
        self._then()

    def __getattr__(self, name: str) -> Any:  # get_data, is_package, ...
        return getattr(self._wrapped, name)
