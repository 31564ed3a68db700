"""Building the syntax tree (``verify.model.syntax``) from the parser's reductions: ``TreeBuilder`` has
one callback per grammar rule, which the fast path (``verify.frontend.fastparse``) calls while parsing
and ``TreeBuilder.transform`` applies to a Lark tree (error recovery's). The values of tokens are read
here, with their report when a number has none (E005, ``NumberError``); ``too_many_tokens`` is the
report of a text over the token limit (E008).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

from ..core.construct import direct_constructor
from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..core.limits import DEFAULT_LIMITS, Limits
from ..core.source import Span
from ..model import syntax as s
from .fastparse import position

if TYPE_CHECKING:  # (Lark is imported where a text takes the error path: valid text never needs it)
    from lark import Token, Tree
    from lark.tree import Meta


def too_many_tokens(path: str, at: int, limits: Limits) -> Diagnostic:
    """E008 at position ``at`` (``fastparse.position``): the first token over ``limits.tokens``."""
    line, column = at >> 32, at & 0xFFFFFFFF
    return DiagnosticSink().emit(
        "E008", f"the file has more than {limits.tokens:,} tokens, the limit for one file",
        Span(path, line, column, line, column + 1), "one token too many",
        help="split the model into several files joined by `import`")


#: a 10,000-task file has about 400,000 spans and 150,000 names: they are built directly (``verify.core.construct``)
_new_span = direct_constructor(Span)
_new_name = direct_constructor(s.Name)


class NumberError(Exception):
    """A NUMBER token without a value (reported: E005)."""


#: a position (``fastparse.position``), None for an empty rule; a clause's positions; a rule's children
_Pos = int | None
_Where = tuple[_Pos, _Pos]
_Children = Sequence[Any]


def _exact(text: str, where: Callable[[], Span], sink: DiagnosticSink, max_length: int) -> Fraction:
    """The value of NUMBER ``text``; ``where()`` gives its span for a report."""
    if text.isascii() and text.isdigit() and len(text) <= max_length:  # common; no regex (Fraction(str))
        return Fraction(int(text))
    if len(text) > max_length:
        sink.emit("E005", f"number has {len(text)} characters; at most {max_length} are allowed",
                  where(), "too long", help="use a larger unit, e.g. `2 s` instead of `2000000000 ns`")
        raise NumberError
    if "/" not in text:  # a decimal: its digits over a power of ten (the value of Fraction(text), no regex)
        whole, _, digits = text.partition(".")
        return Fraction(int(whole + digits), 10 ** len(digits))
    num, den = text.split("/")
    if Fraction(den) == 0:
        sink.emit("E005", "division by zero in a rational number", where(), "denominator is 0",
                  help="write a non-zero denominator, e.g. `100/3 ms`")
        raise NumberError
    return Fraction(num) / Fraction(den)


def _text(text: str, start: int, end: int) -> str:
    return text


def _token_builders(path: str, sink: DiagnosticSink, limits: Limits) -> tuple[
        Callable[[_Pos, _Pos], Span], Callable[[str, int, int], s.Name],
        Callable[[str, int, int], tuple[Fraction, int, int]]]:
    """The three functions the parser calls most, as closures over the file: ``span(start, end)``, the
    span between two positions (``fastparse.position``; the file's first position if empty), and the values of
    a NAME and of a NUMBER token, ``name(text, start, end)`` and ``number(text, start, end)``."""
    new_span, new_name = _new_span, _new_name
    max_length = limits.number_length
    numbers: dict[str, Fraction] = {}  # a file repeats its numbers: each text is read once

    def span(start: int | None, end: int | None) -> Span:
        if start is None or end is None:  # (an empty rule has neither position, any other both)
            return Span(path, 1, 1, 1, 1)
        return new_span(path, start >> 32, start & 0xFFFFFFFF, end >> 32, end & 0xFFFFFFFF)

    def name(text: str, start: int, end: int) -> s.Name:
        return new_name(text, new_span(path, start >> 32, start & 0xFFFFFFFF, end >> 32, end & 0xFFFFFFFF))

    def number(text: str, start: int, end: int) -> tuple[Fraction, int, int]:
        value = numbers.get(text)
        if value is None:
            value = numbers[text] = _exact(text, lambda: span(start, end), sink, max_length)
        return value, start, end

    return span, name, number


def _positions(where: Token | Meta) -> tuple[int, int]:
    """The start and end positions of a token or a tree's meta (a token error recovery inserted lacks
    its end, and so may the tree around it)."""
    line, column = where.line or 1, where.column or 1
    return position(line, column), position(where.end_line or line, where.end_column or column)


class TreeBuilder:
    """Builds ``verify.model.syntax`` nodes; collects repeated clauses for validation to report.

    One method per rule (its alias or name), called with the rule's start and end positions
    (``fastparse.position``; None for an empty rule) and its children as Lark's tree would hold them: nodes
    built by these methods and the tokens the rule keeps (``tokens``: a NAME is a ``syntax.Name``, a NUMBER
    the tuple (value, start, end) — its span is made only where a rule keeps one —, an RBRACE its ``Span``,
    a STRING (its text, its ``Span``), a UNIT its text). ``verify.frontend.fastparse`` calls them while
    parsing; ``transform`` applies them to a Lark tree (error recovery's)."""

    def __init__(self, path: str, sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> None:
        self.path = path
        self.sink = sink
        self._span, self._name, self._number_token = _token_builders(path, sink, limits)

    def callbacks(self, names: Iterable[str]) -> dict[str, Callable[[_Pos, _Pos, _Children], Any]]:
        """The callbacks of the rules ``names`` (``FastParser.callback_names``)."""
        return {name: getattr(self, name) for name in names}

    def transform(self, tree: Tree[Token]) -> Any:
        """The value of a Lark tree (built with positions), bottom-up as Lark's Transformer does."""
        from lark import Tree

        tokens = self.tokens()
        children = [self.transform(c) if isinstance(c, Tree) else tokens.get(c.type, _text)(c.value, *_positions(c))
                    for c in tree.children]
        meta = tree.meta
        if meta.empty:
            return getattr(self, tree.data)(None, None, children)
        return getattr(self, tree.data)(*_positions(meta), children)

    # ---------------------------------------------------------------- helpers
    def tokens(self) -> dict[str, Callable[[str, int, int], Any]]:
        """The value of each kind of token the tree keeps (``fastparse.FastParser.parse``)."""
        return {"NAME": self._name, "NUMBER": self._number_token, "RBRACE": self._span_of, "STRING": self._string}

    def _string(self, text: str, start: int, end: int) -> tuple[str, Span]:
        return text, self._span(start, end)

    def _span_of(self, text: str, start: int, end: int) -> Span:
        return self._span(start, end)

    def _number(self, tok: tuple[Fraction, int, int]) -> s.Number:
        value, start, end = tok
        return s.Number(value, self._span(start, end))

    # ---------------------------------------------------------------- file
    def start(self, start: _Pos, end: _Pos, items: _Children) -> s.Module:
        imports = tuple(i for i in items if isinstance(i, s.Import))
        comps = tuple(i for i in items if isinstance(i, s.Component))
        systems = tuple(i for i in items if isinstance(i, s.System))
        messages = tuple(i for i in items if isinstance(i, s.Message))
        return s.Module(self.path, imports, comps, systems, self._span(start, end), messages)

    def message(self, start: _Pos, end: _Pos, children: _Children) -> s.Message:
        name, (text, where) = children
        return s.Message(name, text[1:-1], self._span(start, end), where)

    def import_decl(self, start: _Pos, end: _Pos, children: _Children) -> s.Import:
        text, where = children[0]
        return s.Import(text[1:-1], self._span(start, end), where)

    # ---------------------------------------------------------------- quantities
    def quantity(self, start: _Pos, end: _Pos, children: _Children) -> s.Quantity:
        num, unit = children
        return s.Quantity(num[0], unit, self._span(start, end))

    # ---------------------------------------------------------------- components
    def component(self, start: _Pos, end: _Pos, children: _Children) -> s.Component:
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

    def in_port(self, start: _Pos, end: _Pos, children: _Children) -> s.InPort:
        return s.InPort(children[0], children[1], self._span(start, end))

    def out_port(self, start: _Pos, end: _Pos, children: _Children) -> s.OutPort:
        return s.OutPort(children[0], children[1], self._span(start, end))

    def _compound(self, start: _Pos, end: _Pos, children: _Children, mode: Literal["and", "or"]) -> s.CompoundPort:
        name, *rest = children
        constraint = rest.pop()[1] if rest and isinstance(rest[-1], tuple) else None
        members = tuple(t for t in rest if isinstance(t, s.Name))
        return s.CompoundPort(name, mode, members, constraint, self._span(start, end))

    def compound_and(self, start: _Pos, end: _Pos, children: _Children) -> s.CompoundPort:
        return self._compound(start, end, children, "and")

    def compound_or(self, start: _Pos, end: _Pos, children: _Children) -> s.CompoundPort:
        return self._compound(start, end, children, "or")

    def preemptive(self, start: _Pos, end: _Pos, children: _Children) -> Literal["preemptive"]:
        return "preemptive"

    def cooperative(self, start: _Pos, end: _Pos, children: _Children) -> Literal["cooperative"]:
        return "cooperative"

    def task(self, start: _Pos, end: _Pos, children: _Children) -> s.Task:
        name, *clauses, rbrace = children
        kind: Literal["preemptive", "cooperative"] = "preemptive"
        if clauses and isinstance(clauses[0], str):
            kind = clauses.pop(0)
        fields: dict[str, Any] = {"reads": [], "produces": []}
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

    def reads(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, list[s.Read], _Where]:
        port, *options = children
        opts: dict[str, Any] = {}
        for key, value in options:
            opts[key] = value
        read = s.Read(port, span=self._span(start, end), **opts)
        return ("reads", [read], (start, end))

    def optional(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, bool]:
        return ("optional", True)

    def required(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, bool]:
        return ("optional", False)

    def oversampling(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Tolerance]:
        return ("oversampling", children[0])

    def undersampling(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Tolerance]:
        return ("undersampling", children[0])

    def tol_ok(self, start: _Pos, end: _Pos, children: _Children) -> s.Tolerance:
        return s.Tolerance("ok", None, self._span(start, end))

    def tol_forbidden(self, start: _Pos, end: _Pos, children: _Children) -> s.Tolerance:
        return s.Tolerance("forbidden", None, self._span(start, end))

    def tol_max(self, start: _Pos, end: _Pos, children: _Children) -> s.Tolerance:
        return s.Tolerance("max", self._number(children[0]), self._span(start, end))

    def produces(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, list[s.Name], _Where]:
        return ("produces", list(children), (start, end))

    def bcet(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Quantity, _Where]:
        return ("bcet", children[0], (start, end))

    def wcet(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Quantity, _Where]:
        return ("wcet", children[0], (start, end))

    def act_constraint(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.ActivationConstraint, _Where]:
        (low, high), *rest = children
        changeable = rest[0] if rest else True
        return ("constraint", s.ActivationConstraint(low, high, changeable, self._span(start, end)), (start, end))

    def bounds_range(self, start: _Pos, end: _Pos, children: _Children) -> tuple[s.Quantity, s.Quantity]:
        return (children[0], children[1])

    def bounds_exact(self, start: _Pos, end: _Pos, children: _Children) -> tuple[s.Quantity, s.Quantity]:
        return (children[0], children[0])

    def bounds_min(self, start: _Pos, end: _Pos, children: _Children) -> tuple[s.Quantity, None]:
        return (children[0], None)

    def bounds_max(self, start: _Pos, end: _Pos, children: _Children) -> tuple[None, s.Quantity]:
        return (None, children[0])

    def fixed(self, start: _Pos, end: _Pos, children: _Children) -> bool:
        return False

    def changeable(self, start: _Pos, end: _Pos, children: _Children) -> bool:
        return True

    # ---------------------------------------------------------------- systems
    def system(self, start: _Pos, end: _Pos, children: _Children) -> s.System:
        name, *members, rbrace = children
        return s.System(
            name,
            tuple(m for m in members if isinstance(m, s.Core)),
            tuple(m for m in members if isinstance(m, s.Instance)),
            tuple(m for m in members if isinstance(m, s.Connection)),
            tuple(m for m in members if isinstance(m, s.Chain)),
            self._span(start, end),
            rbrace,
            tuple(m for m in members if isinstance(m, s.Executor)),
            tuple(m for m in members if isinstance(m, s.ArrivalCost)),
        )

    def arrival_cost(self, start: _Pos, end: _Pos, children: _Children) -> s.ArrivalCost:
        return s.ArrivalCost(children[0], self._span(start, end))

    def executor(self, start: _Pos, end: _Pos, children: _Children) -> s.Executor:
        name, kind, *clauses = children
        fields: dict[str, Any] = {}
        repeated: list[Span] = []
        for tag, value, where in clauses:
            if tag in fields or (tag == "cores" and "core" in fields):
                repeated.append(self._span(*where))
            elif tag == "cores":
                fields["core"], fields["more_cores"] = value[0], tuple(value[1:])
            else:
                fields[tag] = value
        return s.Executor(name, kind, span=self._span(start, end), repeated=tuple(repeated), **fields)

    def executor_cores(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, list[s.Name], _Where]:
        return ("cores", list(children), (start, end))

    def threads(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Number, _Where]:
        return ("threads", self._number(children[0]), (start, end))

    def callback_group(self, start: _Pos, end: _Pos, children: _Children) -> s.CallbackGroup:
        return s.CallbackGroup(children[0], children[1], self._span(start, end))

    def core(self, start: _Pos, end: _Pos, children: _Children) -> s.Core:
        policy = children[1] if len(children) > 1 else None
        return s.Core(children[0], policy, self._span(start, end))

    def instance(self, start: _Pos, end: _Pos, children: _Children) -> s.Instance:
        name, comp, *rest = children
        core: s.Name | None = None
        bindings: tuple[s.TaskBinding, ...] = ()
        groups: tuple[s.CallbackGroup, ...] = ()
        body_end = None
        for r in rest:
            if isinstance(r, s.Name):
                core = r
            else:
                bindings, groups, body_end = r
        return s.Instance(name, comp, core, bindings, self._span(start, end), body_end, groups)

    def instance_body(self, start: _Pos, end: _Pos, children: _Children
                      ) -> tuple[tuple[s.TaskBinding, ...], tuple[s.CallbackGroup, ...], Span]:
        *members, rbrace = children
        return (tuple(m for m in members if isinstance(m, s.TaskBinding)),
                tuple(m for m in members if isinstance(m, s.CallbackGroup)), rbrace)

    def binding(self, start: _Pos, end: _Pos, children: _Children) -> s.TaskBinding:
        name, *clauses = children
        fields: dict[str, Any] = {"activations": []}
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

    def priority(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Number, _Where]:
        return ("priority", self._number(children[0]), (start, end))

    def task_core(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Name, _Where]:
        return ("core", children[0], (start, end))

    def task_executor(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Name, _Where]:
        return ("executor", children[0], (start, end))

    def task_group(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Name, _Where]:
        return ("group", children[0], (start, end))

    def wcrt(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Quantity, _Where]:
        return ("wcrt", children[0], (start, end))

    def deadline(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Quantity, _Where]:
        return ("deadline", children[0], (start, end))

    def timer(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Timer, _Where]:
        phase = children[1] if len(children) > 1 else None
        return ("activations", s.Timer(children[0], phase, self._span(start, end)), (start, end))

    def period_hole(self, start: _Pos, end: _Pos, children: _Children) -> s.PeriodHole:
        low, high, step = (list(children) + [None, None, None])[:3]
        return s.PeriodHole(low, high, step, self._span(start, end))

    def trigger(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Trigger, _Where]:
        port = children[0]
        prescaler = children[1] if len(children) > 1 else s.Number(Fraction(1))
        return ("activations", s.Trigger(port, prescaler, self._span(start, end)), (start, end))

    def prescaler_number(self, start: _Pos, end: _Pos, children: _Children) -> s.Number:
        return self._number(children[0])

    def prescaler_hole(self, start: _Pos, end: _Pos, children: _Children) -> s.PrescalerHole:
        if children:
            return s.PrescalerHole(self._number(children[0]), self._number(children[1]), self._span(start, end))
        return s.PrescalerHole(span=self._span(start, end))

    def sporadic(self, start: _Pos, end: _Pos, children: _Children) -> tuple[str, s.Sporadic, _Where]:
        return ("activations", s.Sporadic(children[0], children[1], self._span(start, end)), (start, end))

    def unknown_activation(self, start: _Pos, end: _Pos,
                           children: _Children) -> tuple[str, s.UnknownActivation, _Where]:
        return ("activations", s.UnknownActivation(self._span(start, end)), (start, end))

    def connection(self, start: _Pos, end: _Pos, children: _Children) -> s.Connection:
        src, dst, *delay = children
        low, high = delay[0] if delay else (None, None)
        return s.Connection(src, dst, low, high, self._span(start, end))

    def delay_exact(self, start: _Pos, end: _Pos, children: _Children) -> tuple[s.Quantity, s.Quantity]:
        return (children[0], children[0])

    def delay_range(self, start: _Pos, end: _Pos, children: _Children) -> tuple[s.Quantity, s.Quantity]:
        return (children[0], children[1])

    def chain(self, start: _Pos, end: _Pos, children: _Children) -> s.Chain:
        name, *rest = children
        refs = tuple(r for r in rest if isinstance(r, s.PortRef))
        specs, body_end = (), None
        if rest and isinstance(rest[-1], tuple):
            specs, body_end = rest[-1]
        return s.Chain(name, refs, specs, self._span(start, end), body_end)

    def chain_body(self, start: _Pos, end: _Pos, children: _Children) -> tuple[tuple[s.Spec, ...], Span]:
        *specs, rbrace = children
        return tuple(specs), rbrace

    def spec_reaction_time(self, start: _Pos, end: _Pos, children: _Children) -> s.Spec:
        return s.Spec("reaction_time", children[0], self._span(start, end))

    def spec_data_age(self, start: _Pos, end: _Pos, children: _Children) -> s.Spec:
        return s.Spec("data_age", children[0], self._span(start, end))

    def spec_jitter(self, start: _Pos, end: _Pos, children: _Children) -> s.Spec:
        return s.Spec("jitter", children[0], self._span(start, end))

    def port_ref(self, start: _Pos, end: _Pos, children: _Children) -> s.PortRef:
        return s.PortRef(children[0], children[1], self._span(start, end))
