"""Activation rates, CPA event models and sampling relations (specs/timing.md §5).

Three results per system, all exact:

* ``ActivationInfo`` per task: the resolved activation and its **rate interval** in hertz (§5.1):
  ``1/T`` for a timer, ``[1/a⁺, 1/a⁻]`` for a sporadic source, the writer's rate divided by the
  prescaler for a data trigger, the minimum of the members for an AND compound, the sum for OR.
* ``EventModel`` per task: the activation stream in the sense of compositional performance analysis
  (Richter 2005; Henia et al. 2005, "SymTA/S"), as a period/jitter pair for the minimum distances
  (``δ⁻(n) = max(0, (n−1)·P⁻ − J⁻)``, used for interference) and one for the maximum distances
  (``δ⁺(n) = (n−1)·P⁺ + J⁺``, used for sampling waits), plus a bound ``F`` on the first activation
  (§5.2). Event models of data-triggered tasks depend on response times; the façade iterates.
* ``LinkSampling`` per connection and reader: over-, undersampled or matched, with the factor (§5.3).

``None`` always means "not bounded" (an unknown rate in a trigger cycle, a jitter that depends on an
unbounded response time); a task that is never activated has a ``silent`` event model.
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from functools import cached_property
from fractions import Fraction
from collections.abc import Iterable, Mapping
from typing import Any


from ..core.construct import direct_constructor
from ..core.diagnostics import DiagnosticSink, Label, name_list
from ..model.syntax import Tolerance
from ..core.ids import TaskId
from ..model.system import CompoundModel, LinkModel, SystemModel, TaskModel
from ..model.units import fmt_number, fmt_rate

ZERO = Fraction(0)


def exact_sum(values: Iterable[Fraction | int]) -> Fraction:
    """``sum(values, Fraction(0))`` for Fractions and ints, computed on one common denominator with a
    single normalisation at the end (a ``Fraction`` addition costs two gcds and a new object)."""
    return ratio_sum(v.as_integer_ratio() for v in values)


def ratio_sum(pairs: Iterable[tuple[int, int]]) -> Fraction:
    """Σ n/d over (n, d) pairs (d > 0), exactly."""
    num, den = 0, 1
    for n, d in pairs:
        if d == den:
            num += n
        else:
            common = math.lcm(den, d)
            num = num * (common // den) + n * (common // d)
            den = common
    return Fraction(num, den)


# ================================================================== rate intervals (§5.1)


@dataclass(frozen=True)
class RateInterval:
    """Long-run activation frequencies in hertz, ``low <= high``."""

    low: Fraction
    high: Fraction

    @property
    def is_point(self) -> bool:
        return self.low == self.high

    def divided(self, k: int) -> RateInterval:
        return _new_rate_interval(self.low / k, self.high / k)

    def __str__(self) -> str:
        if self.is_point:
            return fmt_rate(self.low)
        return f"{fmt_rate(self.low)} .. {fmt_rate(self.high)}"


@dataclass(frozen=True)
class Source:
    """One member of a data trigger: the in-port, the connection into it and its writer task."""

    member: str  # local in-port name
    port: str  # "inst.port"
    writer: TaskId | None  # None: the in-port is not connected
    link: LinkModel | None


@dataclass(frozen=True)
class ActivationInfo:
    """The resolved activation of one task and its rate (§5.1).

    ``kind`` is "timer", "sporadic", "trigger" or "hole"; ``rate`` is None when it is not bounded
    (a task in a trigger cycle, or downstream of one, or a hole). ``derivation`` shows how the rate
    was computed, e.g. ``"40 Hz / 10"``.
    """

    task: str
    kind: str
    rate: RateInterval | None
    derivation: str
    period: Fraction | None = None  # timer
    phase: Fraction | None = None  # timer, when fixed
    interarrival: tuple[Fraction, Fraction] | None = None  # sporadic (a⁻, a⁺)
    trigger_port: str | None = None  # local port or compound name
    mode: str | None = None  # "single" | "and" | "or"
    prescaler: int | None = None
    sources: tuple[Source, ...] = ()
    in_cycle: bool = False

    @property
    def timed(self) -> bool:
        """Released by time (a period or an interarrival range), not by data."""
        return self.period is not None or self.interarrival is not None


#: the constructors of the objects above, built by the thousand (``verify.core.construct``)
_new_rate_interval = direct_constructor(RateInterval)
_new_source = direct_constructor(Source)
_new_activation_info = direct_constructor(ActivationInfo)


def trigger_sources(system: SystemModel, task: TaskModel) -> tuple[Source, ...]:
    """The members of ``task``'s data trigger with the connection into each (``model.link_into``)."""
    out = []
    for member in task.activation.trigger_members:
        port = f"{task.instance}.{member}"
        link = system.link_into(port)
        out.append(_new_source(member, port, link.writer if link else None, link))
    return tuple(out)


