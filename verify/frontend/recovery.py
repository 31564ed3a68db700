"""Error recovery: Lark's parser (``verify.frontend.grammar``) on a text the fast path rejected, with
what it expected in the language's words (never ``__ANON_0`` or ``$END``), help for the usual slips (a
misspelt or glued keyword, an exponent, an unterminated comment or string), and recovery by inserting or
dropping a token, so that one run reports several errors. ``recover`` is the one entry point
(``verify.frontend.parse`` calls it); it also gives what recovery made of the text (``Parsed.partial``).
"""
from __future__ import annotations

import copy
import functools
import re
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import NamedTuple, cast

from lark import Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from lark.parsers.lalr_interactive_parser import InteractiveParser

from ..core.diagnostics import DiagnosticSink, Label
from ..core.limits import DEFAULT_LIMITS, Limits
from ..core.source import Span
from ..model import syntax as s
from .fastparse import SKIP_RE, WORD_RE, TooManyTokens, looks_like_model
from .grammar import counting_tokens, describe_token_type, keyword_terminals, lark_parser, literal_words
from .treebuild import NumberError, TreeBuilder, too_many_tokens

MAX_EXPECTED_SHOWN = 4  # (E002: a longer list says little about a stray character)
#: error recovery gives a file up after this many errors per syntax error it may report (the errors on
#: one line are reported once): with the default limit of 20 reported errors, 1,000 recoveries in all
RECOVERIES_PER_SYNTAX_ERROR = 50


def recovery_limit(limits: Limits) -> int:
    """The errors error recovery recovers from in one file before it gives the file up."""
    return limits.syntax_errors * RECOVERIES_PER_SYNTAX_ERROR


class Recovered(NamedTuple):
    """What ``recover`` made of a text: its tree (None after a syntax error) and, after one, the tree
    recovery built with placeholders for what was missing (None when it made nothing of the text)."""

    module: s.Module | None
    partial: s.Module | None


@dataclass(frozen=True)
class _Notes:
    """What recovery learnt about one syntax error for its report: the terminals the parser really accepts
    there (None: asked at the report), a keyword glued to the word after it, the unit a misspelt one was
    read as (and whether to suggest it), and the symbol inserted to go on."""

    accepted: set[str] | None = None
    glued: tuple[str, Token, Token] | None = None
    unit: tuple[str, bool] | None = None
    inserted: str | None = None


def _describe_expected(names: Iterable[str]) -> str:
    words = sorted({describe_token_type(n) for n in names if not n.startswith("__IGNORE")})
    if not words:
        return "nothing more here"
    if len(words) > 12:
        words = words[:12] + ["…"]
    if len(words) == 1:
        return words[0]
    return "one of " + ", ".join(words)


def _shorten(text: str, width: int = 40) -> str:
    """``text`` from the user's file for a message: at most ``width`` characters, an ellipsis where cut."""
    return text if len(text) <= width else text[:width - 3] + "..."


def _describe_found(token: Token) -> str:
    if token.type == "$END":
        return "the end of the file"
    return f"'{_shorten(str(token))}'"


def _token_span(path: str, tok: Token) -> Span:
    line = tok.line or 1
    col = tok.column or 1
    end_line = tok.end_line or line
    end_col = tok.end_column or col + 1
    return Span(path, line, col, end_line, end_col)


def _number_before(text: str, token: Token) -> tuple[str, tuple[int, int, int, int]] | None:
    """The number just before ``token`` (white space between), as (text, (line, col, end_line, end_col))."""
    pos = token.start_pos if token.type != "$END" and token.start_pos is not None else len(text)
    before = text[:pos].rstrip()
    match = re.search(r"(?<![\w.])[0-9]+(\.[0-9]+)?(/[0-9]+)?$", before)
    if match is None or "//" in before[before.rfind("\n", 0, match.start()) + 1:match.start()]:
        return None
    line = before.count("\n", 0, match.start()) + 1
    col = match.start() - (before.rfind("\n", 0, match.start()) + 1) + 1
    return match.group(0), (line, col, line, col + len(match.group(0)))


