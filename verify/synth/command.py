"""The ``synth`` command: ``synth FILE [--system NAME] [--objective OBJ] [-o OUT [--force] | --diff |
--in-place] [--format text|json] [--rlimit N] [--timeout S]``.

Exit codes: 0 a configuration that meets every spec (printed), 1 unsatisfiable (E401 with an unsat
core), 2 invalid input or usage, 3 undecided (E402; the best configuration found so far is still
printed, marked not proven optimal), 70 internal error.

Where things go: without ``-o``/``--in-place``, the completed file (or with ``--diff`` a unified diff
against the input) goes to standard output and the summary to standard error; with ``-o`` or
``--in-place`` the file is written and the summary goes to standard output. ``--format json`` prints
one ``verify.synth/1`` document instead. The input file is modified only with ``--in-place``.
"""
from __future__ import annotations

import argparse
import json
import sys

OBJECTIVE_HELP = ("what to optimise: utilisation (default: minimum total CPU utilisation), slack (maximum "
                  "minimum margin over all specs), latency:CHAIN (minimum reaction time), age:CHAIN (minimum "
                  "data age), none (any configuration); comma-separated for a lexicographic combination")


def _rlimit(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError("the budget must be 0 (unlimited) or positive")
    return value


def _seconds(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError("the time limit must be positive")
    return value


def add_arguments(p: argparse.ArgumentParser) -> None:
    from .driver import DEFAULT_RLIMIT

    p.add_argument("--objective", metavar="OBJ", default="utilisation", help=OBJECTIVE_HELP)
    where = p.add_mutually_exclusive_group()
    where.add_argument("-o", "--output", metavar="OUT", help="write the completed file to a new file OUT")
    where.add_argument("--diff", action="store_true", help="print a unified diff against FILE instead")
    where.add_argument("--in-place", action="store_true", help="rewrite FILE itself")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")
    p.add_argument("--rlimit", type=_rlimit, default=DEFAULT_RLIMIT, metavar="N",
                   help=f"deterministic solver budget in Z3 resource units (default {DEFAULT_RLIMIT}; 0: unlimited)")
    p.add_argument("--timeout", type=_seconds, metavar="S", help="wall-clock limit in seconds (not deterministic)")


def run(args) -> int:
    from .. import cli
    from ..render import render_all_text
    from .candidates import TooManyCandidates
    from .driver import ObjectiveError, parse_objective, synthesize

    loaded = cli._load_or_fail(args)
    if isinstance(loaded, int):
        return loaded
    system = cli._select(loaded, args)
    if system is None:
        return cli.EXIT_INVALID
    try:
        goals = parse_objective(args.objective, system)
    except ObjectiveError as err:
        print(f"error: --objective: {err}", file=sys.stderr)
        return cli.EXIT_INVALID
    try:
        result = synthesize(loaded, system.name, objective=goals, rlimit=args.rlimit, timeout=args.timeout)
    except TooManyCandidates as err:
        diag = too_many(err)
        _report_only(args, loaded, [diag], None)
        return cli.EXIT_INVALID
    if result.status == "unsat":
        _report_only(args, loaded, list(result.diagnostics), result)
        return cli.EXIT_VIOLATED
    code = cli.EXIT_OK if result.status == "sat" else cli.EXIT_UNDECIDED
    if result.model is None:  # undecided without a configuration
        _report_only(args, loaded, list(result.diagnostics), result)
        return code
    return _emit(args, loaded, result, code, render_all_text)


def too_many(err) -> object:
    from ..diagnostics import DiagnosticSink
    from .candidates import MAX_CANDIDATES

    sink = DiagnosticSink()
    sink.emit("E403", f"`{err.task.id}` would have {err.count} candidate values; synth considers at most "
              f"{MAX_CANDIDATES} per hole", err.task.activation.activation.span, "too many candidates",
              help="use a coarser `step`, or a narrower range")
    return sink.items[0]


def _report_only(args, loaded, diagnostics, result) -> None:
    from ..render import diagnostics_json, render_all_text
    from .report import to_json

    if args.format == "json":
        doc = to_json(result, args.file) if result is not None else {"schema": "verify.synth/1", "file": args.file,
                                                                        "status": "invalid"}
        doc["diagnostics"] = diagnostics_json(diagnostics)["diagnostics"]
        print(json.dumps(doc, indent=2))
    elif diagnostics:
        print(render_all_text(diagnostics, loaded.sources), file=sys.stderr)


def _emit(args, loaded, result, code: int, render_all_text) -> int:
    from .. import cli
    from .report import to_json, to_text
    from .writeback import completed_text, recheck, unified_diff

    text = completed_text(loaded, result.system, result.choices)
    _, _, _, problems = recheck(loaded, result.system, text)
    if problems:  # never print what the analysis would reject
        raise RuntimeError("the synthesized configuration does not pass the re-check: " + "; ".join(problems))
    original = loaded.sources[loaded.project.root].text
    diff = unified_diff(original, text, args.file) if args.diff else None
    written = None
    if args.in_place:
        if text != original:
            with open(args.file, "w", encoding="utf-8") as fh:
                fh.write(text)
        written = args.file
    elif args.output:
        status = cli._write_new_file(args.output, text, args.force)
        if status != cli.EXIT_OK:
            return status
        written = args.output
    if args.format == "json":
        print(json.dumps(to_json(result, args.file, dsl=text, diff=diff, written=written), indent=2))
        return code
    summary = to_text(result)
    if written is not None:
        sys.stdout.write(summary)
    else:
        sys.stdout.write(diff if diff is not None else text)
        sys.stderr.write(summary)
    if result.diagnostics:
        print(render_all_text(list(result.diagnostics), loaded.sources), file=sys.stderr)
    return code