def trigger_order(system: SystemModel) -> tuple[tuple[str, ...], frozenset[str]]:
    """All task ids with every writer of a trigger member before the triggered task, and the set of
    tasks that lie on a trigger cycle (validation only lets cycles through an OR with a live member).

    The order is the lexicographical topological order of the trigger graph's strongly connected
    components, each keyed by its first member in system order, members in system order (as
    ``networkx.lexicographical_topological_sort`` of ``networkx.condensation`` gives it)."""
    tasks = system.tasks
    position = {t.id: i for i, t in enumerate(tasks)}
    successors: list[list[int]] = [[] for _ in tasks]
    for i, t in enumerate(tasks):
        for src in trigger_sources(system, t):
            if src.writer is not None:
                successors[position[src.writer]].append(i)
    order, cyclic = graph_order(successors)
    return tuple(tasks[i].id for i in order), frozenset(tasks[i].id for i in cyclic)


def graph_order(successors: list[list[int]]) -> tuple[list[int], set[int]]:
    """``trigger_order`` of a graph on the nodes 0..n−1 (in system order)."""
    component = _strongly_connected(successors)
    members: dict[int, list[int]] = {}
    for i, c in enumerate(component):
        members.setdefault(c, []).append(i)  # in system order
    cyclic = {i for ms in members.values() if len(ms) > 1 for i in ms}
    cyclic |= {w for w, succ in enumerate(successors) if w in succ}
    indegree = dict.fromkeys(members, 0)
    edges: dict[int, set[int]] = {c: set() for c in members}
    for w, succ in enumerate(successors):
        for i in succ:
            a, b = component[w], component[i]
            if a != b and b not in edges[a]:
                edges[a].add(b)
                indegree[b] += 1
    ready = [(ms[0], c) for c, ms in members.items() if not indegree[c]]
    heapq.heapify(ready)
    order: list[int] = []
    while ready:
        _, c = heapq.heappop(ready)
        order.extend(members[c])
        for b in edges[c]:
            indegree[b] -= 1
            if not indegree[b]:
                heapq.heappush(ready, (members[b][0], b))
    return order, cyclic


def _strongly_connected(successors: list[list[int]]) -> list[int]:
    """The strongly connected component of every node (Tarjan's algorithm, iterative)."""
    n = len(successors)
    index = [-1] * n
    low = [0] * n
    component = [-1] * n
    on_stack = [False] * n
    stack: list[int] = []
    counter = 0
    for root in range(n):
        if index[root] >= 0:
            continue
        work = [(root, 0)]
        while work:
            v, k = work.pop()
            if k == 0:
                index[v] = low[v] = counter
                counter += 1
                stack.append(v)
                on_stack[v] = True
            succ = successors[v]
            while k < len(succ):
                u = succ[k]
                k += 1
                if index[u] < 0:
                    work.append((v, k))
                    work.append((u, 0))
                    break
                if on_stack[u]:
                    low[v] = min(low[v], index[u])
            else:
                if low[v] == index[v]:
                    while True:
                        u = stack.pop()
                        on_stack[u] = False
                        component[u] = v
                        if u == v:
                            break
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[v])
    return component


def activation_rates(system: SystemModel, order: tuple[tuple[str, ...], frozenset[str]] | None = None
                     ) -> dict[str, ActivationInfo]:
    """The rate of every task, propagated in trigger order (§5.1); ``order``: ``trigger_order(system)``
    if already known."""
    ids, cyclic = order or trigger_order(system)
    infos: dict[str, ActivationInfo] = {}
    timers: _Timers = {}  # a system has few distinct periods
    for tid in ids:
        infos[tid] = _activation_info(system, system.task(tid), infos, tid in cyclic, timers)
    return infos


