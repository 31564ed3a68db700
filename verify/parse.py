"""Parse one source text into the typed tree of ``verify.syntax``.

Lark LALR with positions; the grammar is data in ``grammar/verify.lark``. Syntax errors are recovered
from (the offending token is dropped and parsing resumes) so that one run reports several of them, each
in the language's own words: never ``__ANON_0`` or ``$END``. The transformer only builds nodes.
"""
from __future__ import annotations

import functools
import re
from fractions import Fraction
from importlib import resources

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from . import syntax as s
from .construct import direct_constructor
from .diagnostics import DiagnosticSink
from .lalr import FastParser, Unparsable, position
from .source import Span

MAX_SYNTAX_ERRORS = 20
MAX_NUMBER_LENGTH = 40
MAX_EXPECTED_SHOWN = 6

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
    return resources.files("verify.grammar").joinpath("verify.lark").read_text(encoding="utf-8")


@functools.lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark(grammar_text(), parser="lalr", lexer="contextual", propagate_positions=True)


@functools.lru_cache(maxsize=1)
def _literal_words() -> dict[str, str]:
    words = {}
    for term in _parser().terminals:
        if term.pattern.type == "str":
            words[term.name] = f"'{term.pattern.value}'"
    return words


def describe_token_type(name: str) -> str:
    return _TOKEN_WORDS.get(name) or _literal_words().get(name) or name.lower()


def _describe_expected(names) -> str:
    words = sorted({describe_token_type(n) for n in names if not n.startswith("__IGNORE")})
    if not words:
        return "nothing more here"
    if len(words) > 12:
        words = words[:12] + ["…"]
    if len(words) == 1:
        return words[0]
    return "one of " + ", ".join(words)


def _describe_found(token: Token) -> str:
    if token.type == "$END":
        return "the end of the file"
    text = str(token)
    return f"'{text}'" if len(text) <= 40 else f"'{text[:37]}...'"


def token_span(path: str, tok: Token) -> Span:
    line = tok.line or 1
    col = tok.column or 1
    end_line = tok.end_line or line
    end_col = tok.end_column or col + 1
    return Span(path, line, col, end_line, end_col)


def _number_before(text: str, token: Token):
    """The number just before ``token`` (white space between), as (text, (line, col, end_line, end_col))."""
    pos = token.start_pos if token.type != "$END" and token.start_pos is not None else len(text)
    before = text[:pos].rstrip()
    match = re.search(r"(?<![\w.])[0-9]+(\.[0-9]+)?(/[0-9]+)?$", before)
    if match is None or "//" in before[before.rfind("\n", 0, match.start()) + 1:match.start()]:
        return None
    line = before.count("\n", 0, match.start()) + 1
    col = match.start() - (before.rfind("\n", 0, match.start()) + 1) + 1
    return match.group(0), (line, col, line, col + len(match.group(0)))


def _syntax_help(expected: set[str], token: Token) -> str | None:
    if "UNIT" in expected:
        return "write a unit after the number, e.g. `10 ms` or `40 Hz`"
    if "NAME" in expected and token.type != "NAME" and re.fullmatch(r"[A-Za-z_]\w*", str(token)):
        return f"`{token}` is a keyword of the language; choose another name"
    if "RBRACE" in expected and token.type == "$END":
        return "a `}` is missing: every `{` needs its `}`"
    if token.type == "RBRACE" and "COMPONENT" in expected:
        return "this `}` closes nothing: remove it, or add the `{` it belongs to"
    return None


