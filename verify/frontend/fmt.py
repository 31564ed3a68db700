"""The canonical formatter: one way to write every model, with every comment kept.

``format_module`` prints a ``verify.model.syntax.Module`` in canonical form (two-space indentation, one clause
per line, defaults omitted, exact numbers); ``parse(format(m)) == m`` and formatting is idempotent.
Comments are not part of the tree: ``collect_comments`` scans them from the text and ``format_module``
re-attaches each one to the node it stands before (own-line comments) or behind (end-of-line comments).
"""
from __future__ import annotations

import bisect
import re
from collections import defaultdict
from collections.abc import Set
from dataclasses import dataclass, field
from fractions import Fraction
from typing import NamedTuple

from ..model import syntax as s
from ..core.diagnostics import Diagnostic, DiagnosticSink
from .parse import parse_text
from ..core.source import Span
from ..model.units import fmt_number

INDENT = "  "

Pos = tuple[int, int]


@dataclass(frozen=True)
class Comment:
    """A ``//`` or ``/* */`` comment as written, with the line and column where it starts.

    ``own_line`` is true when no code precedes it on its line (other comments may).
    """

    text: str
    line: int
    column: int
    own_line: bool

    @property
    def pos(self) -> Pos:
        return (self.line, self.column)

    @property
    def ends_line(self) -> bool:
        """A line comment swallows the rest of its line: nothing may follow it there."""
        return self.text.startswith("//")


# ------------------------------------------------------------------ comments


#: a string literal (skipped: ``"a//b"`` holds no comment), a line comment or a block comment
_LEXEMES = re.compile(r'"[^"\n]*"?|//[^\n]*|/\*.*?(?:\*/|\Z)', re.S)


def collect_comments(text: str) -> list[Comment]:
    """Every comment of ``text`` in source order, as the grammar's LINE_COMMENT and BLOCK_COMMENT see them."""
    comments: list[Comment] = []
    line, counted, prev_end = 1, 0, 0
    for m in _LEXEMES.finditer(text):
        if m.group().startswith('"'):
            continue
        line += text.count("\n", counted, m.start())
        counted = m.start()
        line_start = text.rfind("\n", 0, m.start()) + 1
        if comments and prev_end > line_start:  # after a comment that ends on this line: inherit its kind
            own_line = comments[-1].own_line and not text[prev_end:m.start()].strip()
        else:
            own_line = not text[line_start:m.start()].strip()
        body = m.group().rstrip() if m.group().startswith("//") else m.group()
        comments.append(Comment(body, line, m.start() - line_start + 1, own_line))
        prev_end = m.end()
    return comments


# ------------------------------------------------------------------ numbers


def format_number(value: Fraction | int) -> str:
    """``10``, ``37.5`` (terminating decimals, exact) or ``100/3``; never a float, never negative."""
    if isinstance(value, float) or value < 0:
        raise ValueError(f"cannot write {value!r}: numbers are exact and not negative")
    return fmt_number(Fraction(value))


def format_quantity(q: s.Quantity) -> str:
    return f"{format_number(q.value)} {q.unit}"


def _bounds(low: s.Quantity, high: s.Quantity) -> str:
    """``low .. high``, or one quantity when both are the same amount."""
    return format_quantity(low) if low == high else f"{format_quantity(low)} .. {format_quantity(high)}"


def _require(condition: bool, what: str) -> None:
    if not condition:
        raise _unformattable(what)


def _unformattable(what: str) -> ValueError:
    return ValueError(f"cannot format: {what}")


# ------------------------------------------------------------------ clause texts


def _constraint(c: s.ActivationConstraint) -> str:
    if c.min is not None and c.max is not None:
        bounds = _bounds(c.min, c.max)
    elif c.min is not None:
        bounds = f"min {format_quantity(c.min)}"
    elif c.max is not None:
        bounds = f"max {format_quantity(c.max)}"
    else:
        raise _unformattable("activation constraint without bounds")
    return f"activation {bounds}" + ("" if c.changeable else " fixed")