#: a timer period (as an integer ratio) -> its (rate interval, derivation)
_Timers = dict[tuple[int, int], tuple[RateInterval, str]]


def _activation_info(system: SystemModel, task: TaskModel, known: Mapping[str, ActivationInfo],
                     in_cycle: bool, timers: _Timers | None = None) -> ActivationInfo:
    act = task.activation
    if act.strict_period is not None:
        key = act.strict_period.as_integer_ratio()
        found = timers.get(key) if timers is not None else None
        if found is None:
            hz = Fraction(1) / act.strict_period
            found = (_new_rate_interval(hz, hz), act.describe())
            if timers is not None:
                timers[key] = found
        return _new_activation_info(task.id, act.kind, found[0], found[1], period=act.strict_period,
                                    phase=act.fixed_phase)
    if act.gaps is not None:
        low, high = act.gaps
        return _new_activation_info(task.id, act.kind, _new_rate_interval(1 / high, 1 / low), act.describe(),
                                    interarrival=act.gaps)
    port, mode = act.trigger_port, act.trigger_mode
    if port is not None and mode is not None:
        sources = trigger_sources(system, task)
        rate, text = _trigger_rate(mode, act.release_every, sources, known, in_cycle)
        return _new_activation_info(task.id, act.kind, rate, text, trigger_port=port, mode=mode,
                                    prescaler=act.release_every, sources=sources, in_cycle=in_cycle)
    return _new_activation_info(task.id, act.kind, None, "not bounded: unresolved synthesis hole")


def _trigger_rate(mode: str, prescaler: int, sources: tuple[Source, ...], known: Mapping[str, ActivationInfo],
                  in_cycle: bool) -> tuple[RateInterval | None, str]:
    """Writer rate / k (single), min of members (AND), sum of members (OR), then / prescaler."""
    if in_cycle:
        return None, "not bounded: the trigger depends on its own output (trigger cycle)"
    combined, text = _event_rate(mode, sources, known)
    if combined is None:
        return None, text
    if prescaler != 1:
        text = f"({text}) / {prescaler}" if mode == "or" else f"{text} / {prescaler}"
    return combined.divided(prescaler), text


def _event_rate(mode: str, sources: tuple[Source, ...], known: Mapping[str, ActivationInfo]
                ) -> tuple[RateInterval | None, str]:
    """The rate of a trigger's activation events before any prescaler (§5.1): the writer's (single),
    the minimum of the members (AND), their sum (OR)."""
    rates: list[RateInterval | None] = []
    for src in sources:
        if src.writer is None:
            rates.append(_new_rate_interval(ZERO, ZERO))
        else:
            rates.append(known[src.writer].rate)
    parts = [("0 Hz (unconnected)" if s.writer is None else str(r) if r is not None else "unbounded")
             for s, r in zip(sources, rates)]
    bounded = [r for r in rates if r is not None]
    if len(bounded) < len(rates):
        return None, "not bounded: a writer's rate is not bounded"
    combined: RateInterval
    if mode == "and":
        combined = _new_rate_interval(min(r.low for r in bounded), min(r.high for r in bounded))
        text = f"min({', '.join(parts)})"
    elif mode == "or":
        combined = _new_rate_interval(sum((r.low for r in bounded), ZERO), sum((r.high for r in bounded), ZERO))
        text = " + ".join(parts)
    else:
        combined, text = bounded[0], parts[0]
    return combined, text


# ================================================================== event models (§5.2)


