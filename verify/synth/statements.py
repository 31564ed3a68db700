"""The user's own statements that synthesis tracks, and the model a configuration gives.

A *statement* is one thing the user wrote that constrains the answer and that an unsat core may name
(specs/synthesis.md §5): a spec bound, a fixed rate (a timer binding, an explicit ``every K``, or a
component's ``fixed`` activation constraint), a hole's range, the lower or upper end of a changeable
activation constraint, a sampling tolerance, an execution time (``wcet``), a core assignment.
Statements written once in a component apply to every instance of it.

Relaxing (switching off) a statement means: a spec bound is dropped; a fixed rate or a range no
longer restricts the candidates (the default grid takes over); a constraint end or a tolerance is
dropped; a ``wcet`` falls to the task's ``bcet``; a task loses its core and runs alone on a core of
its own. ``configured_model`` builds the semantic model of a configuration with some statements off.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from typing import TypedDict, TypeGuard
from collections.abc import Mapping

from ..model import syntax as s
from ..model.activations import Hole
from ..model.system import ActivationModel, ChainModel, CoreModel, ReadModel, SystemModel, TaskModel
from ..frontend.resolve import SystemScope
from ..core.source import NO_SPAN, Span
from ..model.units import fmt_number, fmt_quantity, fmt_rate, fmt_time

#: deletion order of core minimisation: the kinds tried first are the first to leave the core, so
#: what remains is what a user most likely wants to see (specs, fixed rates, constraints)
RANKS = {"range": 0, "wcet": 1, "core": 2, "tolerance": 3, "min_rate": 4, "max_rate": 4, "rate": 5, "spec": 6}
SPEC_KINDS = ("reaction_time", "data_age", "jitter")


@dataclass(frozen=True)
class Statement:
    """One tracked user statement. ``tasks`` are the model tasks it constrains (for a spec: the
    chain's tasks); ``label`` is the short text of a diagnostic label ("fixed at 40 Hz")."""

    key: str
    kind: str
    span: Span
    label: str
    text: str
    tasks: tuple[str, ...]
    chain: str | None = None
    spec_kind: str | None = None
    port: str | None = None
    direction: str | None = None  # tolerance: "over" | "under"

    @property
    def rank(self) -> int:
        return RANKS[self.kind]

    def order_key(self) -> tuple[str, int, int, str]:
        """Source order (file, line, column), then the key: deterministic whatever the input order."""
        return (self.span.file, self.span.line, self.span.column, self.key)


def _real(span: Span | None) -> TypeGuard[Span]:
    return span is not None and span.line > 0


def _span(*candidates: Span | None) -> Span:
    return next((c for c in candidates if _real(c)), NO_SPAN)


# ================================================================== collecting


def collect_statements(model: SystemModel, scope: SystemScope | None) -> tuple[Statement, ...]:
    """Every tracked statement of ``model`` in source order (spans from ``scope`` when given)."""
    found: dict[str, Statement] = {}

    def add(st: Statement) -> None:
        if st.key in found:
            old = found[st.key]
            found[st.key] = replace(old, tasks=old.tasks + tuple(t for t in st.tasks if t not in old.tasks))
        else:
            found[st.key] = st

    for task in model.tasks:
        for st in _task_statements(model, task, scope):
            add(st)
    for chain in model.chains:
        for kind in SPEC_KINDS:
            bound = getattr(chain, kind)
            if bound is None:
                continue
            add(Statement(f"spec:{chain.name}:{kind}", "spec", chain.spec_span(kind), "spec bound",
                          f"{kind} <= {fmt_time(bound)}", chain.tasks, chain=chain.name, spec_kind=kind))
    return tuple(sorted(found.values(), key=Statement.order_key))


def _syntax(task: TaskModel,
            scope: SystemScope | None) -> tuple[s.Task | None, s.TaskBinding | None, s.Instance | None]:
    """(component task node, binding, instance) of ``task``, or Nones without a scope."""
    if scope is None:
        return None, None, None
    comp = scope.component_of.get(task.instance)
    node = comp.get(task.name) if comp else None
    binding = scope.bindings.get((task.instance, task.name))
    return (node if isinstance(node, s.Task) else None), binding, scope.instances.get(task.instance)


def _task_statements(model: SystemModel, task: TaskModel, scope: SystemScope | None) -> list[Statement]:
    node, binding, inst = _syntax(task, scope)
    comp_key = f"{task.component}.{task.name}"
    constraint = node.constraint if node is not None else None
    out: list[Statement] = []
    rate = _rate_statement(task, node, binding, comp_key)
    if rate is not None:
        out.append(rate)
    if task.activation.unknown:
        rng = _range_statement(task)
        if rng is not None:
            out.append(rng)
    if task.changeable:
        c_span = constraint.span if constraint is not None else NO_SPAN
        if task.min_rate is not None:
            out.append(Statement(f"min:{comp_key}", "min_rate", c_span, f"at least {fmt_rate(task.min_rate)}",
                                 f"activation min {fmt_rate(task.min_rate)}", (task.id,)))
        if task.max_rate is not None:
            out.append(Statement(f"max:{comp_key}", "max_rate", c_span, f"at most {fmt_rate(task.max_rate)}",
                                 f"activation max {fmt_rate(task.max_rate)}", (task.id,)))
    for read in task.reads:
        for direction, tol in (("over", read.oversampling), ("under", read.undersampling)):
            if tol is None or tol.kind == "ok":
                continue
            factor = tol.factor  # ("max" has one)
            what = f"{direction}sampling " + ("forbidden" if tol.kind == "forbidden" or factor is None
                                              else f"at most {fmt_number(factor.value)}")
            out.append(Statement(f"tolerance:{comp_key}.{read.port}.{direction}", "tolerance", _span(tol.span),
                                 f"{what} on `{read.port}`", f"reads {read.port} {what}", (task.id,),
                                 port=read.port, direction=direction))
    wcet_span = node.wcet.span if node is not None and node.wcet is not None else NO_SPAN
    out.append(Statement(f"wcet:{comp_key}", "wcet", wcet_span, f"wcet {fmt_time(task.wcet)}",
                         f"wcet {fmt_time(task.wcet)}", (task.id,)))
    out.append(_core_statement(task, binding, inst))
    return out


def _rate_statement(task: TaskModel, node: s.Task | None, binding: s.TaskBinding | None,
                    comp_key: str) -> Statement | None:
    """A fixed rate: a component's ``fixed`` constraint, else a timer binding or an explicit prescaler."""
    act = task.activation
    period, port = act.strict_period, act.trigger_port
    if not task.changeable and (period is not None or port is not None):
        span = node.constraint.span if node is not None and node.constraint is not None else NO_SPAN
        text = _constraint_text(task)
        return Statement(f"fixed:{comp_key}", "rate", span, f"fixed at {text}", f"activation {text} fixed",
                         (task.id,))
    written = binding.activation if binding is not None else None
    if period is not None:
        span = written.span if isinstance(written, s.Timer) else NO_SPAN
        shown = fmt_quantity(written.period) if isinstance(written, s.Timer) and isinstance(
            written.period, s.Quantity) else fmt_time(period)
        return Statement(f"binding:{task.id}", "rate", span, f"set to {shown}", f"timer {shown}", (task.id,))
    if port is not None:
        k = act.release_every
        number = written.prescaler if isinstance(written, s.Trigger) else None
        explicit = _real(number.span) if isinstance(number, s.Number) else k != 1
        if not explicit:
            return None
        span = number.span if isinstance(number, s.Number) and _real(number.span) else NO_SPAN
        return Statement(f"binding:{task.id}", "rate", span, f"every {k}", f"trigger {port} every {k}", (task.id,))
    return None


def _range_statement(task: TaskModel) -> Statement | None:
    hole = task.activation
    if not isinstance(hole, Hole) or not hole.bounded or hole.what == "kind":
        return None
    if hole.what == "period":
        return Statement(f"range:{task.id}", "range", _span(hole.range_span, hole.span),
                         f"period in {hole.range_text}", f"timer ? in {hole.range_text}", (task.id,))
    return Statement(f"range:{task.id}", "range", _span(hole.range_span, hole.span),
                     f"prescaler in {hole.range_text}", f"every ? in {hole.range_text}", (task.id,))


def _core_statement(task: TaskModel, binding: s.TaskBinding | None, inst: s.Instance | None) -> Statement:
    if binding is not None and binding.core is not None:
        return Statement(f"core:{task.id}", "core", binding.core.span, f"on {task.core}", f"on {task.core}", (task.id,))
    span = inst.core.span if inst is not None and inst.core is not None else NO_SPAN
    key = f"core:{task.instance}" if inst is not None else f"core:{task.id}"
    return Statement(key, "core", span, f"on {task.core}", f"on {task.core}", (task.id,))


def _constraint_text(task: TaskModel) -> str:
    low, high = task.min_rate, task.max_rate
    if low is not None and low == high:
        return fmt_rate(low)
    if low is not None and high is not None:
        return f"{fmt_rate(low)} .. {fmt_rate(high)}"
    return f"min {fmt_rate(low)}" if low is not None else f"max {fmt_rate(high)}"


# ================================================================== configured models


_INDEX: dict[int, tuple[tuple[Statement, ...], dict[str, dict[str, str]]]] = {}


def statement_index(statements: tuple[Statement, ...]) -> dict[str, dict[str, str]]:
    """Per task id: statement kind → key (``rate``, ``range``, ``min_rate``, ``max_rate``, ``wcet``,
    ``core``), and ``tolerance:PORT:DIR`` → key. Cached by the identity of ``statements``."""
    cached = _INDEX.get(id(statements))
    if cached is not None and cached[0] is statements:
        return cached[1]
    index = _statement_index(statements)
    if len(_INDEX) > 16:
        _INDEX.clear()
    _INDEX[id(statements)] = (statements, index)
    return index


def _statement_index(statements: tuple[Statement, ...]) -> dict[str, dict[str, str]]:
    index: dict[str, dict[str, str]] = {}
    for st in statements:
        if st.kind == "spec":
            continue
        for tid in st.tasks:
            slot = f"tolerance:{st.port}:{st.direction}" if st.kind == "tolerance" else st.kind
            index.setdefault(tid, {})[slot] = st.key
    return index


def private_core(task_id: str) -> str:
    """The core a task runs on once its core assignment is relaxed: one of its own."""
    return f"{task_id}~own"


def configured_model(model: SystemModel, activations: Mapping[str, ActivationModel],
                     statements: tuple[Statement, ...] = (), off: frozenset[str] = frozenset()) -> SystemModel:
    """``model`` with the given activation per task id and the statements in ``off`` relaxed."""
    index = statement_index(statements) if off else {}
    tasks = tuple(_configured_task(t, activations.get(t.id), index.get(t.id, {}), off) for t in model.tasks)
    cores = list(model.cores)
    known = {c.name for c in cores}
    for t in tasks:
        if t.core not in known:
            cores.append(CoreModel(t.core))
            known.add(t.core)
    chains = tuple(_configured_chain(c, off) for c in model.chains) if off else model.chains
    return SystemModel(model.name, tuple(cores), tasks, model.links, chains, model.span, model.compounds,
                       model.instances, model.components, model.ports, model.executors, model.groups)


class _TaskChanges(TypedDict, total=False):
    """The fields of a ``TaskModel`` a configuration changes (keyword arguments of ``replace``)."""

    activation: ActivationModel
    wcet: Fraction
    core: str
    min_rate: Fraction | None
    max_rate: Fraction | None
    changeable: bool
    reads: tuple[ReadModel, ...]


def _configured_task(task: TaskModel, activation: ActivationModel | None, slots: dict[str, str],
                     off: frozenset[str]) -> TaskModel:
    changes: _TaskChanges = {}
    if activation is not None:
        changes["activation"] = activation
    if off:
        if slots.get("wcet") in off:
            changes["wcet"] = task.bcet
        if slots.get("core") in off:
            changes["core"] = private_core(task.id)
        rate = slots.get("rate")
        if rate in off and rate.startswith("fixed:"):
            changes.update({"min_rate": None, "max_rate": None, "changeable": True})
        if slots.get("min_rate") in off:
            changes["min_rate"] = None
        if slots.get("max_rate") in off:
            changes["max_rate"] = None
        reads = tuple(_configured_read(r, slots, off) for r in task.reads)
        if reads != task.reads:
            changes["reads"] = reads
    return replace(task, **changes) if changes else task


def _configured_read(read: ReadModel, slots: dict[str, str], off: frozenset[str]) -> ReadModel:
    over = None if slots.get(f"tolerance:{read.port}:over") in off else read.oversampling
    under = None if slots.get(f"tolerance:{read.port}:under") in off else read.undersampling
    if over is read.oversampling and under is read.undersampling:
        return read
    return replace(read, oversampling=over, undersampling=under)


def _configured_chain(chain: ChainModel, off: frozenset[str]) -> ChainModel:
    dropped = {k for k in SPEC_KINDS if f"spec:{chain.name}:{k}" in off}
    if not dropped:
        return chain
    return replace(chain, reaction_time=None if "reaction_time" in dropped else chain.reaction_time,
                   data_age=None if "data_age" in dropped else chain.data_age,
                   jitter=None if "jitter" in dropped else chain.jitter)
