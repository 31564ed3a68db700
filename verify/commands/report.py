"""``verify report FILE -o report.html``: one self-contained HTML page about a configured system
(``verify.outputs.htmlreport``): the diagram, the outline, the chain table with margins and ``prove``'s verdicts,
and the Gantt chart of every counterexample.

Exit codes: 0 the report was written (whatever it reports; ``prove`` is the command for CI); 2 invalid
input or usage (holes: E218, run ``synth`` first); 70 internal error.
"""
from __future__ import annotations

import argparse

from .common import exists, fail, load_configured, write_output

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


def run(args: argparse.Namespace) -> int:
    if exists(args.output) and not args.force:
        return fail(f"{args.output} exists; refusing to overwrite it (pass --force to replace it)")
    if args.budget < 0:
        return fail("--budget must be 0 or more")
    loaded = load_configured(args, "report")
    if isinstance(loaded, int):
        return loaded
    _, system = loaded
    from ..outputs.htmlreport import to_html
    from ..prove.core import prove
    from ..timing import analyze

    page = to_html(system, analyze(system), prove(system, budget=args.budget), args.file)
    return write_output(args.output, page, args.force)
