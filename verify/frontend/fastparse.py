"""The parser's fast path: Lark's own LALR(1) table, driven by a one-regex lexer, building values
while parsing.

Lark's contextual lexer, its parser loop and the tree-then-transform pipeline cost about 14 µs per
token (10,000 tasks, 400,000 tokens: 5.5 s without garbage collection). This module reads the parse
table and the rules of the Lark parser built from ``grammar/verify.lark`` — the grammar stays the one
definition of the language — and runs the same automaton with less machinery:

- **Lexing**: one compiled regex skips ignored text (white space, comments) and matches one lexeme: a
  word, a number, a punctuation literal or a string. A word's terminal depends on the parser state,
  exactly as in Lark's contextual lexer (where each state lexes with the terminals it accepts, and a
  keyword is a keyword only if the state accepts it): the keyword if the state accepts that keyword,
  else NAME if it accepts NAME, else UNIT for a unit word if it accepts UNIT.
- **Parsing**: the shift/reduce loop of ``lark.parsers.lalr_parser_state.ParserState.feed_token`` on
  the same table, with Lark's child filtering (anonymous tokens dropped, ``_rule`` children spliced,
  ``?rule`` with one child replaced by it) and Lark's position rule (a node spans from the start of its
  first child to the end of its last one, anonymous tokens included). A position is one integer,
  ``position(line, column)`` (1-based, as Lark counts them), so that the stacks hold no tuples.
- **Building**: a token the tree keeps becomes ``tokens[terminal](text, start, end)`` (or its text),
  and each reduction calls ``callbacks[rule alias or name](start, end, children)`` at once; there is no
  intermediate tree.

**Exact or nothing.** The fast path never reports an error: whenever its lexer or the table rejects the
input, it raises :class:`Unparsable` and the caller runs Lark itself (contextual lexer, error recovery,
the messages). On input it accepts, its tokens are the ones the contextual lexer produces: by induction
over the tokens, both lexers start each token at the same offset in the same parser state; a word, a
number or a string is matched by the same greedy pattern, and the terminal chosen for a word is the one
the state's lexer chooses (Lark embeds keywords matched by NAME into NAME's match, and sorts string
literals longest first). Where the two could differ — a keyword the state accepts as a prefix of a
longer word when it does not accept NAME (``componentX``), or ``.`` where the state accepts ``.`` but
not ``..`` — this lexer takes the longer lexeme, which the state rejects, so the input goes to Lark.
The grammar's lexical level is checked against the patterns this lexer was written for
(``LEXICAL_SHAPE``); any difference disables the fast path (``FastParser.build`` returns None).
"""
from __future__ import annotations

import re
from operator import itemgetter
from typing import TYPE_CHECKING, Any
from collections.abc import Callable, Mapping, Sequence

if TYPE_CHECKING:
    from lark import Lark

#: the terminal patterns (as Lark compiles them) this lexer reproduces
LEXICAL_SHAPE = {  # (Lark writes white space into its patterns as the characters themselves)
    "WS": "(?:[ \t\x0c\r\n])+",
    "LINE_COMMENT": "\\/\\/[^\n]*",
    "BLOCK_COMMENT": "\\/\\*[\\s\\S]*?\\*\\/",
    "NAME": r"[A-Za-z_][A-Za-z0-9_]*",
    "NUMBER": r"[0-9]+(\.[0-9]+)?(\/[0-9]+)?",
    "STRING": '"[^"\n]*"',
    "UNIT": r"(kHz|Hz|ms|us|ns|s)(?![A-Za-z0-9_])",
}
UNIT_WORDS = frozenset({"kHz", "Hz", "ms", "us", "ns", "s"})
#: white space and comments; a word (also used by error recovery, ``verify.frontend.recovery``)
SKIP_RE = re.compile(r"(?:\s+|//[^\n]*|/\*[\s\S]*?\*/)*")
WORD_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_WORD, _NUMBER, _PUNCT, _STRING = 1, 2, 3, 4


