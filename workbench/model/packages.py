"""ROS packages and the mesh URIs of a robot description, resolved when it is loaded.

A URDF names its meshes by URI: ``package://PKG/path`` (a file in the ROS
package PKG), ``file:///abs/path``, or a path relative to the URDF's folder.
:class:`PackageLookup` finds a package the ROS way, by the ``<name>`` of its
``package.xml`` (crawled with :mod:`rospkg`, the ROS tool's own library), or by
its folder name, in this order:

1. packages mapped explicitly (``--package-dir NAME=DIR``,
   ``load_robot(package_dirs=["NAME=DIR"])``);
2. the folders given (``--package-dir DIR``, ``load_robot(package_dirs=...)``):
   each may be a package, or hold packages at any depth;
3. the folders of the ``ROS_PACKAGE_PATH`` environment variable, likewise;
4. the given folders and the description's own folder, then each of their
   parents: the package such a folder is in (the nearest folder with a
   ``package.xml``), the packages beside it, and a folder of the package's
   name in any of them.

:func:`resolve_mesh_uris` rewrites every mesh URI of a description to the
absolute path of its file when the robot is loaded, so that a missing mesh is
one clear error then (it names the URI, where it looked and ``--package-dir``),
never a traceback when the geometry is first used.
"""

from __future__ import annotations

import os
import re
import threading
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote, urlparse

from workbench.errors import URDFLoadError

#: The environment variable of ROS folders holding packages (``os.pathsep``-separated).
ROS_PACKAGE_PATH = "ROS_PACKAGE_PATH"
#: The file that makes a folder a ROS package.
PACKAGE_FILE = "package.xml"
_PACKAGE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
_MESH = re.compile(r"""(<mesh\b[^>]*?\bfilename\s*=\s*)(["'])(.*?)\2""", re.S)


class MeshNotFoundError(URDFLoadError):
    """A mesh of a robot description is not where its URI points."""