def _report_unexpected(sink: DiagnosticSink, path: str, err: UnexpectedInput, text: str) -> None:
    if isinstance(err, UnexpectedToken):
        expected = set(err.expected or ())
        span = token_span(path, err.token)
        if err.token.type == "$END":
            span = _end_span(path, text)
        number = _number_before(text, err.token) if "UNIT" in expected else None
        if number is not None:  # a missing unit: point at the number that lacks it
            sink.emit("E001", f"expected a unit after the number `{number[0]}`, found {_describe_found(err.token)}",
                      Span(path, *number[1]), "this number needs a unit", help=_syntax_help(expected, err.token))
            return
        sink.emit(
            "E001",
            f"expected {_describe_expected(expected)}, found {_describe_found(err.token)}",
            span,
            "unexpected here",
            help=_syntax_help(expected, err.token),
        )
    elif isinstance(err, UnexpectedCharacters):
        ch = text[err.pos_in_stream] if err.pos_in_stream < len(text) else ""
        shown = repr(ch)[1:-1] if ch.isprintable() else f"U+{ord(ch):04X}" if ch else "end of file"
        span = Span(path, err.line, err.column, err.line, err.column + 1)
        allowed = {n for n in err.allowed or () if not n.startswith("__IGNORE")}
        msg = f"unexpected character '{shown}'"
        # the lexer's set is every token that may follow the previous one in *any* context: only a short
        # list says something about this place
        if allowed and len(allowed) <= MAX_EXPECTED_SHOWN:
            msg += f"; expected {_describe_expected(allowed)}"
        near = sorted(w for n in allowed if (w := _literal_words().get(n, "")[1:-1]) and ch and w.startswith(ch))
        help = (f"did you mean `{near[0]}`?" if near
                else "remove it; comments start with `//` or are enclosed in `/* */`")
        sink.emit("E002", msg, span, "not part of the language", help=help)
    else:  # pragma: no cover - lark raises only the two above from LALR
        sink.emit("E001", str(err).splitlines()[0], Span(path, 1, 1, 1, 2))


_INSERTION_ORDER = ("UNIT", "COLON", "NAME", "NUMBER", "RBRACE")


def _repair_by_insertion(err: UnexpectedToken) -> None:
    """Error recovery: insert the one expected token after which the offending token fits.

    Lark then resumes after the offending token; if no single insertion helps, that token is simply
    dropped. This keeps one slip (a missing unit, colon or brace) from cascading into many reports.
    """
    parser = err.interactive_parser
    expected = sorted(err.expected or (), key=lambda n: (n not in _INSERTION_ORDER,
                                                         _INSERTION_ORDER.index(n) if n in _INSERTION_ORDER else 0, n))
    for name in expected:
        filler = Token(name, _placeholder(name), line=err.token.line, column=err.token.column)
        trial = parser.copy(deepcopy_values=False)  # trial feeds only build new nodes
        try:
            trial.feed_token(filler)
            trial.feed_token(err.token)
        except UnexpectedInput:
            continue
        parser.feed_token(filler)
        parser.feed_token(err.token)
        return


def _placeholder(name: str) -> str:
    return {"UNIT": "ms", "NAME": "_", "NUMBER": "0", "STRING": '""'}.get(name) or _literal_words().get(
        name, "'_'")[1:-1]


def _end_span(path: str, text: str) -> Span:
    lines = text.split("\n")
    line = len(lines)
    col = len(lines[-1]) + 1
    return Span(path, line, col, line, col + 1)


def parse_text(text: str, path: str, sink: DiagnosticSink) -> s.Module | None:
    """Parse ``text``; report syntax errors into ``sink``. Returns None when the text has any.

    The fast path (``verify.lalr``) decides valid input; anything it does not accept — every syntax
    error, a number error (E005), or a lexical corner it leaves to Lark — is parsed again by Lark with
    error recovery, which gives the reports. Both build the tree with the same ``_Builder``."""
    fast = _fast_parser()
    if fast is not None:
        try:
            builder = _Builder(path, DiagnosticSink())
            return fast.parse(text, builder.callbacks(), builder.tokens())
        except (Unparsable, _NumberError):
            pass
    return _parse_with_lark(text, path, sink)


def _parse_with_lark(text: str, path: str, sink: DiagnosticSink) -> s.Module | None:
    errors: list[UnexpectedInput] = []
    last_line = [-1]

    def on_error(err: UnexpectedInput) -> bool:
        line = getattr(err, "line", -1)
        at_end = isinstance(err, UnexpectedToken) and err.token.type == "$END"
        # one report per line: a repair often trips the very next token too
        if line != last_line[0] or at_end:
            errors.append(err)
            last_line[0] = line
        if isinstance(err, UnexpectedToken):
            if err.token.type == "$END":
                return False
            _repair_by_insertion(err)
        return len(errors) < MAX_SYNTAX_ERRORS

    try:
        tree = _parser().parse(text, on_error=on_error)
    except UnexpectedInput as err:
        if not errors or getattr(err, "line", None) != last_line[0]:
            errors.append(err)
        tree = None
    for err in errors:
        _report_unexpected(sink, path, err, text)
    if errors or tree is None:
        return None
    try:
        return _Builder(path, sink).transform(tree)
    except _NumberError:
        return None


@functools.lru_cache(maxsize=1)
def _fast_parser() -> FastParser | None:
    return FastParser.build(_parser())