@dataclass(frozen=True)
class EventModel:
    """A CPA event model (Richter 2005; Henia et al. 2005: the periodic-with-jitter model), exact.

    Minimum distances ``δ⁻(n) = max(0, (n−1)·period_min − jitter_min)`` bound how densely
    activations come (interference, ``η⁺``); maximum distances ``δ⁺(n) = (n−1)·period_max +
    jitter_max`` bound how long a task may wait for its next activation. ``first_max`` bounds the
    first activation. Any field None: not bounded. ``silent``: the task is never activated.
    """

    period_min: Fraction | None
    jitter_min: Fraction | None
    period_max: Fraction | None
    jitter_max: Fraction | None
    first_max: Fraction | None
    silent: bool = False

    def eta_plus(self, window: Fraction) -> int | None:
        """``η⁺(Δ) = ⌈(Δ + J⁻)/P⁻⌉``: most activations in a half-open window of length Δ (§5.2)."""
        if self.silent or window <= 0:
            return 0
        if self.period_min is None or self.jitter_min is None:
            return None
        return math.ceil((window + self.jitter_min) / self.period_min)

    def delta_min(self, n: int) -> Fraction | None:
        """``δ⁻(n)``: least distance from the first to the n-th of n consecutive activations."""
        if n <= 1:
            return ZERO
        if self.silent:
            return None  # never: no second activation
        if self.period_min is None or self.jitter_min is None:
            return ZERO
        return max(ZERO, (n - 1) * self.period_min - self.jitter_min)

    def delta_plus(self, n: int) -> Fraction | None:
        """``δ⁺(n)``: greatest distance from the first to the n-th of n consecutive activations."""
        if n <= 1:
            return ZERO
        if self.silent or self.period_max is None or self.jitter_max is None:
            return None
        span = self.period_max if n == 2 else (n - 1) * self.period_max
        return span + self.jitter_max if self.jitter_max else span  # (Fraction arithmetic is slow)

    # the derived bounds below are read many times (deadlines, every chain step): computed once
    @cached_property
    def a_max(self) -> Fraction | None:
        """A⁺ = δ⁺(2): the longest time between two consecutive activations."""
        return self.delta_plus(2)

    @cached_property
    def a_min(self) -> Fraction | None:
        """A⁻ = δ⁻(2): the shortest time between two consecutive activations."""
        return self.delta_min(2)

    @cached_property
    def sampling_wait(self) -> Fraction | None:
        """W⁺ = max(A⁺, F): from any instant t ≥ 0, the next activation after t comes within W⁺."""
        if self.a_max is None or self.first_max is None:
            return None
        return max(self.a_max, self.first_max)


_new_event_model = direct_constructor(EventModel)  # (``verify.core.construct``: built by the thousand)


SILENT = EventModel(None, None, None, None, None, silent=True)
UNBOUNDED = EventModel(None, None, None, None, None)


def _add(a: Fraction | None, b: Fraction | None) -> Fraction | None:
    return None if a is None or b is None else a + b


def source_event_model(task: TaskModel) -> EventModel:
    """Timer ``(T, 0, T, 0)``, first release at the phase (< T); sporadic ``(a⁻, 0, a⁺, 0)``, first
    release before a⁺ (§3)."""
    act = task.activation
    if act.gaps is not None:
        return _new_event_model(act.gaps[0], ZERO, act.gaps[1], ZERO, act.first_release_latest)
    return UNBOUNDED


def output_jitter(wcrt: Fraction | None, bcrt: Fraction, link: LinkModel) -> Fraction | None:
    """The jitter a link adds to its writer's activation stream: ``(R − B) + (d⁺ − d⁻)`` (CPA output
    model, Henia et al. 2005 §3.2; FIFO delivery keeps every arrival in ``[r + B + d⁻, r + R + d⁺]``)."""
    if wcrt is None:
        return None
    return (wcrt - bcrt) + (link.delay_max - link.delay_min)


def arrival_model(writer: EventModel, wcrt: Fraction | None, bcrt: Fraction, link: LinkModel) -> EventModel:
    """The arrivals on ``link.target`` of the values its writer produces (one per writer job)."""
    if writer.silent:
        return SILENT
    extra = output_jitter(wcrt, bcrt, link)
    first = _add(_add(writer.first_max, wcrt), link.delay_max)
    return _new_event_model(writer.period_min, _add(writer.jitter_min, extra), writer.period_max,
                            _add(writer.jitter_max, extra), first)


