"""``verify export TOOL FILE -o DIR``: a configured system as another tool's models (specs/interop.md).

For SmartMDSD: ``SYSTEM.activityArch`` (each task's activation source, priority, core and execution
times), ``SYSTEM.componentArch`` (which node configures which activity: with ``--from``, the original
with only the missing lines added) and ``SYSTEM.causeEffectChain`` (the chains and their reaction-time
specs), written into DIR. Nothing is written when a file would be replaced (unless ``--force``) or when
something cannot be exported (E706); what is exported rounded or left out is reported (E707).

Exit codes: 0 written; 2 invalid input, holes (E218), E706, or a file in the way; 70 internal error.
"""
from __future__ import annotations

import argparse
import os

from ..core.diagnostics import DiagnosticSink
from ..core.fileaccess import write_output
from ..core.sanitize import shown
from .common import EXIT_INVALID, EXIT_OK, cannot_write, exists, load_configured, show_diagnostics, to_stderr, wrote

HELP = "write a configured system as another tool's models (SmartMDSD, CARET)"
RESULT = "diagnostics"
MODEL, SYSTEM = True, True


def add_leading_arguments(p: argparse.ArgumentParser) -> None:
    from ..interop import EXPORTERS

    p.add_argument("tool", metavar="TOOL", choices=EXPORTERS,
                   help=f"whose models to write: {', '.join(EXPORTERS)} (specs/interop.md)")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", metavar="DIR", required=True, help="the directory to write into (created "
                   "if missing)")
    p.add_argument("--from", dest="origin", metavar="PATH", action="append", default=[],
                   help="the models the system was imported from (repeatable): their node names and "
                        "component architecture are kept")
    p.add_argument("--force", action="store_true", help="replace files that exist in DIR")


def run(args: argparse.Namespace) -> int:
    from ..interop import exporter, tool

    loaded = load_configured(args, "export")
    if isinstance(loaded, int):
        return loaded
    result, system = loaded
    sink = DiagnosticSink()
    sources = dict(result.sources)
    origin = None
    if args.origin:
        read = tool(args.tool).read_files(args.origin, sink)
        sources.update(read.sources)
        origin = read.files
        if sink.has_errors:
            show_diagnostics(args, sink.items, sources)
            return EXIT_INVALID
    exported = exporter(args.tool).export_system(system, origin, {p: s.text for p, s in sources.items()}, sink)
    if sink.items:
        show_diagnostics(args, sink.items, sources)
    if exported is None:
        return EXIT_INVALID
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        to_stderr(f"error: {shown(args.output)} exists and is not a directory")
        return EXIT_INVALID
    in_the_way = [n for n in exported.files if exists(os.path.join(args.output, n))]
    if in_the_way and not args.force:
        to_stderr(f"error: {', '.join(map(shown, in_the_way))} exist{'s' if len(in_the_way) == 1 else ''} in "
                  f"{shown(args.output)}; "
                  "nothing was written (pass --force to replace)")
        return EXIT_INVALID
    written: list[str] = []
    try:
        if not os.path.isdir(args.output):
            os.makedirs(args.output)
            written.append(args.output)
        for name, text in exported.files.items():  # (never through a link: ``fileaccess.write_output``)
            path = os.path.join(args.output, name)
            write_output(path, text, replace=args.force)  # (whole or not at all)
            written.append(path)
    except OSError as err:
        return cannot_write(getattr(err, "filename", None) or args.output, err, written)
    for name in exported.files:
        wrote(os.path.join(args.output, name))
    return EXIT_OK
