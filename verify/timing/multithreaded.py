"""Response times of the callbacks of a multi-threaded ROS 2 executor (specs/timing.md §9.4).

The executor has ``m`` workers, one per core of its own (E224); its callbacks share one snapshot and
a callback in a mutually exclusive group waits while another callback of the group runs. For a job
``J`` of callback ``i`` released at ``r`` and started at ``s``, every instant of ``[r, s)`` at which a
worker is idle has ``i``'s group busy (a free worker with nothing to take polls, and the poll would
collect ``J``). The time the group can be busy before ``J`` starts is ``B``; in the rest of the window
every worker runs a callback, so

    s − r ≤ B + W / m,    W = Σ_{m largest} C (jobs started before r) + Σ_{j ≠ i} nⱼ·Cⱼ,

``nⱼ`` the jobs of ``j`` started in ``[r, s)``: at most ``1 + η̄ⱼ(s − r)`` (one pending at ``r``, by
absorption, and the activations after it); when ``i``'s group never holds ``J`` back, at most one
from the snapshot in progress at ``r`` and, for a callback before ``i`` in the processing order (kind,
then system order), one ahead of ``J`` in the snapshot that collects it.
``Rᵢ = (s − r) + Cᵢ``: a started callback runs on a core no other thread shares.

``B``: 0 for a reentrant group; ``Cᵢ`` for a mutually exclusive group of ``i`` alone: ``J`` is held
back only while ``i``'s previous job runs, until some ``f₀ ≤ r + Cᵢ``, and from ``f₀`` on the argument
above applies to ``[f₀, s)`` (the snapshot in progress at ``f₀``, the one that collects ``J``, the jobs
started before ``f₀`` in the carry-in), so the capped counts hold there too; for a mutually exclusive
group in which ``i`` comes first in the processing order, the job running at ``r`` and one job of
each other member taken from the snapshot in progress at ``r`` (a poll with the group free collects
``J``, and ``J`` then precedes every other member). A
member with another member before it can starve: at every poll with the group free, the earlier
member may be pending again and run first, and every poll while it runs leaves ``J`` out (Teper, Kuhse,
Ueter, von der Brüggen and Chen, *Thread Carefully: Preventing Starvation in the ROS 2 Multithreaded
Executor*, EMSOFT 2024); the analysis then gives no bound.

A reentrant callback may run two jobs at once and complete them out of order, which the chain rules
of §7 do not allow for (``may_overlap``): a chain through it gets no bound unless ``Rᵢ ≤ δ⁻ᵢ(2)``, when
a job completes before the next can be released (the bound ``Rᵢ`` holds either way: the jobs started
before ``r`` count in ``W`` on every worker they may occupy).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from fractions import Fraction

from ..model.system import ExecutorModel, GroupModel, SystemModel, TaskModel
from .rates import EventModel
from .kernel import (MAX_STEPS, Interferer, TaskResponse, bcrt, deadline_of, interferer, least_fixed_point, load_of,
                     ratio)

ZERO = Fraction(0)


def multi_threaded_response(system: SystemModel, task: TaskModel, executor: ExecutorModel,
                            events: Mapping[str, EventModel], estimates: Mapping[str, Fraction | None]) -> TaskResponse:
    """WCRT (§9.4) and BCRT of callback ``task`` of the multi-threaded ``executor``."""
    return Workers(system, executor, events, estimates).response(task)


class Workers:
    """What the callbacks of one multi-threaded executor share in §9.4, built once: their streams, the
    carry-in of the workers, and the execution times of the activated callbacks in the processing order."""

    def __init__(self, system: SystemModel, executor: ExecutorModel, events: Mapping[str, EventModel],
                 estimates: Mapping[str, Fraction | None]):
        self.system, self.executor, self.events = system, executor, events
        self.members = system.callbacks(executor.name)
        #: higher threads on its cores: only the arrival tasks of its process (§6.6; E224 allows no other)
        self.higher = higher_on_workers(system, executor)
        self.higher_bounded = all(estimates.get(h.id) is not None for h in self.higher)
        self.higher_flows = [_later(interferer(system, h, events[h.id], estimates.get(h.id), h.wcet),
                                    estimates.get(h.id)) for h in self.higher] if self.higher_bounded else []
        self.flows = {m.id: interferer(system, m, events[m.id], estimates.get(m.id), m.wcet) for m in self.members}
        self.carry = carry_in(system, self.members, len(executor.workers))
        self.live_work = sum((m.wcet for m in self.members if not self.flows[m.id].silent), ZERO)
        self.ahead_work: dict[str, Fraction] = {}  # of the activated callbacks before each one
        done = ZERO
        for m in sorted(self.members, key=lambda m: (executor.kind_rank(m), system.order(m.id))):
            self.ahead_work[m.id] = done
            done += ZERO if self.flows[m.id].silent else m.wcet

    def response(self, task: TaskModel) -> TaskResponse:
        """WCRT (§9.4) and BCRT of callback ``task`` (one of the members)."""
        deadline, deadline_rule = deadline_of(task, self.events[task.id])
        group = callback_group(self.system, task)
        computed, failure = self._window(task)
        hold: Fraction | None = task.wcet
        if self.higher:
            hold = self._held(task)
        if computed is not None:
            computed += task.wcet
            if self.higher:
                computed, failure = self._preempted(task, computed)
        rule = f"multi_threaded executor, {len(self.executor.workers)} workers, {group.describe()}"
        used: Fraction | None = computed
        if task.wcrt_bound is not None:
            used, rule = task.wcrt_bound, "user bound"
        elif computed is None:
            rule = "unbounded"
        return TaskResponse(task.id, task.core, task.priority, bcrt(task), used, computed, rule, deadline,
                            deadline_rule, ZERO, hold, None, None,
                            tuple(m.id for m in self.members if m.id != task.id) + tuple(h.id for h in self.higher),
                            failure)

    def _held(self, task: TaskModel) -> Fraction | None:
        """``Eᵢ = Cᵢ + Σₕ η⁺ₕ(Eᵢ + Rₕ)·Cₕ`` over the higher threads of the executor's cores (§6.6)."""
        if not self.higher_bounded:
            return None
        return least_fixed_point(task.wcet, task.wcet, self.higher_flows)[0]

    def _preempted(self, task: TaskModel, start: Fraction) -> tuple[Fraction | None, str | None]:
        """Rᵢ with the higher threads of the executor's cores (§6.6), or None and why: the least
        ``w = B + W(w)/m + Cᵢ + Σₕ η⁺ₕ(w + Rₕ)·Cₕ`` from ``start`` (its value without them) — the time the
        higher threads take in ``[r, f)`` is at most their demand in it, whether it holds the group back,
        keeps a worker from a callback or preempts the job."""
        if not self.higher_bounded:
            return None, "the response time of a higher thread on its cores is not bounded"
        load = load_of(self.higher_flows)
        if load is None or load >= 1:
            return None, "the higher threads on its cores leave it no time"
        w = start
        for _ in range(MAX_STEPS):
            window = self._window_at(task, w)
            if window is None:
                return None, "the other callbacks' activations are not bounded"
            new = window + task.wcet
            for flow in self.higher_flows:
                demand = flow.demand(w)
                if demand is None:
                    return None, f"the activations of `{flow.task}` are not bounded"
                new += demand
            if new == w:
                return w, None
            w = new
        return None, f"no fixed point within {MAX_STEPS} iteration steps"

    def _window_at(self, task: TaskModel, w: Fraction) -> Fraction | None:
        """``B + W/m`` of §9.4 with the counts ``nⱼ`` taken over a window of length ``w`` (at least
        ``s − r``); the same as ``_window`` where the counts are capped."""
        blocking, why = group_blocking(self.system, task, self.executor)
        assert blocking is not None  # (``_window`` bounded it)
        workers = len(self.executor.workers)
        if not (blocking > 0 and why == "siblings"):
            own = ZERO if self.flows[task.id].silent else task.wcet
            return blocking + (self.carry + self.live_work - own + self.ahead_work[task.id]) / workers
        work = self.carry
        for tid, f in self.flows.items():
            if tid == task.id or f.silent:
                continue
            if f.cost is None or f.period is None or f.jitter is None:
                return None
            work += _jobs(f.period, f.jitter, w) * f.cost
        return blocking + work / workers

    def _window(self, task: TaskModel) -> tuple[Fraction | None, str | None]:
        """The least ``w = B + W(w)/m`` of §9.4 (the longest ``s − r``), or None and why."""
        blocking, why = group_blocking(self.system, task, self.executor)
        if blocking is None:
            return None, why
        workers = len(self.executor.workers)
        if not (blocking > 0 and why == "siblings"):  # (the counts are capped: no fixed point to find)
            # (one job of each activated other callback, two of those before it in the processing order)
            own = ZERO if self.flows[task.id].silent else task.wcet
            return blocking + (self.carry + self.live_work - own + self.ahead_work[task.id]) / workers, None
        live = [f for tid, f in self.flows.items() if tid != task.id and not f.silent]
        return held_window(live, blocking, self.carry, workers)