def combine_or(members: list[EventModel]) -> EventModel:
    """Every arrival on any member is an event (§3). ``η⁺`` of the union is at most the sum of the
    members' ``η⁺``, which the period ``P = 1/Σ(1/Pₘ)`` with jitter ``P·(Σ Jₘ/Pₘ + M − 1)`` covers
    (§5.2); the maximum distances are those of one member m (the one with the smallest W⁺), with
    ``max(0, Fₘ − P⁺ₘ)`` more jitter in case m starts after the first OR event."""
    live = [m for m in members if not m.silent]
    if not live:
        return SILENT
    if len(live) == 1:
        return live[0]
    known = [(p, j) for p, j in ((m.period_min, m.jitter_min) for m in live) if p is not None and j is not None]
    period: Fraction | None = None
    jitter: Fraction | None = None
    if len(known) == len(live):
        period = 1 / sum((1 / p for p, _ in known), ZERO)
        jitter = period * (sum((j / p for p, j in known), ZERO) + len(live) - 1)
    bounded = [m for m in live if m.sampling_wait is not None]
    best = min(bounded, key=lambda m: (m.sampling_wait, m.period_max)) if bounded else None
    firsts = [m.first_max for m in live if m.first_max is not None]
    jitter_max: Fraction | None = None
    if best is not None:  # (it has a sampling wait, so a first release and a maximum period and jitter)
        best_jitter, best_first, best_period = best.jitter_max, best.first_max, best.period_max
        if best_jitter is not None and best_first is not None and best_period is not None:
            jitter_max = best_jitter + max(ZERO, best_first - best_period)
    return _new_event_model(period, jitter, best.period_max if best else None, jitter_max,
                            min(firsts) if firsts else None)


def combine_and(members: list[EventModel]) -> EventModel:
    """An event needs a fresh value on every member (§3). n events span at least n−1 arrivals of each
    member, so ``δ⁻(n) ≥ δ⁻ₘ(n−1)``: period Pₘ, jitter Jₘ + Pₘ of the slowest member. They also span
    n arrivals of the member whose arrival completed the first of them, so ``δ⁻(n) ≥ minₘ δ⁻ₘ(n)``:
    period minₘ Pₘ, jitter maxₘ Jₘ; where every member has the slowest one's period, that model is
    used if its jitter is the smaller. After an event the next comes once every member has a new
    arrival: ``δ⁺(n) ≤ (n−1)·maxₘ A⁺ₘ`` (§5.2)."""
    if not members or any(m.silent for m in members):
        return SILENT
    known = [(p, j) for p, j in ((m.period_min, m.jitter_min) for m in members) if p is not None and j is not None]
    period: Fraction | None = None
    jitter: Fraction | None = None
    if known:
        period, slowest_jitter = max(known, key=lambda pj: (pj[0], -pj[1]))  # the slowest member
        jitter = slowest_jitter + period
        if len(known) == len(members) and all(p == period for p, _ in known):
            jitter = min(jitter, max(j for _, j in known))
    gap = _greatest_if_all([m.a_max for m in members])
    first = _greatest_if_all([m.first_max for m in members])
    return _new_event_model(period, jitter, gap, ZERO if gap is not None else None, first)


def _greatest_if_all(values: list[Fraction | None]) -> Fraction | None:
    """The greatest of ``values`` when none is None, else None."""
    known = [v for v in values if v is not None]
    return max(known) if len(known) == len(values) else None


def first_of_k(stream: EventModel, members: list[EventModel], mode: str, k: int) -> Fraction | None:
    """The latest time of the k-th event of a trigger stream (the prescaler counter may start at 0)."""
    if k == 1 or stream.first_max is None:
        return stream.first_max
    if mode == "or":
        bounds = [_add(m.first_max, m.delta_plus(k)) for m in members if not m.silent]
        known = [b for b in bounds if b is not None]
        return min(known) if known else None
    return _add(stream.first_max, stream.delta_plus(k))


def prescaled(stream: EventModel, k: int, first: Fraction | None) -> EventModel:
    """Every k-th event: ``δ(n) = δ_stream((n−1)·k + 1)``, i.e. periods times k, jitters unchanged."""
    if stream.silent or k == 1:
        return stream if k == 1 else SILENT
    def mul(p: Fraction | None) -> Fraction | None:
        return None if p is None else p * k

    return _new_event_model(mul(stream.period_min), stream.jitter_min, mul(stream.period_max),
                            stream.jitter_max, first)


def trigger_stream(members: list[EventModel], mode: str) -> EventModel:
    """The activation-event stream of a data trigger before its prescaler."""
    if mode == "and":
        return combine_and(members)
    if mode == "or":
        return combine_or(members)
    return members[0] if members else SILENT