@functools.lru_cache(maxsize=1)
def _punct_terminals() -> list[tuple[str, str]]:
    """(literal, terminal) for the punctuation literals, longest first (as Lark's lexer tries them)."""
    kws = set(keyword_terminals().values())
    return sorted(((w[1:-1], n) for n, w in literal_words().items() if n not in kws),
                  key=lambda p: (-len(p[0]), p[0]))


_NUMBER_RE = re.compile(r"[0-9]+(\.[0-9]+)?(/[0-9]+)?")
_EXPONENT_RE = re.compile(r"[eE][+-]?[0-9]+")
_UNITS = ("kHz", "Hz", "ms", "us", "ns", "s")


def _next_types(text: str, pos: int) -> list[str]:
    """The terminals the lexeme at ``pos`` (white space and comments already skipped) may be, for trial
    feeds."""
    if pos >= len(text):
        return ["$END"]
    if m := WORD_RE.match(text, pos):
        word = m.group(0)
        kinds = [keyword_terminals()[word]] if word in keyword_terminals() else []
        return kinds + (["UNIT"] if word in _UNITS else []) + ["NAME"]
    if _NUMBER_RE.match(text, pos):
        return ["NUMBER"]
    if text.startswith('"', pos):
        return ["STRING"]
    for literal, name in _punct_terminals():
        if text.startswith(literal, pos):
            return [name]
    return []


def _lookahead(text: str, pos: int, count: int = 2) -> list[list[Token]]:
    """The next ``count`` lexemes from ``pos``, each as the tokens it may be (for trial feeds): every
    combination of alternatives, or fewer lexemes where the text ends or a lexeme is not recognised."""
    combos: list[list[Token]] = [[]]
    for _ in range(count):
        skipped = SKIP_RE.match(text, pos)
        pos = skipped.end() if skipped is not None else pos  # (it matches the empty string)
        kinds = _next_types(text, pos)
        if not kinds:
            break
        m = WORD_RE.match(text, pos) or _NUMBER_RE.match(text, pos)
        length = len(m.group(0)) if m else 1
        combos = [c + [Token(k, "")] for c in combos for k in kinds]
        if kinds == ["$END"]:
            break
        pos += length
        if kinds == ["STRING"]:
            end = text.find('"', pos)
            pos = end + 1 if end >= 0 else len(text)
        elif m is None:
            pos += next((len(lit) for lit, name in _punct_terminals() if name == kinds[0]), 1) - 1
    return combos


def _fits(parser: InteractiveParser, tokens: list[Token], ahead: list[list[Token]]) -> bool:
    """Whether ``parser`` accepts ``tokens`` followed by the next lexemes of the text (``ahead``, from
    ``_lookahead``: looked up once for all the trials at one place, as it scans what white space and
    comments follow)."""
    return any(_feeds(parser, tokens + more) for more in ahead)


def _feeds(parser: InteractiveParser, tokens: list[Token]) -> bool:
    """Whether a copy of ``parser`` accepts ``tokens``. The copy shares the parser's values, so it runs
    without callbacks (as Lark's own ``accepts``): a callback may extend the child list of a tree on the
    stack in place, which would change the tree error recovery goes on to build (``parse.Parsed.partial``)."""
    trial = parser.copy(deepcopy_values=False)  # type: ignore[no-untyped-call]  # (Lark leaves it unannotated)
    conf = copy.copy(trial.parser_state.parse_conf)
    conf.callbacks = {}
    trial.parser_state.parse_conf = conf
    try:
        for tok in tokens:
            trial.feed_token(tok)
    except UnexpectedInput:
        return False
    return True


