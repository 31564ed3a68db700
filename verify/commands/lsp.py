"""``verify lsp``: the language server, over standard input and output (``verify.lsp``;
docs/guide/editors.md)."""
from __future__ import annotations

import argparse

HELP = "the language server (LSP over standard input and output) for any LSP editor"
RESULT = None
MODEL, SYSTEM = False, False


def add_arguments(p: argparse.ArgumentParser) -> None:
    """(the editor starts it; one option bounds what a message may make it hold)"""
    from ..core.limits import LSP_MESSAGE_BYTES as MESSAGE_BYTES

    p.add_argument("--max-message-bytes", type=_positive, default=MESSAGE_BYTES, metavar="N",
                   help=f"the largest LSP message read (default {MESSAGE_BYTES:,} bytes: a file at the size limit "
                        "fits); a larger one is answered with an error and dropped")


def _positive(text: str) -> int:
    value = int(text) if text.isdigit() else 0
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number of bytes, got {text!r}")
    return value


def run(args: argparse.Namespace) -> int:
    from ..lsp.server import main

    return main(args.max_message_bytes)
