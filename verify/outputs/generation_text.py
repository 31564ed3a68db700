"""``verify gen``: what was written, what was already up to date, which user files were left alone."""
from __future__ import annotations

from ..core.sanitize import shown
from . import Output, Report


def render(report: Report) -> Output:
    outcome, directory = report.result, report.extra["directory"]
    lines = [f"generated {report.extra['target']} code for system {report.model.name} in {shown(directory)}"]
    for title, paths in (("written", outcome.written), ("unchanged", outcome.unchanged),
                         ("left alone (yours)", outcome.kept)):
        if paths:
            lines.append(f"  {title}: {len(paths)}")
            lines += [f"    {shown(p)}" for p in paths]
    return Output(stdout="\n".join(lines) + "\n")