def _glued_keyword(err: UnexpectedToken, text: str) -> tuple[str, Token, Token] | None:
    """A keyword glued to the word after it (``outx`` for ``out x``, ``priority1`` for ``priority 1``):
    (the keyword, its token, the token of the rest) if the parser accepts them and what follows them."""
    tok = err.token
    parser = getattr(err, "interactive_parser", None)
    if parser is None or tok.type != "NAME" or tok.start_pos is None:
        return None
    word = str(tok)
    keywords = keyword_terminals()
    candidates = sorted((kw for kw, name in keywords.items()
                         if name in (err.expected or ()) and len(word) > len(kw) and word.startswith(kw)),
                        key=len, reverse=True)
    ahead = _lookahead(text, tok.end_pos) if candidates else []
    for kw in candidates:
        rest = word[len(kw):]
        kind = "NAME" if WORD_RE.fullmatch(rest) else "NUMBER" if rest.isdigit() else None
        if kind is None:
            continue
        head = Token(keywords[kw], kw, start_pos=tok.start_pos, line=tok.line, column=tok.column,
                     end_line=tok.line, end_column=tok.column + len(kw), end_pos=tok.start_pos + len(kw))
        tail = Token(kind, rest, start_pos=tok.start_pos + len(kw), line=tok.line, column=tok.column + len(kw),
                     end_line=tok.end_line, end_column=tok.end_column, end_pos=tok.end_pos)
        if _fits(parser, [head, tail], ahead):
            return kw, head, tail
    return None


def _edit_distance(a: str, b: str) -> int:
    """Optimal string alignment distance (insertions, deletions, substitutions, transpositions)."""
    prev2: list[int] = []
    prev = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        cur = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cur[j] = min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1]))
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                cur[j] = min(cur[j], prev2[j - 2] + 1)
        prev2, prev = prev, cur
    return prev[-1]


def _misspelt_keyword(word: str, accepted: set[str]) -> str | None:
    """The accepted keyword ``word`` is a likely misspelling of (``compnent``, ``priorty``), or None."""
    if not WORD_RE.fullmatch(word):
        return None
    best = None
    for kw, name in keyword_terminals().items():
        if name not in accepted or kw == word or abs(len(word) - len(kw)) > 2:  # (the distance is at least that)
            continue
        dist = _edit_distance(word.lower(), kw)
        if dist <= (1 if len(kw) <= 4 else 2) and dist < len(kw) and (best is None or (dist, kw) < best):
            best = (dist, kw)
    return best[1] if best else None


def _syntax_help(expected: set[str], token: Token, glued: tuple[str, Token, Token] | None = None,
                 repair: str | None = None) -> str:
    """The help of an E001: specific where the slip is recognised, else what to do in general."""
    word = str(token) if token.type != "$END" else ""
    if glued is not None:
        kw, _, tail = glued
        return f"did you mean `{kw} {_shorten(str(tail))}`? a keyword is separated from the word after it by a space"
    if "UNIT" in expected:
        return "write a unit after the number, e.g. `10 ms` or `40 Hz`"
    if token.type == "RBRACE" and "COMPONENT" in expected:
        return "this `}` closes nothing: remove it, or add the `{` it belongs to"
    near = _misspelt_keyword(word, expected)
    if near is not None:
        return f"did you mean `{near}`?"
    if "NAME" in expected and token.type != "NAME" and WORD_RE.fullmatch(word):
        return f"`{token}` is a keyword of the language; choose another name"
    if "RBRACE" in expected and token.type == "$END":
        return "a `}` is missing: every `{` needs its `}`"
    if token.type == "$END":
        return f"the file ends too early: complete the declaration with {_describe_expected(expected)}"
    keywords = keyword_terminals()
    if repair is not None and repair not in keywords.values():  # a missing symbol that recovery supplied
        return f"insert {describe_token_type(repair)} before {_describe_found(token)}"
    if WORD_RE.fullmatch(word) and any(n in keywords.values() for n in expected):
        if word in keywords:
            return (f"`{word}` cannot stand here: it belongs to another kind of declaration; "
                    f"specs/language.md gives the syntax of each")
        return (f"`{_shorten(word)}` is not a keyword of the language; specs/language.md gives the syntax of each "
                "declaration")
    if len(expected) == 1:
        found = _describe_found(token)
        return f"insert {_describe_expected(expected)} before {found}, or remove {found}"
    return (f"remove {_describe_found(token)}, or write what the declaration needs before it; "
            f"specs/language.md gives the syntax of each declaration")


