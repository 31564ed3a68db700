"""The fast parser's tables, kept between processes without Lark (docs/guide/untrusted.md, "The cache").

A command that parses valid text needs only ``verify.frontend.fastparse.FastParser``: Lark's LALR table for
the grammar and the lexer of ``fastparse.py``. Building it needs Lark (about 20 ms to import, 9 ms to load
its own cache of the tables); this module keeps the finished table as JSON in the user's private
cache directory, so that a later process builds the parser from that file alone and imports Lark
only when a text needs the error path. The file's name holds a digest of the grammar and of
``fastparse.py`` (which decides what the table holds): editing either makes a new file. A file that does
not describe a parser — not a regular file, too large, changed since it was written (its first line
is the SHA-256 of the rest), not JSON of a parser's shape — is ignored and written anew; nothing is
read from a directory another user could write (the same rule as Lark's own cache,
``grammar.lark_cache_file``), and only regular files are read there (``verify.core.fileaccess``).
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import stat

from ..core.fileaccess import Refused, read_regular
from collections.abc import Callable

from ..core.resources import data_text
from .fastparse import FastParser

#: the directory (under ``$XDG_CACHE_HOME``, else ``~/.cache``) that holds the parser's tables
CACHE_DIR = "verify-timing"
#: the largest table file read (the grammar's is about 30 kB)
MAX_TABLE_BYTES = 4 * 1024 * 1024


def private_cache_dir() -> str | None:
    """The cache directory, made if need be (mode 0700), or None when it is not such a private directory
    of this user (or cannot be made). Any permission for others is refused, not only writing: a
    directory that a checkout made (0755) — ``$XDG_CACHE_HOME`` pointing into a repository — may hold
    files a pull request committed, and Lark's cache is a pickle."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    directory = os.path.join(base, CACHE_DIR)
    try:
        os.makedirs(directory, mode=0o700, exist_ok=True)
        info = os.lstat(directory)
    except (OSError, ValueError):
        return None
    getuid = getattr(os, "getuid", None)
    mine = getuid is None or info.st_uid == getuid()
    if not stat.S_ISDIR(info.st_mode) or not mine or info.st_mode & 0o077:
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
    return data_text("grammar", "verify.lark").encode("utf-8")  # (a packaging without plain files)


def table_file(directory: str) -> str:
    """The cache file of the current grammar and ``fastparse.py``."""
    from . import fastparse

    digest = hashlib.sha256(_grammar_bytes())
    with open(fastparse.__file__, "rb") as fh:
        digest.update(fh.read())
    return os.path.join(directory, f"fast-{digest.hexdigest()[:24]}.json")


def load_fast_parser(build: Callable[[], FastParser | None]) -> FastParser | None:
    """The fast parser: from the cache file when there is a valid one, else ``build()`` (from Lark's
    parser; the file written); None when the grammar is not of the shape the fast path handles."""
    directory = private_cache_dir()
    path = table_file(directory) if directory is not None else None
    if path is not None:
        cached = read_table(path)
        if cached is not None:
            return cached
    fast = build()
    if fast is not None and path is not None:
        _write(path, stamped_table(json.dumps(fast.to_data(), separators=(",", ":"))))
    return fast


def stamped_table(text: str) -> str:
    """The cache file's text for the table ``text`` (JSON): a first line with its SHA-256, then ``text``."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest() + "\n" + text


def read_table(path: str) -> FastParser | None:
    """The parser the cache file ``path`` describes, or None for anything else: a file that is not a
    regular file (a FIFO is never waited on, a link never followed), is too large, whose first line is
    not the SHA-256 of the rest (a file changed after it was written), or that does not describe a
    parser (``FastParser.from_data``). The caller then builds the table and writes the file anew."""
    try:
        raw = read_regular(path, MAX_TABLE_BYTES, follow_links=False)
    except (Refused, OSError):
        return None
    digest, newline, body = raw.partition(b"\n")
    if len(raw) > MAX_TABLE_BYTES or not newline or hashlib.sha256(body).hexdigest().encode("ascii") != digest:
        return None
    try:
        data = json.loads(body)
        return FastParser.from_data(data) if isinstance(data, dict) else None
    except (ValueError, RecursionError):
        return None


def clear_if_not_regular(path: str) -> None:
    """Remove what stands at ``path`` in the private cache directory unless it is a regular file (a FIFO,
    a link, a directory): Lark opens its cache file itself, and would wait on a FIFO or write through a
    link."""
    try:
        if stat.S_ISREG(os.lstat(path).st_mode):
            return
    except OSError:
        return
    with contextlib.suppress(OSError):
        if os.path.isdir(path) and not os.path.islink(path):
            os.rmdir(path)
        else:
            os.unlink(path)


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