def position(line: int, column: int) -> int:
    """A line and a column in one integer: ``pos >> 32`` is the line, ``pos & 0xFFFFFFFF`` the column."""
    return line << 32 | column


#: the words a model file can start with (``start: item*``, each item opened by one of them)
_FIRST_WORDS = frozenset({"import", "component", "system", "message"})


def looks_like_model(text: str) -> bool:
    """The first word of ``text`` (after white space and comments) can start a model, or it has none."""
    if text.startswith("\ufeff"):
        text = text[1:]
    skipped = SKIP_RE.match(text)
    pos = skipped.end() if skipped is not None else 0  # (it matches the empty string)
    if pos >= len(text):
        return True
    word = WORD_RE.match(text, pos)
    return word is not None and word.group(0) in _FIRST_WORDS


def _no_callback(start: int | None, end: int | None, children: Any) -> Any:
    """The callback slot of a rule whose value no callback builds (never called)."""
    raise AssertionError("a rule without a callback was built")


class Unparsable(Exception):
    """The fast path does not decide this input: run Lark."""


class TooManyTokens(Exception):
    """The text has more tokens than a parse may lex; ``at`` is the position of the first one too many."""

    def __init__(self, at: int):
        super().__init__(at)
        self.at = at


# rule modes: how a reduction makes its value
_NODE = 0  # a callback's value
_INLINE = 1  # a _rule: the list of its children, spliced into its parent's
_EXPAND1 = 2  # a ?rule: its only child, else a callback's value
_PASS = 3  # a ?rule of one symbol: the child's value and position stay as they are (a shortcut)
_APPEND = 4  # _rule -> _rule x: x appended to the list (left recursion of x* and x+; a shortcut)

#: the children a rule keeps, from the values of its symbols (a list, or a tuple from ``itemgetter``)
_Picker = Callable[[list[Any]], Sequence[Any]]
#: a rule: (mode, origin, size, picker, may have empty children)
_Rule = tuple[int, str, int, _Picker, bool]
#: what a rule is made of: (mode, origin, size, kept children as (index, spliced), may have empty children)
_Shape = tuple[int, str, int, tuple[tuple[int, bool], ...], bool]


def _picker(include: tuple[tuple[int, bool], ...], size: int, as_list: bool) -> _Picker:
    """The children a rule keeps, as Lark's child filter gives them (``ChildFilterLALR_NoPlaceholders``:
    filtered tokens dropped, a ``_rule``'s children spliced, its list reused when it comes first)."""
    if not any(expand for _, expand in include):
        indices = tuple(i for i, _ in include)
        if indices == tuple(range(size)):
            return lambda kids: kids  # the stack slice is a new list already
        if not indices:
            return lambda kids: []
        if len(indices) == 1:
            only = indices[0]
            return lambda kids: [kids[only]]
        get = itemgetter(*indices)
        return (lambda kids: list(get(kids))) if as_list else get

    def pick(kids: list[Any]) -> list[Any]:
        children: list[Any] | None = None
        for i, expand in include:
            if expand:
                if children:
                    children += kids[i]
                else:
                    children = kids[i]
            elif children is None:
                children = [kids[i]]
            else:
                children.append(kids[i])
        return [] if children is None else children

    return pick


def _lexeme(punct: Mapping[str, str]) -> re.Pattern[str]:
    """The one regex of the lexer: ignored text, then a word, a number, a punctuation literal, a string
    or the end."""
    # a punctuation literal is matched longest first, as Lark's lexer sorts string literals
    literals = "|".join(re.escape(p) for p in sorted(punct, key=lambda p: (-len(p), p)))
    return re.compile(
        # ignored text (WS, LINE_COMMENT, BLOCK_COMMENT): white space, then comments each followed by
        # white space; possessive and atomic, so that a failing lexeme after it does not make the
        # regex engine retry with a shorter line comment or a longer block comment
        r"[ \t\f\r\n]*+(?>(?:(?://[^\n]*|/\*[\s\S]*?\*/)[ \t\f\r\n]*+)*)"
        r"(?:([A-Za-z_][A-Za-z0-9_]*+)"  # 1: a word (NAME, keyword or UNIT)
        r"|([0-9]++(?:\.[0-9]+)?+(?:/[0-9]+)?+)"  # 2: NUMBER
        rf"|({literals})"  # 3: punctuation
        r'|("[^"\n]*")'  # 4: STRING
        r"|\Z)"  # nothing more: the end
    )