def _accepted(err: UnexpectedInput) -> set[str]:
    """The terminals the parser really accepts where ``err`` happened.

    The table's row for the state (``err.expected``) merges LALR lookaheads across contexts: after a
    quantity it lists every token that may follow one anywhere. ``accepts()`` tries each of them on a
    copy of the parser and keeps those that are shifted after the reductions they cause. Error path only."""
    parser = getattr(err, "interactive_parser", None)
    fallback = set(getattr(err, "expected", None) or getattr(err, "allowed", None) or ())
    if parser is None:
        return fallback
    try:
        return set(parser.accepts()) or fallback
    except Exception:  # pragma: no cover - a Lark internal: the table's row is a safe approximation
        return fallback


def _exponent_after(text: str, number: tuple[str, tuple[int, int, int, int]]) -> str | None:
    """``e5`` in ``1e5`` (exponent notation right after the number), or None."""
    (digits, (line, col, _, end_col)) = number
    offset = sum(len(row) + 1 for row in text.split("\n")[:line - 1]) + end_col - 1
    m = _EXPONENT_RE.match(text, offset)
    return m.group(0) if m else None


#: other spellings of the units (a word here after a number is read as its unit, with a hint)
_UNIT_SPELLINGS = {
    "sec": "s", "secs": "s", "second": "s", "seconds": "s", "msec": "ms", "msecs": "ms", "millisecond": "ms",
    "milliseconds": "ms", "usec": "us", "usecs": "us", "microsecond": "us", "microseconds": "us", "nsec": "ns",
    "nsecs": "ns", "nanosecond": "ns", "nanoseconds": "ns", "hertz": "Hz", "kilohertz": "kHz",
}


def _unit_meant(token: Token) -> tuple[str, bool] | None:
    """For a word where a unit must follow a number (``50 mss``, ``50 sec``, ``50 foo``): the unit the
    parser goes on with, and whether the word is close enough to it to suggest it (another spelling, or
    at most two edits away); None for anything but a word that is no keyword (on_error has made those
    keyword tokens)."""
    word = str(token)
    if token.type != "NAME":
        return None
    if word.lower() in _UNIT_SPELLINGS:
        return _UNIT_SPELLINGS[word.lower()], True
    distance, unit = min((_edit_distance(word, u), u) for u in _UNITS)
    return unit, distance <= min(2, len(word) - 1)


def _unit_in_other_case(token: Token) -> str | None:
    """The unit ``token`` spells in another case (``hz``, ``KHZ``, ``MS``), if it is a word that does."""
    word = str(token)
    if token.type not in ("NAME",) and not word.isalpha():
        return None
    return next((u for u in _UNITS if u.lower() == word.lower() and u != word), None)


def _line_col(text: str, offset: int) -> tuple[int, int]:
    """The 1-based line and column of ``offset`` (lines end at "\\n" only, as the lexer counts)."""
    return text.count("\n", 0, offset) + 1, offset - text.rfind("\n", 0, offset)


def _nested_comment_before(text: str, tok: Token) -> tuple[int, int, int] | None:
    """(offsets of) the ``/*`` opening a block comment that ends right before ``tok``, a second ``/*``
    inside it, and the ``*/`` that closed it — when the text before ``tok`` looks like an attempt at
    nesting block comments; else None."""
    start = getattr(tok, "start_pos", None)
    if start is None:
        return None
    before = text[:start].rstrip()
    if not before.endswith("*/"):
        return None
    close = len(before) - 2
    inner = text.rfind("/*", 0, close)
    outer = text.rfind("/*", 0, inner) if inner > 0 else -1
    if outer < 0 or text.find("*/", outer + 2, inner) >= 0:
        return None
    line_start = text.rfind("\n", 0, outer) + 1
    if "//" in text[line_start:outer] or text.count('"', line_start, outer) % 2:
        return None  # (the first `/*` is in a line comment or a string)
    return outer, inner, close