def held_window(live: list[Interferer], blocking: Fraction, carry: Fraction, workers: int
                ) -> tuple[Fraction | None, str | None]:
    """The least ``w = B + (carry + Σ nⱼ(w)·Cⱼ)/m`` of §9.4 over the activated other callbacks ``live``
    when other members of the group hold the job back (the counts follow the activations)."""
    streams: list[tuple[Fraction, Fraction, Fraction]] = []  # (C, P, J) of each
    for f in live:
        if f.cost is None or f.period is None or f.jitter is None:
            return None, f"the activations of `{f.task}` are not bounded"
        streams.append((f.cost, f.period, f.jitter))
    if (load := sum((c / p for c, p, _j in streams), ZERO)) >= workers:
        return None, f"the other callbacks' utilisation is {ratio(load)}, not below its {workers} workers"
    w = blocking + (carry + sum((_jobs(p, j, ZERO) * c for c, p, j in streams), ZERO)) / workers
    for _ in range(MAX_STEPS):
        new = blocking + (carry + sum((_jobs(p, j, w) * c for c, p, j in streams), ZERO)) / workers
        if new == w:
            return w, None
        w = new
    return None, f"no fixed point within {MAX_STEPS} iteration steps"


def higher_on_workers(system: SystemModel, executor: ExecutorModel) -> tuple[TaskModel, ...]:
    """The tasks on the executor's cores whose threads outrank its own (§6.6: its process's arrival tasks)."""
    return tuple(t for core in executor.workers for t in system.tasks_on(core) if t.priority > executor.priority)