#: a 10,000-task file has about 400,000 spans and 150,000 names: they are built directly (``verify.construct``)
_new_span = direct_constructor(Span)
_new_name = direct_constructor(s.Name)


class _NumberError(Exception):
    pass


def parse_number(tok: Token, path: str, sink: DiagnosticSink) -> Fraction:
    """The exact value of a NUMBER token (E005 into ``sink`` and ``_NumberError`` if it has none)."""
    return _exact(str(tok), lambda: token_span(path, tok), sink)


def _exact(text: str, where, sink: DiagnosticSink) -> Fraction:
    """The value of NUMBER ``text``; ``where()`` gives its span for a report."""
    if text.isascii() and text.isdigit() and len(text) <= MAX_NUMBER_LENGTH:  # common; no regex (Fraction(str))
        return Fraction(int(text))
    if len(text) > MAX_NUMBER_LENGTH:
        sink.emit("E005", f"number has {len(text)} characters; at most {MAX_NUMBER_LENGTH} are allowed",
                  where(), "too long", help="use a larger unit, e.g. `2 s` instead of `2000000000 ns`")
        raise _NumberError
    if "/" not in text:  # a decimal: its digits over a power of ten (the value of Fraction(text), no regex)
        whole, _, digits = text.partition(".")
        return Fraction(int(whole + digits), 10 ** len(digits))
    num, den = text.split("/")
    if Fraction(den) == 0:
        sink.emit("E005", "division by zero in a rational number", where(), "denominator is 0",
                  help="write a non-zero denominator, e.g. `100/3 ms`")
        raise _NumberError
    return Fraction(num) / Fraction(den)


def _text(text: str, start: int, end: int) -> str:
    return text


def _token_builders(path: str, sink: DiagnosticSink):
    """The three functions the parser calls most, as closures over the file: ``span(start, end)``, the
    span between two positions (``lalr.position``; the file's first position if empty), and the values of
    a NAME and of a NUMBER token, ``name(text, start, end)`` and ``number(text, start, end)``."""
    new_span, new_name = _new_span, _new_name
    numbers: dict[str, Fraction] = {}  # a file repeats its numbers: each text is read once

    def span(start: int | None, end: int | None) -> Span:
        if start is None:
            return Span(path, 1, 1, 1, 1)
        return new_span(path, start >> 32, start & 0xFFFFFFFF, end >> 32, end & 0xFFFFFFFF)

    def name(text: str, start: int, end: int) -> s.Name:
        return new_name(text, new_span(path, start >> 32, start & 0xFFFFFFFF, end >> 32, end & 0xFFFFFFFF))

    def number(text: str, start: int, end: int) -> tuple[Fraction, int, int]:
        value = numbers.get(text)
        if value is None:
            value = numbers[text] = _exact(text, lambda: span(start, end), sink)
        return value, start, end

    return span, name, number


