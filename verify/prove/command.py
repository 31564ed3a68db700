"""The ``prove`` command (``prove FILE`` / ``verify prove FILE``), specs/proof.md §9.

    prove FILE [--system NAME] [--format text|json|sarif] [--trace-svg FILE] [--budget N]
               [--timeout S] [--data-age reduced|non-reduced] [-o OUT] [--force]

Exit codes: 0 every spec and deadline proved, 1 one is violated (a counterexample is shown),
2 invalid input or usage, 3 undecided within the budget. ``-o`` and ``--trace-svg`` never replace
an existing file unless ``--force`` is given.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from .. import api
from ..render import diagnostics_json, render_all_text
from ..timing.report import exact
from ..units import fmt_time
from .core import DEFAULT_BUDGET, DEFAULT_RLIMIT, prove
from .verdict import ProofResult, Verdict

EXIT_OK, EXIT_VIOLATED, EXIT_INVALID, EXIT_UNDECIDED = 0, 1, 2, 3
SCHEMA = "verify.proof/1"
COLLAPSE = 20  # more task deadlines than this proved by bound are summarised in one line


def add_arguments(p: argparse.ArgumentParser) -> None:
    for action in p._actions:  # the shared --format gains "sarif"
        if "--format" in action.option_strings:
            action.choices = ("text", "json", "sarif")
            action.help = "output format: text, json (schema verify.proof/1) or sarif (SARIF 2.1.0)"
    p.add_argument("--trace-svg", metavar="FILE", help="write every counterexample as an SVG Gantt chart (one below the other)")
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


def _fail(message: str) -> int:
    print(f"error: {message}", file=sys.stderr)
    return EXIT_INVALID


def _emit(text: str, args) -> int:
    if args.output:
        try:
            with open(args.output, "w", encoding="utf-8") as fh:
                fh.write(text)
        except OSError as err:
            return _fail(f"cannot write {args.output}: {err.strerror or err}")
    else:
        sys.stdout.write(text)
    return EXIT_OK


def _invalid(diagnostics, sources, args) -> int:
    """Report input problems in the chosen format; exit 2."""
    if args.format == "json":
        doc = {"schema": SCHEMA, "system": None, "verdicts": []}
        doc.update(diagnostics_json(diagnostics))
        doc["exit_code"] = EXIT_INVALID
        _emit(json.dumps(doc, indent=2) + "\n", args)
    elif args.format == "sarif":
        from .sarif import to_sarif

        _emit(json.dumps(to_sarif(list(diagnostics)), indent=2) + "\n", args)
    if diagnostics and args.format != "json":
        print(render_all_text(list(diagnostics), sources), file=sys.stderr)
    return EXIT_INVALID


def cmd_prove(args) -> int:
    if args.budget < 1:
        return _fail("--budget must be at least 1")
    if args.timeout is not None and not args.timeout > 0:
        return _fail("--timeout must be a positive number of seconds")
    if args.jobs < 0:
        return _fail("--jobs must be 0 (every available CPU) or a positive number of processes")
    for path, what in ((args.output, "-o"), (args.trace_svg, "--trace-svg")):
        if not path:
            continue
        if os.path.realpath(path) == os.path.realpath(args.file):
            return _fail(f"{what} {path} is the model being proved; name another file")
        if os.path.exists(path) and not args.force:
            return _fail(f"{path} exists; refusing to overwrite it (pass --force to replace it)")
        if not os.path.isdir(os.path.dirname(os.path.abspath(path))):
            return _fail(f"{what} {path}: the directory {os.path.dirname(os.path.abspath(path))} does not exist")
    if args.output and args.trace_svg and os.path.realpath(args.output) == os.path.realpath(args.trace_svg):
        return _fail("-o and --trace-svg name the same file")
    result = api.load(args.file, root=args.root, include=tuple(args.include or ()))
    if not result.ok:
        return _invalid(result.diagnostics, result.sources, args)
    try:
        model = result.system(args.system)
    except api.SelectionError as err:
        return _invalid([err.diagnostic], result.sources, args)
    holes = api.require_configured(model, "prove")
    if holes:
        return _invalid(holes, result.sources, args)
    proof = prove(model, budget=args.budget, rlimit=DEFAULT_RLIMIT, timeout=args.timeout, data_age=args.data_age,
                  jobs=args.jobs)
    code = proof.exit_code
    if args.format == "json":
        status = _emit(json.dumps(to_json(model, proof), indent=2) + "\n", args)
    elif args.format == "sarif":
        from .sarif import to_sarif

        status = _emit(json.dumps(to_sarif(list(proof.diagnostics)), indent=2) + "\n", args)
    else:
        status = _emit(to_text(model, proof), args)
    if proof.diagnostics and args.format != "json":
        print(render_all_text(list(proof.diagnostics), result.sources), file=sys.stderr)
    if status:
        return status
    if args.trace_svg:
        drawn = [v for v in proof.verdicts if v.counterexample is not None]
        if not drawn:
            print(f"note: no counterexample, so nothing was drawn to {args.trace_svg}", file=sys.stderr)
        else:
            from .trace import to_svg_all

            try:
                with open(args.trace_svg, "w", encoding="utf-8") as fh:
                    fh.write(to_svg_all(model, drawn))
            except OSError as err:
                return _fail(f"cannot write {args.trace_svg}: {err.strerror or err}")
    return code


# ------------------------------------------------------------------ reports


def _cell(x) -> str:
    return "-" if x is None else fmt_time(x)


def _task_proved_by_bound(v: Verdict) -> bool:
    return v.subject == "task" and v.status == "proved" and v.method == "bound"


def to_text(model, proof: ProofResult) -> str:
    from .trace import Runs, to_text as timeline

    counts = {s: sum(v.status == s for v in proof.verdicts) for s in ("proved", "violated", "undecided")}
    lines = [f"system {proof.system}  (proof verify.proof/1; data age {proof.data_age_variant}; "
             f"{proof.explored} scenario{'s' * (proof.explored != 1)} simulated of a budget of {proof.budget})",
             f"{len(proof.verdicts)} properties: {counts['proved']} proved, {counts['violated']} violated, "
             f"{counts['undecided']} undecided", ""]
    rows = [["property", "status", "method", "spec", "bound", "exact worst", "margin"]]
    tasks_by_bound = sum(_task_proved_by_bound(v) for v in proof.verdicts)
    collapse = tasks_by_bound > COLLAPSE
    for v in proof.verdicts:
        if collapse and _task_proved_by_bound(v):
            continue
        exact_cell = _cell(v.exact)
        if v.kind == "jitter" and v.exact is not None:
            exact_cell += " (jitter)"
        margin = _cell(v.margin)
        if v.status == "violated" and v.counterexample is not None:
            margin += f" (run: {fmt_time(v.counterexample.latency)})"
        rows.append([v.label, v.status, v.method, "<= " + fmt_time(v.spec), _cell(v.bound), exact_cell, margin])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    for r in rows:
        lines.append("  " + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
    if collapse:
        lines.append(f"  ... and {tasks_by_bound} task deadlines proved by bound")
    runs = Runs(model, proof.verdicts)  # (each counterexample scenario run once)
    for v in proof.verdicts:
        if v.counterexample is not None:
            lines += ["", timeline(model, v, runs)]
    return "\n".join(lines) + "\n"


def _location(v: Verdict) -> dict | None:
    s = v.span
    if s.line < 1:
        return None
    return {"file": s.file, "line": s.line, "column": s.column, "end_line": s.end_line, "end_column": s.end_column}


def verdict_json(model, v: Verdict, runs=None) -> dict:
    from .trace import to_json as cex_json

    return {"subject": v.subject, "name": v.name, "kind": v.kind, "variant": v.variant, "spec": exact(v.spec),
            "status": v.status, "method": v.method, "bound": exact(v.bound), "exact": exact(v.exact),
            "exact_best": exact(v.exact_best), "margin": exact(v.margin), "explored": v.explored,
            "note": v.note or None, "location": _location(v),
            "counterexample": None if v.counterexample is None else cex_json(model, v, runs)}


def to_json(model, proof: ProofResult) -> dict:
    from .trace import Runs

    runs = Runs(model, proof.verdicts)  # (each counterexample scenario run once)
    doc = {"schema": SCHEMA, "system": proof.system, "data_age_variant": proof.data_age_variant,
           "budget": {"scenarios": proof.budget, "simulated": proof.explored},
           "verdicts": [verdict_json(model, v, runs) for v in proof.verdicts]}
    doc["diagnostics"] = diagnostics_json(list(proof.diagnostics))["diagnostics"]
    doc["summary"] = {s: sum(v.status == s for v in proof.verdicts) for s in ("proved", "violated", "undecided")}
    doc["exit_code"] = proof.exit_code
    return doc