def _later(stream: Interferer, response: Fraction | None) -> Interferer:
    """``stream`` with its jitter widened by ``response``: a job of it runs up to that long after its release."""
    return stream if stream.jitter is None or response is None else replace(stream, jitter=stream.jitter + response)


def callback_group(system: SystemModel, task: TaskModel) -> GroupModel:
    """The callback group of callback ``task`` (every callback has one: the model gives it)."""
    if task.group is None:
        raise ValueError(f"`{task.id}` is not a callback of an executor")
    return system.group(task.group)


def may_overlap(system: SystemModel, task: TaskModel, wcrt: Fraction | None, events: EventModel) -> bool:
    """Whether two jobs of callback ``task`` (response bound ``wcrt``) may run at once (§9.4): on a
    multi-threaded executor in a reentrant group, unless ``wcrt ≤ δ⁻(2)``."""
    if task.executor is None or task.group is None or system.group(task.group).exclusive:
        return False
    if not system.executor(task.executor).multi_threaded:
        return False
    distance = events.delta_min(2)
    return wcrt is None or distance is None or wcrt > distance


def group_blocking(system: SystemModel, task: TaskModel, executor: ExecutorModel) -> tuple[Fraction | None, str]:
    """``B`` of §9.4, and "siblings" when other members of a mutually exclusive group hold the job back
    (then the counts ``nⱼ`` follow the activations); None, with the reason, when a member before
    ``task`` can starve it."""
    group = callback_group(system, task)
    if not group.exclusive:
        return ZERO, ""
    siblings = [m for m in system.callbacks(executor.name) if m.group == task.group and m.id != task.id]
    if not siblings:
        return task.wcet, ""
    place = (executor.kind_rank(task), system.order(task.id))
    ahead = [m for m in siblings if (executor.kind_rank(m), system.order(m.id)) < place]
    if ahead:
        return None, (f"it may starve: `{ahead[0].id}` comes before it in {group.describe()} "
                      "(Teper et al., EMSOFT 2024)")
    return max(m.wcet for m in (task, *siblings)) + sum((m.wcet for m in siblings), ZERO), "siblings"


def _jobs(period: Fraction, jitter: Fraction, window: Fraction) -> int:
    """``nⱼ ≤ 1 + η̄ⱼ(window)``: the jobs of a callback of least period ``period`` and jitter ``jitter`` started
    in a window (§9.4)."""
    return int(1 + (window + jitter) // period + 1)


def carry_in(system: SystemModel, members: tuple[TaskModel, ...], workers: int) -> Fraction:
    """The most work the workers still have of jobs started before the window: the ``m`` largest
    execution times, a reentrant callback's up to ``m`` times (it may run on several workers)."""
    costs: list[Fraction] = []
    for m in members:
        copies = 1 if callback_group(system, m).exclusive else workers
        costs += [m.wcet] * copies
    return sum(sorted(costs, reverse=True)[:workers], ZERO)
