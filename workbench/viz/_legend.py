"""The title and legend drawn over a viewer page (an HTML box, top left).

Meshcat draws the 3D scene only; what its colours and markers mean is said
here, next to it: the singularity colour ramp, the tool path with its start and
end markers, the frame triads, the ghost arms. Each entry is an HTML fragment;
:func:`render_overlay` stacks them under the page title. Meshcat's own control
panel stays at the top right, so the box sits at the top left, and it ignores
the mouse so the scene can still be turned underneath it. In a small view (a page
inlined in a notebook or the docs) the box starts folded to its title, which opens
it with a click.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence

import numpy as np
import numpy.typing as npt

from workbench.viz._shapes import AXIS_COLORS
from workbench.viz.singularity_gauge import SingularityGauge

_AXIS_RGB = tuple(
    ((c >> 16) / 255.0, ((c >> 8) & 0xFF) / 255.0, (c & 0xFF) / 255.0)
    for c in AXIS_COLORS
)

_STYLE = """<style>
#workbench-legend {
  position: absolute; top: 8px; left: 8px; z-index: 10; max-width: 330px;
  padding: 8px 10px; border-radius: 4px; pointer-events: none;
  background: rgba(255, 255, 255, 0.88); color: #222;
  font: 12px/1.35 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif;
  box-shadow: 0 1px 3px rgba(0, 0, 0, 0.3);
}
#workbench-legend h1 { font-size: 15px; margin: 0; display: inline; }
#workbench-legend summary { pointer-events: auto; cursor: pointer;
  list-style: none; margin-bottom: 6px; }
#workbench-legend summary::-webkit-details-marker { display: none; }
#workbench-legend summary::after { content: " ▾"; color: #555; }
#workbench-legend:not([open]) { padding: 4px 8px; }
#workbench-legend:not([open]) summary { margin-bottom: 0; }
#workbench-legend:not([open]) h1 { font-size: 13px; }
#workbench-legend:not([open]) summary::after { content: " ▸ legend";
  font-size: 11px; }
#workbench-legend .row { display: flex; align-items: center; margin: 2px 0; }
#workbench-legend .key { flex: none; width: 22px; margin-right: 6px; }
#workbench-legend .dot { height: 10px; width: 10px; border-radius: 50%;
  margin: 0 12px 0 6px; }
#workbench-legend .line { height: 3px; }
#workbench-legend .ramp { height: 10px; margin: 3px 0 1px 0; }
#workbench-legend .ticks { position: relative; height: 14px;
  font-size: 11px; color: #555; }
#workbench-legend .ticks span { position: absolute; transform: translateX(-50%);
  white-space: nowrap; }
#workbench-legend .ends { display: flex; justify-content: space-between;
  font-size: 11px; color: #555; }
