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

from collections.abc import Callable, Mapping
from dataclasses import replace
from functools import partial
from fractions import Fraction

from ..model import ExecutorModel, SystemModel, TaskModel
from .rates import EventModel
from .rta import MAX_JOBS, MAX_STEPS, Interferer, TaskResponse, bcrt, deadline_of, interferer, least_fixed_point, ratio

ZERO = Fraction(0)


def closed_count(events: EventModel, window: Fraction) -> int | None:
    """``η̄(Δ) = ⌊(Δ + J⁻)/P⁻⌋ + 1``: the most activations in a closed window of length Δ ≥ 0."""
    if events.silent:
        return 0
    if events.period_min is None or events.jitter_min is None:
        return None
    return int((window + events.jitter_min) // events.period_min) + 1


def higher_threads(system: SystemModel, executor: ExecutorModel) -> tuple[TaskModel, ...]:
    """hp(π): the tasks of the executor's core whose threads outrank the executor's."""
    return tuple(t for t in system.tasks_on(executor.core) if t.priority > executor.priority)


def executor_responses(system: SystemModel, events: Mapping[str, EventModel],
                       estimates: Mapping[str, Fraction | None]) -> dict[str, TaskResponse]:
    """The response of every callback (the tasks bound to an executor)."""
    return {t.id: callback_response(system, t, events, estimates) for t in system.tasks if t.executor is not None}


def callback_response(system: SystemModel, task: TaskModel, events: Mapping[str, EventModel],
                      estimates: Mapping[str, Fraction | None]) -> TaskResponse:
    """WCRT (§9.3) and BCRT (``bcet``) of callback ``task``."""
    assert task.executor is not None
    executor = system.executor(task.executor)
    deadline, deadline_rule = deadline_of(task, events[task.id])
    members = system.callbacks(executor.name)
    hp = higher_threads(system, executor)
    streams = [interferer(system, h, events[h.id], estimates.get(h.id), h.wcet) for h in hp]
    hold, _ = least_fixed_point(task.wcet, task.wcet, streams)
    computed: Fraction | None
    computed, offsets, critical, failure = _wcrt(system, task, executor, members, hp, events, estimates)
    rule = (f"{executor.kind} executor, {'FIFO' if not executor.polls else 'non-preemptive'} busy window, "
            f"{offsets} offset{'s' if offsets != 1 else ''}")
    rounds = round_bound(system, task, members, hp, events, estimates) if executor.polls else None
    if rounds is not None and (computed is None or rounds < computed):
        computed, rule, failure = rounds, f"{executor.kind} executor, polling rounds", None
    used: Fraction | None = computed
    if task.wcrt_bound is not None:
        used, rule = task.wcrt_bound, "user bound"
    elif computed is None:
        rule = "unbounded"
    names = tuple(m.id for m in members if m.id != task.id) + tuple(h.id for h in hp)
    return TaskResponse(task.id, task.core, task.priority, bcrt(task), used, computed, rule, deadline, deadline_rule,
                        ZERO, hold, offsets, critical, names, failure)


def _wcrt(system: SystemModel, task: TaskModel, executor: ExecutorModel, members: tuple[TaskModel, ...],
          hp: tuple[TaskModel, ...], events: Mapping[str, EventModel], estimates: Mapping[str, Fraction | None]
          ) -> tuple[Fraction | None, int | None, int | None, str | None]:
    """(R, the number of offsets searched, the critical one (1-based), failure)."""
    own = events[task.id]
    unbounded = [m.id for m in members + hp if closed_count(events[m.id], ZERO) is None]
    if unbounded:
        return None, None, None, f"the activations of `{unbounded[0]}` are not bounded"
    load = sum((m.wcet / events[m.id].period_min for m in members + hp  # type: ignore[operator]  # (bounded)
                if not events[m.id].silent), ZERO)
    if load >= 1:
        return None, None, None, f"the utilisation of its executor's level is {ratio(load)} (at least 1)"
    preempting = [interferer(system, h, events[h.id], estimates.get(h.id), h.wcet) for h in hp]
    own_stream = [interferer(system, m, events[m.id], estimates.get(m.id), m.wcet) for m in members]
    length, why = least_fixed_point(ZERO, sum((m.wcet for m in members), ZERO), own_stream + preempting)
    if length is None:
        return None, None, None, why
    best: tuple[Fraction, int] | None = None
    offsets = _offsets(own, length)
    if offsets is None:
        return None, None, None, f"the busy window holds more than {MAX_JOBS} jobs of `{task.id}`"
    others = [m for m in members if m.id != task.id]
    for n, offset in enumerate(offsets, 1):
        if executor.polls:
            finish = _finish(partial(_polled, task, others, events, offset, preempting),
                             own_count(own, offset) * task.wcet)
        else:
            queued = sum((own_count(events[m.id], offset) * m.wcet for m in members), ZERO)
            finish = _finish(partial(_queued, queued, preempting), queued)
        if finish is None:
            return None, n, None, f"no fixed point within {MAX_STEPS} iteration steps"
        if best is None or finish - offset > best[0]:
            best = (finish - offset, n)
    assert best is not None  # (offset 0 is always searched)
    return best[0], len(offsets), best[1], None


def round_bound(system: SystemModel, task: TaskModel, members: tuple[TaskModel, ...], hp: tuple[TaskModel, ...],
                events: Mapping[str, EventModel], estimates: Mapping[str, Fraction | None]) -> Fraction | None:
    """The polling-point bound of a wait-set executor (§9.3, after Blaß et al., RTSS 2021: a polled
    callback runs at most once per snapshot): the least ``w`` with

        w = Cᵢ + Σ_{c ∈ E} C_c + Σ_{j ≠ i} Cⱼ + Σ_{h ∈ hp(π)} η⁺ₕ(w + Rₕ)·Cₕ.

    Every callback has at most one pending job (§9.1), so when i's job is released the round in progress
    runs at most one job of each callback (i's previous job included), and the next snapshot, which
    holds i's job, runs at most one job of each other callback before it; a job of h that runs in the
    window was released at most Rₕ before it. None when some Rₕ is unbounded."""
    if any(estimates.get(h.id) is None for h in hp):
        return None
    base = task.wcet + sum((m.wcet for m in members), ZERO) + sum((m.wcet for m in members if m.id != task.id), ZERO)
    streams = [replace(s, jitter=s.jitter + estimates[h.id]) if s.jitter is not None else s  # type: ignore[operator]
               for h in hp for s in [interferer(system, h, events[h.id], estimates.get(h.id), h.wcet)]]
    value, _ = least_fixed_point(base, base, streams)
    return value


def own_count(events: EventModel, offset: Fraction) -> int:
    """η̄ᵢ(A): the analysed callback's jobs released in ``[0, A]`` (its job at A the last of them)."""
    count = closed_count(events, offset)
    assert count is not None  # (bounded: checked before)
    return count


def _work(task: TaskModel, others: list[TaskModel], events: Mapping[str, EventModel], offset: Fraction,
          finish: Fraction) -> Fraction:
    """Eq. (6)'s executor work up to ``finish``: i's jobs up to its job at ``offset``, and every job of
    another callback released no later than i's job starts (at ``finish − Cᵢ`` at the latest)."""
    start = finish - task.wcet
    total = own_count(events[task.id], offset) * task.wcet
    for j in others:
        total += own_count(events[j.id], start) * j.wcet
    return total


def _polled(task: TaskModel, others: list[TaskModel], events: Mapping[str, EventModel], offset: Fraction,
            preempting: list[Interferer], finish: Fraction) -> Fraction:
    """The right-hand side of Eq. (6) at ``finish``."""
    return _work(task, others, events, offset, finish) + _preemption(preempting, finish)


def _queued(queued: Fraction, preempting: list[Interferer], finish: Fraction) -> Fraction:
    """The right-hand side of the FIFO bound at ``finish``: the queued work and the preemption."""
    return queued + _preemption(preempting, finish)


def _preemption(streams: list[Interferer], window: Fraction) -> Fraction:
    """The work of the higher threads released in ``[0, window)``."""
    return sum((s.demand(window) or ZERO for s in streams), ZERO)  # (bounded: their activations were checked)


def _finish(step: Callable[[Fraction], Fraction], start: Fraction) -> Fraction | None:
    """The least fixed point of ``step`` from ``start`` (which must not exceed it), within the step budget."""
    value = start
    for _ in range(MAX_STEPS):
        new = step(value)
        if new == value:
            return value
        value = new
    return None


def _offsets(events: EventModel, length: Fraction) -> list[Fraction] | None:
    """The steps of η̄ᵢ in ``[0, L)``: 0 and ``k·P⁻ − J⁻`` for k ≥ 1 where positive; None beyond ``MAX_JOBS``."""
    if events.silent:
        return [ZERO]
    assert events.period_min is not None and events.jitter_min is not None
    points = [ZERO]
    k = 1
    while (a := k * events.period_min - events.jitter_min) < length:
        if a > 0:
            points.append(a)
        k += 1
        if len(points) > MAX_JOBS:
            return None
    return points