def _report_unexpected(sink: DiagnosticSink, path: str, err: UnexpectedInput, text: str, notes: _Notes) -> None:
    if isinstance(err, UnexpectedToken):
        expected = notes.accepted
        if expected is None:
            expected = _accepted(err)
        glued = notes.glued
        span = _token_span(path, err.token)
        if err.token.type == "$END":
            span = _end_span(path, text)
        number = _number_before(text, err.token) if "UNIT" in expected else None
        if number is not None and (exponent := _exponent_after(text, number)):
            line, col, _, end_col = number[1]
            sink.emit("E001", f"exponent notation is not supported: `{number[0]}{exponent}`",
                      Span(path, line, col, line, end_col + len(exponent)), "a number with an exponent",
                      help="write the number out in full with a unit, or choose a larger or smaller unit "
                           "to keep it short, e.g. `2 s` instead of `2000 ms`")
            return
        unit = _unit_in_other_case(err.token) if "UNIT" in expected else None
        if unit is not None:
            sink.emit("E001", f"unknown unit `{err.token}`: units are case-sensitive", span, "not a unit",
                      help=f"write `{unit}`")
            return
        meant = notes.unit
        if number is not None and meant is not None:
            close, sure = meant
            sink.emit("E001", f"unknown unit `{err.token}`" + (f"; did you mean `{close}`?" if sure else ""),
                      span, "not a unit", help="the units are s, ms, us and ns for times, Hz and kHz for "
                                               f"frequencies: write e.g. `{number[0]} {close if sure else 'ms'}`")
            return
        if number is not None:  # a missing unit: point at the number that lacks it
            sink.emit("E001", f"expected a unit after the number `{number[0]}`, found {_describe_found(err.token)}",
                      Span(path, *number[1]), "this number needs a unit", help=_syntax_help(expected, err.token))
            return
        nested = _nested_comment_before(text, err.token) if err.token.type != "$END" else None
        if nested is not None:
            (o_line, o_col), (i_line, i_col), (c_line, c_col) = (_line_col(text, off) for off in nested)
            sink.emit("E001", f"expected {_describe_expected(expected)}, found {_describe_found(err.token)}",
                      span, f"unexpected here: the comment opened at {o_line}:{o_col} ended at {c_line}:{c_col}",
                      secondary=[Label(Span(path, i_line, i_col, i_line, i_col + 2),
                                       "this `/*` inside the comment opens no nested one")],
                      help="block comments do not nest: remove the inner `/*` (or close it before the "
                           "outer one), or use `//` comments")
            return
        sink.emit(
            "E001",
            f"expected {_describe_expected(expected)}, found {_describe_found(err.token)}",
            span,
            "unexpected here",
            help=_syntax_help(expected, err.token, glued, notes.inserted),
        )
    elif isinstance(err, UnexpectedCharacters):
        pos = cast(int, err.pos_in_stream)  # (Lark declares it None in UnexpectedInput; this subclass sets it)
        ch = text[pos] if pos < len(text) else ""
        span = Span(path, err.line, err.column, err.line, err.column + 1)
        if text.startswith("/*", pos):
            sink.emit("E002", "unterminated block comment", Span(path, err.line, err.column, err.line, err.column + 2),
                      "this comment is never closed", help="close the comment with `*/`")
            return
        if ch == '"':
            sink.emit("E002", "unterminated string", span, "this string is never closed",
                      help='close the file name with `"` on the same line')
            return
        if ch == "-" and re.match(r"-[ \t]*[0-9]", text[pos:pos + 40]):
            sink.emit("E002", "unexpected character '-': numbers are never negative", span, "a minus sign",
                      help="times, frequencies and priorities are non-negative: remove the `-`")
            return
        shown = repr(ch)[1:-1] if ch.isprintable() else f"U+{ord(ch):04X}" if ch else "end of file"
        allowed = notes.accepted
        if allowed is None:
            allowed = _accepted(err)
        msg = f"unexpected character '{shown}'"
        # (a long list says little about this place: a character is rarely a misspelt word)
        if allowed and len(allowed) <= MAX_EXPECTED_SHOWN:
            msg += f"; expected {_describe_expected(allowed)}"
        near = sorted(w for n in allowed if (w := literal_words().get(n, "")[1:-1]) and ch and w.startswith(ch))
        help = (f"did you mean `{near[0]}`?" if near
                else "remove it; comments start with `//` or are enclosed in `/* */`")
        sink.emit("E002", msg, span, "not part of the language", help=help)
    else:  # pragma: no cover - lark raises only the two above from LALR
        sink.emit("E001", str(err).splitlines()[0], Span(path, 1, 1, 1, 2),
                  help="specs/language.md gives the syntax of each declaration")


