"""``trace --format json``: schema ``verify.trace/1`` (``verify.trace.report``), the findings as
``verify.diagnostics/1`` items."""
from __future__ import annotations

from . import Output, Report
from .diagnostics_json import render as diagnostics, with_diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    from ..trace.report import to_json

    return with_diagnostics(to_json(report.result), report)
