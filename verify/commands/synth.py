"""``synth FILE`` / ``verify synth FILE``: fill the holes so that every spec holds, or explain why not.

    synth FILE [--system NAME] [--objective OBJ] [-o OUT [--force] | --diff | --in-place] [--canonical]
               [--format text|json] [--rlimit N] [--timeout S]

Exit codes: 0 a configuration that meets every spec (printed), 1 unsatisfiable (E401 with an unsat
core), 2 invalid input or usage, 3 undecided (E402; the best configuration found so far is still
printed, marked not proven optimal), 70 internal error.

Where things go: without ``-o``/``--in-place``, the completed file (or with ``--diff`` a unified diff
against the input) goes to standard output and the summary to standard error; with ``-o`` or
``--in-place`` the file is written and the summary goes to standard output. ``--format json`` prints
one ``verify.synth/1`` document instead. The input file is modified only with ``--in-place``. What is
written changes only the holes of the file (``--canonical``: the whole file as ``verify fmt`` prints it).
"""
from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..outputs import Report, render
from ..core.sanitize import shown
from .common import (EXIT_INVALID, EXIT_OK, EXIT_UNDECIDED, EXIT_VIOLATED, load_system, replace_file, show,
                     show_diagnostics, to_stderr, write_new_file)

if TYPE_CHECKING:
    from ..api import LoadResult
    from ..synth.driver import SynthResult

HELP = "synthesize periods, prescalers and activation kinds, or explain why no configuration exists"
RESULT = "synthesis"
MODEL, SYSTEM = True, True
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
    from ..core.budgets import SYNTH_RLIMIT as DEFAULT_RLIMIT

    p.add_argument("--objective", metavar="OBJ", default="utilisation", help=OBJECTIVE_HELP)
    where = p.add_mutually_exclusive_group()
    where.add_argument("-o", "--output", metavar="OUT", help="write the completed file to a new file OUT")
    where.add_argument("--diff", action="store_true", help="print a unified diff against FILE instead")
    where.add_argument("--in-place", action="store_true", help="rewrite FILE itself")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")
    p.add_argument("--canonical", action="store_true",
                   help="format the whole file canonically (as `verify fmt`), not only the filled holes")
    p.add_argument("--rlimit", type=_rlimit, default=DEFAULT_RLIMIT, metavar="N",
                   help=f"deterministic solver budget in Z3 resource units (default {DEFAULT_RLIMIT}; 0: unlimited)")
    p.add_argument("--timeout", type=_seconds, metavar="S", help="wall-clock limit in seconds (not deterministic)")


def run(args: argparse.Namespace) -> int:
    from ..synth.candidates import TooManyCandidates
    from ..synth.driver import ObjectiveError, parse_objective, synthesize

    if args.file == "-" and args.in_place:
        to_stderr("error: --in-place needs a file, not standard input (`-`)")
        return EXIT_INVALID
    found = load_system(args)
    if isinstance(found, int):
        return found
    loaded, system = found
    try:
        goals = parse_objective(args.objective, system)
    except ObjectiveError as err:
        to_stderr(f"error: --objective: {shown(str(err))}")
        return EXIT_INVALID
    try:
        result = synthesize(loaded, system.name, objective=goals, rlimit=args.rlimit, timeout=args.timeout)
    except TooManyCandidates as err:
        _show(args, loaded, (err.diagnostic(),), None)
        return EXIT_INVALID
    if result.status == "unsat":
        _show(args, loaded, result.diagnostics, result)
        return EXIT_VIOLATED
    code = EXIT_OK if result.status == "sat" else EXIT_UNDECIDED
    if result.model is None:  # undecided without a configuration
        _show(args, loaded, result.diagnostics, result)
        return code
    return _write_back(args, loaded, result, code)


def _show(args: argparse.Namespace, loaded: LoadResult, diagnostics: Sequence[Diagnostic], result: SynthResult | None,
          **extra: str | None) -> None:
    show(render(RESULT, args.format, Report(RESULT, args.file, tuple(diagnostics), loaded.sources, result,
                                            extra=extra)))


def _write_back(args: argparse.Namespace, loaded: LoadResult, result: SynthResult, code: int) -> int:
    from ..synth.writeback import completed_text, recheck, unified_diff

    imports = _relocated_imports(args, loaded) if args.output else {}
    if isinstance(imports, int):
        return imports
    text = completed_text(loaded, result.system, result.choices, canonical=args.canonical, imports=imports)
    _, _, _, problems = recheck(loaded, result.system, text)
    if problems:  # never print what the analysis would reject
        raise RuntimeError("the synthesized configuration does not pass the re-check: " + "; ".join(problems))
    if args.output and not _loads_from(args, loaded, text):
        return EXIT_INVALID
    original = loaded.sources[loaded.project.root].text
    diff = unified_diff(original, text, args.file) if args.diff else None
    written = None
    if args.in_place:
        if text != original:
            status = replace_file(args.file, text)
            if status != EXIT_OK:
                return status
        written = args.file
    elif args.output:
        status = write_new_file(args.output, text, args.force)
        if status != EXIT_OK:
            return status
        written = args.output
    _show(args, loaded, result.diagnostics, result, dsl=text, diff=diff, written=written)
    return code


def _relocated_imports(args: argparse.Namespace, loaded: LoadResult) -> dict[str, str] | int:
    """The new names of the root file's imports for the file written to ``-o OUT`` (the same files named
    from OUT's directory), or EXIT_INVALID after a located error for an import that cannot be renamed."""
    from ..frontend.roots import Refusal, project_roots
    from ..synth.writeback import relocated_imports

    roots, _ = project_roots(args.file, args.root, tuple(args.include or ()))
    module = loaded.project.root_module
    if roots is None or module is None:  # (it loaded with these roots)
        return {}
    found = relocated_imports(module, loaded.project.root, roots, args.output)
    spans = {imp.path: imp.path_span for imp in module.imports}
    sink = DiagnosticSink()
    for name, new in found.items():
        if isinstance(new, Refusal):
            sink.emit(new.code, new.message, spans[name], new.label, help=new.help)
    if sink.items:
        show_diagnostics(args, sink.items, loaded.sources)
        return EXIT_INVALID
    return {name: new for name, new in found.items() if isinstance(new, str)}


def _loads_from(args: argparse.Namespace, loaded: LoadResult, text: str) -> bool:
    """Whether ``text`` written to ``-o OUT`` loads from there (its imports resolve within OUT's roots,
    found for OUT as they will be when it is checked); else, False after showing why, noted as being
    about the file not written."""
    from dataclasses import replace

    from .. import api

    again = api.load(args.output, root=args.root, include=tuple(args.include or ()), overlay={args.output: text})
    if again.ok:
        return True
    note = (f"in the completed file as it would be written to {args.output}; nothing was written (write it "
            f"next to {args.file}, or choose a root that holds both with `--root DIR`)")
    # (an import that does not resolve is the cause; the unknown names it leaves follow from it)
    causes = [d for d in again.diagnostics if d.code < "E100"] or list(again.diagnostics)
    show_diagnostics(args, [replace(d, notes=d.notes + (note,)) for d in causes], {**loaded.sources, **again.sources})
    return False