#workbench-legend .ticks span:first-child { transform: none; }
#workbench-legend .ticks span:last-child { transform: translateX(-100%); }
</style>"""


#: Width and height [CSS px] below which the legend starts folded.
SMALL_VIEW_PX = (720, 480)
_FOLD_IN_SMALL_VIEW = f"""<script>
(function () {{
  var box = document.getElementById("workbench-legend");
  if (box && (window.innerWidth < {SMALL_VIEW_PX[0]}
              || window.innerHeight < {SMALL_VIEW_PX[1]})) box.open = false;
}})();
</script>"""


def _css(rgb: npt.ArrayLike) -> str:
    """CSS colour of an RGB triple in [0, 1]."""
    r, g, b = (round(255 * float(c)) for c in np.clip(rgb, 0.0, 1.0))
    return f"rgb({r}, {g}, {b})"


def _row(key: str, label: str) -> str:
    return f'<div class="row">{key}<span>{html.escape(label)}</span></div>'


def dot(rgb: npt.ArrayLike, label: str) -> str:
    """A legend row: a round marker of colour ``rgb`` (in [0, 1])."""
    key = f'<span class="key dot" style="background: {_css(rgb)}"></span>'
    return _row(key, label)


def line(rgb: npt.ArrayLike, label: str) -> str:
    """A legend row: a line of colour ``rgb`` (in [0, 1])."""
    return _row(
        f'<span class="key line" style="background: {_css(rgb)}"></span>', label
    )


def color_scale(
    title: str,
    what: str,
    stops: Sequence[tuple[float, Sequence[float]]],
    ticks: Sequence[tuple[float, str]],
    ends: tuple[str, str] | None = None,
) -> str:
    """A colour ramp with its tick labels (and words at its two ends).

    Args:
        title: Bold heading, e.g. "Arm colour".
        what: What the colour measures, with its unit.
        stops: ``(position in [0, 1], RGB in [0, 1])``, increasing positions.
        ticks: ``(position in [0, 1], label)`` under the ramp.
        ends: Words under the two ends (e.g. "singular", "far"), if any.
    """
    gradient = ", ".join(f"{_css(rgb)} {100 * x:g}%" for x, rgb in stops)
    if stops[-1][0] < 1.0:
        gradient += f", {_css(stops[-1][1])} 100%"
    marks = "".join(
        f'<span style="left: {100 * x:g}%">{html.escape(text)}</span>'
        for x, text in ticks
    )
    words = ""
    if ends is not None:
        words = "".join(f"<span>{html.escape(word)}</span>" for word in ends)
        words = f'<div class="ends">{words}</div>'
    return (
        f"<div><b>{html.escape(title)}</b>: {html.escape(what)}"
        f'<div class="ramp" style="background: linear-gradient(to right, {gradient})">'
        f'</div><div class="ticks">{marks}</div>{words}</div>'
    )


def singularity_scale(gauge: SingularityGauge) -> str:
    """The colour ramp of the arm's links and what its distance measures."""
    if gauge.method == "analytic":
        measure = "min(|shoulder| / reach, |sin elbow|, |sin θ5|)"
    else:
        measure = "inverse condition number of J, scaled"
    return color_scale(
        "Arm colour",
        f"distance to the nearest singularity, {measure}",
        SingularityGauge.COLOR_STOPS,
        ((0.0, "0"), (0.2, "0.2"), (0.5, "0.5"), (1.0, "1")),
        ("singular", "far"),
    )


def tool_path(
    path_rgb: Sequence[float], start_rgb: Sequence[float], end_rgb: Sequence[float]
) -> str:
    """The tool path line and its start and end markers."""
    return (
        line(path_rgb, "tool path")
        + dot(start_rgb, "start of the path")
        + dot(end_rgb, "end of the path")
    )


def triads(what: str) -> str:
    """Frame triads drawn for ``what`` (e.g. "tool frame", "targets")."""
    key = (
        '<span class="key" style="display: flex; gap: 2px">'
        + "".join(
            f'<span class="line" style="flex: 1; background: {_css(rgb)}"></span>'
            for rgb in _AXIS_RGB
        )
        + "</span>"
    )
    return _row(key, f"{what}: x red, y green, z blue")


def ghosts(labels: Sequence[str], colors: Sequence[Sequence[float]]) -> str:
    """One row per translucent ghost arm (e.g. each IK branch)."""
    rows = "".join(dot(rgb, label) for label, rgb in zip(labels, colors, strict=True))
    return f"<div><b>Ghost arms</b>{rows}</div>"


def collisions(obstacles: Sequence[str]) -> str:
    """The colours of a collision-checked page (links, contacts, closest pair)."""
    from workbench.viz.collision_overlay import CLOSEST_RGB, CONTACT_RGB, LINK_RGB

    named = f" ({', '.join(obstacles)})" if obstacles else ""
    return (
        f"<div><b>Collisions</b> with the scene{html.escape(named)}"
        + dot(LINK_RGB, "link, no contact")
        + dot(CONTACT_RGB, "in contact")
        + dot(CLOSEST_RGB, "closest pair (markers on the closest points)")
        + "</div>"
    )


def render_overlay(title: str, entries: Iterable[str]) -> str:
    """The box: ``title`` as a heading, then each legend entry (HTML).

    The box is a ``<details>`` element: open, unless the view is smaller than
    :data:`SMALL_VIEW_PX`, where it starts folded to its title.
    """
    body = "".join(entries)
    return (
        f'{_STYLE}<details id="workbench-legend" open><summary>'
        f"<h1>{html.escape(title)}</h1></summary>{body}</details>{_FOLD_IN_SMALL_VIEW}"
    )
