"""``verify completion bash|zsh|fish``: the shell's completion script, on standard output.

    source <(verify completion bash)                                     # bash, for this shell
    verify completion bash > ~/.local/share/bash-completion/completions/verify
    verify completion zsh > "${fpath[1]}/_verify"                         # zsh
    verify completion fish > ~/.config/fish/completions/verify.fish      # fish

Exit codes: 0 printed; 2 usage.
"""
from __future__ import annotations

import argparse
import sys

from .common import EXIT_OK

HELP = "print the shell completion script for bash, zsh or fish"
RESULT = None
MODEL, SYSTEM = False, False
#: ``args.parser``: the command line's parser, which the script is written from
PARSER = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..outputs.completion import SHELLS

    p.add_argument("shell", choices=SHELLS, metavar="SHELL", help="bash, zsh or fish")


def run(args: argparse.Namespace) -> int:
    from ..outputs.completion import script

    sys.stdout.write(script(args.shell, args.parser))
    return EXIT_OK
