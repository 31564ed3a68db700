"""``trace``: the measurements on standard output (``verify.trace.report.to_text``), the findings
(E801–E806) on standard error."""
from __future__ import annotations

from ..core.sanitize import shown_lines
from . import Output, Report
from .diagnostics_text import render as diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    from ..trace.report import to_text

    return Output(shown_lines(to_text(report.result)), diagnostics(report).stderr)
