"""The command line: a thin layer over the library façade.

Exit codes (stable, documented in README.md):
  0  ok: the model is valid / every spec holds
  1  a spec is violated, or synthesis is unsatisfiable
  2  invalid input or usage (diagnostics say where)
  3  undecided (solver budget exhausted, or the command cannot decide yet)
  70 internal error (a bug: please report it)
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Callable

from . import api
from .codes import CODES
from .render import diagnostics_json, render_all_text

EXIT_OK, EXIT_VIOLATED, EXIT_INVALID, EXIT_UNDECIDED, EXIT_INTERNAL = 0, 1, 2, 3, 70


def _emit_diagnostics(result: api.LoadResult, fmt: str, extra: dict | None = None) -> None:
    if fmt == "json":
        doc = diagnostics_json(result.diagnostics)
        if extra:
            doc.update(extra)
        print(json.dumps(doc, indent=2, sort_keys=False))
    elif result.diagnostics:
        print(render_all_text(result.diagnostics, result.sources), file=sys.stderr)


def load_args(args) -> api.LoadResult:
    """``api.load`` of the command's FILE, with its ``--root`` and ``--include``."""
    return api.load(args.file, root=args.root, include=tuple(args.include or ()))


def _load_or_fail(args) -> api.LoadResult | int:
    result = load_args(args)
    if not result.ok:
        _emit_diagnostics(result, args.format)
        return EXIT_INVALID
    return result


def cmd_check(args) -> int:
    result = load_args(args)
    _emit_diagnostics(result, args.format)
    if not result.ok:
        return EXIT_INVALID
    if args.format == "text":
        comps = len(result.project.components)
        systems = len(result.project.systems)
        print(f"{args.file}: ok ({comps} component{'s' * (comps != 1)}, "
              f"{systems} system{'s' * (systems != 1)})")
    return EXIT_OK


def _select(result: api.LoadResult, args):
    try:
        return result.system(args.system)
    except api.SelectionError as err:
        _emit_diagnostics(api.LoadResult(result.project, result.resolution, {}, (err.diagnostic,)),
                          getattr(args, "format", "text"))
        return None


def cmd_pending(what: str) -> Callable:
    """``synth`` and ``prove`` before their issues land: run the checks, say what is not done yet."""

    def run(args) -> int:
        result = _load_or_fail(args)
        if isinstance(result, int):
            return result
        if _select(result, args) is None:
            return EXIT_INVALID
        print(f"{args.file}: the model is valid, but `{what}` is not implemented yet: "
              f"nothing was {'synthesized' if what == 'synth' else 'proved'}.", file=sys.stderr)
        return EXIT_UNDECIDED

    return run


def cmd_fmt(args) -> int:
    from .fmt import format_text
    from .loader import _read
    from .diagnostics import DiagnosticSink
    from .render import render_all_text as render

    sink = DiagnosticSink()
    text = _read(os.path.normpath(args.file), sink, None)
    if text is None:
        print(render(sink.items, {}), file=sys.stderr)
        return EXIT_INVALID
    formatted, diagnostics = format_text(text, args.file)
    if formatted is None:
        from .source import SourceFile

        print(render(diagnostics, {args.file: SourceFile(args.file, text)}), file=sys.stderr)
        return EXIT_INVALID
    if args.check:
        if formatted != text:
            print(f"{args.file}: not canonically formatted (run `verify fmt --in-place {args.file}`)",
                  file=sys.stderr)
            return EXIT_VIOLATED
        return EXIT_OK
    if args.in_place:
        if formatted != text:
            return _replace_file(args.file, formatted)
        return EXIT_OK
    if args.output:
        return _write_new_file(args.output, formatted, args.force)
    sys.stdout.write(formatted)
    return EXIT_OK


def _cannot_write(path: str, err: OSError) -> int:
    """E004 for a file that cannot be written (exit 2); the file itself is left as it was."""
    from .diagnostics import DiagnosticSink
    from .source import Span

    sink = DiagnosticSink()
    sink.emit("E004", f"cannot write {path}: {err.strerror or err}", Span(path, 1, 1, 1, 1), "cannot be written",
              help="check that the file and its directory are writable; nothing was changed")
    print(render_all_text(sink.items, {}), file=sys.stderr)
    return EXIT_INVALID


def _replace_file(path: str, text: str) -> int:
    """Rewrite ``path`` atomically: write a temporary file in the same directory, give it the file's
    mode, and rename it over the file (through a symbolic link, the file it points to). On any failure
    the original file is untouched and the temporary file removed."""
    import stat
    import tempfile

    target = os.path.realpath(path)
    tmp = None
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
        fd, tmp = tempfile.mkstemp(prefix=".", suffix=".vfy.tmp", dir=os.path.dirname(target))
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, target)
        tmp = None
    except OSError as err:
        return _cannot_write(path, err)
    finally:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
    return EXIT_OK


def _write_new_file(path: str, text: str, force: bool) -> int:
    if os.path.exists(path) and not force:
        print(f"error: {path} exists; refusing to overwrite it (pass --force to replace it)", file=sys.stderr)
        return EXIT_INVALID
    try:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as err:
        return _cannot_write(path, err)
    return EXIT_OK


