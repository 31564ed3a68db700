"""``verify analyze FILE``: rates, sampling, response times and chain latencies (specs/timing.md).

The text leads with the verdict of every spec, then the cores, tasks and chains in short; ``--explain``
(``-v``) prints the whole derivation instead. JSON and SARIF are the same either way.

Exit codes: 0 every latency spec and deadline proved by the analysis' bounds; 3 a spec or deadline not
proved by its bound (an upper bound above it proves nothing either way: ``prove`` decides it, E316 for a
deadline); 1 the system misses its timing (``TIMING_FAILURES``); 2 invalid input; 70 internal error.
"""
from __future__ import annotations

import argparse
from collections.abc import Iterable

from ..core.diagnostics import Diagnostic
from ..outputs import Report, render
from .common import EXIT_INVALID, EXIT_OK, EXIT_UNDECIDED, EXIT_VIOLATED, load_configured, show

HELP = "rates, sampling, response times and chain latencies"
RESULT = "analysis"
MODEL, SYSTEM = True, True

#: analysis errors that say the configured system misses its timing (overload, a response time with
#: no bound at all): exit 1, as `prove` exits 1 on a missed deadline (E503); every other
#: analysis error (a rate outside a constraint or tolerance) says the configuration is invalid: exit 2
TIMING_FAILURES = frozenset({"E311", "E312"})


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data-age", choices=("reduced", "non-reduced"), default="reduced",
                   help="data age measured from the first task's read (reduced) or from the earliest event")
    p.add_argument("--explain", "-v", "--verbose", dest="explain", action="store_true",
                   help="text: the derivation of every number (activation models, the rule of specs/timing.md "
                        "behind each bound, each chain hop by hop) after the outline")


def run(args: argparse.Namespace) -> int:
    loaded = load_configured(args, "analyze")
    if isinstance(loaded, int):
        return loaded
    result, system = loaded
    from ..timing import analyze, diagnostics_of

    analysis = analyze(system, data_age=args.data_age)
    problems = diagnostics_of(analysis)
    show(render(RESULT, args.format, Report(RESULT, args.file, tuple(problems), result.sources, analysis, system,
                                            {"explain": args.explain})))
    code = analysis_exit_code(problems)
    if code == EXIT_OK and (any(not s.ok for c in analysis.chains for s in c.specs)
                            or any(d.code == "E316" for d in problems)):
        return EXIT_UNDECIDED  # (a spec or deadline the bound does not prove: as `prove` before it decides)
    return code


def analysis_exit_code(problems: Iterable[Diagnostic]) -> int:
    errors = {d.code for d in problems if d.severity.value == "error"}
    if not errors:
        return EXIT_OK
    return EXIT_VIOLATED if errors <= TIMING_FAILURES else EXIT_INVALID
