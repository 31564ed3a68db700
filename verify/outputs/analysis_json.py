"""``analyze --format json``: schema ``verify.analysis/1`` (``verify.timing.report``), the problems as
``verify.diagnostics/1`` items."""
from __future__ import annotations

from ..timing.report import to_json
from . import Output, Report
from .diagnostics_json import render as diagnostics, with_diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    return with_diagnostics(to_json(report.result), report)
