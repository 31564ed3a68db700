"""``verify fmt FILE``: the canonical formatting (comments kept); ``--check``, ``--in-place``, ``-o NEW``."""
from __future__ import annotations

import argparse
import os
import sys

from ..core.diagnostics import DiagnosticSink
from ..outputs.rendering import render_all_text
from ..core.sanitize import shown
from ..core.source import SourceFile
from .common import EXIT_INVALID, EXIT_OK, EXIT_VIOLATED, STDIN, read_stdin, replace_file, to_stderr, write_new_file

HELP = "print the canonical formatting of a file"
DESCRIPTION = "print the canonical formatting of a file (comments are kept)"
RESULT = None
MODEL, SYSTEM = False, False


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="the .vfy file; `-`: standard input")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--check", action="store_true", help="exit 1 if the file is not canonically formatted")
    group.add_argument("--in-place", action="store_true", help="rewrite FILE itself")
    group.add_argument("-o", "--output", metavar="OUT", help="write to a new file OUT")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")


def run(args: argparse.Namespace) -> int:
    from ..frontend.fmt import format_text
    from ..core.fileaccess import area_of
    from ..frontend.loader import read_text

    sink = DiagnosticSink()
    if args.file == "-":
        if args.in_place:
            to_stderr("error: --in-place needs a file, not standard input (`-`)")
            return EXIT_INVALID
        args.file = STDIN
        text = read_stdin(sink)
    else:
        path = os.path.normpath(args.file)
        # (the rule of every model file: a link that leads out of the file's directory is refused, E006)
        text = read_text(path, sink, area=area_of([path]))
    if text is None:
        to_stderr(render_all_text(sink.items, {}))
        return EXIT_INVALID
    formatted, diagnostics = format_text(text, args.file)
    if formatted is None:
        from ..frontend.parse import parse_source

        opaque = parse_source(text, args.file).opaque
        to_stderr(render_all_text(diagnostics, {args.file: SourceFile(args.file, text, opaque)}))
        return EXIT_INVALID
    if args.check:
        if formatted != text:
            print(f"{shown(args.file)}: not canonically formatted (run `verify fmt --in-place {shown(args.file)}`)",
                  file=sys.stderr)
            return EXIT_VIOLATED
        return EXIT_OK
    if args.in_place:
        if formatted != text:
            return replace_file(args.file, formatted)
        return EXIT_OK
    if args.output:
        return write_new_file(args.output, formatted, args.force)
    sys.stdout.write(formatted)
    return EXIT_OK