def _consistent(rows: list[dict[str, int]], shapes: list[_Shape], names: list[str | None]) -> bool:
    """Every state and rule a table names exists, every rule's kept children lie among its children, and
    every rule whose value a callback builds names one (a table read from a file may be corrupt)."""
    states, rules = len(rows), len(shapes)
    if not all(0 <= code < states if code >= 0 else ~code < rules for row in rows for code in row.values()):
        return False
    for (mode, _origin, size, include, _empty), name in zip(shapes, names, strict=True):
        if mode not in (_NODE, _INLINE, _EXPAND1, _PASS, _APPEND) or size < 0:
            return False
        if not all(0 <= i < size for i, _ in include) or (mode in (_NODE, _EXPAND1) and name is None):
            return False
    return True


class FastParser:
    """Lark's LALR table for one grammar with the lexer above; ``parse`` is reentrant."""

    def __init__(self, rows: list[dict[str, int]], start: int, end: int, shapes: list[_Shape],
                 names: list[str | None], keywords: dict[str, str], punct: dict[str, str]) -> None:
        self.rows = rows  # per state: {terminal or rule name: state (shift, goto) or ~rule (reduce)}
        self.start = start
        self.end = end
        self.shapes = shapes  # per rule: (mode, origin, size, kept children, may have empty children)
        self.rules: list[_Rule] = [(mode, origin, size, _picker(include, size, origin.startswith("_")), empty)
                                   for mode, origin, size, include, empty in shapes]
        self.names = names  # per rule: its callback's name (its alias or its name)
        self.keywords = keywords  # word -> terminal
        self.punct = punct  # literal -> terminal
        self.lexeme = _lexeme(punct)

    def to_data(self) -> dict[str, Any]:
        """Everything the parser is made of, as JSON data (``from_data`` makes it again, without Lark)."""
        return {"rows": self.rows, "start": self.start, "end": self.end, "names": self.names,
                "keywords": self.keywords, "punct": self.punct,
                "shapes": [[mode, origin, size, [list(k) for k in include], empty]
                           for mode, origin, size, include, empty in self.shapes]}

    @classmethod
    def from_data(cls, data: Mapping[str, Any]) -> FastParser:
        """The parser ``to_data`` describes; ValueError when ``data`` is not such a description."""
        try:
            shapes: list[_Shape] = [(int(mode), str(origin), int(size), tuple((int(i), bool(e)) for i, e in include),
                                     bool(empty)) for mode, origin, size, include, empty in data["shapes"]]
            rows = [{str(k): int(v) for k, v in row.items()} for row in data["rows"]]
            names = [None if n is None else str(n) for n in data["names"]]
            parser = cls(rows, int(data["start"]), int(data["end"]), shapes, names,
                         {str(k): str(v) for k, v in data["keywords"].items()},
                         {str(k): str(v) for k, v in data["punct"].items()})
        except (KeyError, TypeError, ValueError, AttributeError, re.error) as err:
            raise ValueError(f"not a parser description: {err}") from None
        if len(names) != len(shapes) or not all(0 <= s < len(rows) for s in (parser.start, parser.end)):
            raise ValueError("not a parser description: inconsistent sizes")
        if not _consistent(rows, shapes, names):
            raise ValueError("not a parser description: a state, rule or child out of range")
        return parser

    @classmethod
    def build(cls, lark: Lark) -> FastParser | None:
        """The fast path for a Lark LALR parser, or None if its grammar is not the shape it handles."""
        from lark.grammar import Terminal

        try:
            table = lark.parser.parser.parser.parse_table
        except AttributeError:  # pragma: no cover - another Lark version
            return None
        patterns = {t.name: t.pattern for t in lark.terminals}
        if set(lark.lexer_conf.ignore) != {"WS", "LINE_COMMENT", "BLOCK_COMMENT"}:
            return None
        name_re = re.compile(LEXICAL_SHAPE["NAME"])
        keywords, punct = {}, {}
        for name, pattern in patterns.items():
            if pattern.type == "str":
                if pattern.flags:
                    return None
                if name_re.fullmatch(pattern.value):
                    keywords[pattern.value] = str(name)
                elif re.fullmatch(r"[^\w\s\"/]+", pattern.value):
                    punct[pattern.value] = str(name)
                else:
                    return None
            elif LEXICAL_SHAPE.get(name) != pattern.to_regexp() or pattern.flags:
                return None
        if set(patterns) - set(keywords.values()) - set(punct.values()) != set(LEXICAL_SHAPE):
            return None
        nullable: set[str] = set()  # the rules that can derive nothing
        while True:
            more = {str(r.origin.name) for r in lark.rules
                    if all(not sym.is_term and str(sym.name) in nullable for sym in r.expansion)}
            if more <= nullable:
                break
            nullable |= more
        rule_index: dict[Any, int] = {}
        shapes: list[_Shape] = []
        names: list[str | None] = []
        for rule in lark.rules:
            options = rule.options
            if options.keep_all_tokens or any(options.empty_indices or ()):
                return None
            kept: list[tuple[int, bool]] = []
            for i, sym in enumerate(rule.expansion):
                if not (isinstance(sym, Terminal) and sym.filter_out):
                    kept.append((i, not sym.is_term and sym.name.startswith("_")))
            include = tuple(kept)
            size = len(rule.expansion)
            may_be_empty = any(not sym.is_term and str(sym.name) in nullable for sym in rule.expansion)
            inline = rule.origin.name.startswith("_")
            expand1 = bool(options.expand1) and not rule.alias
            if inline and expand1:
                return None
            mode = _INLINE if inline else _EXPAND1 if expand1 else _NODE
            if mode == _EXPAND1 and size == 1 and include == ((0, False),):
                mode = _PASS
            elif mode == _INLINE and size == 2 and include == ((0, True), (1, False)) and not may_be_empty:
                mode = _APPEND
            rule_index[rule] = len(shapes)
            shapes.append((mode, str(rule.origin.name), size, include, may_be_empty))
            names.append(None if mode in (_INLINE, _PASS, _APPEND) else str(rule.alias or options.template_source
                                                                              or rule.origin.name))
        if sorted(table.states) != list(range(len(table.states))):
            return None
        rows = []
        for state in range(len(table.states)):
            row = {}
            for symbol, (action, arg) in table.states[state].items():
                # plain str keys: Lark names rules with Tokens, whose __eq__ is a Python method
                row[str(symbol)] = arg if action.name == "Shift" else ~rule_index[arg]
            rows.append(row)
        return cls(rows, table.start_states["start"], table.end_states["start"], shapes, names, keywords, punct)

    def callback_names(self) -> set[str]:
        """The rules whose values ``parse`` builds with a callback."""
        return {name for name in self.names if name is not None}

    def parse(self, text: str, callbacks: Mapping[str, Callable[[int | None, int | None, Any], Any]],
              tokens: Mapping[str, Callable[[str, int, int], Any]], max_tokens: int | None = None) -> Any:
        """The value of the start rule, or :class:`Unparsable`. ``callbacks[name](start, end, children)``
        builds the value of a rule from its positions and its children (a list or a tuple);
        ``tokens[terminal](text, start, end)`` the value of a token (default: its text). More than
        ``max_tokens`` tokens raise :class:`TooManyTokens` (counted only when the text is longer than that,
        since every token has a character)."""
        rows, rules, keywords, punct = self.rows, self.rules, self.keywords, self.punct
        token_value = tokens.get
        build = [_no_callback if name is None else callbacks[name] for name in self.names]
        match = self.lexeme.match
        end_state = self.end
        stack = [self.start]  # parser states
        values: list[Any] = []
        starts: list[int | None] = []  # positions
        ends: list[int | None] = []
        push_state, push_value, push_start, push_end = stack.append, values.append, starts.append, ends.append
        row = rows[self.start]
        pos = 0
        # a position is offset + base with base = position(line, 1) - line start, updated at each new line
        line, base = 1, 1 << 32 | 1
        size_text = len(text)
        left = max_tokens if max_tokens is not None and size_text > max_tokens else -1  # (-1: not counted)
        next_newline = text.find("\n")
        if next_newline < 0:
            next_newline = size_text
        term: str | None
        while True:
            m = match(text, pos)
            if m is None:
                raise Unparsable
            kind = m.lastindex
            previous, pos = pos, m.end()
            if kind is None:  # only ignored text was left
                term, value, start, end = "$END", None, None, None
            else:
                lex = m.group(kind)
                offset = pos - len(lex)
                if offset > next_newline:  # the ignored text before the lexeme ended a line or more
                    line += text.count("\n", previous, offset)
                    base = (line << 32 | 1) - (text.rfind("\n", previous, offset) + 1)  # position(line, 1) - ...
                    next_newline = text.find("\n", offset)
                    if next_newline < 0:
                        next_newline = size_text
                start, end = offset + base, pos + base  # (no lexeme spans lines)
                if left >= 0:
                    left -= 1
                    if left < 0:
                        raise TooManyTokens(start)
                if kind == _WORD:
                    term = keywords.get(lex)
                    if term is None or term not in row:
                        if "NAME" in row:
                            term = "NAME"
                        elif lex in UNIT_WORDS and "UNIT" in row:
                            term = "UNIT"
                        else:
                            raise Unparsable
                elif kind == _NUMBER:
                    term = "NUMBER"
                elif kind == _PUNCT:
                    term = punct[lex]
                else:
                    term = "STRING"
                convert = token_value(term)
                value = lex if convert is None else convert(lex, start, end)
            while True:  # reduce as long as the table says so, then shift
                try:
                    code = row[term]
                except KeyError:
                    raise Unparsable from None
                if code >= 0:
                    break
                mode, origin, size, pick, may_be_empty = rules[~code]
                if mode == _PASS:  # one symbol for one: only the state changes
                    goto = stack[-1] = rows[stack[-2]][origin]
                    row = rows[goto]
                    continue
                if mode == _APPEND:
                    del stack[-1]
                    goto = stack[-1] = rows[stack[-2]][origin]
                    item = values.pop()
                    values[-1].append(item)
                    del starts[-1]
                    last = ends.pop()
                    ends[-1] = last
                    row = rows[goto]
                    continue
                if size:
                    kids = values[-size:]
                    del values[-size:]
                    del stack[-size:]
                    first, last = starts[-size], ends[-1]
                    if may_be_empty and (first is None or last is None):  # an empty child spans nothing
                        first = next((x for x in starts[-size:] if x is not None), None)
                        last = next((x for x in reversed(ends[-size:]) if x is not None), None)
                    del starts[-size:]
                    del ends[-size:]
                    children = pick(kids)
                else:
                    children, first, last = [], None, None
                if mode == _NODE or (mode == _EXPAND1 and len(children) != 1):
                    # (a _NODE or _EXPAND1 rule has a name, so a callback)
                    node = build[~code](first, last, children)
                elif mode == _INLINE:
                    node = children
                else:
                    node = children[0]
                goto = rows[stack[-1]][origin]
                if goto == end_state:  # the start rule is reduced, on the end only
                    return node
                push_state(goto)
                push_value(node)
                push_start(first)
                push_end(last)
                row = rows[goto]
            if start is None:  # pragma: no cover - Lark's table never shifts the end
                raise Unparsable
            push_state(code)
            push_value(value)
            push_start(start)
            push_end(end)
            row = rows[code]
