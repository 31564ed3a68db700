"""``analyze``: the analysis report on standard output — the short view (``verify.timing.report.to_brief``:
verdicts first) or, with ``--explain``, the whole derivation (``to_text``) — and its problems (E305/E306,
E310, E311, E312) on standard error."""
from __future__ import annotations

from ..core.sanitize import shown_lines
from ..timing.report import to_brief, to_text
from . import Output, Report
from .diagnostics_text import render as diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    view = to_text if report.extra.get("explain") else to_brief
    return Output(shown_lines(view(report.result)) + "\n", diagnostics(report).stderr)
