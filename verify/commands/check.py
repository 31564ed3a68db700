"""``verify check FILE``: parse, resolve names and validate; every problem with its location."""
from __future__ import annotations

import argparse

from ..outputs import Report, render
from .common import EXIT_INVALID, EXIT_OK, load_args, show

HELP = "parse, resolve and validate a model"
RESULT = "check"
MODEL, SYSTEM = True, False


def add_arguments(p: argparse.ArgumentParser) -> None:
    """(no options of its own)"""


def run(args: argparse.Namespace) -> int:
    result = load_args(args)
    show(render(RESULT, args.format, Report(RESULT, args.file, result.diagnostics, result.sources, result)))
    return EXIT_OK if result.ok else EXIT_INVALID