def _compound(c: s.CompoundPort) -> str:
    _require(len(c.members) >= 2, f"compound port {c.name} needs at least two members")
    op = " & " if c.mode == "and" else " | "
    text = f"in {c.name} = " + op.join(m.text for m in c.members)
    return text + (f" {_constraint(c.constraint)}" if c.constraint else "")


def _tolerance(t: s.Tolerance) -> str:
    if t.kind == "max":
        if t.factor is None:
            raise _unformattable("sampling tolerance `<=` without a factor")
        return f"<= {format_number(t.factor.value)}"
    return t.kind


def _read(r: s.Read) -> str:
    text = f"reads {r.port}" + (" optional" if r.optional else "")
    if r.oversampling:
        text += f" oversampling {_tolerance(r.oversampling)}"
    if r.undersampling:
        text += f" undersampling {_tolerance(r.undersampling)}"
    return text


def _period(p: s.Quantity | s.PeriodHole) -> str:
    if isinstance(p, s.Quantity):
        return format_quantity(p)
    low, high = p.low, p.high
    if low is None and high is None and p.step is None:
        return "?"
    if low is None or high is None:
        raise _unformattable("period hole needs both bounds, and a step only with bounds")
    text = f"? in {format_quantity(low)} .. {format_quantity(high)}"
    return text + (f" step {format_quantity(p.step)}" if p.step else "")


def _prescaler(p: s.Number | s.PrescalerHole) -> str:
    if isinstance(p, s.Number):
        return "" if p.value == 1 else f" every {format_number(p.value)}"
    low, high = p.low, p.high
    if low is None and high is None:
        return " every ?"
    if low is None or high is None:
        raise _unformattable("prescaler hole needs both bounds or none")
    return f" every ? in {format_number(low.value)} .. {format_number(high.value)}"


def format_activation(a: s.Activation) -> str:
    """The canonical text of an activation source (``timer 50 ms``, ``trigger scan every 2``)."""
    return _activation(a)


def _activation(a: s.Activation) -> str:
    if isinstance(a, s.Timer):
        return f"timer {_period(a.period)}" + (f" phase {format_quantity(a.phase)}" if a.phase else "")
    if isinstance(a, s.Trigger):
        return f"trigger {a.port}{_prescaler(a.prescaler)}"
    if isinstance(a, s.Sporadic):
        return f"sporadic {format_quantity(a.low)} .. {format_quantity(a.high)}"
    return "activation ?"


def _binding(b: s.TaskBinding) -> str:
    clauses = [
        f"priority {format_number(b.priority.value)}" if b.priority is not None else None,
        f"on {b.core}" if b.core is not None else None,
        f"executor {b.executor}" if b.executor is not None else None,
        f"group {b.group}" if b.group is not None else None,
        f"wcrt {format_quantity(b.wcrt)}" if b.wcrt is not None else None,
        f"deadline {format_quantity(b.deadline)}" if b.deadline is not None else None,
        *(_activation(a) for a in b.activations),
    ]
    return " ".join([f"task {b.task}", *(c for c in clauses if c)])


def _executor(e: s.Executor) -> str:
    clauses = [f"{format_number(e.threads.value)} threads" if e.threads is not None else None,
               f"on {', '.join(c.text for c in e.cores)}" if e.core is not None else None,
               f"priority {format_number(e.priority.value)}" if e.priority is not None else None]
    return " ".join([f"executor {e.name} {e.kind}", *(c for c in clauses if c)])


def _connection(c: s.Connection) -> str:
    low, high = c.delay_min, c.delay_max
    if (low is None) != (high is None):
        raise _unformattable("connection delay needs both bounds or none")
    text = f"connect {c.source} -> {c.target}"
    return f"{text} delay {_bounds(low, high)}" if low is not None and high is not None else text


def _spec(spec: s.Spec) -> str:
    return f"{spec.kind} <= {format_quantity(spec.bound)}"


