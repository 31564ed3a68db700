"""``verify check FILE...``: parse, resolve names and validate; every problem with its location.

Each FILE is checked as the root of a project (its imports followed); a directory stands for every
``.vfy`` file under it (hidden directories left out), in name order. One exit code for all: 0 when every
file is valid, 2 when one is not (or a directory holds no model). A diagnostic that several roots share
(an imported file's) is shown once. With ``--format json`` or ``sarif`` the diagnostics of every file
are one document.
"""
from __future__ import annotations

import argparse
import os

from ..core.diagnostics import Diagnostic
from ..outputs import Report, render
from ..core.source import SourceFile
from .common import EXIT_INVALID, EXIT_OK, fail, load_args, show

HELP = "parse, resolve and validate models (files, or directories of .vfy files)"
RESULT = "check"
MODEL, SYSTEM = True, False
#: FILE is one or more paths (``verify.cli``)
FILES = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    """(no options of its own)"""


def models_under(directory: str) -> list[str]:
    """The ``.vfy`` files under ``directory``, in name order; hidden files and directories left out."""
    found = []
    for here, dirs, names in os.walk(directory):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        found += [os.path.join(here, n) for n in sorted(names) if n.endswith(".vfy") and not n.startswith(".")]
    return sorted(found)


def model_files(paths: list[str]) -> list[str] | str:
    """The files to check: each path as given, a directory as its ``.vfy`` files; or what is wrong."""
    files: list[str] = []
    for path in paths:
        if path != "-" and os.path.isdir(path):
            found = models_under(path)
            if not found:
                return f"{path} holds no .vfy file"
            files += found
        else:
            files.append(path)
    if "-" in files and len(files) > 1:
        return "`-` (standard input) is a model of its own: check it alone"
    return list(dict.fromkeys(files))


def run(args: argparse.Namespace) -> int:
    files = model_files(args.file if isinstance(args.file, list) else [args.file])
    if isinstance(files, str):
        return fail(files)
    if len(files) == 1:
        args.file = files[0]
        result = load_args(args)
        show(render(RESULT, args.format, Report(RESULT, args.file, result.diagnostics, result.sources, result)))
        return EXIT_OK if result.ok else EXIT_INVALID
    return check_all(args, files)


def check_all(args: argparse.Namespace, files: list[str]) -> int:
    """Several roots: each file's report (text), or one document of them all; a shared diagnostic once."""
    seen: set[Diagnostic] = set()
    every: list[Diagnostic] = []
    sources: dict[str, SourceFile] = {}
    status = EXIT_OK
    for file in files:
        one = argparse.Namespace(**{**vars(args), "file": file})
        result = load_args(one)
        status = status if result.ok else EXIT_INVALID
        new = tuple(d for d in result.diagnostics if d not in seen)
        seen.update(new)
        every += new
        sources.update(result.sources)
        if args.format == "text" and (new or result.ok):
            show(render(RESULT, "text", Report(RESULT, file, new, result.sources, result if result.ok else None)))
    if args.format != "text":
        show(render(RESULT, args.format, Report(RESULT, files[0], tuple(every), sources, None)))
    return status
