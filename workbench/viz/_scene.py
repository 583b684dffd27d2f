"""An in-memory Meshcat scene: records commands, renders a self-contained page.

:class:`SceneRecorder` stands where ``meshcat.Visualizer`` expects its ZMQ
window: every command (``set_object``, ``set_transform``, …) is packed as
Meshcat's viewer expects it and kept in a scene tree, like Meshcat's own
server does. No server process is started. The tree renders to one HTML page
that embeds Meshcat's JavaScript viewer and replays the commands, so it works
offline; listeners (the live server) receive each command as it is sent.
"""

from __future__ import annotations

import base64
import json
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

import umsgpack

from workbench.viz._camera import CameraView

Listener = Callable[[bytes], None]


@dataclass(slots=True)
class _Node:
    """A node of the scene tree: its latest object, transform and properties."""

    object: bytes | None = None
    transform: bytes | None = None
    properties: dict[str, bytes] = field(default_factory=dict)
    children: dict[str, _Node] = field(default_factory=dict)

    def walk(self) -> Iterator[_Node]:
        """This node, then its descendants depth first, in insertion order."""
        yield self
        for child in self.children.values():
            yield from child.walk()


def _split(path: str) -> list[str]:
    return [part for part in path.split("/") if part]


class SceneRecorder:
    """Meshcat window that keeps the scene in memory (thread-safe).

    Pass it as ``meshcat.Visualizer(window=SceneRecorder())``.
    """

    web_url = ""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._root = _Node()
        self._animation: bytes | None = None
        self._listeners: list[Listener] = []

    def send(self, command: Any) -> None:
        """Record one Meshcat command (anything with ``lower()``) and forward it."""
        data = command.lower()
        packed = umsgpack.packb(data)
        kind = data["type"]
        with self._lock:
            if kind == "set_animation":
                self._animation = packed
            else:
                self._record(kind, _split(data["path"]), data, packed)
            listeners = list(self._listeners)
        for listener in listeners:
            listener(packed)

    def _record(self, kind: str, path: list[str], data: dict, packed: bytes) -> None:
        if kind == "delete":
            if not path:
                self._root = _Node()
                self._animation = None
                return
            parent = self._find(path[:-1])
            parent.children.pop(path[-1], None)
            return
        node = self._find(path)
        if kind == "set_object":
            node.object = packed
            node.properties = {}
        elif kind == "set_transform":
            node.transform = packed
        elif kind == "set_property":
            node.properties[data["property"]] = packed

    def _find(self, path: list[str]) -> _Node:
        node = self._root
        for name in path:
            node = node.children.setdefault(name, _Node())
        return node

    def get_commands(self) -> list[bytes]:
        """The packed commands that rebuild the scene, parents first, animation last."""
        with self._lock:
            commands: list[bytes] = []
            for node in self._root.walk():
                if node.object is not None:
                    commands.append(node.object)
                commands.extend(node.properties.values())
                if node.transform is not None:
                    commands.append(node.transform)
            if self._animation is not None:
                commands.append(self._animation)
            return commands

    def add_listener(self, listener: Listener) -> None:
        """Call ``listener(packed_command)`` for every later command."""
        with self._lock:
            self._listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        """Stop forwarding commands to ``listener``."""
        with self._lock:
            if listener in self._listeners:
                self._listeners.remove(listener)

    def get_scene(self) -> str:
        """Self-contained HTML of the current scene (``Visualizer.static_html``)."""
        return render_page(self.get_commands(), camera=None)


def _viewer_javascript() -> str:
    dist = resources.files("meshcat") / "viewer" / "dist" / "main.min.js"
    return dist.read_text(encoding="utf-8")


_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
{overlay}
<script>
{viewer_js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
(function (sceneNode) {{
  /* Meshcat 0.3 colours a node through material.color, which Collada meshes
     with several materials lack: colour every material of every mesh instead. */
  const setProperty = sceneNode.set_property;
  sceneNode.set_property = function (property, value) {{
    if (property !== "color") return setProperty.call(this, property, value);
    this.object.traverse(function (child) {{
      for (const material of [].concat(child.material || [])) {{
        if (!material.color) continue;
        material.color.setRGB(value[0], value[1], value[2]);
        material.opacity = value[3];
        material.transparent = value[3] < 1.0;
      }}
    }});
  }};
}})(Object.getPrototypeOf(viewer.scene_tree));
const WORKBENCH_SCENE = {commands};
for (const text of WORKBENCH_SCENE) {{
  const raw = atob(text);
  const bytes = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  try {{
    viewer.handle_command_bytearray(bytes);
  }} catch (error) {{
    console.error("workbench viewer: a scene command failed:", error);
  }}
}}
(function (view) {{
  if (view === null) return;
  /* Meshcat turns its three.js scene (y up) so that the base frame has z up;
     the camera and its orbit target live in three.js coordinates (x, z, -y). */
  const [px, py, pz] = view.position;
  const [tx, ty, tz] = view.target;
  viewer.camera.fov = view.fov;
  viewer.camera.position.set(px, pz, -py);
  viewer.controls.target.set(tx, tz, -ty);
  viewer.controls.update();
  viewer.set_3d_pane_size();
}})({camera});
{live}
</script>
</body>
</html>
"""

_CONNECT = """try {
  viewer.connect("ws://" + location.host + "/ws");
} catch (e) {
  console.info("Not connected to the workbench viewer server: ", e);
}"""


def render_page(
    commands: list[bytes],
    *,
    camera: CameraView | None,
    title: str = "workbench viewer",
    live: bool = False,
    overlay: str = "",
) -> str:
    """HTML page that embeds Meshcat's viewer and replays ``commands``.

    Args:
        commands: Packed commands, as from :meth:`SceneRecorder.get_commands`.
        camera: Initial camera; None keeps Meshcat's default.
        title: Page title (HTML-escaped here).
        live: Also connect to the live server's websocket (``/ws`` on the
            page's own host) for later commands.
        overlay: HTML drawn over the scene (the title and legend box).

    Returns:
        The page; it needs no network access unless ``live``.
    """
    view = None
    if camera is not None:
        view = {
            "position": [float(x) for x in camera.position],
            "target": [float(x) for x in camera.target],
            "fov": float(camera.fov_deg),
        }
    encoded = [base64.b64encode(c).decode("ascii") for c in commands]
    escaped = title.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return _PAGE.format(
        title=escaped,
        viewer_js=_viewer_javascript(),
        commands=json.dumps(encoded),
        camera=json.dumps(view),
        live=_CONNECT if live else "",
        overlay=overlay,
    )