# ------------------------------------------------------------------ lines


@dataclass
class _Line:
    """One output line and the source positions of the nodes it prints (its anchors).

    ``extents`` holds, per anchor, where that node ends in the source, or None for a block header (its
    body's comments belong to the body). A ``closes`` line is a ``}``; an ``optional`` one closes an
    empty body that is printed only if comments need it.
    """

    depth: int
    text: str
    anchors: list[Pos] = field(default_factory=list)
    extents: list[Pos | None] = field(default_factory=list)
    closes: bool = False
    optional: bool = False


class _Printer:
    """Collects the lines of a module in canonical order."""

    def __init__(self) -> None:
        self.lines: list[_Line] = []

    def line(self, depth: int, text: str, *spans: Span | None, leaf: bool = True, **flags: bool) -> None:
        real = [sp for sp in spans if sp is not None and sp.line > 0]
        self.lines.append(_Line(depth, text, [(sp.line, sp.column) for sp in real],
                                [(sp.end_line, sp.end_column) if leaf else None for sp in real], **flags))

    def close(self, depth: int, end: Span | None, optional: bool = False) -> None:
        self.line(depth, "}", end, closes=True, optional=optional)

    def blank(self) -> None:
        self.lines.append(_Line(0, ""))


def _has_span(span: Span | None) -> bool:
    return span is not None and span.line > 0


def _top_level_items(module: s.Module) -> list[s.Message | s.Component | s.System]:
    items: list[s.Message | s.Component | s.System] = [*module.messages, *module.components, *module.systems]
    if all(_has_span(item.span) for item in items):
        items.sort(key=lambda item: (item.span.line, item.span.column))
    return items


def _print_module(p: _Printer, module: s.Module) -> None:
    for imp in module.imports:
        p.line(0, f'import "{imp.path}"', imp.span)
    previous: s.Message | s.Component | s.System | None = None
    for item in _top_level_items(module):
        if (previous is not None or module.imports) and not (isinstance(item, s.Message)
                                                              and isinstance(previous, s.Message)):
            p.blank()  # (message declarations one after another stay together)
        previous = item
        if isinstance(item, s.Message):
            p.line(0, f'message {item.name} = ros "{item.ros}"', item.span)
        elif isinstance(item, s.Component):
            _print_component(p, item)
        else:
            _print_system(p, item)


def _print_component(p: _Printer, c: s.Component) -> None:
    p.line(0, f"component {c.name} {{", c.span, leaf=False)
    for port in c.in_ports:
        p.line(1, f"in {port.name} : {port.type}", port.span)
    for out in c.out_ports:
        p.line(1, f"out {out.name} : {out.type}", out.span)
    for compound in c.compounds:
        p.line(1, _compound(compound), compound.span)
    for task in c.tasks:
        _print_task(p, task)
    p.close(0, c.end)


def _print_task(p: _Printer, t: s.Task) -> None:
    kind = " cooperative" if t.kind == "cooperative" else ""
    p.line(1, f"task {t.name}{kind} {{", t.span, leaf=False)
    for read in t.reads:
        p.line(2, _read(read), read.span)
    if t.produces:
        p.line(2, "produces " + ", ".join(n.text for n in t.produces), *(n.span for n in t.produces))
    if t.bcet is not None:
        p.line(2, f"bcet {format_quantity(t.bcet)}", t.bcet.span)
    if t.wcet is not None:
        p.line(2, f"wcet {format_quantity(t.wcet)}", t.wcet.span)
    if t.constraint is not None:
        p.line(2, _constraint(t.constraint), t.constraint.span)
    p.close(1, t.end)


