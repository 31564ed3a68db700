"""Parse one source text into the typed tree of ``verify.syntax``.

Lark LALR with positions; the grammar is data in ``grammar/verify.lark``. Valid input goes through the
fast path (``verify.lalr``); input it rejects goes through Lark, whose error path (``verify.larkparse``)
recovers from syntax errors so that one run reports several of them, each in the language's own words.
The transformer only builds nodes.
"""
from __future__ import annotations

import functools
from fractions import Fraction

from lark import Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from . import syntax as s
from .construct import direct_constructor
from .diagnostics import DiagnosticSink
from .lalr import FastParser, Unparsable, position
from .larkparse import (MAX_NUMBER_LENGTH, MAX_SYNTAX_ERRORS, _accepted, _glued_keyword, _keyword_terminals,
                        _parser, _repair, _report_unexpected, _skip_unterminated_string, token_span)
from .source import Span


def parse_text(text: str, path: str, sink: DiagnosticSink) -> s.Module | None:
    """Parse ``text``; report syntax errors into ``sink``. Returns None when the text has any.

    The fast path (``verify.lalr``) decides valid input; anything it does not accept — every syntax
    error, a number error (E005), or a lexical corner it leaves to Lark — is parsed again by Lark with
    error recovery, which gives the reports. Both build the tree with the same ``_Builder``.

    A byte order mark at the start of the text is skipped (columns on line 1 count from after it)."""
    if text.startswith("\ufeff"):
        text = text[1:]
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
        if isinstance(err, UnexpectedToken):
            tok = err.token
            if tok.type == "NAME" and str(tok) in _keyword_terminals():
                # a state that does not accept it lexes a keyword as a NAME (``_WholeWords``): recovery
                # and messages treat it as the keyword it is, as Lark's root lexer would
                err.token = Token.new_borrow_pos(_keyword_terminals()[str(tok)], str(tok), tok)
            err.verify_glued = _glued_keyword(err, text)  # (before the repair changes the parser)
        if line != last_line[0] or at_end:
            err.verify_accepted = _accepted(err)
            errors.append(err)
            last_line[0] = line
        if isinstance(err, UnexpectedToken):
            if err.token.type == "$END":
                return False
            _repair(err, text)
        elif isinstance(err, UnexpectedCharacters):
            if text.startswith("/*", err.pos_in_stream):
                return False  # an unterminated comment: the rest of the file is its text
            if text.startswith('"', err.pos_in_stream):
                _skip_unterminated_string(err, text)
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