def event_models(system: SystemModel, infos: Mapping[str, ActivationInfo], order: tuple[str, ...],
                 wcrt: Mapping[str, Fraction | None], bcrt: Mapping[str, Fraction],
                 memo: dict[str, Any] | None = None) -> dict[str, EventModel]:
    """The activation event model of every task, given response-time estimates (§5.2).

    ``memo``, kept by the caller across CPA rounds, lets a task keep last round's model *object* when
    nothing it depends on changed (the values are the same either way), so that what is derived from
    it (``a_max`` and the like, ``fastrta``'s per-task data) need not be computed again. Its entry for a
    source is its ``EventModel``; for a trigger (what its model was computed from, the model)."""
    models: dict[str, EventModel] = {}
    for tid in order:
        info = infos[tid]
        if info.timed:
            model = memo.get(tid) if memo is not None else None
            if model is None:
                model = source_event_model(system.task(tid))
                if memo is not None:
                    memo[tid] = model
            models[tid] = model
        elif info.trigger_port is not None and not info.in_cycle:
            if memo is not None:
                key = [(models.get(src.writer), wcrt.get(src.writer)) for src in info.sources if src.writer]
                last = memo.get(tid)
                if last is not None and len(last[0]) == len(key) and all(
                        a[0] is b[0] and a[1] == b[1] for a, b in zip(last[0], key)):
                    models[tid] = last[1]
                    continue
            arrivals = member_arrivals(info, models, wcrt, bcrt)
            stream = trigger_stream(arrivals, info.mode or "single")
            k = info.prescaler or 1
            models[tid] = prescaled(stream, k, first_of_k(stream, arrivals, info.mode or "single", k))
            if memo is not None:
                memo[tid] = (key, models[tid])
        else:
            models[tid] = UNBOUNDED
    return models


def member_arrivals(info: ActivationInfo, models: Mapping[str, EventModel],
                    wcrt: Mapping[str, Fraction | None], bcrt: Mapping[str, Fraction]) -> list[EventModel]:
    """The arrival stream on every member of ``info``'s trigger (SILENT for an unconnected one)."""
    out = []
    for src in info.sources:
        if src.writer is None or src.link is None:
            out.append(SILENT)
        else:
            out.append(arrival_model(models.get(src.writer, UNBOUNDED), wcrt.get(src.writer),
                                     bcrt[src.writer], src.link))
    return out


# ================================================================== sampling (§5.3)


@dataclass(frozen=True)
class LinkSampling:
    """How ``reader`` samples the values of ``link``: its activation rate against the writer's.

    ``oversampling`` = reader rate / writer rate and ``undersampling`` = writer rate / reader rate,
    each in its worst direction over the rate intervals (reader fastest against writer slowest, and
    vice versa); a factor is reported only when it exceeds 1, and None inside a flag that is True
    means "unbounded" (a writer or reader that may stop). A reader triggered by this very in-port
    (not a compound) is matched, or undersampled by exactly its prescaler (``by_trigger``).
    """

    source: str
    target: str
    writer: str
    reader: str
    writer_rate: RateInterval | None
    reader_rate: RateInterval | None
    relation: str  # "matched" | "oversampled" | "undersampled" | "varies" | "unknown"
    oversampled: bool
    oversampling: Fraction | None
    undersampled: bool
    undersampling: Fraction | None
    by_trigger: bool = False


_new_link_sampling = direct_constructor(LinkSampling)  # (``verify.core.construct``: built by the thousand)


def sampling_relations(system: SystemModel, infos: Mapping[str, ActivationInfo]) -> tuple[LinkSampling, ...]:
    """Every (connection, reader) pair, in connection order."""
    return tuple(_sampling(system, link, reader, infos) for link in system.links for reader in link.readers)


def _ratio(num: Fraction, den: Fraction) -> Fraction | None:
    return None if den == 0 else num / den