class _Builder:
    """Builds ``verify.syntax`` nodes; collects repeated clauses for validation to report.

    One method per rule (its alias or name), called with the rule's start and end positions
    (``lalr.position``; None for an empty rule) and its children as Lark's tree would hold them: nodes built by these
    methods and the tokens the rule keeps (``tokens``: a NAME is a ``syntax.Name``, a NUMBER the tuple (value,
    start, end) — its span is made only where a rule keeps one —, an RBRACE its ``Span``, a UNIT or STRING its
    text). ``verify.lalr`` calls them while parsing; ``transform`` applies them to a Lark tree (the
    error-recovering path)."""

    def __init__(self, path: str, sink: DiagnosticSink):
        self.path = path
        self.sink = sink
        self._span, self._name, self._number_token = _token_builders(path, sink)

    def callbacks(self) -> dict:
        return {name: getattr(self, name) for name in _fast_parser().callback_names()}

    def transform(self, tree: Tree):
        """The value of a Lark tree (built with positions), bottom-up as Lark's Transformer does."""
        tokens = self.tokens()
        children = [self.transform(c) if isinstance(c, Tree) else tokens.get(c.type, _text)(
                    c.value, position(c.line, c.column), position(c.end_line, c.end_column)) for c in tree.children]
        meta = tree.meta
        if meta.empty:
            return getattr(self, tree.data)(None, None, children)
        return getattr(self, tree.data)(position(meta.line, meta.column), position(meta.end_line, meta.end_column),
                                        children)

    # ---------------------------------------------------------------- helpers
    def tokens(self) -> dict:
        """The value of each kind of token the tree keeps (``lalr.FastParser.parse``)."""
        return {"NAME": self._name, "NUMBER": self._number_token, "RBRACE": self._span_of}

    def _span_of(self, text: str, start: int, end: int) -> Span:
        return self._span(start, end)

    def _number(self, tok: tuple[Fraction, int, int]) -> s.Number:
        value, start, end = tok
        return s.Number(value, self._span(start, end))

    # ---------------------------------------------------------------- file
    def start(self, start, end, items):
        imports = tuple(i for i in items if isinstance(i, s.Import))
        comps = tuple(i for i in items if isinstance(i, s.Component))
        systems = tuple(i for i in items if isinstance(i, s.System))
        return s.Module(self.path, imports, comps, systems, self._span(start, end))

    def import_decl(self, start, end, children):
        return s.Import(children[0][1:-1], self._span(start, end))

    # ---------------------------------------------------------------- quantities
    def quantity(self, start, end, children):
        num, unit = children
        return s.Quantity(num[0], unit, self._span(start, end))

    # ---------------------------------------------------------------- components
    def component(self, start, end, children):
        name, *members, rbrace = children
        return s.Component(
            name,
            tuple(m for m in members if isinstance(m, s.InPort)),
            tuple(m for m in members if isinstance(m, s.OutPort)),
            tuple(m for m in members if isinstance(m, s.CompoundPort)),
            tuple(m for m in members if isinstance(m, s.Task)),
            self._span(start, end),
            rbrace,
        )

    def in_port(self, start, end, children):
        return s.InPort(children[0], children[1], self._span(start, end))

    def out_port(self, start, end, children):
        return s.OutPort(children[0], children[1], self._span(start, end))

    def _compound(self, start, end, children, mode):
        name, *rest = children
        constraint = rest.pop()[1] if rest and isinstance(rest[-1], tuple) else None
        members = tuple(t for t in rest if isinstance(t, s.Name))
        return s.CompoundPort(name, mode, members, constraint, self._span(start, end))

    def compound_and(self, start, end, children):
        return self._compound(start, end, children, "and")

    def compound_or(self, start, end, children):
        return self._compound(start, end, children, "or")

    def preemptive(self, start, end, children):
        return "preemptive"

    def cooperative(self, start, end, children):
        return "cooperative"

    def task(self, start, end, children):
        name, *clauses, rbrace = children
        kind = "preemptive"
        if clauses and isinstance(clauses[0], str):
            kind = clauses.pop(0)
        fields: dict = {"reads": [], "produces": []}
        repeated: list[Span] = []
        for tag, value, where in clauses:
            if tag in ("reads", "produces"):
                fields[tag].extend(value)
            elif tag in fields:
                repeated.append(self._span(*where))
            else:
                fields[tag] = value
        return s.Task(
            name, kind, tuple(fields.pop("reads")), tuple(fields.pop("produces")),
            span=self._span(start, end), repeated=tuple(repeated), end=rbrace, **fields,
        )

    def reads(self, start, end, children):
        port, *options = children
        opts: dict = {}
        for key, value in options:
            opts[key] = value
        read = s.Read(port, span=self._span(start, end), **opts)
        return ("reads", [read], (start, end))

    def optional(self, start, end, children):
        return ("optional", True)

    def required(self, start, end, children):
        return ("optional", False)

    def oversampling(self, start, end, children):
        return ("oversampling", children[0])

    def undersampling(self, start, end, children):
        return ("undersampling", children[0])

    def tol_ok(self, start, end, children):
        return s.Tolerance("ok", None, self._span(start, end))

    def tol_forbidden(self, start, end, children):
        return s.Tolerance("forbidden", None, self._span(start, end))

    def tol_max(self, start, end, children):
        return s.Tolerance("max", self._number(children[0]), self._span(start, end))

    def produces(self, start, end, children):
        return ("produces", list(children), (start, end))

    def bcet(self, start, end, children):
        return ("bcet", children[0], (start, end))

    def wcet(self, start, end, children):
        return ("wcet", children[0], (start, end))

    def act_constraint(self, start, end, children):
        (low, high), *rest = children
        changeable = rest[0] if rest else True
        return ("constraint", s.ActivationConstraint(low, high, changeable, self._span(start, end)), (start, end))

    def bounds_range(self, start, end, children):
        return (children[0], children[1])

    def bounds_exact(self, start, end, children):
        return (children[0], children[0])

    def bounds_min(self, start, end, children):
        return (children[0], None)

    def bounds_max(self, start, end, children):
        return (None, children[0])

    def fixed(self, start, end, children):
        return False

    def changeable(self, start, end, children):
        return True

    # ---------------------------------------------------------------- systems
    def system(self, start, end, children):
        name, *members, rbrace = children
        return s.System(
            name,
            tuple(m for m in members if isinstance(m, s.Core)),
            tuple(m for m in members if isinstance(m, s.Instance)),
            tuple(m for m in members if isinstance(m, s.Connection)),
            tuple(m for m in members if isinstance(m, s.Chain)),
            self._span(start, end),
            rbrace,
        )

    def core(self, start, end, children):
        policy = children[1] if len(children) > 1 else None
        return s.Core(children[0], policy, self._span(start, end))

    def instance(self, start, end, children):
        name, comp, *rest = children
        core = None
        bindings: tuple = ()
        body_end = None
        for r in rest:
            if isinstance(r, s.Name):
                core = r
            else:
                bindings, body_end = r
        return s.Instance(name, comp, core, bindings, self._span(start, end), body_end)

    def instance_body(self, start, end, children):
        *bindings, rbrace = children
        return tuple(bindings), rbrace

    def binding(self, start, end, children):
        name, *clauses = children
        fields: dict = {"activations": []}
        repeated: list[Span] = []
        for tag, value, where in clauses:
            if tag == "activations":
                fields[tag].append(value)
            elif tag in fields:
                repeated.append(self._span(*where))
            else:
                fields[tag] = value
        fields["activations"] = tuple(fields["activations"])
        return s.TaskBinding(name, span=self._span(start, end), repeated=tuple(repeated), **fields)

    def priority(self, start, end, children):
        return ("priority", self._number(children[0]), (start, end))

    def task_core(self, start, end, children):
        return ("core", children[0], (start, end))

    def wcrt(self, start, end, children):
        return ("wcrt", children[0], (start, end))

    def deadline(self, start, end, children):
        return ("deadline", children[0], (start, end))

    def timer(self, start, end, children):
        phase = children[1] if len(children) > 1 else None
        return ("activations", s.Timer(children[0], phase, self._span(start, end)), (start, end))

    def period_hole(self, start, end, children):
        low, high, step = (list(children) + [None, None, None])[:3]
        return s.PeriodHole(low, high, step, self._span(start, end))

    def trigger(self, start, end, children):
        port = children[0]
        prescaler = children[1] if len(children) > 1 else s.Number(Fraction(1))
        return ("activations", s.Trigger(port, prescaler, self._span(start, end)), (start, end))

    def prescaler_number(self, start, end, children):
        return self._number(children[0])

    def prescaler_hole(self, start, end, children):
        if children:
            return s.PrescalerHole(self._number(children[0]), self._number(children[1]), self._span(start, end))
        return s.PrescalerHole(span=self._span(start, end))

    def sporadic(self, start, end, children):
        return ("activations", s.Sporadic(children[0], children[1], self._span(start, end)), (start, end))

    def unknown_activation(self, start, end, children):
        return ("activations", s.UnknownActivation(self._span(start, end)), (start, end))

    def connection(self, start, end, children):
        src, dst, *delay = children
        low, high = delay[0] if delay else (None, None)
        return s.Connection(src, dst, low, high, self._span(start, end))

    def delay_exact(self, start, end, children):
        return (children[0], children[0])

    def delay_range(self, start, end, children):
        return (children[0], children[1])

    def chain(self, start, end, children):
        name, *rest = children
        refs = tuple(r for r in rest if isinstance(r, s.PortRef))
        specs, body_end = (), None
        if rest and isinstance(rest[-1], tuple):
            specs, body_end = rest[-1]
        return s.Chain(name, refs, specs, self._span(start, end), body_end)

    def chain_body(self, start, end, children):
        *specs, rbrace = children
        return tuple(specs), rbrace

    def spec_reaction_time(self, start, end, children):
        return s.Spec("reaction_time", children[0], self._span(start, end))

    def spec_data_age(self, start, end, children):
        return s.Spec("data_age", children[0], self._span(start, end))

    def spec_jitter(self, start, end, children):
        return s.Spec("jitter", children[0], self._span(start, end))

    def port_ref(self, start, end, children):
        return s.PortRef(children[0], children[1], self._span(start, end))
