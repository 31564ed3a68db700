"""Response times of ROS 2 executor callbacks (specs/timing.md §9.3).

An executor is one thread of priority π on its core; its callbacks run one at a time, never preempting
each other, and the thread is preempted by the threads of higher priority on the core (tasks and the
callbacks of executors of higher priority). The bounds are busy-window analyses over the executor's
level-π busy window, in exact rationals:

* **wait-set executors** (``single_threaded``, ``static_single_threaded``): Casini, Blaß, Lütkebohle
  and Brandenburg, *Response-Time Analysis of ROS 2 Processing Chains Under Reservation-Based
  Scheduling*, ECRTS 2019, Lemmas 4–5 and Eq. (6), with every other callback of the executor as an
  interferer (whatever the processing order): for each offset ``A`` of the analysed job in the busy
  window, the least ``F`` with

      F = η̄ᵢ(A)·Cᵢ + Σ_{j ≠ i} η̄ⱼ(F − Cᵢ)·Cⱼ + Σ_{h ∈ hp(π)} η⁺ₕ(F)·Cₕ,

  and ``Rᵢ = max_A (F(A) − A)``. A job of another callback that runs before the analysed job starts
  (at ``F − Cᵢ`` or earlier) arrived no later than that start; the executor is busy whenever it has
  a pending job, so the work done before ``F`` is what the right-hand side counts.
* **events executor** (FIFO): a job waits only for the events queued before it, ties included (Blaß
  et al., ``response-time-analysis-rs``, ``fifo/rta.rs``, with preemption by higher threads):

      F = Σ_{c} η̄_c(A)·C_c + Σ_{h ∈ hp(π)} η⁺ₕ(F)·Cₕ.

``η̄(Δ) = ⌊(Δ + J⁻)/P⁻⌋ + 1`` counts the activations in a closed window of length Δ (``η⁺`` of
``rates.EventModel`` the half-open one). Offsets ``A`` are the steps of ``η̄ᵢ`` in ``[0, L)``, ``L`` the
longest level-π busy window. Absorbed activations (§9.1) only lower the work, so the bounds count every
activation. The time from a callback's start to its completion is its own execution under preemption by
higher threads alone: ``E = Cᵢ + Σ_{hp(π)} η⁺ₕ(E)·Cₕ`` (reported as the task's ``hold``).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import replace
from fractions import Fraction

from ..model.system import ExecutorModel, SystemModel, TaskModel
from .multithreaded import Workers, multi_threaded_response
from .rates import EventModel
from ..core.timebase import TimeBase
from .kernel import (MAX_JOBS, MAX_STEPS, Interferer, TaskResponse, bcrt, deadline_of, interferer, least_fixed_point,
                     ratio)

ZERO = Fraction(0)


def higher_threads(system: SystemModel, executor: ExecutorModel) -> tuple[TaskModel, ...]:
    """hp(π): the tasks of the executor's core whose threads outrank the executor's."""
    return tuple(t for t in system.tasks_on(executor.core) if t.priority > executor.priority)


def executor_responses(system: SystemModel, events: Mapping[str, EventModel],
                       estimates: Mapping[str, Fraction | None]) -> dict[str, TaskResponse]:
    """The response of every callback (the tasks bound to an executor), in system order; what the
    callbacks of one executor share (their streams, the time base, the busy window) is built once."""
    found: dict[str, TaskResponse] = {}
    for executor in system.executors:
        members = system.callbacks(executor.name)
        if executor.multi_threaded:
            workers = Workers(system, executor, events, estimates)
            found.update((t.id, workers.response(t)) for t in members)
        elif members:
            level = _Level(system, executor, events, estimates, members)
            found.update((t.id, level.response(t)) for t in members)
    return {t.id: found[t.id] for t in system.tasks if t.executor is not None}


def callback_response(system: SystemModel, task: TaskModel, events: Mapping[str, EventModel],
                      estimates: Mapping[str, Fraction | None]) -> TaskResponse:
    """WCRT (§9.3) and BCRT (``bcet``) of callback ``task``."""
    assert task.executor is not None
    executor = system.executor(task.executor)
    if executor.multi_threaded:
        return multi_threaded_response(system, task, executor, events, estimates)
    return _Level(system, executor, events, estimates, (task,)).response(task)


class _Stream:
    """A stream of jobs in integer ticks: cost C, least period P, jitter J; silent: never activated."""

    __slots__ = ("cost", "period", "jitter", "silent")

    def __init__(self, cost: int, period: int, jitter: int, silent: bool):
        self.cost, self.period, self.jitter, self.silent = cost, period, jitter, silent

    def closed(self, window: int) -> int:
        """η̄(Δ) = ⌊(Δ + J)/P⌋ + 1: activations in a closed window of length Δ ≥ 0."""
        return 0 if self.silent else (window + self.jitter) // self.period + 1

    def open(self, window: int) -> int:
        """η⁺(Δ) = ⌈(Δ + J)/P⌉: activations in a half-open window of length Δ (0 for Δ ≤ 0)."""
        return 0 if self.silent or window <= 0 else -(-(window + self.jitter) // self.period)


class _Level:
    """The level-π busy window of one executor, for the callbacks ``tasks`` of it: its members' and the
    higher threads' streams in integer ticks of the coarsest base in which every time involved (the
    polling-round bounds of ``tasks`` included) is whole, and the longest busy window ``L``."""

    def __init__(self, system: SystemModel, executor: ExecutorModel, events: Mapping[str, EventModel],
                 estimates: Mapping[str, Fraction | None], tasks: tuple[TaskModel, ...]):
        self.system, self.executor, self.events = system, executor, events
        self.members = system.callbacks(executor.name)
        self.hp = higher_threads(system, executor)
        polling = PollingRounds(system, executor, self.members, self.hp, events, estimates) if executor.polls else None
        self.rounds = {t.id: None if polling is None else polling.bound(t) for t in tasks}
        self.above_flows = [interferer(system, h, events[h.id], estimates.get(h.id), h.wcet) for h in self.hp]
        flows: dict[str, Interferer] = {t.id: interferer(system, t, events[t.id], estimates.get(t.id), t.wcet)
                                        for t in self.members}
        flows.update(zip((h.id for h in self.hp), self.above_flows))
        costs: dict[str, Fraction] = {t.id: t.wcet for t in (*self.members, *self.hp)}
        activated = _activated(flows)
        self.failure = activated if isinstance(activated, str) else None
        self.holds: dict[Fraction, Fraction | None] = {}
        self.children = _local_children(system, self.members)
        self.position = {m.id: k for k, m in enumerate(self.members)}
        self.names = tuple(m.id for m in self.members), tuple(h.id for h in self.hp)
        if isinstance(activated, str):
            return
        times = [v for triple in activated.values() for v in triple]
        caps = [c for c in self.rounds.values() if c is not None]
        self.base = TimeBase.gcd_of(times + caps)
        ticks = self.base.ticks
        self.streams = {tid: _Stream(ticks(costs[tid]), 1, 0, True) if tid not in activated else
                        _Stream(ticks(activated[tid][0]), ticks(activated[tid][1]), ticks(activated[tid][2]), False)
                        for tid in flows}
        self.work = _costs(self.streams[m.id] for m in self.members)  # (per period and jitter, below)
        self.above = _listed(_costs(self.streams[h.id] for h in self.hp))
        everyone = list(self.streams.values())
        self.length = _fixed(lambda w: sum(s.open(w) * s.cost for s in everyone),
                             sum(self.streams[m.id].cost for m in self.members))

    def _hold(self, wcet: Fraction) -> Fraction | None:
        """``E = C + Σ_{hp(π)} η⁺ₕ(E)·Cₕ`` for a callback of execution time ``wcet`` (one per distinct one)."""
        if wcet not in self.holds:
            self.holds[wcet] = least_fixed_point(wcet, wcet, list(self.above_flows))[0]
        return self.holds[wcet]

    def response(self, task: TaskModel) -> TaskResponse:
        """WCRT (§9.3) and BCRT (``bcet``) of callback ``task``."""
        executor = self.executor
        deadline, deadline_rule = deadline_of(task, self.events[task.id])
        hold = self._hold(task.wcet)
        rounds = self.rounds[task.id]
        computed, offsets, critical, failure = self._wcrt(task, rounds)
        rule = (f"{executor.kind} executor, {'FIFO' if not executor.polls else 'non-preemptive'} busy window, "
                f"{offsets} offset{'s' if offsets != 1 else ''}")
        if rounds is not None and (computed is None or rounds < computed):
            computed, rule, failure = rounds, f"{executor.kind} executor, polling rounds", None
        used: Fraction | None = computed
        if task.wcrt_bound is not None:
            used, rule = task.wcrt_bound, "user bound"
        elif computed is None:
            rule = "unbounded"
        ids, above = self.names
        k = self.position[task.id]
        names = ids[:k] + ids[k + 1:] + above
        return TaskResponse(task.id, task.core, task.priority, bcrt(task), used, computed, rule, deadline,
                            deadline_rule, ZERO, hold, offsets, critical, names, failure)

    def _wcrt(self, task: TaskModel, cap: Fraction | None
              ) -> tuple[Fraction | None, int | None, int | None, str | None]:
        """(R, the number of offsets searched, the critical one (1-based), failure) of the busy-window
        bound; with ``cap`` (a bound known already), the search stops as soon as it reaches it (R is
        then None)."""
        if self.failure is not None:
            return None, None, None, self.failure
        if self.length is None:
            return None, None, None, f"no fixed point within {MAX_STEPS} iteration steps"
        streams, above = self.streams, self.above
        own, cost = streams[task.id], streams[task.id].cost
        caused = _descendants(self.children, task.id)
        left = dict(self.work)  # every member's work but its own and its causal descendants'
        for tid in (task.id, *caused):
            if not streams[tid].silent:
                left[streams[tid].period, streams[tid].jitter] -= streams[tid].cost
        others = _listed(left)
        downstream = _listed(_costs(streams[tid] for tid in caused))
        offsets = _offsets(own, self.length)
        if offsets is None:
            return None, None, None, f"the busy window holds more than {MAX_JOBS} jobs of `{task.id}`"
        best: tuple[int, int] | None = None
        bound = None if cap is None else self.base.ticks(cap)
        last = 0  # F(A) grows with A (the right-hand sides do): each search starts at the last
        for n, offset in enumerate(offsets, 1):
            limit = None if bound is None else offset + bound
            jobs = own.closed(offset)
            mine = jobs * cost
            if self.executor.polls:  # Eq. (6)
                finish = _fixed(lambda f: mine + _closed_work(others, f - cost)  # noqa: B023
                                + _closed_work(downstream, f - cost, jobs - 1)  # noqa: B023
                                + _open_work(above, f), max(last, mine), limit)
            else:  # FIFO
                queued = mine + _closed_work(others, offset) + _closed_work(downstream, offset, jobs - 1)
                finish = _fixed(lambda f: queued + _open_work(above, f),  # noqa: B023
                                max(last, queued), limit)
            if finish is None:
                return None, n, None, f"no fixed point within {MAX_STEPS} iteration steps"
            if limit is not None and finish >= limit:
                return None, n, None, "not below the polling-round bound"
            last = finish
            if best is None or finish - offset > best[0]:
                best = (finish - offset, n)
        assert best is not None  # (offset 0 is always searched)
        return self.base.seconds(best[0]), len(offsets), best[1], None


def _activated(flows: Mapping[str, Interferer]) -> dict[str, tuple[Fraction, Fraction, Fraction]] | str:
    """(C, P, J) of each stream of a level that is ever activated, or why the level has no bound: a stream
    whose activations are not bounded (the first), or a utilisation of at least 1."""
    activated: dict[str, tuple[Fraction, Fraction, Fraction]] = {}
    for tid, f in flows.items():
        if f.silent:
            continue
        if f.cost is None or f.period is None or f.jitter is None:
            return f"the activations of `{tid}` are not bounded"
        activated[tid] = (f.cost, f.period, f.jitter)
    load = sum((c / p for c, p, _j in activated.values()), ZERO)
    if load >= 1:
        return f"the utilisation of its executor's level is {ratio(load)} (at least 1)"
    return activated


def _costs(streams: Iterable[_Stream]) -> dict[tuple[int, int], int]:
    """The total cost of the activated streams of each (P, J): they count their jobs alike."""
    costs: dict[tuple[int, int], int] = {}
    for s in streams:
        if not s.silent:
            costs[s.period, s.jitter] = costs.get((s.period, s.jitter), 0) + s.cost
    return costs


def _listed(costs: Mapping[tuple[int, int], int]) -> list[tuple[int, int, int]]:
    """``_costs`` as (P, J, C) for the sums below, without the streams of no cost left."""
    return [(p, j, c) for (p, j), c in costs.items() if c]


def _closed_work(merged: list[tuple[int, int, int]], window: int, most: int | None = None) -> int:
    """``Σ η̄(window)·C`` over merged streams (window ≥ 0), each count at most ``most`` if given."""
    if most is None:
        return sum(((window + j) // p + 1) * c for p, j, c in merged)
    return sum(min((window + j) // p + 1, most) * c for p, j, c in merged)


def _open_work(merged: list[tuple[int, int, int]], window: int) -> int:
    """``Σ η⁺(window)·C`` over merged streams (0 for window ≤ 0)."""
    return sum(-(-(window + j) // p) * c for p, j, c in merged) if window > 0 else 0


def _local_children(system: SystemModel, members: tuple[TaskModel, ...]) -> dict[str, list[str]]:
    """Per callback of an executor, the callbacks of it that its completions alone release at once:
    triggered by one port alone, connected from it without delay (``local_descendants``)."""
    on = {m.id for m in members}
    children: dict[str, list[str]] = {}
    for m in members:
        port = m.activation.single_port
        link = None if port is None else system.link_into(f"{m.instance}.{port}")
        if link is not None and link.delay_max == 0 and link.writer in on and link.writer != m.id:
            children.setdefault(link.writer, []).append(m.id)
    return children


def _descendants(children: Mapping[str, list[str]], task: str) -> set[str]:
    found: set[str] = set()
    todo = list(children.get(task, ()))
    while todo:
        m = todo.pop()
        if m != task and m not in found:
            found.add(m)
            todo += children.get(m, ())
    return found


def local_descendants(system: SystemModel, task: TaskModel, members: tuple[TaskModel, ...]) -> set[str]:
    """The callbacks of ``task``'s executor whose every activation is caused by a completion of
    ``task`` at that instant (§9.3, "causal caps"): triggered by one port alone, connected without
    delay from ``task`` or from another such callback."""
    return _descendants(_local_children(system, members), task.id)


def _fixed(step: Callable[[int], int], start: int, limit: int | None = None) -> int | None:
    """The least fixed point of the monotone ``step`` from ``start`` (which must not exceed it), within
    the step budget; with ``limit``, the first iterate at or above it once one is (the fixed point is
    not below it)."""
    value = start
    for _ in range(MAX_STEPS):
        new = step(value)
        if new == value or (limit is not None and new >= limit):
            return new
        value = new
    return None


def _offsets(own: _Stream, length: int) -> list[int] | None:
    """The steps of η̄ᵢ in ``[0, L)``: 0 and ``k·P − J`` for k ≥ 1 where positive; None beyond ``MAX_JOBS``."""
    if own.silent:
        return [0]
    points = [0]
    k = 1
    while (a := k * own.period - own.jitter) < length:
        if a > 0:
            points.append(a)
        k += 1
        if len(points) > MAX_JOBS:
            return None
    return points


class PollingRounds:
    """The polling-point bound of a wait-set executor (§9.3, after Blaß et al., RTSS 2021: a polled
    callback runs at most once per snapshot), for each callback ``i`` of it the least ``w`` with

        w = Cᵢ + Σ_{c ∈ E} C_c + Σ_{j ≺ i} Cⱼ + Σ_{h ∈ hp(π)} η⁺ₕ(w + Rₕ)·Cₕ.

    Every callback has at most one pending job (§9.1), so when i's job is released the round in progress
    runs at most one job of each callback (i's previous job included), and the next snapshot, which
    holds i's job, runs at most one job before it of each callback that comes before i in the processing
    order (kind, then system order: ``j ≺ i``); a job of h that runs in the window was released at most
    Rₕ before it. None when some Rₕ is unbounded. What the callbacks share (``Σ_E C``, the sums over
    the processing order, the higher threads' streams) is built once."""

    def __init__(self, system: SystemModel, executor: ExecutorModel, members: tuple[TaskModel, ...],
                 hp: tuple[TaskModel, ...], events: Mapping[str, EventModel],
                 estimates: Mapping[str, Fraction | None]):
        self.bounded = all(estimates.get(h.id) is not None for h in hp)
        self.total = sum((m.wcet for m in members), ZERO)
        self.ahead: dict[str, Fraction] = {}
        done = ZERO
        for m in sorted(members, key=lambda m: (executor.kind_rank(m), system.order(m.id))):
            self.ahead[m.id] = done
            done += m.wcet
        self.streams = [_later(interferer(system, h, events[h.id], estimates.get(h.id), h.wcet), estimates.get(h.id))
                        for h in hp] if self.bounded else []

    def bound(self, task: TaskModel) -> Fraction | None:
        """The bound of callback ``task`` (one of the members)."""
        if not self.bounded:
            return None
        base = task.wcet + self.total + self.ahead[task.id]
        value, _ = least_fixed_point(base, base, self.streams)
        return value


def _later(stream: Interferer, response: Fraction | None) -> Interferer:
    """``stream`` with its jitter widened by ``response``: a job of it runs up to that long after its release."""
    return stream if stream.jitter is None or response is None else replace(stream, jitter=stream.jitter + response)
