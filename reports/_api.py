"""Public names of :mod:`jointwear.reports` (validation reports and the demo)."""

from jointwear.reports.builder import (
    ReportInput,
    build_report,
    format_value,
    render_html,
    report_from_files,
)
from jointwear.reports.demo import run_demo
from jointwear.reports.pdf import write_pdf

__all__ = [
    "ReportInput",
    "build_report",
    "format_value",
    "render_html",
    "report_from_files",
    "write_pdf",
    "run_demo",
]
