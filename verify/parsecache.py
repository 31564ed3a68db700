"""The fast parser's tables, kept between processes without Lark (README, "Running on untrusted input").

A command that parses valid text needs only ``verify.lalr.FastParser``: Lark's LALR table for the
grammar and the lexer of ``lalr.py``. Building it needs Lark (about 20 ms to import, 9 ms to load
its own cache of the tables); this module keeps the finished table as JSON in the user's private
cache directory, so that a later process builds the parser from that file alone and imports Lark
only when a text needs the error path. The file's name holds a digest of the grammar and of
``lalr.py`` (which decides what the table holds): editing either makes a new file. A file that does
not describe a parser is ignored and written anew; nothing is read from a directory another user
could write (the same rule as Lark's own cache, ``larkparse._cache_file``).
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import stat

from .lalr import FastParser

#: the directory (under ``$XDG_CACHE_HOME``, else ``~/.cache``) that holds the parser's tables
CACHE_DIR = "verify-timing"


def private_cache_dir() -> str | None:
    """The cache directory, made if need be, or None when it is not a directory only this user can
    write to (or cannot be made)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    directory = os.path.join(base, CACHE_DIR)
    try:
        os.makedirs(directory, mode=0o700, exist_ok=True)
        info = os.lstat(directory)
    except (OSError, ValueError):
        return None
    getuid = getattr(os, "getuid", None)
    mine = getuid is None or info.st_uid == getuid()
    if not stat.S_ISDIR(info.st_mode) or not mine or info.st_mode & 0o022:
        return None
    return directory


def _grammar_bytes() -> bytes:
    import importlib.util

    spec = importlib.util.find_spec("verify.grammar")
    for location in (spec.submodule_search_locations or []) if spec is not None else []:
        try:
            with open(os.path.join(location, "verify.lark"), "rb") as fh:
                return fh.read()
        except OSError:
            continue
    from .larkparse import grammar_text  # (a packaging without plain files: ask importlib.resources)

    return grammar_text().encode("utf-8")


def table_file(directory: str) -> str:
    """The cache file of the current grammar and ``lalr.py``."""
    from . import lalr

    digest = hashlib.sha256(_grammar_bytes())
    with open(lalr.__file__, "rb") as fh:
        digest.update(fh.read())
    return os.path.join(directory, f"fast-{digest.hexdigest()[:24]}.json")


def load_fast_parser() -> FastParser | None:
    """The fast parser: from the cache file when there is a valid one, else built from Lark's parser
    (and the file written); None when the grammar is not of the shape the fast path handles."""
    directory = private_cache_dir()
    path = table_file(directory) if directory is not None else None
    if path is not None:
        try:
            with open(path, encoding="utf-8") as fh:
                return FastParser.from_data(json.load(fh))
        except (OSError, ValueError):
            pass
    from .larkparse import _parser

    fast = FastParser.build(_parser())
    if fast is not None and path is not None:
        _write(path, json.dumps(fast.to_data(), separators=(",", ":")))
    return fast


def _write(path: str, text: str) -> None:
    """Write ``path`` whole or not at all (a private temporary file renamed over it)."""
    temporary = f"{path}.{os.getpid()}.tmp"
    try:
        fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(temporary, path)
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