_INSERTION_ORDER = ("UNIT", "COLON", "NAME", "NUMBER", "RBRACE")


def _repair(err: UnexpectedToken, text: str, notes: _Notes) -> _Notes:
    """Error recovery: the smallest edit after which the parser goes on; ``notes`` with what it did.

    In order: a keyword glued to the next word is split (``outx`` read as ``out x``); the one expected
    symbol after which the offending token fits is inserted (a missing unit, colon or brace); a
    misspelt keyword is replaced by the keyword if what follows fits (``activaton`` read as
    ``activation``); for a word where only keywords may stand, a keyword is inserted before it, or
    else replaces it (``output x`` read as ``out x``), closest in spelling first, if what follows
    fits; a keyword after which the offending token fits is inserted. Lark then
    resumes after the offending token; if nothing helps, that token is simply dropped. This keeps one
    slip from cascading into many reports.
    """
    parser = err.interactive_parser
    glued = notes.glued
    if glued is not None:  # `outx : T`: go on as if it read `out x : T`
        parser.feed_token(glued[1])
        parser.feed_token(glued[2])
        return notes
    unit = _unit_in_other_case(err.token) if "UNIT" in (err.expected or ()) else None
    if unit is not None:  # `50 hz`: go on as if it read `50 Hz`
        parser.feed_token(Token("UNIT", unit, line=err.token.line, column=err.token.column))
        return notes
    meant = _unit_meant(err.token) if "UNIT" in (err.expected or ()) else None
    if meant is not None and err.token.end_pos is not None:  # `50 mss`, `50 sec`: as if it read a unit ...
        unit_token = Token("UNIT", meant[0], line=err.token.line, column=err.token.column)
        if _fits(parser, [unit_token], _lookahead(text, err.token.end_pos)):  # ... if what follows fits then
            parser.feed_token(unit_token)
            return replace(notes, unit=meant)
    keywords = keyword_terminals()
    keyword_names = set(keywords.values())
    expected = sorted(err.expected or (), key=lambda n: (n not in _INSERTION_ORDER,
                                                         _INSERTION_ORDER.index(n) if n in _INSERTION_ORDER else 0, n))
    inserted = _insert_one(parser, err.token, [n for n in expected if n not in keyword_names])
    if inserted is not None:
        return replace(notes, inserted=inserted)
    tok = err.token
    if tok.type == "NAME" and tok.end_pos is not None:
        ahead = _lookahead(text, tok.end_pos)
        near = _misspelt_keyword(str(tok), set(expected))
        keyword = Token(keywords[near], near, line=tok.line, column=tok.column) if near else None
        if keyword is not None and _fits(parser, [keyword], ahead):  # replace the misspelt word
            parser.feed_token(keyword)
            return notes
        candidates = sorted((k for k, n in keywords.items() if n in expected),
                            key=lambda k: (_edit_distance(str(tok).lower(), k), k))
        for kw in candidates:  # a keyword before it, after which the rest fits
            keyword = Token(keywords[kw], kw, line=tok.line, column=tok.column)
            if _fits(parser, [keyword, tok], ahead):
                parser.feed_token(keyword)
                parser.feed_token(tok)
                return notes
        for kw in candidates:  # the closest keyword instead of it (`output x : T` read as `out x : T`)
            keyword = Token(keywords[kw], kw, line=tok.line, column=tok.column)
            if _fits(parser, [keyword], ahead):
                parser.feed_token(keyword)
                return notes
    _insert_one(parser, err.token, [n for n in expected if n in keyword_names])
    return notes


