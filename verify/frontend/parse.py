"""Parse one source text into the typed tree of ``verify.model.syntax``.

The grammar is data in ``grammar/verify.lark``. Valid input goes through the fast path
(``verify.frontend.fastparse``, its table kept between runs by ``verify.frontend.parsecache``: Lark is not
even imported); input it rejects goes through error recovery (``verify.frontend.recovery``), Lark's
parser with recovery from syntax errors, so that one run reports several of them, each in the language's
own words. Both build the tree with the same ``verify.frontend.treebuild.TreeBuilder``.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..core.limits import DEFAULT_LIMITS, Limits
from ..core.source import Span
from ..model import syntax as s
from .fastparse import FastParser, TooManyTokens, Unparsable, looks_like_model
from .treebuild import NumberError, TreeBuilder, too_many_tokens


@dataclass(frozen=True)
class Parsed:
    """What parsing one text gave: the tree (None after a syntax error), the diagnostics, and — for a
    text that is not the language from its first token — the span of that token, the only part of the
    text a report may show (``SourceFile.only``)."""

    module: s.Module | None
    diagnostics: tuple[Diagnostic, ...] = ()
    opaque: Span | None = None
    #: after a syntax error, what error recovery made of the text (missing symbols filled in with
    #: placeholders: a name ``_``, a number 0), for an editor's outline and completion; None when the
    #: text has no error, is not a model, or recovery made nothing of it
    partial: s.Module | None = None


def parse_text(text: str, path: str, sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> s.Module | None:
    """Parse ``text``; report syntax errors into ``sink``. Returns None when the text has any."""
    parsed = parse_source(text, path, limits)
    sink.items.extend(parsed.diagnostics)
    return parsed.module


def parse_source(text: str, path: str, limits: Limits = DEFAULT_LIMITS) -> Parsed:
    """Parse ``text`` (the contents of file ``path``).

    The fast path (``verify.frontend.fastparse``) decides valid input; anything it does not accept — every syntax
    error, a number error (E005), or a lexical corner it leaves to Lark — is parsed again by Lark with
    error recovery (``recovery.recover``), which gives the reports. Both build the tree with the same
    ``TreeBuilder``. A text of
    more than ``limits.tokens`` tokens is refused at the first one too many (E008).

    A byte order mark at the start of the text is skipped (columns on line 1 count from after it)."""
    if text.startswith("\ufeff"):
        text = text[1:]
    fast = fast_parser()
    if fast is not None:
        try:
            builder = TreeBuilder(path, DiagnosticSink(), limits)
            return Parsed(fast.parse(text, builder.callbacks(fast.callback_names()), builder.tokens(), limits.tokens))
        except TooManyTokens as err:
            return Parsed(None, (too_many_tokens(path, err.at, limits),))
        except (Unparsable, NumberError):
            pass
    from .recovery import recover  # (Lark: only a text the fast path rejects needs it)

    sink = DiagnosticSink()
    module, partial = recover(text, path, sink, limits)
    if module is None and sink.items and not looks_like_model(text):
        first = sink.items[0]  # (at the first token: no model starts otherwise)
        return Parsed(None, (first,), first.span)
    return Parsed(module, tuple(sink.items), None, partial)


@functools.lru_cache(maxsize=1)
def fast_parser() -> FastParser | None:
    """The fast path's parser, from its table kept between runs when there is one (``parsecache``); None
    when the grammar is not of the shape the fast path handles."""
    from .parsecache import load_fast_parser

    return load_fast_parser(_fast_parser_from_lark)


def _fast_parser_from_lark() -> FastParser | None:
    """The fast path's parser built from Lark's parser of the grammar (when no kept table serves)."""
    from .grammar import lark_parser

    return FastParser.build(lark_parser())
