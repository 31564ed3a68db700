"""Validation: structure (E2xx) and timing (E3xx) rules on resolved components and systems.

Runs after name resolution. Each rule is one function; each reports every violation it finds. Rules
that need propagated rates (triggered tasks against their constraints, sampling tolerances) live in
the timing analysis, which runs after this pass succeeds.
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from fractions import Fraction
from typing import TYPE_CHECKING

from ..model import syntax as s
from ..core.diagnostics import DiagnosticSink, Label, name_list
from ..model.system import SystemModel
from .build import chain_path
from .resolve import ComponentScope, MemberNode, Resolution, SystemScope
from ..core.source import Span
from ..model.units import fmt_number, fmt_quantity, fmt_rate, fmt_time, quantity_base, quantity_hertz, quantity_seconds
from .validate_executors import check_executors

if TYPE_CHECKING:  # (networkx is imported where a cycle of triggers is reported: it costs start-up time)
    import networkx as nx


# ================================================================== components


def validate_component(scope: ComponentScope, sink: DiagnosticSink) -> None:
    comp = scope.component
    for task in comp.tasks:
        _check_repeated(task.repeated, f"task `{task.name.text}`", sink)
        _check_execution_times(task, sink)
        if task.constraint is not None:
            _check_constraint(task.constraint, sink)
        _check_reads(task, sink)
    for compound in comp.compounds:
        if compound.constraint is not None:
            _check_constraint(compound.constraint, sink)
    _check_producers(scope, sink)


def _check_repeated(spans: Iterable[Span], what: str, sink: DiagnosticSink) -> None:
    for span in spans:
        sink.emit("E212", f"this clause is given more than once for {what}", span, "given again here",
                  help="keep one of them")


def _dimension(q: s.Quantity | None, want: str, role: str, sink: DiagnosticSink) -> bool:
    """E302: ``q`` must be a time or a frequency as ``want`` says."""
    if q is None or q.dimension == want:
        return True
    example = "`5 ms`" if want == "time" else "`20 Hz`"
    sink.emit("E302", f"{role} must be a {want}, found the {q.dimension} {fmt_quantity(q)}", q.span,
              f"a {q.dimension}", help=f"write a {want}, e.g. {example}")
    return False


def _positive(q: s.Quantity | None, role: str, sink: DiagnosticSink, allow_zero: bool = False) -> bool:
    if q is None or q.value.numerator > 0 or (allow_zero and not q.value):
        return True
    sink.emit("E307", f"{role} must be {'non-negative' if allow_zero else 'positive'}, found {fmt_quantity(q)}",
              q.span, "not positive", help=f"give a {role} above zero")
    return False


def _ordered(low: s.Quantity | s.Number | None, high: s.Quantity | s.Number | None, role: str,
             sink: DiagnosticSink, span: Span) -> bool:
    """E303: ``low .. high`` must not be inverted (compared in the dimension written)."""
    if low is None or high is None:
        return True
    lv = quantity_base(low) if isinstance(low, s.Quantity) else low.value
    hv = quantity_base(high) if isinstance(high, s.Quantity) else high.value
    if lv <= hv:
        return True
    def show(bound: s.Quantity | s.Number) -> str:
        return fmt_quantity(bound) if isinstance(bound, s.Quantity) else fmt_number(bound.value)

    sink.emit("E303", f"{role} is inverted: {show(low)} .. {show(high)} contains nothing", span,
              "lower bound above upper bound", help=f"write it as {show(high)} .. {show(low)}")
    return False


def _check_execution_times(task: s.Task, sink: DiagnosticSink) -> None:
    name = task.name.text
    if task.wcet is None:
        sink.emit("E217", f"task `{name}` has no worst-case execution time", task.name.span, "no `wcet`",
                  help="add a line such as `wcet 2 ms` to the task")
    ok = _dimension(task.bcet, "time", "bcet", sink) & _dimension(task.wcet, "time", "wcet", sink)
    ok &= _positive(task.bcet, "bcet", sink, allow_zero=True) & _positive(task.wcet, "wcet", sink)
    if ok and task.bcet is not None and task.wcet is not None and quantity_base(task.bcet) > quantity_base(task.wcet):
        sink.emit("E301", f"task `{name}`: bcet {fmt_quantity(task.bcet)} exceeds wcet {fmt_quantity(task.wcet)}",
                  task.bcet.span, "best case above worst case",
                  secondary=(Label(task.wcet.span, "worst case"),),
                  help="the best-case execution time must not exceed the worst case; swap or correct them")


def _check_constraint(c: s.ActivationConstraint, sink: DiagnosticSink) -> None:
    """E302, E307, E303 on an activation constraint; one report per slip: an exact rate (``activation
    10 Hz``: both bounds one quantity) is checked once, and a range written in times is one E302."""
    exact = c.min is c.max
    bounds = [(q, role) for q, role in ((c.min, "minimum activation frequency"),
                                        (c.max, "maximum activation frequency")) if q is not None]
    if exact:
        bounds = bounds[:1]
    times = [q for q, _ in bounds if q.dimension == "time"]
    if len(times) == 2 and c.min is not None and c.max is not None:
        sink.emit("E302", f"an activation constraint is a range of frequencies, found the times "
                  f"{fmt_quantity(c.min)} .. {fmt_quantity(c.max)}", c.min.span.to(c.max.span), "times",
                  help=f"write the rates, e.g. `{_as_rate(c.max)} .. {_as_rate(c.min)}`")
        return
    for q in times:
        sink.emit("E302", f"an activation-constraint bound must be a frequency, found the time {fmt_quantity(q)}",
                  q.span, "a time", help=f"write the rate, e.g. `{_as_rate(q)}` for a period of {fmt_quantity(q)}")
    ok = not times
    for q, role in bounds:
        ok &= _positive(q, role if not exact else "activation frequency", sink)
    if ok:
        _ordered(c.min, c.max, "activation constraint", sink, c.span)


def _as_rate(q: s.Quantity) -> str:
    """The frequency of period ``q`` as the user would write it (``100 ms`` → ``10 Hz``)."""
    return fmt_rate(quantity_hertz(q)) if q.value.numerator > 0 else "10 Hz"


def _check_reads(task: s.Task, sink: DiagnosticSink) -> None:
    seen: dict[str, s.Read] = {}
    for read in task.reads:
        if read.port.text in seen:
            sink.emit("E102", f"task `{task.name.text}` reads `{read.port.text}` twice", read.port.span,
                      "read again", secondary=(Label(seen[read.port.text].port.span, "first read here"),),
                      help="merge the two `reads` lines")
        seen[read.port.text] = read
        for tol in (read.oversampling, read.undersampling):
            if tol is not None and tol.kind == "max" and tol.factor is not None and tol.factor.value < 1:
                sink.emit("E303", f"a sampling factor below 1 ({fmt_number(tol.factor.value)}) allows nothing",
                          tol.span, "factor below 1", help="use `forbidden`, or a factor of at least 1")


def _check_producers(scope: ComponentScope, sink: DiagnosticSink) -> None:
    producers: dict[str, list[s.Task]] = {}
    for task in scope.component.tasks:
        first: dict[str, s.Name] = {}
        for out in task.produces:
            if out.text in first:
                sink.emit("E102", f"task `{task.name.text}` produces `{out.text}` twice", out.span, "produced again",
                          secondary=(Label(first[out.text].span, "first produced here"),),
                          help=f"name `{out.text}` once")
                continue
            first[out.text] = out
            producers.setdefault(out.text, []).append(task)
    comp = scope.component.name.text
    for port in scope.component.out_ports:
        if scope.get(port.name.text) is not port:  # a duplicate name, reported as E102
            continue
        tasks = producers.get(port.name.text, [])
        if not tasks:
            sink.emit("E202", f"out-port `{port.name.text}` of `{comp}` is produced by no task", port.name.span,
                      "never written", help=f"add `produces {port.name.text}` to the task that writes it")
        elif len(tasks) > 1:
            sink.emit("E203", f"out-port `{port.name.text}` of `{comp}` is produced by "
                      + " and ".join(f"`{t.name.text}`" for t in tasks), port.name.span,
                      "written by more than one task",
                      secondary=tuple(Label(next(p.span for p in t.produces if p.text == port.name.text),
                                            f"produced by `{t.name.text}`") for t in tasks),
                      help="every out-port is produced by exactly one task; give each task its own out-port")


# ================================================================== systems


def _instance_tasks(scope: SystemScope) -> Iterator[tuple[s.Instance, ComponentScope, s.Task, s.TaskBinding | None]]:
    """Every (instance, component scope, task definition, binding or None), in source order."""
    for inst in scope.system.instances:
        comp = scope.component_of.get(inst.name.text)
        if comp is None:
            continue
        for task in comp.component.tasks:
            yield inst, comp, task, scope.bindings.get((inst.name.text, task.name.text))


def validate_system(scope: SystemScope, sink: DiagnosticSink) -> None:
    for inst, comp, task, binding in _instance_tasks(scope):
        if binding is None:
            sink.emit("E207", f"task `{inst.name.text}.{task.name.text}` has no activation binding",
                      inst.name.span, "instance declared here",
                      help=f"add `task {task.name.text} priority 1 timer 100 ms` (or a trigger) "
                           f"to the body of instance `{inst.name.text}`")
            continue
        executor = scope.executors.get(binding.executor.text) if binding.executor else None
        _check_binding(inst, task, binding, comp, sink, executor)
    check_executors(scope, [(inst, task, b) for inst, _c, task, b in _instance_tasks(scope)], sink)
    _check_connections(scope, sink)
    _check_trigger_sources(scope, sink)
    _check_arrival_cost(scope.system, sink)
    for chain in scope.system.chains:
        first: dict[str, s.Spec] = {}
        for spec in chain.specs:
            _dimension(spec.bound, "time", f"the {spec.kind.replace('_', ' ')} bound", sink) and _positive(
                spec.bound, f"{spec.kind.replace('_', ' ')} bound", sink)
            if spec.kind in first:
                sink.emit("E212", f"the `{spec.kind}` spec is given more than once for chain `{chain.name.text}`",
                          spec.span, "given again here", secondary=(Label(first[spec.kind].span, "first given here"),),
                          help="keep one of them (a chain has at most one bound of each kind)")
            else:
                first[spec.kind] = spec


def _check_arrival_cost(system: s.System, sink: DiagnosticSink) -> None:
    """``arrival_cost``: at most one (E212), a time (E302), above zero (E307)."""
    for cost in system.arrival_costs[:1]:
        _dimension(cost.cost, "time", "the arrival cost", sink) and _positive(cost.cost, "arrival cost", sink)
    for again in system.arrival_costs[1:]:
        sink.emit("E212", f"`arrival_cost` is given more than once for system `{system.name.text}`", again.span,
                  "given again here", secondary=(Label(system.arrival_costs[0].span, "first given here"),),
                  help="keep one of them (a system has one arrival cost)")


def _check_binding(inst: s.Instance, task: s.Task, b: s.TaskBinding, comp: ComponentScope,
                   sink: DiagnosticSink, executor: s.Executor | None = None) -> None:
    who = f"`{inst.name.text}.{task.name.text}`"
    _check_repeated(b.repeated, f"task {who}", sink)
    if b.executor is not None:
        _check_callback(task, b, who, sink)
    elif b.priority is None:
        sink.emit("E213", f"task {who} has no priority", b.task.span, "no `priority`",
                  help="add `priority N` (a larger number is a higher priority)")
    elif not b.priority.is_integer or b.priority.value < 0:
        sink.emit("E309", f"priority of {who} must be a non-negative integer, found {fmt_number(b.priority.value)}",
                  b.priority.span, "not a priority", help="use a whole number such as `priority 3`")
    if b.core is None and inst.core is None and b.executor is None:
        sink.emit("E214", f"task {who} has no core", b.task.span, "no core",
                  help=f"add `on CORE` to instance `{inst.name.text}` or to this task")
    if _dimension(b.wcrt, "time", "wcrt", sink) and _positive(b.wcrt, "wcrt", sink):
        _check_user_bound(b, task, who, sink)
    _dimension(b.deadline, "time", "deadline", sink) and _positive(b.deadline, "deadline", sink)
    if not b.activations:
        sink.emit("E207", f"task {who} has no activation binding", b.task.span, "not activated",
                  help="add `timer 100 ms`, `trigger PORT`, `sporadic 10 ms .. 50 ms`, or `activation ?`")
        return
    if len(b.activations) > 1:
        triggers = [a for a in b.activations if isinstance(a, s.Trigger)]
        what = "data trigger" if len(triggers) > 1 else "activation binding"
        sink.emit("E204", f"task {who} has more than one {what}", b.activations[1].span, "second binding",
                  secondary=(Label(b.activations[0].span, "first binding"),),
                  help="a task has exactly one activation source; to fire on several inputs declare a compound "
                       "in-port (`in both = a & b` or `in any = a | b`) and trigger on it")
    act = b.activations[0]
    if _check_activation_values(act, sink):
        _check_against_constraint(act, task, who, sink)
    if isinstance(act, s.Trigger):
        _check_trigger_reads(act, task, comp, who, sink)
    if executor is not None:
        _check_callback_activation(act, executor, who, sink)


def _check_callback(task: s.Task, b: s.TaskBinding, who: str, sink: DiagnosticSink) -> None:
    """E220: a callback runs in its executor's thread, which has the core and the priority; E221: a
    cooperative task (callbacks of one single-threaded executor never overlap anyway)."""
    assert b.executor is not None
    for clause, what in ((b.priority, "priority"), (b.core, "core")):
        if clause is not None:
            sink.emit("E220", f"task {who} runs on executor `{b.executor.text}` and also has a {what}",
                      clause.span, f"{what} of a callback",
                      help=f"remove the {what}: a callback runs in its executor's thread, at the executor's "
                           "priority on the executor's core")
    if task.kind == "cooperative":
        sink.emit("E221", f"task {who} is cooperative, which a callback on executor `{b.executor.text}` "
                  "cannot be", b.executor.span, "cooperative task bound to an executor",
                  secondary=(Label(task.name.span, "declared cooperative here"),),
                  help="declare the task preemptive (callbacks of one executor never overlap), or bind it "
                       "with a priority and a core instead of an executor")


def _check_callback_activation(act: s.Activation, executor: s.Executor, who: str, sink: DiagnosticSink) -> None:
    """E221: a ROS 2 subscription runs its callback on every message it takes, so a callback has no
    prescaler; and an executor callback's kind (timer or subscription) is the integrator's choice."""
    name = executor.name.text
    if isinstance(act, s.UnknownActivation):
        sink.emit("E221", f"task {who} on executor `{name}` has no activation kind to choose", act.span,
                  "kind hole on a callback",
                  help="bind the callback as a timer (`timer ?` lets synth choose its period) or as a "
                       "subscription (`trigger PORT`)")
    elif isinstance(act, s.Trigger) and (isinstance(act.prescaler, s.PrescalerHole) or act.prescaler.value != 1):
        sink.emit("E221", f"task {who} on executor `{name}` has a prescaler, which a ROS 2 subscription "
                  "callback does not have", act.span, "prescaler on a callback",
                  help="drop `every …`: a subscription runs its callback on every message it takes "
                       "(a callback that works on every k-th message is modelled as a timer reading the port, "
                       "or bound with a priority instead of an executor)")


def _check_user_bound(b: s.TaskBinding, task: s.Task, who: str, sink: DiagnosticSink) -> None:
    """E315: a user response-time bound below the wcet cannot hold (specs/timing.md §6.2): a job may
    run for its wcet, and it starts no earlier than its release."""
    w = task.wcet
    if b.wcrt is None or w is None or w.dimension != "time" or w.value <= 0:
        return  # (a missing or malformed wcet is E217, E302 or E307)
    bound, wcet = quantity_seconds(b.wcrt), quantity_seconds(w)
    if bound >= wcet:
        return
    sink.emit("E315", f"task {who}: the response-time bound {fmt_quantity(b.wcrt)} is below its worst-case "
              f"execution time {fmt_quantity(w)}, so it cannot hold", b.wcrt.span, "below the wcet",
              secondary=(Label(w.span, "worst-case execution time"),),
              notes=("a job may run for its full wcet and starts no earlier than its release, so a response "
                     f"time of {fmt_time(wcet)} is possible",),
              help=f"give a bound of at least {fmt_time(wcet)}, or remove `wcrt` to use the computed one")


def _check_activation_values(act: s.Activation, sink: DiagnosticSink) -> bool:
    """Dimensions, signs, ranges and integrality of one activation binding."""
    if isinstance(act, s.Timer):
        return _check_timer(act, sink)
    if isinstance(act, s.Sporadic):
        ok = _dimension(act.high, act.low.dimension, "the sporadic upper bound", sink)
        ok &= _positive(act.low, "inter-arrival bound", sink) & _positive(act.high, "inter-arrival bound", sink)
        return ok and _ordered(act.low, act.high, "sporadic range", sink, act.span)
    if isinstance(act, s.Trigger):
        return _check_prescaler(act.prescaler, sink)
    return True


def _check_timer(t: s.Timer, sink: DiagnosticSink) -> bool:
    if isinstance(t.period, s.PeriodHole):
        h = t.period
        ok = _positive(h.low, "period bound", sink) & _positive(h.high, "period bound", sink)
        ok &= _positive(h.step, "grid step", sink)
        if h.low is not None and h.high is not None:
            ok &= _dimension(h.high, h.low.dimension, "the upper bound of the range", sink)
            ok = ok and _ordered(h.low, h.high, "period range", sink, h.span)
        if h.step is not None:
            step_ok = _dimension(h.step, "time", "grid step", sink)
            ok &= step_ok
            if step_ok and h.low is not None and h.low.dimension != "time":  # (one E302 per span)
                sink.emit("E302", "a grid step needs a range of periods (times)", h.step.span, "step",
                          help="write the range as periods, e.g. `? in 10 ms .. 100 ms step 5 ms`")
                ok = False
        ok &= _dimension(t.phase, "time", "phase", sink)
        return ok
    ok = _positive(t.period, "period", sink) & _dimension(t.phase, "time", "phase", sink)
    ok &= _positive(t.phase, "phase", sink, allow_zero=True)
    if ok and t.phase is not None and quantity_base(t.phase) >= quantity_seconds(t.period):
        sink.emit("E308", f"phase {fmt_quantity(t.phase)} is not below the period "
                  f"{fmt_quantity(t.period)}", t.phase.span, "phase too large",
                  help="a phase lies in [0, period); subtract whole periods")
        ok = False
    return ok


def _check_prescaler(p: s.Number | s.PrescalerHole, sink: DiagnosticSink) -> bool:
    if isinstance(p, s.PrescalerHole):
        ok = all(_check_prescaler(n, sink) for n in (p.low, p.high) if n is not None)
        return ok and _ordered(p.low, p.high, "prescaler range", sink, p.span)
    if p.is_integer and p.value >= 1:
        return True
    sink.emit("E304", f"prescaler must be a whole number of at least 1, found {fmt_number(p.value)}", p.span,
              "invalid prescaler",
              help="`every 1` fires on every arrival, `every 10` on every tenth")
    return False


def _binding_rates(act: s.Activation) -> tuple[Fraction, Fraction] | None:
    """The rate interval (Hz) a timer or sporadic binding gives, or None if not fixed here."""
    if isinstance(act, s.Timer) and isinstance(act.period, s.Quantity):
        rate = quantity_hertz(act.period)
        return rate, rate
    if isinstance(act, s.Sporadic):
        rates = sorted((quantity_hertz(act.low), quantity_hertz(act.high)))
        return rates[0], rates[1]
    return None


def _check_against_constraint(act: s.Activation, task: s.Task, who: str, sink: DiagnosticSink) -> None:
    c = task.constraint
    if c is None or not _well_formed(c):  # (an invalid one is reported once, in its component)
        return
    if not c.changeable and s.is_hole(act):
        sink.emit("E216", f"task {who} has a fixed rate ({_constraint_text(c)}), so it cannot be left to synthesis",
                  act.span, "hole on a fixed task", secondary=(Label(c.span, "the component fixes the rate"),),
                  help=f"bind it as its component requires, e.g. `{_fixed_binding_hint(c)}`")
        return
    if isinstance(act, s.Timer) and isinstance(act.period, s.PeriodHole):
        _check_hole_candidates(act.period, c, who, sink)
        return
    rates = _binding_rates(act)
    if rates is None:
        return
    low, high = rates
    lo = quantity_hertz(c.min) if c.min else None
    hi = quantity_hertz(c.max) if c.max else None
    outside = (lo is not None and low < lo) or (hi is not None and high > hi)
    if not outside and (c.changeable or lo != hi or (low, high) == (lo, hi)):
        return
    given = fmt_rate(low) if low == high else f"{fmt_rate(low)} .. {fmt_rate(high)}"
    if not c.changeable and (outside or (lo == hi and (low, high) != (lo, hi))):
        sink.emit("E306", f"task {who} runs at a fixed {_constraint_text(c)}, but is bound to {given}", act.span,
                  f"gives {given}", secondary=(Label(c.span, "fixed by the component"),),
                  help=f"bind it as `{_fixed_binding_hint(c)}`; the component does not allow another rate")
    elif outside:
        sink.emit("E305", f"task {who} would run at {given}, outside its activation constraint {_constraint_text(c)}",
                  act.span, f"gives {given}", secondary=(Label(c.span, "constraint declared here"),),
                  help=f"choose a rate within {_constraint_text(c)}")


def _check_hole_candidates(h: s.PeriodHole, c: s.ActivationConstraint, who: str, sink: DiagnosticSink) -> None:
    """E313: a period hole's range (and grid, ``low + k * step``) must hold a period within the constraint."""
    if h.low is None or h.high is None or not _well_formed(c):
        return
    shortest, longest = sorted((quantity_seconds(h.low), quantity_seconds(h.high)))
    if c.max is not None:
        shortest = max(shortest, 1 / quantity_hertz(c.max))
    if c.min is not None:
        longest = min(longest, 1 / quantity_hertz(c.min))
    candidates = shortest <= longest
    what, notes = f"{fmt_quantity(h.low)} .. {fmt_quantity(h.high)}", []
    if candidates and h.step is not None:  # a grid of periods (validation made the range and step times)
        start, step = quantity_seconds(h.low), quantity_seconds(h.step)
        first = -((start - shortest) // step)  # ceil((shortest - start) / step)
        candidates = start + first * step <= longest
        what += f" step {fmt_quantity(h.step)}"
        notes.append(f"the constraint allows {fmt_time(shortest)} .. {fmt_time(longest)} of this range, but the "
                     f"grid {fmt_quantity(h.low)}, {fmt_time(start + step)}, ... has no period there")
    if candidates:
        return
    sink.emit("E313", f"task {who}: no period in `? in {what}` lies within its activation constraint "
              f"{_constraint_text(c)}", h.span, "no candidate period",
              secondary=(Label(c.span, "constraint declared here"),), notes=notes,
              help=f"choose periods the constraint allows: {_allowed_periods(c)}")


def _well_formed(c: s.ActivationConstraint) -> bool:
    """What ``_check_constraint`` accepts: positive frequencies, not inverted."""
    bounds = [q for q in (c.min, c.max) if q is not None]
    if any(q.dimension != "frequency" or q.value <= 0 for q in bounds):
        return False
    return c.min is None or c.max is None or quantity_base(c.min) <= quantity_base(c.max)


def _allowed_periods(c: s.ActivationConstraint) -> str:
    if c.min is not None and c.max is not None:
        if c.min == c.max:
            return fmt_time(1 / quantity_hertz(c.max))
        return f"{fmt_time(1 / quantity_hertz(c.max))} .. {fmt_time(1 / quantity_hertz(c.min))}"
    if c.max is not None:
        return f"at least {fmt_time(1 / quantity_hertz(c.max))}"
    assert c.min is not None, "a constraint has a bound"
    return f"at most {fmt_time(1 / quantity_hertz(c.min))}"




def _constraint_text(c: s.ActivationConstraint) -> str:
    if c.min is not None and c.max is not None:
        if c.min == c.max:
            return fmt_quantity(c.min)
        return f"{fmt_quantity(c.min)} .. {fmt_quantity(c.max)}"
    if c.min is not None:
        return f"at least {fmt_quantity(c.min)}"
    assert c.max is not None, "a constraint has a bound"
    return f"at most {fmt_quantity(c.max)}"


def _fixed_binding_hint(c: s.ActivationConstraint) -> str:
    if c.min is not None and c.max is not None and c.min == c.max:
        return f"timer {fmt_quantity(c.min)}"
    if c.min is not None and c.max is not None:
        return f"sporadic {fmt_quantity(c.min)} .. {fmt_quantity(c.max)}"
    return "sporadic ..."


def _check_trigger_reads(act: s.Trigger, task: s.Task, comp: ComponentScope, who: str, sink: DiagnosticSink) -> None:
    node = comp.get(act.port.text)
    members = [m.text for m in node.members] if isinstance(node, s.CompoundPort) else [act.port.text]
    read = {r.port.text for r in task.reads}
    missing = [m for m in members if m not in read]
    if missing:
        sink.emit("E215", f"task {who} is triggered by `{act.port.text}` but does not read "
                  + ", ".join(f"`{m}`" for m in missing), act.port.span, "trigger port not read",
                  secondary=(Label(task.name.span, "task declared here"),),
                  help=f"add `reads {missing[0]}` to task `{task.name.text}` of component `{comp.name}`")


# ------------------------------------------------------------------ connections


def _port_node(scope: SystemScope, ref: s.PortRef) -> MemberNode | None:
    comp = scope.component_of.get(ref.instance.text)
    return comp.get(ref.member.text) if comp else None


def _check_connections(scope: SystemScope, sink: DiagnosticSink) -> None:
    incoming: dict[str, s.Connection] = {}
    for conn in scope.system.connections:
        src, dst = _port_node(scope, conn.source), _port_node(scope, conn.target)
        if isinstance(src, s.OutPort) and isinstance(dst, s.InPort) and src.type.text != dst.type.text:
            sink.emit("E201", f"`{conn.source}` carries `{src.type.text}` but `{conn.target}` expects "
                      f"`{dst.type.text}`", conn.span, "types differ",
                      secondary=(Label(src.type.span, f"declared `{src.type.text}` here"),
                                 Label(dst.type.span, f"declared `{dst.type.text}` here")),
                      help="connect ports of the same type")
        key = str(conn.target)
        if key in incoming:
            sink.emit("E211", f"in-port `{key}` has more than one incoming connection", conn.span,
                      "second connection", secondary=(Label(incoming[key].span, "first connection"),),
                      help="an in-port has one writer; declare separate in-ports and, to react to either, "
                           "an OR compound (`in any = a | b`)")
        else:
            incoming[key] = conn
        _dimension(conn.delay_min, "time", "delay", sink) and _positive(conn.delay_min, "delay", sink, True)
        if conn.delay_max is not conn.delay_min:
            _dimension(conn.delay_max, "time", "delay", sink) and _positive(conn.delay_max, "delay", sink, True)
            if (conn.delay_min and conn.delay_max and conn.delay_min.dimension == conn.delay_max.dimension == "time"):
                _ordered(conn.delay_min, conn.delay_max, "delay range", sink,
                         conn.delay_min.span.to(conn.delay_max.span))
    _check_unconnected(scope, incoming, sink)


def _check_unconnected(scope: SystemScope, incoming: dict[str, s.Connection], sink: DiagnosticSink) -> None:
    for inst, comp, task, binding in _instance_tasks(scope):
        act = binding.activation if binding else None
        if isinstance(act, s.Trigger):
            _check_trigger_connected(inst, act, comp, incoming, sink)
        for read in task.reads:
            if not read.optional and f"{inst.name.text}.{read.port.text}" not in incoming:
                sink.emit("E206", f"in-port `{inst.name.text}.{read.port.text}` is required by "
                          f"`{task.name.text}` but not connected", inst.name.span, "instance declared here",
                          secondary=(Label(read.port.span, "read as required here"),),
                          help=f"add `connect SOURCE.port -> {inst.name.text}.{read.port.text}`, "
                               f"or mark the read `optional` in component `{comp.name}`")


def _check_trigger_connected(inst: s.Instance, act: s.Trigger, comp: ComponentScope, incoming: dict[str, s.Connection],
                             sink: DiagnosticSink) -> None:
    node = comp.get(act.port.text)
    members = [m.text for m in node.members] if isinstance(node, s.CompoundPort) else [act.port.text]
    unconnected = [m for m in members if f"{inst.name.text}.{m}" not in incoming]
    never = unconnected and (not isinstance(node, s.CompoundPort) or node.mode == "and"
                             or len(unconnected) == len(members))
    if never:
        sink.emit("E205", f"data trigger on `{inst.name.text}.{act.port.text}`, but "
                  + ", ".join(f"`{inst.name.text}.{m}`" for m in unconnected) + " is not connected",
                  act.port.span, "this trigger never fires",
                  help=f"connect an out-port to `{inst.name.text}.{unconnected[0]}`, or use a timer")


# ------------------------------------------------------------------ trigger cycles


def _trigger_graph(scope: SystemScope) -> tuple[list[str], list[tuple[str, str]], dict[str, str], set[str]]:
    """The trigger graph: its nodes (task ids, in the order they first appear: each bound task, then the
    writers triggering it), its edges writer task → triggered task, the mode ("and" | "or") of each
    triggered task, and the set of tasks with an independent source."""
    nodes: dict[str, None] = {}  # (an ordered set)
    edges: list[tuple[str, str]] = []
    modes: dict[str, str] = {}
    sources: set[str] = set()
    writer_of: dict[str, str] = {}
    for conn in scope.system.connections:
        comp = scope.component_of.get(conn.source.instance.text)
        if comp is None:
            continue
        for task in comp.component.tasks:
            if any(p.text == conn.source.member.text for p in task.produces):
                writer_of[str(conn.target)] = f"{conn.source.instance.text}.{task.name.text}"
    for (inst, task_name), binding in scope.bindings.items():
        tid = f"{inst}.{task_name}"
        nodes[tid] = None
        act = binding.activation
        if not isinstance(act, s.Trigger):
            sources.add(tid)
            continue
        node = scope.component_of[inst].get(act.port.text)
        members = [m.text for m in node.members] if isinstance(node, s.CompoundPort) else [act.port.text]
        modes[tid] = node.mode if isinstance(node, s.CompoundPort) else "and"
        for m in members:
            w = writer_of.get(f"{inst}.{m}")
            if w is not None:
                nodes.setdefault(w, None)
                edges.append((w, tid))
    return list(nodes), edges, modes, sources


def _activated(edges: list[tuple[str, str]], modes: dict[str, str], sources: set[str]) -> set[str]:
    """The tasks that can be activated: the sources, and (to the least fixed point) every task whose
    trigger fires once its writers are: any of them for "or", all of them for "and"."""
    writers: dict[str, set[str]] = {}
    triggered: dict[str, set[str]] = {}
    for w, tid in edges:
        writers.setdefault(tid, set()).add(w)
        triggered.setdefault(w, set()).add(tid)
    live = set(sources)
    waiting = {tid: len(ws) for tid, ws in writers.items()}  # writers not yet known to be activated
    work = list(sources)
    while work:
        for tid in triggered.get(work.pop(), ()):
            if tid in live:
                continue
            waiting[tid] -= 1
            if modes.get(tid, "and") == "or" or not waiting[tid]:
                live.add(tid)
                work.append(tid)
    return live


def _check_trigger_sources(scope: SystemScope, sink: DiagnosticSink) -> None:
    """E210: tasks activated only by data triggers that, around a cycle, can never be activated."""
    nodes, edges, modes, sources = _trigger_graph(scope)
    live = _activated(edges, modes, sources)
    if len(live) == len(nodes):  # (the common case: nothing to report)
        return
    import networkx as nx

    graph: nx.DiGraph[str] = nx.DiGraph()
    graph.add_nodes_from(nodes)
    graph.add_edges_from(edges)
    dead = graph.subgraph(n for n in graph.nodes if n not in live)
    order = {n: i for i, n in enumerate(graph.nodes)}
    for component in sorted(nx.strongly_connected_components(dead), key=sorted):
        members = sorted(component, key=order.__getitem__)
        if len(members) == 1 and not dead.has_edge(members[0], members[0]):
            continue
        cycle = _cycle_through(dead.subgraph(members), members[0], order)
        others = [m for m in members if m not in cycle]
        sink.emit("E210", "these tasks only trigger each other and are never activated: "
                  + " -> ".join(f"`{m}`" for m in cycle + [cycle[0]]), _trigger_span(scope, members[0]),
                  "part of the cycle",
                  secondary=tuple(Label(_trigger_span(scope, m), f"`{m}`") for m in members[1:]),
                  notes=(("in the same cycle of triggers: " + name_list(others),)
                         if others else ()),
                  help="activate one task of the cycle by a timer or a sporadic source")


def _trigger_span(scope: SystemScope, tid: str) -> Span:
    """Where task ``tid`` (in a cycle of triggers: bound, by a data trigger) is bound."""
    inst, task = tid.split(".", 1)
    activation = scope.bindings[(inst, task)].activation
    assert activation is not None, "a task in a cycle of triggers is bound to a trigger"
    return activation.span


def _cycle_through(component: nx.DiGraph[str], first: str, order: dict[str, int]) -> list[str]:
    """A shortest cycle of the strongly connected ``component`` through ``first``, in the direction of the
    triggers, as its nodes from ``first`` on (ties broken by source order, so the text is stable)."""
    import networkx

    best: list[str] | None = None
    for succ in sorted(component.successors(first), key=order.__getitem__):
        back = networkx.shortest_path(component, succ, first)  # succ … first (``[first]`` for a self-loop)
        if best is None or len(back) < len(best):
            best = back
    assert best is not None, "a node of a strongly connected component with an edge has a successor"
    return [first] + best[:-1]


# ------------------------------------------------------------------ chains


def validate_chains(scope: SystemScope, model: SystemModel, sink: DiagnosticSink) -> None:
    """E208/E209: every chain element reachable from the previous one; an unambiguous end."""
    for chain in scope.system.chains:
        _, _, problem = chain_path(chain, model, scope)
        if problem is None:
            continue
        index, kind, detail = problem
        prev, ref = chain.refs[index - 1], chain.refs[index]
        if kind == "ambiguous":
            assert isinstance(detail, tuple), "an ambiguous end names its readers"
            sink.emit("E209", f"chain `{chain.name.text}` ends at in-port `{ref}`, which "
                      + " and ".join(f"`{d}`" for d in detail) + (" both read" if len(detail) == 2 else " all read"),
                      ref.span, "ambiguous end",
                      help=f"close the chain with the consuming task instead, e.g. `{detail[0]}`")
            continue
        notes = _reachability_notes(prev, model)
        end = _port_node(scope, ref)
        if isinstance(end, s.InPort) and kind == "unreachable":
            start = _port_node(scope, prev)
            fixes = []
            if (isinstance(start, s.OutPort) and start.type.text == end.type.text
                    and model.link_into(str(ref)) is None):
                fixes.append(f"add `connect {prev} -> {ref}`")
            if any(lk.source == str(prev) for lk in model.links):
                fixes.append(f"end the chain at an in-port that `{prev}` is connected to")
            sink.emit("E208", f"chain `{chain.name.text}`: `{ref}` is not reachable from `{prev}`", ref.span,
                      "broken link", secondary=(Label(prev.span, "previous element"),), notes=notes,
                      help=", or ".join(fixes) or "correct the chain, or the connections it follows")
            continue
        if kind == "no-reader":
            sink.emit("E208", f"chain `{chain.name.text}`: no task reads `{ref}`", ref.span, "nobody reads this",
                      notes=notes, help="close the chain with an in-port that a task reads, or with the task")
            continue
        sink.emit("E208", f"chain `{chain.name.text}`: `{ref}` is not reachable from `{prev}`", ref.span,
                  "broken link", secondary=(Label(prev.span, "previous element"),),
                  notes=notes + _consumer_notes(ref, scope, model),
                  help=f"connect `{prev}` to an in-port that {_consumer_phrase(ref, scope, model)} reads, "
                       "or correct the order of the chain")


def _reachability_notes(prev: s.PortRef, model: SystemModel) -> list[str]:
    targets = [lk for lk in model.links if lk.source == str(prev)]
    if not targets:
        return [f"`{prev}` is not connected to anything"]
    return [f"`{prev}` is connected to `{lk.target}`"
            + (f" (read by {', '.join(f'`{r}`' for r in lk.readers)})" if lk.readers else " (read by no task)")
            for lk in targets]


def _consumer_phrase(ref: s.PortRef, scope: SystemScope, model: SystemModel) -> str:
    kind = scope.component_of[ref.instance.text].kind_of(ref.member.text)
    if kind == "out-port":
        return f"`{model.producer(str(ref))}`"
    if kind == "task":
        return f"`{ref}`"
    return "a task"


def _consumer_notes(ref: s.PortRef, scope: SystemScope, model: SystemModel) -> list[str]:
    comp = scope.component_of[ref.instance.text]
    if comp.kind_of(ref.member.text) != "out-port":
        return []
    producer = model.producer(str(ref))
    assert producer is not None, "a task produces every out-port (E202)"
    task = model.task(producer)
    reads = ", ".join(f"`{r.port}`" for r in task.reads) or "nothing"
    return [f"`{ref}` is produced by `{producer}`, which reads {reads}"]


# ================================================================== entry point


def validate(resolution: Resolution, sink: DiagnosticSink) -> None:
    """Run every component and system rule; collect all diagnostics."""
    for component in resolution.components.values():
        validate_component(component, sink)
    for system in resolution.systems.values():
        if system.resolved:
            validate_system(system, sink)
