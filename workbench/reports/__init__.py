"""Self-contained HTML reports (figures embedded as PNG data URIs)."""

from workbench.reports.html_report import HtmlReport
from workbench.reports.singularity_report import (
    SingularityReport,
    build_singularity_report,
    write_singularity_report,
)
from workbench.reports.workspace_report import (
    WorkspaceReport,
    build_workspace_report,
    choose_heights,
    compute_singular_distances,
    write_workspace_report,
)

__all__ = [
    "HtmlReport",
    "SingularityReport",
    "WorkspaceReport",
    "build_singularity_report",
    "build_workspace_report",
    "choose_heights",
    "compute_singular_distances",
    "write_singularity_report",
    "write_workspace_report",
]
