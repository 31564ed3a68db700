"""The grammar (``grammar/verify.lark``) as Lark's LALR parser with positions, and its terminals in the
language's words. Error recovery (``verify.frontend.recovery``) parses with it; the fast path's table
(``verify.frontend.parsecache``) is built from it; an editor's keyword completion asks it.
"""
from __future__ import annotations

import contextlib
import contextvars
import functools
import os
import re
from collections.abc import Iterator

from lark import Lark, Token
from lark.exceptions import LarkError, UnexpectedInput
from lark.lark import PostLex

from ..core.resources import data_text
from .fastparse import UNIT_WORDS, TooManyTokens, position
from .parsecache import clear_if_not_regular, private_cache_dir

#: how terminals are named in messages
_TOKEN_WORDS = {
    "NAME": "a name",
    "NUMBER": "a number",
    "UNIT": "a unit (s, ms, us, ns, Hz, kHz)",
    "STRING": 'a quoted file name ("...")',
    "$END": "the end of the file",
}


@functools.lru_cache(maxsize=1)
def grammar_text() -> str:
    return data_text("grammar", "verify.lark")


class WholeWords(PostLex):
    """Gives the contextual lexer NAME in every state, so that keywords are whole words.

    Lark's contextual lexer lexes each parser state with the terminals that state accepts; in a state
    that accepts keywords but no name, a keyword would match the start of a longer word (``outx`` as
    ``out`` + ``x``). With NAME always in, a word is matched whole and is a keyword only if it is exactly
    one that the state accepts (Lark's embedding of keywords into NAME); otherwise it is a NAME, which
    such a state rejects with an error naming the word. The fast path (``verify.frontend.fastparse``) lexes words the
    same way. The tokens themselves pass through unchanged."""

    always_accept = ("NAME",)

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        budget = _TOKEN_BUDGET.get()
        if budget is None:
            return stream
        return budget.count(stream)


class _TokenBudget:
    """The tokens one parse may still lex (``Limits.tokens``), across the restarts of error recovery."""

    def __init__(self, limit: int):
        self.left = limit

    def count(self, stream: Iterator[Token]) -> Iterator[Token]:
        for tok in stream:
            self.left -= 1
            if self.left < 0:
                assert tok.line is not None and tok.column is not None  # (a lexed token has both)
                raise TooManyTokens(position(tok.line, tok.column))
            yield tok


_TOKEN_BUDGET: contextvars.ContextVar[_TokenBudget | None] = contextvars.ContextVar("token_budget", default=None)


@contextlib.contextmanager
def counting_tokens(limit: int) -> Iterator[None]:
    """Within the block, a parse by ``lark_parser()`` raises ``TooManyTokens`` at its ``limit + 1``-th token."""
    reset = _TOKEN_BUDGET.set(_TokenBudget(limit))
    try:
        yield
    finally:
        _TOKEN_BUDGET.reset(reset)


@functools.lru_cache(maxsize=1)
def lark_parser() -> Lark:
    """The parser; its tables are built once per Lark release and kept in ``lark_cache_file()`` (Lark's
    cache: a later process loads them in a tenth of the time it takes to build them)."""
    return Lark(grammar_text(), parser="lalr", lexer="contextual", propagate_positions=True,
                postlex=WholeWords(), cache=lark_cache_file())


def lark_cache_file() -> str | bool:
    """The file for Lark's cache of the parser tables, or False (no cache) when there is no directory
    that only this user can write: Lark stores the tables with ``pickle``, so a file that another user
    could have written is never read. Lark checks the grammar, its options, its own release and
    Python's against the file's and builds the tables afresh on any difference."""
    import lark

    directory = private_cache_dir()
    if directory is None:
        return False
    path = os.path.join(directory, f"lark-{lark.__version__}-parser.cache")
    clear_if_not_regular(path)  # (Lark opens the file itself: never a FIFO it would wait on, never a link)
    return path


@functools.lru_cache(maxsize=1)
def literal_words() -> dict[str, str]:
    """terminal -> its literal in quotes (``'component'``), for the terminals that are literals."""
    words = {}
    for term in lark_parser().terminals:
        if term.pattern.type == "str":
            words[term.name] = f"'{term.pattern.value}'"
    return words


def describe_token_type(name: str) -> str:
    return _TOKEN_WORDS.get(name) or literal_words().get(name) or name.lower()


@functools.lru_cache(maxsize=1)
def keyword_terminals() -> dict[str, str]:
    """keyword -> its terminal (the literals that are words)."""
    return {w[1:-1]: n for n, w in literal_words().items() if re.fullmatch(r"'[A-Za-z_]\w*'", w)}


def reserved_words() -> frozenset[str]:
    """The words a name cannot be: the keywords and the units (an importer renames such names)."""
    return frozenset(keyword_terminals()) | UNIT_WORDS


def expected_keywords(text: str) -> list[str]:
    """The keywords the grammar accepts right after ``text`` (an editor's completion), sorted; every
    keyword when ``text`` does not parse up to its end."""
    try:
        interactive = lark_parser().parse_interactive(text)
        interactive.exhaust_lexer()
        accepted = interactive.accepts()  # type: ignore[no-untyped-call]  # (Lark leaves it unannotated)
    except (UnexpectedInput, LarkError):
        return sorted(keyword_terminals())
    words = {terminal: word for word, terminal in keyword_terminals().items()}
    return sorted(words[t] for t in accepted if t in words)
