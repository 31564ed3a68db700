"""``verify report FILE -o report.html``: one self-contained HTML page about a configured system
(``verify.outputs.htmlreport``): the diagram, the outline, the chain table with margins and ``prove``'s verdicts,
and the Gantt chart of every counterexample.

``--trace TRACE...`` adds what a robot measured (``verify trace``): per task and chain, the measured
distribution beside the model's execution times, bounds and specs.

Exit codes: 0 the report was written (whatever it reports; ``prove`` is the command for CI); 2 invalid
input or usage (holes: E218, run ``synth`` first); 70 internal error.
"""
from __future__ import annotations

import argparse

from typing import TYPE_CHECKING

from .common import EXIT_INVALID, exists, fail, load_configured, show_diagnostics, write_output

if TYPE_CHECKING:
    from .. import api
    from ..model.system import SystemModel

HELP = "one self-contained HTML page: diagram, outline, chains with margins, counterexamples"
RESULT = None
FORMATS = ("html",)
FORMAT_HELP = "html (the only one)"
MODEL, SYSTEM = True, True


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..core.budgets import PROVE_BUDGET

    p.add_argument("-o", "--output", metavar="OUT", required=True, help="the HTML file to write (a new file)")
    p.add_argument("--force", action="store_true", help="replace OUT if it exists")
    p.add_argument("--budget", metavar="N", type=int, default=PROVE_BUDGET,
                   help=f"scenarios prove's searches may simulate (default {PROVE_BUDGET})")
    p.add_argument("--trace", metavar="TRACE", nargs="+",
                   help="measurements to show beside the bounds: LTTng trace directories or job-record files "
                        "(as `verify trace` reads them)")


def run(args: argparse.Namespace) -> int:
    if exists(args.output) and not args.force:
        return fail(f"{args.output} exists; refusing to overwrite it (pass --force to replace it)")
    if args.budget < 0:
        return fail("--budget must be 0 or more")
    loaded = load_configured(args, "report")
    if isinstance(loaded, int):
        return loaded
    _, system = loaded
    from ..model.arrivals import with_arrivals
    from ..outputs.htmlreport import to_html
    from ..prove.core import prove
    from ..timing import analyze

    measured: str | None = None
    if args.trace:
        found = _measured(args, loaded)
        if isinstance(found, int):
            return found
        measured = found
    system = with_arrivals(system)  # (the page lists the arrival tasks the analysis charges, specs/timing.md §6.6)
    page = to_html(system, analyze(system), prove(system, budget=args.budget), args.file, measured)
    return write_output(args.output, page, args.force)


def _measured(args: argparse.Namespace, loaded: tuple[api.LoadResult, SystemModel]) -> str | int:
    """The section of the traces' measurements, or EXIT_INVALID after showing why they cannot be read."""
    from ..core.diagnostics import DiagnosticSink
    from ..trace.html import section
    from ..trace.run import read_traces, trace_system

    result, system = loaded
    sink = DiagnosticSink()
    recording = read_traces(args.trace, sink)
    if recording is None:
        show_diagnostics(args, sink.items, result.sources)
        return EXIT_INVALID
    return section(trace_system(system, result.project, recording))
