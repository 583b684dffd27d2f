"""3D viewer on Meshcat: configurations, animations, tool paths, triads, ghosts.

Imported on demand (``from workbench import viz``); the core modules never
import it. Needs ``meshcat``; :class:`TeachPanel` also needs ``ipywidgets``.

Example::

    from workbench import load_robot
    from workbench.viz import Viewer

    viewer = Viewer(load_robot("puma560"), color_by_singularity=True)
    viewer.display([0.0, -0.8, 3.1, 0.0, 0.8, 0.0])
    viewer.save_html("puma.html")      # offline page
    print(viewer.start_server())       # or live, on http://127.0.0.1:PORT/
    viewer.serve_forever()
"""

from workbench.viz import _meshcat  # noqa: F401  (first: quiet import)
from workbench.viz.motion_page import write_motion_html
from workbench.viz.preview import write_trajectory_html
from workbench.viz.redundancy_sweep import (
    MAX_SWEEP,
    RedundancySweep,
    compute_redundancy_sweep,
    find_branch,
    show_redundancy_sweep,
    spread_over_intervals,
)
from workbench.viz.singularity_gauge import SingularityGauge, get_singularity_color
from workbench.viz.teach import TeachPanel
from workbench.viz.viewer import Viewer
from workbench.viz.workspace_view import (
    get_map_robot,
    make_workspace_viewer,
    write_workspace_view,
)

__all__ = [
    "MAX_SWEEP",
    "RedundancySweep",
    "SingularityGauge",
    "TeachPanel",
    "Viewer",
    "compute_redundancy_sweep",
    "find_branch",
    "get_map_robot",
    "get_singularity_color",
    "make_workspace_viewer",
    "show_redundancy_sweep",
    "spread_over_intervals",
    "write_motion_html",
    "write_trajectory_html",
    "write_workspace_view",
]