def cmd_explain(args) -> int:
    from .explain import explain

    code = args.code.upper()
    if code not in CODES:
        from .diagnostics import suggest

        starting = sorted(c for c in CODES if c.startswith(code)) if len(code) >= 2 else []
        hint = ("one of " + ", ".join(starting) if starting else suggest(code, CODES))
        print(f"error: unknown diagnostic code {args.code}" + (f"; did you mean {hint}?" if hint else ""),
              file=sys.stderr)
        return EXIT_INVALID
    print(explain(code))
    return EXIT_OK


def cmd_analyze(args) -> int:
    result = _load_or_fail(args)
    if isinstance(result, int):
        return result
    system = _select(result, args)
    if system is None:
        return EXIT_INVALID
    holes = api.require_configured(system, "analyze")
    if holes:
        _emit_diagnostics(api.LoadResult(result.project, result.resolution, {}, tuple(holes)), args.format)
        return EXIT_INVALID
    from .timing import analyze, diagnostics_of
    from .timing.report import to_json, to_text

    analysis = analyze(system, data_age=args.data_age)
    problems = diagnostics_of(analysis)
    if args.format == "json":
        doc = to_json(analysis)
        doc["diagnostics"] = diagnostics_json(problems)["diagnostics"]
        print(json.dumps(doc, indent=2))
    else:
        print(to_text(analysis))
        if problems:
            print(render_all_text(problems, result.sources), file=sys.stderr)
    return analysis_exit_code(problems)


#: analysis errors that say the configured system misses its timing (overload, a response time with
#: no bound within the deadline): exit 1, as `prove` exits 1 on a missed deadline (E503); every other
#: analysis error (a rate outside a constraint or tolerance) says the configuration is invalid: exit 2
TIMING_FAILURES = frozenset({"E311", "E312"})


def analysis_exit_code(problems) -> int:
    errors = {d.code for d in problems if d.severity.value == "error"}
    if not errors:
        return EXIT_OK
    return EXIT_VIOLATED if errors <= TIMING_FAILURES else EXIT_INVALID


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="verify", description="Timing verification for component-based "
                                     "robotics software: check, analyze, synthesize and prove.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def add(name: str, func, help: str, system: bool = True) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help, description=help)
        p.add_argument("file", metavar="FILE", help="the .vfy file (imports are followed)")
        p.add_argument("--format", choices=("text", "json"), default="text", help="output format")
        p.add_argument("--root", metavar="DIR", help="the project root: imports must stay inside it (default: "
                       "the `root` of [tool.verify] in pyproject.toml, else the directory of FILE)")
        p.add_argument("--include", metavar="DIR", action="append", default=[],
                       help="a library directory imports may also come from (repeatable)")
        if system:
            p.add_argument("--system", metavar="NAME", help="the system to use when the file holds several")
        p.set_defaults(func=func)
        return p

    add("check", cmd_check, "parse, resolve and validate a model", system=False)
    p = add("analyze", cmd_analyze, "rates, sampling, response times and chain latencies")
    p.add_argument("--data-age", choices=("reduced", "non-reduced"), default="reduced",
                   help="data age measured from the first task's read (reduced) or from the earliest event")
    from .synth import command as synth_command

    synth_command.add_arguments(add("synth", synth_command.run, "synthesize periods, prescalers and activation "
                                    "kinds, or explain why no configuration exists"))
    from .prove.command import add_arguments as prove_arguments, cmd_prove
    prove_arguments(add("prove", cmd_prove, "prove every latency spec and deadline of a configured system"))

    p = sub.add_parser("fmt", help="print the canonical formatting of a file",
                       description="print the canonical formatting of a file (comments are kept)")
    p.add_argument("file", metavar="FILE")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--check", action="store_true", help="exit 1 if the file is not canonically formatted")
    group.add_argument("--in-place", action="store_true", help="rewrite FILE itself")
    group.add_argument("-o", "--output", metavar="OUT", help="write to a new file OUT")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")
    p.set_defaults(func=cmd_fmt)

    p = sub.add_parser("explain", help="explain a diagnostic code with a minimal failing example")
    p.add_argument("code", metavar="CODE")
    p.set_defaults(func=cmd_explain)
    return parser


def main(argv: list[str] | None = None) -> int:
    try:
        args = _parser().parse_args(argv)
        return args.func(args)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # the reader went away (`verify explain E101 | head`): not an error of ours
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK
    except SystemExit as exit_:
        return int(exit_.code) if isinstance(exit_.code, int) else EXIT_INVALID
    except Exception as err:  # the last line of defence: never a traceback for the user
        if os.environ.get("VERIFY_DEBUG"):
            raise
        print(f"internal error: {type(err).__name__}: {err}\n"
              "This is a bug in verify; please report it with the input file. "
              "Set VERIFY_DEBUG=1 to see the traceback.", file=sys.stderr)
        return EXIT_INTERNAL


def _command_main(command: str) -> None:
    sys.exit(main([command, *sys.argv[1:]]))


def synth_main() -> None:
    """The ``synth`` console script: ``synth FILE`` is ``verify synth FILE``."""
    _command_main("synth")


def prove_main() -> None:
    """The ``prove`` console script: ``prove FILE`` is ``verify prove FILE``."""
    _command_main("prove")
