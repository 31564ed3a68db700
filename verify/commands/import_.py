"""``verify import TOOL PATH... [-o OUT.vfy]``: another tool's model in verify's language (specs/interop.md).

The files under the PATHs (directories are searched recursively) are read; the system they describe
(``--system`` when there are several) is written as one .vfy file: its components, then the system.
What has no counterpart is reported where it stands (E703), what the timing model needs but the files
do not give (E704) too; then the written model is checked as ``verify check`` would, so that what is
left to complete is listed with the place in OUT where it goes.

Exit codes: 0 written and valid; 2 nothing written (a file that cannot be read or parsed, no system or
several, an inconsistent model: E701, E705), or written but incomplete (``verify check OUT`` reports
errors); 70 internal error.
"""
from __future__ import annotations

import argparse
import sys

from collections.abc import Mapping, Sequence

from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..outputs import Report, render
from ..core.sanitize import shown
from ..core.source import SourceFile
from .common import EXIT_INVALID, EXIT_OK, show, to_stderr, write_new_file

HELP = "read another tool's model (SmartMDSD, CARET) into verify's language"
RESULT = None
MODEL, SYSTEM = False, False


def add_leading_arguments(p: argparse.ArgumentParser) -> None:
    from ..interop import IMPORTERS

    p.add_argument("tool", metavar="TOOL", choices=IMPORTERS,
                   help=f"whose models to read: {', '.join(IMPORTERS)} (specs/interop.md)")


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..outputs import formats

    p.add_argument("paths", metavar="PATH", nargs="+",
                   help="model files, or directories searched recursively (the system's and its components')")
    p.add_argument("-o", "--output", metavar="OUT", help="write the model to a new file OUT (default: standard "
                   "output)")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")
    p.add_argument("--system", metavar="NAME", help="the system to import when the files hold several")
    p.add_argument("--format", choices=formats("diagnostics"), default="text", help="how to show diagnostics")


def run(args: argparse.Namespace) -> int:
    from .. import api
    from ..interop import tool

    sink = DiagnosticSink()
    imported, sources = tool(args.tool).import_dirs(args.paths, args.system, sink)
    args.file = args.paths[0]
    if imported is None or sink.has_errors:
        _show(args, sink.items, sources)
        return EXIT_INVALID
    out = args.output or "<stdout>"
    checked = api.load_text(imported.text, out)
    diagnostics = list(sink.items) + list(checked.diagnostics)
    if args.output:
        code = write_new_file(args.output, imported.text, args.force)
        if code != EXIT_OK:
            _show(args, sink.items, sources)
            return code
    else:
        sys.stdout.write(imported.text)
    _show(args, diagnostics, {**sources, **checked.sources})
    if not checked.ok:
        errors = sum(1 for d in checked.diagnostics if d.severity == "error")
        to_stderr(f"{shown(out)}: written, but incomplete: `verify check` reports {errors} error"
                  f"{'s' if errors != 1 else ''} (above) to complete")
        return EXIT_INVALID
    return EXIT_OK


def _show(args: argparse.Namespace, diagnostics: Sequence[Diagnostic], sources: Mapping[str, SourceFile]) -> None:
    if diagnostics:
        show(render("diagnostics", args.format, Report("diagnostics", args.file, tuple(diagnostics), sources)))