def _sampling(system: SystemModel, link: LinkModel, reader: str,
              infos: Mapping[str, ActivationInfo]) -> LinkSampling:
    w, r = infos[link.writer].rate, infos[reader].rate
    act = system.task(reader).activation
    member = link.target.split(".", 1)[1]
    if act.single_port == member:
        k = Fraction(act.release_every)
        return _new_link_sampling(link.source, link.target, link.writer, reader, w, r,
                                  "matched" if k == 1 else "undersampled", False, None, k > 1,
                                  k if k > 1 else None, by_trigger=True)
    if w is None or r is None:
        return _new_link_sampling(link.source, link.target, link.writer, reader, w, r, "unknown",
                                  False, None, False, None)
    over, under = _ratio(r.high, w.low), _ratio(w.high, r.low)
    is_over = over is None or over > 1
    is_under = under is None or under > 1
    if r.high == 0:
        is_over = False  # a reader that never runs samples nothing
    if w.high == 0:
        is_under = False
    relation = {(False, False): "matched", (True, False): "oversampled",
                (False, True): "undersampled", (True, True): "varies"}[(is_over, is_under)]
    return _new_link_sampling(link.source, link.target, link.writer, reader, w, r, relation,
                              is_over, over if is_over else None, is_under, under if is_under else None)


def _factor_text(value: Fraction | None) -> str:
    return "an unbounded factor" if value is None else f"a factor of {fmt_number(value)}"


def tolerance_limit(tol: Tolerance) -> Fraction:
    """The greatest over- or undersampling factor a tolerance that is not ``ok`` allows: 1 when it is
    forbidden, else its factor (at least 1)."""
    if tol.kind == "forbidden" or tol.factor is None:
        return Fraction(1)
    return max(Fraction(1), Fraction(tol.factor.value))


def tolerance_violation(tol: Tolerance | None, flagged: bool, factor: Fraction | None) -> str | None:
    """The tolerance's wording if a flagged factor violates it, else None."""
    if tol is None or not flagged or tol.kind == "ok":
        return None
    if tol.kind == "forbidden":
        return "forbidden"
    limit = tol.factor.value if tol.factor is not None else None
    if limit is None:
        return None
    if factor is None or factor > limit:
        return f"at most {fmt_number(limit)}"
    return None


def _rates_text(s: LinkSampling, direction: str) -> str:
    # only a flagged relation is described: a prescaler above 1, or both rates known
    if s.by_trigger:
        assert s.undersampling is not None
        return f"triggered by this port with prescaler {fmt_number(s.undersampling)}"
    w, r = s.writer_rate, s.reader_rate
    assert w is not None and r is not None
    if direction == "over":
        text = f"reader {fmt_rate(r.high)} / writer {fmt_rate(w.low)}"
    else:
        text = f"writer {fmt_rate(w.high)} / reader {fmt_rate(r.low)}"
    if not (w.is_point and r.is_point):
        text += "; rate intervals compared in their worst direction"
    return text


def check_sampling(system: SystemModel, samplings: tuple[LinkSampling, ...], sink: DiagnosticSink) -> None:
    """E310: a read whose over- or undersampling exceeds its tolerance (§5.3)."""
    for s in samplings:
        task = system.task(s.reader)
        port = s.target.split(".", 1)[1]
        read = next((rd for rd in task.reads if rd.port == port), None)
        if read is None:
            continue
        for direction, tol, flagged, factor in (("over", read.oversampling, s.oversampled, s.oversampling),
                                                ("under", read.undersampling, s.undersampled, s.undersampling)):
            allowed = tolerance_violation(tol, flagged, factor)
            if allowed is None:
                continue
            assert tol is not None  # a violated tolerance exists
            link = system.link_into(s.target)
            secondary: tuple[Label, ...] = (Label(link.span, f"`{s.writer}` writes here"),) if link else ()
            if tol.span is not None and getattr(tol.span, "line", None):
                secondary += (Label(tol.span, "the tolerance"),)
            sink.emit("E310", f"`{s.reader}` reads `{port}` {direction}sampled by {_factor_text(factor)} "
                      f"({_rates_text(s, direction)}); its {direction}sampling tolerance is {allowed}",
                      task.span, f"{direction}samples `{port}`", secondary=secondary,
                      notes=(f"writer `{s.writer}` runs at {s.writer_rate or 'an unbounded rate'}, reader "
                             f"`{s.reader}` at {s.reader_rate or 'an unbounded rate'}",),
                      help="change the reader's or the writer's rate, or relax the tolerance")


