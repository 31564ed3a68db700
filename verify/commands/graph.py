"""``verify graph FILE``: the system as a picture (specs/codegen.md is not involved: ``verify.outputs.diagram``).

    verify graph FILE [--format dot|svg|png|pdf] [-o OUT [--force]]

DOT (the default) needs nothing; SVG, PNG and PDF are laid out by Graphviz's ``dot``
(``scripts/install-tools`` installs it). A configured system is drawn with its analysis
(rates, response times, chain bounds against their specs, over/undersampling); one with synthesis
holes is drawn without it. Without ``--format``, ``-o OUT`` takes the format from OUT's extension
(``EXTENSIONS``: ``.dot``/``.gv`` or none DOT, ``.svg``, ``.png``, ``.pdf``); another extension is
refused rather than given text it does not name. Without ``-o`` the picture goes to standard output
(PNG and PDF only to a file or a pipe, never to a terminal). ``-o`` writes a new file (``--force``
replaces one) and says so on standard error.

Exit codes: 0 drawn; 2 invalid input or usage (Graphviz missing for SVG/PNG); 70 internal error.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import TYPE_CHECKING

from .common import EXIT_OK, exists, fail, load_system, write_output

if TYPE_CHECKING:
    from ..model.system import SystemModel

HELP = "draw the system: instances, ports, data flow, activations, chains (DOT, SVG, PNG, PDF)"
RESULT = None
FORMATS = ("dot", "svg", "png", "pdf")
FORMAT_HELP = "dot (Graphviz's text, the default), svg, png or pdf (laid out by Graphviz)"
#: the format ``-o OUT`` gives without ``--format``, by OUT's extension
EXTENSIONS = {"": "dot", ".dot": "dot", ".gv": "dot", ".svg": "svg", ".png": "png", ".pdf": "pdf"}
#: formats that are not text, never written to a terminal
BINARY = ("png", "pdf")
MODEL, SYSTEM = True, True


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", metavar="OUT", help="write the picture to a new file OUT")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")


def picture(system: SystemModel, fmt: str) -> bytes:
    """The picture of a loaded system in ``fmt`` (raises ``diagram.GraphvizMissing`` for SVG/PNG
    without Graphviz, ``diagram.GraphvizFailed`` when it fails)."""
    from ..outputs import diagram
    from ..timing import analyze

    analysis = analyze(system) if system.is_configured else None
    text = diagram.to_dot(system, analysis)
    return text.encode("utf-8") if fmt == "dot" else diagram.layout(text, fmt)


def run(args: argparse.Namespace) -> int:
    from ..outputs.diagram import GraphvizFailed, GraphvizMissing

    if not args.format_given and args.output:  # (the format from OUT's extension: nav.svg, nav.png)
        ext = os.path.splitext(args.output)[1].lower()
        if ext not in EXTENSIONS:
            return fail(f"cannot tell which picture to write from the extension `{ext}` of {args.output}: "
                        "name it .dot (or .gv), .svg, .png or .pdf, or give --format")
        args.format = EXTENSIONS[ext]

    if args.format in BINARY and not args.output and sys.stdout.isatty():
        return fail(f"a {args.format.upper()} is not shown on a terminal: write it with `-o FILE.{args.format}` "
                    "(or pipe it)")
    if args.output and exists(args.output) and not args.force:
        return fail(f"{args.output} exists; refusing to overwrite it (pass --force to replace it)")
    loaded = load_system(args)
    if isinstance(loaded, int):
        return loaded
    _, system = loaded
    try:
        data = picture(system, args.format)
    except GraphvizMissing:
        return fail(f"--format {args.format} needs Graphviz's `dot`: install graphviz "
                    "(scripts/install-tools), or use --format dot")
    except GraphvizFailed as err:
        return fail(f"{err}; `--format dot` gives the text, for another Graphviz")
    if not args.output:
        sys.stdout.flush()
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
        return EXIT_OK
    return write_output(args.output, data, args.force)
