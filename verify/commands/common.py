"""What the commands share: exit codes, loading the model a command names, showing a report, and
writing files without ever losing what the user wrote.

Exit codes (stable, documented in README.md and docs/reference/commands.md):
  0  ok: the model is valid / every spec holds
  1  a spec is violated, or synthesis is unsatisfiable
  2  invalid input or usage (diagnostics say where)
  3  undecided (solver budget exhausted, or the command cannot decide yet)
  70 internal error (a bug: please report it)
"""
from __future__ import annotations

import argparse
import contextlib
import os
import stat
import sys
import tempfile
from collections.abc import Mapping, Sequence

from typing import TYPE_CHECKING

from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..outputs import Output, Report, render
from ..outputs.rendering import render_all_text
from ..core.sanitize import shown
from ..core.source import SourceFile, Span

if TYPE_CHECKING:  # (the front end is imported when a command runs: `--help` stays quick)
    from .. import api
    from ..model.system import SystemModel

EXIT_OK, EXIT_VIOLATED, EXIT_INVALID, EXIT_UNDECIDED, EXIT_INTERNAL = 0, 1, 2, 3, 70


#: how messages name standard input (FILE ``-``); its imports are relative to the working directory
STDIN = "<stdin>"


def read_stdin(sink: DiagnosticSink) -> str | None:
    """The text piped into the command (FILE ``-``), or None after reporting why not (E003, E008)."""
    from ..frontend.loader import read_stream

    return read_stream(sys.stdin.buffer, STDIN, sink)


def load_args(args: argparse.Namespace) -> api.LoadResult:
    """``api.load`` of the command's FILE, with its ``--root`` and ``--include``. FILE ``-`` is standard
    input, read once (then named ``<stdin>``, in the working directory)."""
    from .. import api
    from ..frontend.loader import Project

    include = tuple(args.include or ())
    if args.file != "-":
        return api.load(args.file, root=args.root, include=include)
    args.file = STDIN
    sink = DiagnosticSink()
    text = read_stdin(sink)
    if text is None:
        return api.LoadResult(Project(STDIN, (), {}), None, {}, tuple(sink.items))
    return api.load(STDIN, root=args.root, include=include, overlay={STDIN: text})


def show(output: Output) -> None:
    """Write a rendered report: its standard output part, then its standard error part (diagnostics:
    coloured on a terminal, ``verify.outputs.colour``)."""
    if output.stdout:
        sys.stdout.write(output.stdout)
    if output.stderr:
        to_stderr(output.stderr, end="")


def to_stderr(text: str, end: str = "\n") -> None:
    """``text`` (diagnostics as ``render_all_text`` makes them) on standard error, coloured when that is
    a terminal and colour is not turned off (``verify.outputs.colour.wanted``); a control character in it is
    shown escaped (``verify.core.sanitize.shown_lines``)."""
    from ..outputs.colour import paint, wanted
    from ..core.sanitize import shown_lines

    text = shown_lines(text)  # (no control character reaches the terminal, whatever a message quotes)
    sys.stderr.write((paint(text) if wanted(sys.stderr) else text) + end)


def show_diagnostics(args: argparse.Namespace, diagnostics: Sequence[Diagnostic],
                     sources: Mapping[str, SourceFile]) -> None:
    """Diagnostics of a model that does not load, in the command's ``--format``."""
    from ..outputs import formats

    fmt = getattr(args, "format", "text")
    if fmt not in formats("diagnostics"):  # (a picture's format: diagnostics are text)
        fmt = "text"
    show(render("diagnostics", fmt, Report("diagnostics", args.file, tuple(diagnostics), sources)))


def load_or_fail(args: argparse.Namespace) -> api.LoadResult | int:
    """The loaded model, or EXIT_INVALID after showing why it does not load."""
    result = load_args(args)
    if not result.ok:
        show_diagnostics(args, result.diagnostics, result.sources)
        return EXIT_INVALID
    return result


def select(result: api.LoadResult, args: argparse.Namespace) -> SystemModel | None:
    """The system ``--system`` names (or the only one), or None after showing why there is none."""
    from .. import api

    try:
        return result.system(args.system)
    except api.SelectionError as err:
        show_diagnostics(args, (err.diagnostic,), result.sources)
        return None


def load_system(args: argparse.Namespace) -> tuple[api.LoadResult, SystemModel] | int:
    """The loaded model and the system ``--system`` names (or its only one), or EXIT_INVALID after
    showing why there is none."""
    result = load_or_fail(args)
    if isinstance(result, int):
        return result
    system = select(result, args)
    return EXIT_INVALID if system is None else (result, system)


def load_configured(args: argparse.Namespace, command: str) -> tuple[api.LoadResult, SystemModel] | int:
    """The loaded model and its configured system (no synthesis holes), or EXIT_INVALID."""
    loaded = load_system(args)
    if isinstance(loaded, int):
        return loaded
    result, system = loaded
    from .. import api

    holes = api.require_configured(system, command)
    if holes:
        show_diagnostics(args, holes, result.sources)
        return EXIT_INVALID
    return result, system


def wrote(path: str) -> None:
    """The one-line confirmation of a file written (on standard error: standard output stays the result)."""
    to_stderr(f"wrote {shown(path)}")


def fail(message: str) -> int:
    """A usage error (exit 2): ``message`` is one line, whatever a file name in it holds."""
    to_stderr(f"error: {shown(message)}")
    return EXIT_INVALID


def cannot_write(path: str, err: OSError, written: Sequence[str] = ()) -> int:
    """E004 for a file that cannot be written (exit 2); the file itself is left as it was. ``written``:
    what the command wrote before the failure (each in a note), so the message says exactly what
    changed: nothing, or those."""
    sink = DiagnosticSink()
    count = "the path in the note" if len(written) == 1 else f"the {len(written)} paths in the notes"
    done = f"before the failure only {count} changed" if written else "nothing was changed"
    sink.emit("E004", f"cannot write {path}: {err.strerror or err}", Span(path, 1, 1, 1, 1), "cannot be written",
              notes=[f"{'made' if os.path.isdir(w) else 'written'} before the failure: {w}" for w in written],
              help=f"check that the file and its directory are writable; {done}")
    to_stderr(render_all_text(sink.items, {}))
    return EXIT_INVALID


def replace_file(path: str, text: str) -> int:
    """Rewrite ``path`` atomically: write a temporary file in the same directory, give it the file's
    mode, and rename it over the file (through a symbolic link, the file it points to). On any failure
    the original file is untouched and the temporary file removed."""
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
        return cannot_write(path, err)
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    wrote(path)
    return EXIT_OK


def exists(path: str) -> bool:
    """Something is at ``path``: a file, a directory, or a symbolic link (even one that leads nowhere)."""
    return os.path.lexists(path)


def write_output(path: str, data: str | bytes, force: bool) -> int:
    """Write ``data`` to ``path``, which must not exist unless ``force`` (E004 when it cannot be written).
    A symbolic link there is never written through (``verify.core.fileaccess.write_output``): without
    ``force`` it is in the way, with ``force`` it is replaced by the file."""
    from ..core.fileaccess import write_output as write

    if exists(path) and not force:
        to_stderr(f"error: {shown(path)} exists; refusing to overwrite it (pass --force to replace it)")
        return EXIT_INVALID
    try:
        write(path, data, replace=force)
    except OSError as err:
        return cannot_write(path, err)
    wrote(path)
    return EXIT_OK


def write_new_file(path: str, text: str, force: bool) -> int:
    """Write ``text`` to ``path``, which must not exist unless ``force``."""
    return write_output(path, text, force)
