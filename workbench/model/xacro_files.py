"""xacro robot descriptions, expanded to URDF by the ROS ``xacro`` package.

Most ROS description packages ship xacro (macros, includes, arguments), not
URDF. :func:`expand_xacro` runs the ``xacro`` package from the package index
(the ROS tool itself) on a file, with its ``<xacro:arg>`` values and with
``$(find PKG)`` resolved by the workbench's package lookup
(:mod:`workbench.model.packages`: ``--package-dir``, ``ROS_PACKAGE_PATH``, the
file's folders) instead of a ROS installation. Its messages (warnings on
stderr) are kept out of the output; an error is one :class:`URDFLoadError`.
"""

from __future__ import annotations

import contextlib
import io
import re
import threading
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path

from workbench.errors import URDFLoadError
from workbench.model.packages import PackageLookup

#: Suffixes of files read as xacro.
XACRO_SUFFIXES = (".xacro", ".urdf.xacro")
_LOCK = threading.Lock()  # xacro keeps its state in module globals
_UNSET = re.compile(r"[Uu]ndefined substitution argument (\S+)")


def is_xacro(path: str | Path) -> bool:
    """Whether ``path`` names a xacro file (by its suffix)."""
    return str(path).lower().endswith(".xacro")


def expand_xacro(
    path: str | Path, lookup: PackageLookup, args: Mapping[str, str] | None = None
) -> str:
    r"""The URDF text of the xacro file ``path``.

    Args:
        path: The ``.xacro`` file.
        lookup: Where ``$(find PKG)`` looks for packages.
        args: Values of the file's ``<xacro:arg>``\\ s (as ``NAME:=VALUE`` on
            the xacro command line).

    Raises:
        URDFLoadError: If the file cannot be read, a package is not found, an
            argument is missing, or xacro refuses the file (its message).
    """
    import xacro  # type: ignore[import-untyped]
    from xacro import substitution_args

    path = Path(path)
    if not path.is_file():
        raise URDFLoadError(f"xacro file not found: {path}")

    def find(name: str) -> str:
        folder = lookup.find(name)
        if folder is None:
            raise URDFLoadError(
                f"{path}: $(find {name}): package {name!r} not found (looked in "
                f"{lookup.describe_search()}); give its folder with --package-dir "
                f"DIR or --package-dir {name}=DIR"
            )
        return str(folder)

    mappings = {str(k): str(v) for k, v in (args or {}).items()}
    with _LOCK, _patched(substitution_args, find), _quiet() as messages:
        try:
            document = xacro.process_file(str(path), mappings=mappings)
        except URDFLoadError:
            raise
        except Exception as err:  # xacro raises many kinds; its message says what
            reason = str(err).strip() or type(err).__name__
            unset = _UNSET.search(reason)
            if unset is not None:
                name = unset.group(1)
                raise URDFLoadError(
                    f"{path}: xacro argument {name!r} is not set (give it with "
                    f"--xacro-arg {name}:=VALUE, or xacro_args={{{name!r}: ...}})"
                ) from None
            detail = next((m for m in messages() if m.strip()), "")
            more = f" ({detail.strip()})" if detail and detail not in reason else ""
            raise URDFLoadError(f"{path}: xacro: {reason}{more}") from None
    return str(document.toprettyxml(indent="  "))


@contextlib.contextmanager
def _patched(module: object, find: object) -> Iterator[None]:
    """Xacro's ``$(find)`` (and ``find`` of its expressions) replaced by ``find``."""
    saved = module._eval_find  # type: ignore[attr-defined]
    saved_eval = module._eval_dict.get("find")  # type: ignore[attr-defined]
    module._eval_find = find  # type: ignore[attr-defined]
    module._eval_dict["find"] = find  # type: ignore[attr-defined]
    try:
        yield
    finally:
        module._eval_find = saved  # type: ignore[attr-defined]
        module._eval_dict["find"] = saved_eval  # type: ignore[attr-defined]


@contextlib.contextmanager
def _quiet() -> Iterator[Callable[[], list[str]]]:
    """Collect what xacro prints on stderr (warnings) instead of printing it."""
    sink = io.StringIO()
    with contextlib.redirect_stderr(sink), contextlib.redirect_stdout(sink):
        yield lambda: sink.getvalue().splitlines()


__all__ = ["XACRO_SUFFIXES", "expand_xacro", "is_xacro"]
