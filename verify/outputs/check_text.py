"""``check``: the diagnostics on standard error, and a one-line summary when the model is valid."""
from __future__ import annotations

from ..core.diagnostics import has_errors
from ..core.sanitize import shown
from . import Output, Report
from .diagnostics_text import render as diagnostics


def render(report: Report) -> Output:
    out = diagnostics(report)
    if has_errors(report.diagnostics) or report.result is None:
        return out
    comps, systems = len(report.result.project.components), len(report.result.project.systems)
    return Output(f"{shown(report.file)}: ok ({comps} component{'s' * (comps != 1)}, "
                  f"{systems} system{'s' * (systems != 1)})\n", out.stderr)
