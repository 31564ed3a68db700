"""``synth``: the completed file (or ``--diff``) on standard output and the summary on standard error; with
``-o``/``--in-place`` the summary on standard output. Without a configuration, the diagnostics only."""
from __future__ import annotations

from .rendering import render_all_text
from ..core.sanitize import shown_lines
from ..synth.report import to_text
from . import Output, Report


def render(report: Report) -> Output:
    dsl = report.extra.get("dsl")
    diagnostics = render_all_text(report.diagnostics, report.sources) + "\n" if report.diagnostics else ""
    if dsl is None:
        return Output(stderr=diagnostics)
    summary = shown_lines(to_text(report.result))  # (the model text itself is the user's, kept as it is)
    if report.extra.get("written") is not None:
        return Output(summary, diagnostics)
    diff = report.extra.get("diff")
    return Output(diff if diff is not None else dsl, summary + diagnostics)