@dataclass
class PackageLookup:
    """Where the ROS packages of one description are looked for (module docs).

    Attributes:
        mapped: Packages given explicitly, name → folder.
        roots: Folders holding packages (given, then ``ROS_PACKAGE_PATH``).
        description: The description file whose folders are searched last.
    """

    mapped: dict[str, Path]
    roots: tuple[Path, ...]
    description: Path
    _crawled: dict[str, str] | None = field(default=None, repr=False)
    _found: dict[str, Path | None] = field(default_factory=dict, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def find(self, name: str) -> Path | None:
        """The folder of package ``name``, or None where it is in none of them."""
        if name not in self._found:
            self._found[name] = self._find(name)
        return self._found[name]

    def _find(self, name: str) -> Path | None:
        if name in self.mapped:
            return self.mapped[name]
        crawled = self._packages_in_roots().get(name)
        if crawled is not None:
            return Path(crawled)
        for root in self.roots:  # by folder name: a package's own folder, or in it
            if root.name == name:
                return root
            if (root / name).is_dir():
                return root / name
        for start in (*self.roots, self.description.resolve().parent):
            found = _find_upwards(start, name)
            if found is not None:
                return found
        return None

    def describe_search(self) -> str:
        """Where :meth:`find` looks, for messages."""
        parts = [f"{n}={p}" for n, p in self.mapped.items()]
        parts += [str(root) for root in self.roots]
        parts.append(f"{self.description.resolve().parent} and its parents")
        if self.roots:
            parts[-1] = f"the parents of these and {parts[-1]}"
        return "; ".join(parts)

    def _packages_in_roots(self) -> dict[str, str]:
        """Package name → folder of every ``package.xml`` under the roots."""
        with self._lock:
            if self._crawled is None:
                self._crawled = _crawl(self.roots)
            return self._crawled


def get_package_lookup(
    description: str | Path, package_dirs: Sequence[str | Path] = ()
) -> PackageLookup:
    """The lookup of a description's packages (module docs for the order).

    Args:
        description: The URDF (or xacro) file.
        package_dirs: Folders holding packages (or packages themselves), and
            ``"NAME=DIR"`` entries mapping one package to its folder.

    Raises:
        URDFLoadError: If a given folder does not exist.
    """
    mapped: dict[str, Path] = {}
    roots: list[Path] = []
    for entry in package_dirs:
        name, folder = split_package_dir(entry)
        path = Path(folder).expanduser()
        if not path.is_dir():
            given = str(entry) if name is None else f"{name}={path}"
            raise URDFLoadError(f"package folder not found: {given}")
        if name is None:
            roots.append(path.resolve())
        else:
            mapped[name] = path.resolve()
    for entry in os.environ.get(ROS_PACKAGE_PATH, "").split(os.pathsep):
        if entry and Path(entry).is_dir():
            roots.append(Path(entry).resolve())
    return PackageLookup(mapped, tuple(dict.fromkeys(roots)), Path(description))


def split_package_dir(entry: str | Path) -> tuple[str | None, str | Path]:
    """``(name, folder)`` of a ``NAME=DIR`` entry, ``(None, entry)`` of a folder.

    An entry is a mapping when it holds ``=``, what precedes it is a package
    name (letters, digits, ``_`` and ``-``) and the whole entry is no folder.
    """
    text = str(entry)
    if "=" in text and not Path(text).is_dir():
        name, folder = text.split("=", 1)
        if _PACKAGE_NAME.fullmatch(name) and folder:
            return name, folder
    return None, entry


def resolve_uri(uri: str, lookup: PackageLookup, base: Path) -> Path:
    """The file a mesh URI names.

    Args:
        uri: ``package://PKG/path``, ``file:///path`` or a relative or
            absolute path.
        lookup: Where packages are looked for.
        base: The folder relative paths start from (the description's).

    Raises:
        MeshNotFoundError: If the package or the file is not found; the
            message names the URI, where it looked and ``--package-dir``.
    """
    parsed = urlparse(uri)
    if parsed.scheme == "package":
        name, rest = parsed.netloc, unquote(parsed.path).lstrip("/")
        if not name:  # package:///PKG/path, a slash too many (read as ROS does)
            name, _, rest = rest.partition("/")
        folder = lookup.find(name)
        if folder is None:
            raise MeshNotFoundError(
                f"{lookup.description}: mesh {uri}: package {name!r} not found (looked "
                f"in {lookup.describe_search()}); give its folder with --package-dir "
                f"DIR or --package-dir {name}=DIR"
            )
        path = folder / rest
        where = f"in package {name} at {folder}"
    elif parsed.scheme == "file":
        path = Path(unquote(parsed.path))
        where = "(a file:// URI)"
    elif parsed.scheme and len(parsed.scheme) > 1:  # (not a Windows drive letter)
        raise MeshNotFoundError(
            f"{lookup.description}: mesh {uri}: URIs of scheme {parsed.scheme!r} are "
            "not supported (package://, file:// or a path)"
        )
    else:
        path = base / uri
        where = f"relative to {base}"
    if not path.is_file():
        raise MeshNotFoundError(
            f"{lookup.description}: mesh {uri} not found: no file {path} ({where}); "
            "give the package's folder with --package-dir DIR or --package-dir NAME=DIR"
        )
    return path.resolve()


def resolve_mesh_uris(text: str, lookup: PackageLookup) -> str:
    """The description ``text`` with every mesh URI replaced by its file's path.

    Raises:
        MeshNotFoundError: For the first mesh that is not found
            (:func:`resolve_uri`).
    """
    base = lookup.description.resolve().parent
    resolved: dict[str, str] = {}

    def replace(match: re.Match[str]) -> str:
        uri = _unescape(match.group(3).strip())
        if uri not in resolved:
            resolved[uri] = _escape(str(resolve_uri(uri, lookup, base)))
        return f"{match.group(1)}{match.group(2)}{resolved[uri]}{match.group(2)}"

    return _MESH.sub(replace, text)


def _crawl(roots: Sequence[Path]) -> dict[str, str]:
    """Package name → folder under ``roots``, the first root winning (rospkg)."""
    if not roots:
        return {}
    import rospkg  # type: ignore[import-untyped]  # the ROS package crawler

    found: dict[str, str] = {}
    for root in roots:
        pack = rospkg.RosPack(ros_paths=[str(root)])
        for name in pack.list():
            found.setdefault(name, pack.get_path(name))
    return found


def _find_upwards(start: Path, name: str) -> Path | None:
    """Package ``name`` at ``start`` or a parent: that folder, in it or beside it."""
    for folder in (start, *start.parents):
        if _package_name(folder) == name:
            return folder
        if (folder / name).is_dir():
            return folder / name
        for child in _children(folder):
            if _package_name(child) == name:
                return child
    return None


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of ``folder/package.xml``, or None."""
    manifest = folder / PACKAGE_FILE
    if not manifest.is_file():
        return None
    try:
        name = ET.parse(manifest).getroot().findtext("name")
    except (OSError, ET.ParseError):
        return None
    return name.strip() if name else None


def _children(folder: Path) -> list[Path]:
    try:
        return [
            c for c in folder.iterdir() if c.is_dir() and not c.name.startswith(".")
        ]
    except OSError:
        return []


def _unescape(value: str) -> str:
    return (
        value.replace("&quot;", '"').replace("&apos;", "'").replace("&lt;", "<")
        .replace("&gt;", ">").replace("&amp;", "&")
    )  # fmt: skip


def _escape(value: str) -> str:
    return (
        value.replace("&", "&amp;").replace('"', "&quot;").replace("'", "&apos;")
        .replace("<", "&lt;").replace(">", "&gt;")
    )  # fmt: skip


__all__ = [
    "PACKAGE_FILE",
    "ROS_PACKAGE_PATH",
    "MeshNotFoundError",
    "PackageLookup",
    "get_package_lookup",
    "resolve_mesh_uris",
    "resolve_uri",
    "split_package_dir",
]