def _print_system(p: _Printer, system: s.System) -> None:
    p.line(0, f"system {system.name} {{", system.span, leaf=False)
    for core in system.cores:
        p.line(1, f"core {core.name}" + (f" policy {core.policy}" if core.policy else ""), core.span)
    for ex in system.executors:
        p.line(1, _executor(ex), ex.span)
    for cost in system.arrival_costs:
        p.line(1, f"arrival_cost {format_quantity(cost.cost)}", cost.span)
    for inst in system.instances:
        header = f"instance {inst.name} : {inst.component}" + (f" on {inst.core}" if inst.core else "")
        members = [(_binding(b), b.span) for b in inst.bindings]
        members += [(f"group {g.name} {g.kind}", g.span) for g in inst.groups]
        _print_block(p, header, inst.span, inst.end, sorted(members, key=lambda m: (m[1].line, m[1].column)))
    for conn in system.connections:
        p.line(1, _connection(conn), conn.span)
    for chain in system.chains:
        _require(len(chain.refs) >= 1, f"chain {chain.name} has no port references")
        header = f"chain {chain.name}: " + " -> ".join(str(r) for r in chain.refs)
        _print_block(p, header, chain.span, chain.end, [(_spec(sp), sp.span) for sp in chain.specs])
    p.close(0, system.end)


def _print_block(p: _Printer, header: str, span: Span, end: Span | None, body: list[tuple[str, Span]]) -> None:
    """An instance or chain: its body is printed when it has lines, or (empty) when comments are inside."""
    if body:
        p.line(1, header + " {", span, leaf=False)
        for text, line_span in body:
            p.line(2, text, line_span)
        p.close(1, end)
    elif _has_span(end):
        p.line(1, header, span, leaf=False)
        p.close(1, end, optional=True)
    else:
        p.line(1, header, span)


# ------------------------------------------------------------------ placing comments


class _Anchor(NamedTuple):
    pos: Pos  # where the node starts in the source
    line: int  # the output line that prints it
    end: Pos | None  # where it ends, for a node printed on one line


@dataclass
class _Placement:
    leading: dict[int, list[Comment]] = field(default_factory=lambda: defaultdict(list))
    trailing: dict[int, list[Comment]] = field(default_factory=lambda: defaultdict(list))
    at_end: list[Comment] = field(default_factory=list)


def _place_comments(lines: list[_Line], comments: list[Comment]) -> _Placement:
    """Attach each comment to the line of the node it precedes (own line) or follows (same line)."""
    anchors = [_Anchor(pos, i, end) for i, ln in enumerate(lines) for pos, end in zip(ln.anchors, ln.extents)]
    anchors.sort(key=lambda a: a.pos)
    starts = [a.pos for a in anchors]
    placed = _Placement()
    for c in sorted(comments, key=lambda c: c.pos):
        k = bisect.bisect_right(starts, c.pos)
        prev = anchors[k - 1] if k else None
        nxt = anchors[k] if k < len(anchors) else None
        if prev and ((prev.end and c.pos < prev.end) or (nxt and nxt.line == prev.line)):
            placed.trailing[prev.line].append(c)  # inside a node printed on one line
        elif nxt and placed.trailing[nxt.line]:
            placed.trailing[nxt.line].append(c)  # an earlier comment already went behind that node
        elif c.own_line or not prev:
            (placed.leading[nxt.line] if nxt else placed.at_end).append(c)
        elif nxt and placed.leading[nxt.line]:
            # the code before it on its line leads into the next node, and own-line comments are
            # already placed before that node: keep the order by putting this one behind the node
            placed.trailing[nxt.line].append(c)
        else:
            placed.trailing[prev.line].append(c)
    return placed


def _spill_trailing(lines: list[_Line], placed: _Placement) -> dict[int, list[Comment]]:
    """Split each line's trailing comments into those printed on the line and those moved below it.

    What cannot follow on the line (after a ``//`` comment, or an own-line comment found inside a
    multi-line node) goes before the next line that prints a node, as a comment on its own line.
    """
    inline: dict[int, list[Comment]] = {}
    for i in sorted(placed.trailing):
        comments = placed.trailing[i]
        n = 0
        while n < len(comments) and not comments[n].own_line and (n == 0 or not comments[n - 1].ends_line):
            n += 1
        inline[i] = comments[:n]
        if comments[n:]:
            nxt = next((j for j in range(i + 1, len(lines)) if lines[j].anchors), None)
            target = placed.leading[nxt] if nxt is not None else placed.at_end
            target[:0] = comments[n:]
    return inline


