"""``verify lsp``: the language server, over standard input and output (``verify.lsp``; README,
"Editors")."""
from __future__ import annotations

import argparse

HELP = "the language server (LSP over standard input and output) for any LSP editor"
RESULT = None
MODEL, SYSTEM = False, False


def add_arguments(p: argparse.ArgumentParser) -> None:
    """(no options: the editor starts it)"""


def run(args: argparse.Namespace) -> int:
    from ..lsp.server import main

    return main()
