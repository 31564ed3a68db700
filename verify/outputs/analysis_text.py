"""``analyze``: the analysis report (``verify.timing.report.to_text``) on standard output, its problems
(E305/E306, E310, E311, E312) on standard error."""
from __future__ import annotations

from ..sanitize import shown_lines
from ..timing.report import to_text
from . import Output, Report
from .diagnostics_text import render as diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    return Output(shown_lines(to_text(report.result)) + "\n", diagnostics(report).stderr)