def _insert_one(parser: InteractiveParser, token: Token, names: list[str]) -> str | None:
    """Insert the first of ``names`` after which ``token`` fits, then ``token``; the one inserted."""
    for name in names:
        filler = Token(name, _placeholder(name), line=token.line, column=token.column)
        if _feeds(parser, [filler, token]):  # trial feeds only build new nodes
            parser.feed_token(filler)
            parser.feed_token(token)
            return name
    return None


def _skip_unterminated_string(err: UnexpectedCharacters, text: str) -> None:
    """Recovery from an unterminated string: the rest of its line is taken as the string."""
    parser = getattr(err, "interactive_parser", None)
    if parser is None:  # pragma: no cover - Lark's LALR errors carry their parser
        return
    start = err.pos_in_stream
    end = text.find("\n", start)
    if end < 0:
        end = len(text)
    string = Token("STRING", text[start:end] + '"', line=err.line, column=err.column)
    if _feeds(parser, [string]):
        parser.feed_token(string)
    parser.lexer_thread.state.line_ctr.feed(text[start:end])


def _placeholder(name: str) -> str:
    return {"UNIT": "ms", "NAME": "_", "NUMBER": "0", "STRING": '""'}.get(name) or literal_words().get(
        name, "'_'")[1:-1]


def _end_span(path: str, text: str) -> Span:
    line = text.count("\n") + 1
    col = len(text) - text.rfind("\n")  # (the last line's length + 1)
    return Span(path, line, col, line, col + 1)