def check_trigger_constraints(system: SystemModel, infos: Mapping[str, ActivationInfo],
                              sink: DiagnosticSink) -> None:
    """E305/E306: a data-triggered task whose propagated rate leaves its activation constraint
    (timer and sporadic bindings are checked by validation); E314: a compound in-port whose event rate
    leaves its own constraint (``check_compound_constraints``)."""
    check_compound_constraints(system, infos, sink)
    for task in system.tasks:
        info = infos[task.id]
        if info.trigger_port is None or info.rate is None:
            continue
        if task.min_rate is None and task.max_rate is None:
            continue
        low_ok = task.min_rate is None or info.rate.low >= task.min_rate
        high_ok = task.max_rate is None or info.rate.high <= task.max_rate
        if low_ok and high_ok:
            continue
        code = "E305" if task.changeable else "E306"
        where = (f"below its minimum activation rate {fmt_rate(task.min_rate)}" if not low_ok
                 else f"above its maximum activation rate {fmt_rate(task.max_rate)}")
        sink.emit(code, f"`{task.id}` is activated at {info.rate} ({info.derivation}), {where}",
                  task.span, f"activated at {info.rate}",
                  notes=(f"the constraint is {_constraint_text(task)}",),
                  help="change the prescaler or the writer's rate"
                  + ("" if task.changeable else "; the component fixes this rate"))


def compound_rate(system: SystemModel, compound: CompoundModel, infos: Mapping[str, ActivationInfo]
                  ) -> tuple[RateInterval | None, str]:
    """The rate of a compound in-port's events (§5.1, before any prescaler), with its derivation;
    None when a member's writer has no bounded rate (a trigger cycle, a synthesis hole)."""
    sources = []
    for member in compound.members:
        port = f"{compound.instance}.{member}"
        link = system.link_into(port)
        sources.append(_new_source(member, port, link.writer if link else None, link))
    return _event_rate(compound.mode, tuple(sources), infos)


def check_compound_constraints(system: SystemModel, infos: Mapping[str, ActivationInfo],
                               sink: DiagnosticSink) -> None:
    """E314: a compound in-port whose event rate leaves its own activation constraint (§5.1). The
    constraint is a requirement, like a task's: nothing enforces it, so the rate is never clamped."""
    for compound in system.compounds:
        if not compound.constrained:
            continue
        rate, derivation = compound_rate(system, compound, infos)
        if rate is None:
            continue  # unbounded: reported where it matters (E312)
        low_ok = compound.min_rate is None or rate.low >= compound.min_rate
        high_ok = compound.max_rate is None or rate.high <= compound.max_rate
        if low_ok and high_ok:
            continue
        where = (f"below its minimum activation rate {fmt_rate(compound.min_rate)}" if not low_ok
                 else f"above its maximum activation rate {fmt_rate(compound.max_rate)}")
        kind = "AND" if compound.mode == "and" else "OR"
        secondary = [Label(compound.constraint_span, "fixed by the component" if not compound.changeable
                           else "constraint declared here")]
        for member in compound.members:
            link = system.link_into(f"{compound.instance}.{member}")
            if link is not None:
                secondary.append(Label(link.span, f"`{link.writer}` writes `{member}` at {infos[link.writer].rate}"))
        triggered = [t.id for t in system.tasks if t.instance == compound.instance
                     and t.activation.trigger_port == compound.name]
        text = _constraint_text(compound)
        notes = [f"the constraint is {text}" + ("" if compound.changeable or text.endswith("fixed") else " fixed"),
                 "the analysis uses the propagated rate: nothing in the system enforces the constraint"]
        if triggered:
            notes.append("it triggers " + name_list(triggered))
        sink.emit("E314", f"{kind} compound in-port `{compound.id}` is activated at {rate} ({derivation}), {where}",
                  compound.span, f"`{compound.name}` activated at {rate}", secondary=tuple(secondary),
                  notes=tuple(notes),
                  help="change the rates of the tasks writing its members"
                  + (", or the compound's constraint" if compound.changeable else "; the component fixes this rate"))


def _constraint_text(task: TaskModel | CompoundModel) -> str:
    low = fmt_rate(task.min_rate) if task.min_rate is not None else None
    high = fmt_rate(task.max_rate) if task.max_rate is not None else None
    if task.min_rate is not None and task.min_rate == task.max_rate:
        assert low is not None
        return f"{low} fixed" if not task.changeable else low
    if low and high:
        return f"{low} .. {high}"
    return f"min {low}" if low else f"max {high}"
