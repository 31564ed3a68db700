"""``prove FILE`` / ``verify prove FILE`` (specs/proof.md §9).

    prove FILE [--system NAME] [--format text|json|sarif] [--trace-svg FILE] [--budget N]
               [--timeout S] [--data-age reduced|non-reduced] [-o OUT] [--force]

Exit codes: 0 every spec and deadline proved, 1 one is violated (a counterexample is shown),
2 invalid input or usage, 3 undecided within the budget. ``-o`` and ``--trace-svg`` never replace
an existing file unless ``--force`` is given.
"""
from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from ..core.diagnostics import Diagnostic
from ..core.fileaccess import write_output
from ..outputs import Output, Report, render
from ..core.sanitize import shown, shown_lines
from ..core.source import SourceFile
from .common import EXIT_INVALID, EXIT_OK, fail, load_args, to_stderr, wrote

if TYPE_CHECKING:
    from ..model.system import SystemModel
    from ..prove.verdict import ProofResult

HELP = "prove every latency spec and deadline of a configured system"
RESULT = "proof"
MODEL, SYSTEM = True, True


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..core.budgets import PROVE_BUDGET as DEFAULT_BUDGET

    p.add_argument("--trace-svg", metavar="FILE",
                   help="write every counterexample as an SVG Gantt chart (one below the other)")
    p.add_argument("--budget", metavar="N", type=int, default=DEFAULT_BUDGET,
                   help=f"scenarios the exact and falsifying searches may simulate (default {DEFAULT_BUDGET})")
    p.add_argument("--timeout", metavar="S", type=float, default=None,
                   help="wall-clock limit in seconds for the searches (default: none, fully deterministic)")
    p.add_argument("--jobs", metavar="N", type=int, default=0,
                   help="processes a large exact enumeration or large falsifying searches may use (default 0: "
                        "every available CPU; the result is the same for any N)")
    p.add_argument("--data-age", choices=("reduced", "non-reduced"), default="reduced",
                   help="data-age variant checked by data_age and jitter specs")
    p.add_argument("-o", "--output", metavar="OUT", help="write the report to OUT instead of standard output")
    p.add_argument("--force", action="store_true", help="replace OUT or the SVG file if it exists")


FORMAT_HELP = "output format: text, json (schema verify.proof/1) or sarif (SARIF 2.1.0)"


def _emit(output: Output, args: argparse.Namespace) -> int:
    """The report's standard output part to ``-o`` or standard output, then its standard error part."""
    status = EXIT_OK
    if args.output and output.stdout:
        try:
            write_output(args.output, output.stdout, replace=args.force)
            wrote(args.output)
        except OSError as err:
            status = fail(f"cannot write {args.output}: {err.strerror or err}")
    elif output.stdout:
        sys.stdout.write(output.stdout)
    if output.stderr:
        sys.stderr.write(shown_lines(output.stderr))
    return status


def _check_paths(args: argparse.Namespace) -> int | None:
    if args.budget < 1:
        return fail("--budget must be at least 1")
    if args.timeout is not None and not args.timeout > 0:
        return fail("--timeout must be a positive number of seconds")
    if args.jobs < 0:
        return fail("--jobs must be 0 (every available CPU) or a positive number of processes")
    for path, what in ((args.output, "-o"), (args.trace_svg, "--trace-svg")):
        if not path:
            continue
        if os.path.realpath(path) == os.path.realpath(args.file):
            return fail(f"{what} {path} is the model being proved; name another file")
        if os.path.lexists(path) and not args.force:  # (a link, even to nothing, is never written through)
            return fail(f"{path} exists; refusing to overwrite it (pass --force to replace it)")
        if not os.path.isdir(os.path.dirname(os.path.abspath(path))):
            return fail(f"{what} {path}: the directory {os.path.dirname(os.path.abspath(path))} does not exist")
    if args.output and args.trace_svg and os.path.realpath(args.output) == os.path.realpath(args.trace_svg):
        return fail("-o and --trace-svg name the same file")
    return None


def _invalid(diagnostics: Sequence[Diagnostic], sources: Mapping[str, SourceFile], args: argparse.Namespace) -> int:
    """Report input problems in the chosen format; exit 2."""
    _emit(render(RESULT, args.format, Report(RESULT, args.file, tuple(diagnostics), sources)), args)
    return EXIT_INVALID


def run(args: argparse.Namespace) -> int:
    from .. import api

    refused = _check_paths(args)
    if refused is not None:
        return refused
    result = load_args(args)
    if not result.ok:
        return _invalid(result.diagnostics, result.sources, args)
    try:
        model = result.system(args.system)
    except api.SelectionError as err:
        return _invalid([err.diagnostic], result.sources, args)
    holes = api.require_configured(model, "prove")
    if holes:
        return _invalid(holes, result.sources, args)
    from ..prove.core import DEFAULT_RLIMIT, prove

    proof = prove(model, budget=args.budget, rlimit=DEFAULT_RLIMIT, timeout=args.timeout, data_age=args.data_age,
                  jobs=args.jobs)
    status = _emit(render(RESULT, args.format, Report(RESULT, args.file, tuple(proof.diagnostics), result.sources,
                                                      proof, model)), args)
    if status:
        return status
    if args.trace_svg:
        return _trace_svg(model, proof, args) or proof.exit_code
    return proof.exit_code


def _trace_svg(model: SystemModel, proof: ProofResult, args: argparse.Namespace) -> int | None:
    drawn = [v for v in proof.verdicts if v.counterexample is not None]
    if not drawn:
        to_stderr(f"note: no counterexample, so nothing was drawn to {shown(args.trace_svg)}")
        return None
    from ..prove.gantt import to_svg_all

    try:
        write_output(args.trace_svg, to_svg_all(model, drawn), replace=args.force)
    except OSError as err:
        return fail(f"cannot write {args.trace_svg}: {err.strerror or err}")
    wrote(args.trace_svg)
    return None
