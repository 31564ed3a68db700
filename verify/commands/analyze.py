"""``verify analyze FILE``: rates, sampling, response times and chain latencies (specs/timing.md)."""
from __future__ import annotations

import argparse
from collections.abc import Iterable

from ..diagnostics import Diagnostic
from ..outputs import Report, render
from .common import EXIT_INVALID, EXIT_OK, EXIT_VIOLATED, load_configured, show

HELP = "rates, sampling, response times and chain latencies"
RESULT = "analysis"
MODEL, SYSTEM = True, True

#: analysis errors that say the configured system misses its timing (overload, a response time with
#: no bound within the deadline): exit 1, as `prove` exits 1 on a missed deadline (E503); every other
#: analysis error (a rate outside a constraint or tolerance) says the configuration is invalid: exit 2
TIMING_FAILURES = frozenset({"E311", "E312"})


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data-age", choices=("reduced", "non-reduced"), default="reduced",
                   help="data age measured from the first task's read (reduced) or from the earliest event")


def run(args: argparse.Namespace) -> int:
    loaded = load_configured(args, "analyze")
    if isinstance(loaded, int):
        return loaded
    result, system = loaded
    from ..timing import analyze, diagnostics_of

    analysis = analyze(system, data_age=args.data_age)
    problems = diagnostics_of(analysis)
    show(render(RESULT, args.format, Report(RESULT, args.file, tuple(problems), result.sources, analysis, system)))
    return analysis_exit_code(problems)


def analysis_exit_code(problems: Iterable[Diagnostic]) -> int:
    errors = {d.code for d in problems if d.severity.value == "error"}
    if not errors:
        return EXIT_OK
    return EXIT_VIOLATED if errors <= TIMING_FAILURES else EXIT_INVALID
