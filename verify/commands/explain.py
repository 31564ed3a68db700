"""``verify explain CODE``: the meaning of a diagnostic code, with its minimal failing example;
``verify explain --list``: every code with its title."""
from __future__ import annotations

import argparse
import sys

from ..core.codes import CODES
from .common import EXIT_INVALID, EXIT_OK

HELP = "explain a diagnostic code with a minimal failing example"
RESULT = None
MODEL, SYSTEM = False, False


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("code", metavar="CODE", nargs="?", help="a diagnostic code, e.g. E101")
    p.add_argument("--list", action="store_true", help="list every code with its title")


def run(args: argparse.Namespace) -> int:
    from ..core.explain import explain

    if args.list or args.code is None:
        if args.code is not None or not args.list:
            print("error: give a CODE (e.g. `verify explain E101`) or --list", file=sys.stderr)
            return EXIT_INVALID
        print("".join(f"{c.code}  {c.title}\n" for c in CODES.values()), end="")
        return EXIT_OK
    code = args.code.upper()
    if code not in CODES:
        from ..core.diagnostics import suggest

        starting = sorted(c for c in CODES if c.startswith(code)) if len(code) >= 2 else []
        hint = ("one of " + ", ".join(starting) if starting else suggest(code, CODES))
        print(f"error: unknown diagnostic code {args.code}" + (f"; did you mean {hint}?" if hint else ""),
              file=sys.stderr)
        return EXIT_INVALID
    print(explain(code))
    return EXIT_OK
