"""Diagnostics as text on standard error (rustc style, ``verify.outputs.rendering.render_all_text``)."""
from __future__ import annotations

from .rendering import render_all_text
from . import Output, Report


def render(report: Report) -> Output:
    if not report.diagnostics:
        return Output()
    return Output(stderr=render_all_text(report.diagnostics, report.sources) + "\n")
