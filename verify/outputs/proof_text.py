"""``prove``: the table of verdicts and every counterexample's timeline (``verify.prove.report``) on
standard output, the diagnostics (E501–E503, or why the input is invalid) on standard error."""
from __future__ import annotations

from ..prove.report import to_text
from ..core.sanitize import shown_lines
from . import Output, Report
from .diagnostics_text import render as diagnostics


def render(report: Report) -> Output:
    stderr = diagnostics(report).stderr
    if report.result is None:
        return Output(stderr=stderr)
    return Output(shown_lines(to_text(report.model, report.result)), stderr)