def recover(text: str, path: str, sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> Recovered:
    """Parse ``text`` (the contents of file ``path``) with error recovery: (the tree, None) of a text
    without syntax errors; else (None, the partial tree), what recovery made of the text, completed at its
    end where it stops early (best effort: None when even that fails). Syntax errors go to ``sink``;
    recovery stops within ``recovery_limit(limits)`` repairs, and at the first error of a text that is not
    a model."""
    state = _Recovery(text, limits)
    too_many = None
    tree: Tree[Token] | None
    try:
        with counting_tokens(limits.tokens):
            tree = lark_parser().parse(text, on_error=state.on_error)
    except UnexpectedInput as err:
        if not state.errors or getattr(err, "line", None) != state.last_line:
            seen = state.last is not None and state.last[0] is err
            state.errors.append((err, state.last[1] if state.last is not None and seen else _Notes()))
        tree = state.completed
    except TooManyTokens as err:
        too_many, tree = err, None
    for error, notes in state.errors:
        _report_unexpected(sink, path, error, text, notes)
    if too_many is not None:
        sink.add(too_many_tokens(path, too_many.at, limits))
    if state.errors or tree is None:
        return Recovered(None, _partial(tree, path, limits))
    try:
        return Recovered(TreeBuilder(path, sink, limits).transform(tree), None)
    except NumberError:
        return Recovered(None, None)


class _Recovery:
    """One recovering parse: Lark calls ``on_error`` at each syntax error; it records the error to report
    (one per line: a repair often trips the very next token too) with its notes, repairs, and says whether
    to go on. Every error recovered from counts, so that recovery stops within ``recovery_limit`` repairs
    on any text; a text that is not a model reports only its first error, so recovery stops there."""

    def __init__(self, text: str, limits: Limits) -> None:
        self.text = text
        self.limits = limits
        self.errors: list[tuple[UnexpectedInput, _Notes]] = []  # the errors to report
        self.last: tuple[UnexpectedInput, _Notes] | None = None  # the error seen last, with its notes
        self.last_line = -1
        self.recoveries = 0
        self.most = recovery_limit(limits) if looks_like_model(text) else 1
        self.completed: Tree[Token] | None = None  # the tree completed where recovery gave up

    def give_up(self, err: UnexpectedInput) -> bool:
        self.completed = _complete_at_end(err)
        return False

    def on_error(self, err: UnexpectedInput) -> bool:
        text = self.text
        line = getattr(err, "line", -1)
        at_end = isinstance(err, UnexpectedToken) and err.token.type == "$END"
        notes = _Notes()
        if isinstance(err, UnexpectedToken):
            tok = err.token
            keywords = keyword_terminals()
            if tok.type == "NAME" and str(tok) in keywords:
                # a state that does not accept it lexes a keyword as a NAME (``WholeWords``): recovery
                # and messages treat it as the keyword it is, as Lark's root lexer would
                err.token = Token.new_borrow_pos(keywords[str(tok)], str(tok), tok)
            notes = _Notes(glued=_glued_keyword(err, text))  # (before the repair changes the parser)
        reported = line != self.last_line or at_end
        if reported:
            notes = replace(notes, accepted=_accepted(err))
            self.errors.append((err, notes))
            self.last_line = line
        self.last = (err, notes)
        if isinstance(err, UnexpectedToken):
            if err.token.type == "$END":
                return self.give_up(err)
            notes = _repair(err, text, notes)
            self.last = (err, notes)
            if reported:
                self.errors[-1] = (err, notes)
        elif isinstance(err, UnexpectedCharacters):
            if text.startswith("/*", err.pos_in_stream):
                return self.give_up(err)  # an unterminated comment: the rest of the file is its text
            if text.startswith('"', err.pos_in_stream):
                _skip_unterminated_string(err, text)
        self.recoveries += 1
        return (len(self.errors) < self.limits.syntax_errors and self.recoveries < self.most) or self.give_up(err)


#: the terminals a completion at the end of the text inserts first (a closing brace, then what a
#: clause most often lacks)
_COMPLETION_ORDER = ("RBRACE", "NAME", "NUMBER", "UNIT", "STRING")


def _complete_at_end(err: UnexpectedInput) -> Tree[Token] | None:
    """The tree the parser at ``err`` reaches when the text ends there, after inserting placeholder
    tokens (a missing ``}``, a name, a number ...) until the end is accepted; None if it cannot."""
    parser = getattr(err, "interactive_parser", None)
    if parser is None:
        return None
    # (the parser itself: it is given up after this; a copy would share its values, and a deep copy of a
    # token drops its end position)
    where = err.token if isinstance(err, UnexpectedToken) else None
    line, column = getattr(err, "line", 1) or 1, getattr(err, "column", 1) or 1
    try:
        for _ in range(64):
            accepted = parser.accepts()
            if "$END" in accepted:
                return cast("Tree[Token]", parser.feed_eof(where))  # (the tree of the start rule)
            pick = next((n for n in _COMPLETION_ORDER if n in accepted), None) or min(accepted, default=None)
            if pick is None:
                return None
            parser.feed_token(Token(pick, _placeholder(pick), line=line, column=column, end_line=line,
                                    end_column=column))
    except UnexpectedInput:
        return None
    return None


def _partial(tree: Tree[Token] | None, path: str, limits: Limits) -> s.Module | None:
    """The syntax tree of a recovered Lark tree (placeholders included), or None."""
    if tree is None:
        return None
    try:
        module: s.Module = TreeBuilder(path, DiagnosticSink(), limits).transform(tree)
        return module
    except Exception:  # best effort: a tree recovery made need not build (an impossible number, ...)
        return None