# ------------------------------------------------------------------ rendering


def _last_source_line(ln: _Line) -> int:
    ends = [end[0] if end else pos[0] for pos, end in zip(ln.anchors, ln.extents)]
    return max(ends, default=0)


def _wants_blank(ln: _Line, leading: list[Comment], prev_line: int, out: list[str], blanks: Set[int]) -> bool:
    """Keep one blank line between two members of a block where the source had one (or more)."""
    if ln.closes or not ln.anchors or not out or not out[-1] or out[-1].endswith("{") or ln.depth == 0:
        return False
    first = min([c.line for c in leading] + [pos[0] for pos in ln.anchors])
    return any(prev_line < b < first for b in blanks)


def _render(lines: list[_Line], comments: list[Comment], blanks: Set[int] = frozenset()) -> str:
    placed = _place_comments(lines, comments)
    inline = _spill_trailing(lines, placed)
    kept = [not ln.optional or bool(placed.leading.get(i) or inline.get(i)) for i, ln in enumerate(lines)]
    out: list[str] = []
    prev_line = 0
    for i, ln in enumerate(lines):
        if not kept[i]:
            continue
        comment_depth = ln.depth + 1 if ln.closes else ln.depth
        leading = placed.leading.get(i, [])
        if blanks and _wants_blank(ln, leading, prev_line, out, blanks):
            out.append("")
        prev_line = max(prev_line, _last_source_line(ln))
        out.extend(INDENT * comment_depth + c.text for c in leading)
        text = ln.text
        if i + 1 < len(lines) and lines[i + 1].optional and kept[i + 1]:
            text += " {"
        text += "".join("  " + c.text for c in inline.get(i, ()))
        out.append(INDENT * ln.depth + text if text else "")
    if placed.at_end and out:
        out.append("")
    out.extend(c.text for c in placed.at_end)
    return "\n".join(out) + "\n" if out else ""


def blank_lines(text: str) -> set[int]:
    """The numbers of the lines of ``text`` that hold only white space."""
    return {i for i, line in enumerate(text.split("\n"), 1) if not line.strip()}


def format_module(module: s.Module, comments: list[Comment] | None = None, blanks: set[int] | None = None) -> str:
    """The canonical text of ``module``, with ``comments`` (from ``collect_comments``) re-attached and,
    where ``blanks`` (from ``blank_lines``) says the source had them, one blank line kept between members.

    Raises ValueError for a tree no text can express (e.g. a negative number or a one-member compound).
    """
    printer = _Printer()
    _print_module(printer, module)
    return _render(printer.lines, comments or [], blanks or set())


def format_text(text: str, path: str = "<text>") -> tuple[str | None, list[Diagnostic]]:
    """Parse and format ``text``. None (with the diagnostics) when it has syntax errors, or when
    formatting would drop a clause given twice (the tree keeps only the first)."""
    sink = DiagnosticSink()
    module = parse_text(text, path, sink)
    if module is None or _report_repeated(module, sink):
        return None, sink.items
    return format_module(module, collect_comments(text), blank_lines(text)), sink.items


def _report_repeated(module: s.Module, sink: DiagnosticSink) -> bool:
    nodes: list[s.Task | s.TaskBinding | s.Executor] = [t for c in module.components for t in c.tasks]
    nodes += [b for system in module.systems for inst in system.instances for b in inst.bindings]
    nodes += [e for system in module.systems for e in system.executors]
    spans = sorted(span for node in nodes for span in node.repeated)
    for span in spans:
        sink.emit("E212", "clause given more than once; formatting would drop it", span, "given again here",
                  help="remove one of the two clauses, then format again")
    return bool(spans)
