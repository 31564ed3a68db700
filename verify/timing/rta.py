"""Response-time analysis per core: fixed-priority preemptive with jitter (specs/timing.md §6).

The worst case is the level-i busy window with q jobs (Lehoczky 1990; Tindell et al. 1994; in CPA
form Richter 2005), specs/timing.md §6.2:

    w(q) = q·(Cᵢ+βᵢ) + Σ_{j ∈ hp(i)} min(η⁺ⱼ(w), capⱼ(q))·Cⱼ + Σ_{s ∈ remote(i)} η⁺ₛ(w)·Eₛ
    Rᵢ   = max_{1 ≤ q ≤ Q} (w(q) − δ⁻ᵢ(q)),   Q = min { q : w(q) ≤ δ⁻ᵢ(q+1) }

with ``η⁺ⱼ(Δ) = ⌈(Δ + Jⱼ)/Pⱼ⌉`` (Joseph & Pandya 1986; Audsley et al. 1993; jitter: Tindell 1994).
``hp(i)`` holds the other tasks of i's core with priority ≥ i's; ``capⱼ`` bounds a task that only
runs because i completed (§6.2). Cooperative tasks of one instance are sequenced (§1, §6.3): ``βᵢ``
is the longest hold ``Eₛ`` of a sibling that may hold the token when a job of i is released, remote
siblings may take the token while i's core is busy, and a sibling waiting for the token suspends
itself, which its lower-priority neighbours see as extra release jitter ``Rₛ − Cₛ`` (suspension as
jitter: Bletsas et al. 2018; Chen et al., *Many suspensions, many problems*, 2019). The best case
is ``bcet`` (§6.4).

This is the reference statement, task by task; it builds on ``kernel`` alone (the demand streams, the
fixed point, ``TaskResponse``) and imports neither the fast path (``fastrta``) nor the executor
analyses. One round over every task, callbacks included, is ``reference.response_times``.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from collections.abc import Mapping

from ..core.diagnostics import DiagnosticSink, Label, name_list
from ..model.system import SystemModel, TaskModel
from ..model.units import fmt_number, fmt_time
from .kernel import (MAX_JOBS, ZERO, Budget, Interferer, TaskResponse, bcrt, causes, deadline_of, interferer,
                     least_fixed_point, load_of, ratio, siblings, suspension_jitter)
from .pipeline import Case, cases, upstream
from .rates import ActivationInfo, EventModel, ratio_sum


# ================================================================== utilisation


@dataclass(frozen=True)
class CoreLoad:
    """The utilisation ``Σ wcet · (highest activation rate)`` of one core; None if some rate is not
    bounded."""

    core: str
    utilisation: Fraction | None
    tasks: tuple[str, ...]

    @property
    def overloaded(self) -> bool:
        return self.utilisation is not None and self.utilisation > 1


def core_loads(system: SystemModel, infos: Mapping[str, ActivationInfo]) -> tuple[CoreLoad, ...]:
    """Per core: ``U = Σ Cᵢ · fᵢ⁺`` with fᵢ⁺ the upper end of the task's rate interval (§6.1); the
    cores of a multi-threaded executor share its callbacks' load evenly (§9.4)."""
    loads = []
    shared = {c: e for e in system.executors if e.multi_threaded for c in e.workers}
    for core in _cores(system):
        owner = shared.get(core)
        tasks = system.tasks_on(core) if owner is None else system.callbacks(owner.name)
        total = _load(tasks, infos)
        if owner is not None:  # (its process's arrival tasks, §6.6, are the core's own)
            others = tuple(t for t in system.tasks_on(core) if t.executor != owner.name)
            own = _load(others, infos) if others else ZERO
            total = None if total is None or own is None else total / len(owner.workers) + own
            tasks += others
        loads.append(CoreLoad(core, total, tuple(t.id for t in tasks)))
    return tuple(loads)


def _load(tasks: tuple[TaskModel, ...], infos: Mapping[str, ActivationInfo]) -> Fraction | None:
    """``Σ Cᵢ · fᵢ⁺`` of ``tasks``, None when a rate is not bounded."""
    rates = [r for t in tasks if (r := infos[t.id].rate) is not None]
    if len(rates) < len(tasks):
        return None
    return ratio_sum(_times(t.wcet.as_integer_ratio(), r.high.as_integer_ratio()) for t, r in zip(tasks, rates))


def _times(a: tuple[int, int], b: tuple[int, int]) -> tuple[int, int]:
    return a[0] * b[0], a[1] * b[1]


def _cores(system: SystemModel) -> list[str]:
    names = [c.name for c in system.cores] + [c for e in system.executors for c in e.workers]
    names += [t.core for t in system.tasks if t.core not in names and not names.count(t.core)]
    return list(dict.fromkeys(names))


def percent(value: Fraction) -> str:
    """A utilisation as a percentage, exact or rounded to two decimals (marked ≈)."""
    exact = value * 100
    shown = round(exact, 2)
    return f"{'' if shown == exact else '≈'}{fmt_number(Fraction(shown))} %"


def check_utilisation(system: SystemModel, loads: tuple[CoreLoad, ...], infos: Mapping[str, ActivationInfo],
                      sink: DiagnosticSink) -> None:
    """E311: a core whose utilisation exceeds 1."""
    spans = {c.name: c.span for c in system.cores}
    for load in loads:
        if not load.overloaded or load.utilisation is None:  # (an overloaded core has a utilisation)
            continue
        # an overloaded core's tasks have bounded rates (else it has no utilisation)
        shares = [f"`{t}` {fmt_number(system.task(t).wcet * rate.high)}"
                  for t in load.tasks if (rate := infos[t].rate) is not None]
        secondary = tuple(Label(system.task(t).span, f"`{t}` on `{load.core}`") for t in load.tasks)
        sink.emit("E311", f"core `{load.core}` is utilised {ratio(load.utilisation)} "
                  f"({percent(load.utilisation)}) by " + name_list(load.tasks),
                  spans.get(load.core, system.task(load.tasks[0]).span), "utilisation above 1",
                  secondary=secondary, notes=("shares (wcet × highest rate): " + ", ".join(shares),),
                  help="move tasks to another core, lower their rates or their execution times")


# ================================================================== one core


def causal_path(system: SystemModel, source: TaskModel, target: TaskModel,
                estimates: Mapping[str, Fraction | None]
                ) -> tuple[tuple[int, ...], Fraction, tuple[int, ...], tuple[int, ...] | None] | None:
    """If every activation of ``source`` is caused by completions of ``target`` through data
    triggers: the prescalers on the way (from ``source`` back), the largest latency L⁺ from a
    completion of ``target`` to the release it causes (Σ d⁺ + Σ R of the tasks in between), per
    hop the events that need no new arrival (``causes``: 1 at an AND compound), and the same with
    one more at every hop from a task in between where the path is **local** — no delay, every task
    in between on ``target``'s core with a priority at least its and ``C⁻ > 0`` (specs/timing.md
    §6.2) — else None. None if there is no such path. A single-port trigger is caused by its writer; an AND
    compound by the writer of any of its members, whose arrivals it consumes one per event
    (specs/timing.md §6.2). The walk is depth first, members in order, each task entered once; the
    first path found counts."""
    visited = {source.id}
    # (task, its causes not yet tried, prescalers, L⁺, extras, local extras): the path so far, innermost last
    path: tuple[int, ...] = ()
    local: tuple[int, ...] | None = ()
    stack = [(source, iter(causes(system, source)), path, ZERO, path, local)]
    while stack:
        current, pending, prescalers, latency, extras, local = stack[-1]
        step = next(pending, None)
        if step is None:
            stack.pop()
            continue
        k, extra, link = step
        here = (prescalers + (k,), latency + link.delay_max, extras + (extra,))
        near = None if local is None or link.delay_max != 0 else local + (extra,)
        if link.writer == target.id:
            return here + (near,)
        estimate = estimates.get(link.writer)
        if link.writer in visited or estimate is None:
            continue
        visited.add(link.writer)
        writer = system.task(link.writer)
        through = (near[:-1] + (extra + 1,) if near is not None and writer.core == target.core
                   and writer.priority >= target.priority and writer.bcet > 0 else None)
        stack.append((writer, iter(causes(system, writer)), here[0], here[1] + estimate, here[2], through))
    return None


def carry_in(task: TaskModel, events: EventModel, response: Fraction | None, latency: Fraction) -> int | None:
    """Completions of ``task`` in a closed interval of length L⁺ before its busy window, the least of
    ``⌊(L⁺ + J⁻ + R − B)/P⁻⌋ + 1`` (completions lie in ``[r + B, r + R]``) and, where ``C⁻ > 0``,
    ``⌊L⁺/C⁻⌋ + 1`` (the jobs of a task run one after another, each for at least C⁻, so its
    completions are at least C⁻ apart); None when neither is known."""
    if events.silent:
        return 0
    by_gap = int(latency // task.bcet) + 1 if task.bcet > 0 else None
    if events.period_min is None or events.jitter_min is None or response is None:
        return by_gap
    by_rate = int((latency + events.jitter_min + response - bcrt(task)) // events.period_min) + 1
    return by_rate if by_gap is None else min(by_rate, by_gap)


def cooperative_counts(system: SystemModel) -> dict[str, int]:
    """The number of cooperative tasks per instance (a token is shared where there are two)."""
    count: dict[str, int] = {}
    for task in system.tasks:
        if task.kind == "cooperative":
            count[task.instance] = count.get(task.instance, 0) + 1
    return count


def higher_priority(system: SystemModel, task: TaskModel) -> tuple[TaskModel, ...]:
    """hp(i): the other tasks of i's core with priority ≥ i's (equal priorities interfere)."""
    return tuple(t for t in system.tasks_on(task.core) if t.id != task.id and t.priority >= task.priority)


def hold_time(system: SystemModel, task: TaskModel, events: Mapping[str, EventModel],
              estimates: Mapping[str, Fraction | None]) -> Fraction | None:
    """Eᵢ: from the start of a job to its completion, ``w = Cᵢ + Σ_{hp(i)} η⁺ⱼ(w)·Cⱼ`` (no own backlog,
    no token wait): how long a cooperative job holds its instance's token."""
    streams = [interferer(system, j, events[j.id], estimates.get(j.id), j.wcet) for j in higher_priority(system, task)]
    value, _ = least_fixed_point(task.wcet, task.wcet, streams)
    return value


@dataclass(frozen=True)
class Demand:
    """Everything the busy window of one task needs."""

    cost: Fraction
    blocking: Fraction  # per job (a sibling on another core may hold the token at every release)
    streams: list[Interferer]
    own: EventModel
    once: Fraction = ZERO  # once per busy window (a lower-priority sibling of the same core)
    cases: tuple[Case, ...] = ()  # the pipeline release offsets of verify.timing.pipeline


def wcrt(d: Demand) -> tuple[Fraction | None, int | None, int | None, str | None]:
    """The WCRT ``Rᵢ = max_{q ≤ Q} (w(q) − δ⁻ᵢ(q))`` over the level-i busy window of §6.2 (Joseph &
    Pandya 1986; Lehoczky 1990; Tindell et al. 1994): returns (R, Q, critical q, failure)."""
    if not d.own.silent and (d.own.period_min is None or d.own.jitter_min is None):
        return None, None, None, ("its activations are not bounded" if d.own.period_min is None else
                                  "its activation jitter is not bounded (a writer upstream has no WCRT bound)")
    # the load without the blocking, which may come once per busy window: at 1 or more the window never
    # closes; below 1 it does (the per-job blocking term is only a bound, and the job budget guards it)
    load = load_of(d.streams + [Interferer("", d.cost, d.own.period_min, ZERO, d.own.silent)])
    if load is not None and load >= 1:
        return None, None, None, "the utilisation of its level is 1 or more"
    best: tuple[Fraction, int] | None = None
    w, budget = ZERO, Budget()
    for q in range(1, MAX_JOBS + 1):
        offset = least_distance(d.own, q)
        found, why = least_fixed_point(q * (d.cost + d.blocking) + d.once, w + d.cost + d.blocking, d.streams, q,
                                       budget)
        if found is None:
            return None, q, None, why
        w = found
        if best is None or w - offset > best[0]:
            best = (w - offset, q)
        following = d.own.delta_min(q + 1)
        if following is None or w <= following:
            offsets = pipeline_response(d, q) if d.cases else None
            if offsets is not None and offsets[0] < best[0]:
                best = offsets
            return best[0], q, best[1], None
    return None, MAX_JOBS, None, f"the busy window does not close within {MAX_JOBS} jobs"


def least_distance(own: EventModel, q: int) -> Fraction:
    """``δ⁻ᵢ(q)`` in a busy window of q jobs. It is None only for a silent task and q > 1, which no busy
    window reaches (a silent task's closes at q = 1); 0 then."""
    distance = own.delta_min(q)
    return ZERO if distance is None else distance


def pipeline_response(d: Demand, jobs: int) -> tuple[Fraction, int] | None:
    """The WCRT by the pipeline release offsets of §6.2 (``verify.timing.pipeline``): the most, over
    the jobs q of the busy window (``jobs`` of them) and the ``Case``s, of ``w_c(q) − Case.gone``,
    where ``w_c(q)`` is the busy window with the counts of the path's
    tasks whose cascade job was released before it reduced (``Interferer.before``): (R, critical q),
    or None when a fixed point is not found."""
    best: tuple[Fraction, int] | None = None
    for case in d.cases:
        streams = [replace(s, before=case.before[s.task]) if s.task in case.before else s for s in d.streams]
        w, budget = ZERO, Budget()
        for q in range(1, jobs + 1):
            found, _ = least_fixed_point(q * (d.cost + d.blocking) + d.once, w + d.cost + d.blocking, streams, q,
                                         budget)
            if found is None:
                return None
            w = found
            low = least_distance(d.own, q)
            value = w - case.gone(q, low)
            if best is None or value > best[0]:
                best = (value, q)
    return best


def response_time(system: SystemModel, task: TaskModel, events: Mapping[str, EventModel],
                  estimates: Mapping[str, Fraction | None]) -> TaskResponse:
    """WCRT and BCRT of one task, given every task's event model and the current WCRT estimates."""
    deadline, deadline_rule = deadline_of(task, events[task.id])
    hp = higher_priority(system, task)
    streams = [causally_capped(system, task, j, events, estimates) for j in hp]
    hold = hold_time(system, task, events, estimates)
    blocking, once, remote = cooperative_blocking(system, task, events, estimates)
    names = tuple(j.id for j in hp) + tuple(s.task for s in remote)
    computed: Fraction | None
    failure: str | None
    used: Fraction | None
    if blocking is None or once is None:
        computed, q, crit, failure = None, None, None, "a cooperative sibling's hold time is not bounded"
        blocking = None
    else:
        offsets = cases(upstream(system, task, cooperative_counts(system)), estimates)
        computed, q, crit, failure = wcrt(Demand(task.wcet, blocking, streams + remote, events[task.id], once,
                                                 offsets))
        blocking = max(blocking, once)  # (reported: the longest wait for the token)
    if task.activation.unknown:
        failure = "its activation is an unresolved synthesis hole (run `synth` first)"
    if task.wcrt_bound is not None:
        used, rule = task.wcrt_bound, "user bound"
    else:
        used = computed
        rule = f"busy window, {q} job{'s' if q != 1 else ''}" if computed is not None else "unbounded"
    return TaskResponse(task.id, task.core, task.priority, bcrt(task), used, computed, rule, deadline,
                        deadline_rule, blocking, hold, q, crit, names, failure)


def causally_capped(system: SystemModel, task: TaskModel, j: TaskModel, events: Mapping[str, EventModel],
                    estimates: Mapping[str, Fraction | None]) -> Interferer:
    """j's demand on ``task``'s busy window, capped when j only runs because ``task`` completed."""
    stream = interferer(system, j, events[j.id], estimates.get(j.id), j.wcet)
    if suspension_jitter(system, j, estimates.get(j.id)) is None:
        return stream  # (a job of j may wait for its token without bound: released early, it runs late)
    path = causal_path(system, j, task, estimates)
    if path is None:
        return stream
    carry = carry_in(task, events[task.id], estimates.get(task.id), path[1])
    local = None
    if path[3] is not None:
        local_carry = carry_in(task, events[task.id], estimates.get(task.id), ZERO)
        local = None if local_carry is None else (local_carry, path[3])
    return Interferer(stream.task, stream.cost, stream.period, stream.jitter, stream.silent, path[0], carry, path[2],
                      local)


def cooperative_blocking(system: SystemModel, task: TaskModel, events: Mapping[str, EventModel],
                         estimates: Mapping[str, Fraction | None]
                         ) -> tuple[Fraction | None, Fraction | None, list[Interferer]]:
    """(βᵢ per job, βᵢ once per busy window, remote sibling streams). A sibling on another core may hold
    the token at the release of every job of i: the most of their hold times ``Eₛ``, per job. A sibling
    of i's core with lower priority can start only while i has no pending job, so it holds the token at
    most once per level-i busy window: the most of their ``Eₛ``, once (a local sibling of higher or
    equal priority is already in hp(i)). Remote siblings can also take the token while i's core is
    busy, once per activation: demand ``η⁺ₛ(w)·Eₛ`` (§6.3)."""
    sibs = siblings(system, task)
    if not sibs:
        return ZERO, ZERO, []
    holds = {s.id: hold_time(system, s, events, estimates) for s in sibs}

    def most(blockers: list[TaskModel]) -> Fraction | None:
        values = [v for s in blockers if (v := holds[s.id]) is not None]
        return None if len(values) < len(blockers) else max(values, default=ZERO)

    per_job = most([s for s in sibs if s.core != task.core])
    once = most([s for s in sibs if s.core == task.core and s.priority < task.priority])
    remote = [token_stream(s, events[s.id], estimates.get(s.id), holds[s.id]) for s in sibs if s.core != task.core]
    return per_job, once, remote


def token_stream(sibling: TaskModel, events: EventModel, response: Fraction | None,
                 hold: Fraction | None) -> Interferer:
    """How often a remote sibling can hold the token: every job holds it within ``[r, r + R]``, so
    jobs released up to R before a window can still hold it in the window: jitter ``J⁻ + R``."""
    jitter = None if events.jitter_min is None or response is None else events.jitter_min + response
    return Interferer(sibling.id, hold, events.period_min, jitter, events.silent)


# ================================================================== diagnostics


def _unbounded_help(system: SystemModel, task: TaskModel) -> str:
    """What would give a task without a bound one (E312)."""
    if task.executor is not None and system.executor(task.executor).multi_threaded:
        return ("put it in a callback group of its own (`group NAME mutually_exclusive` in its instance, "
                "`group NAME` on the task) or in a reentrant group, or lower the load of its executor")
    return "give it a higher priority, move higher-priority tasks to another core, or lower the load of its core"


def check_response_times(system: SystemModel, responses: Mapping[str, TaskResponse],
                         sink: DiagnosticSink) -> None:
    """E312: no response-time bound; E316: a bound above the deadline, which it does not prove (tasks with a
    user bound are trusted)."""
    for task in system.tasks:
        r = responses[task.id]
        if task.wcrt_bound is not None or (r.wcrt is not None and (r.deadline is None or r.wcrt <= r.deadline)):
            continue
        notes = [f"higher-or-equal-priority tasks on `{r.core}`: "
                 + (name_list(r.interferers) or "none")]
        if r.blocking:
            notes.append(f"cooperative blocking (the longest wait for the token): {fmt_time(r.blocking)}")
        interferers = tuple(Label(system.task(t).span, "interferes") for t in r.interferers[:3])
        if r.wcrt is None:
            where = f"on executor `{task.executor}`" if task.executor is not None else f"on core `{r.core}`"
            sink.emit("E312", f"no response-time bound for `{task.id}` {where}: "
                      f"{r.failure or 'no bound'}", task.span, "no bound", secondary=interferers, notes=tuple(notes),
                      help=_unbounded_help(system, task))
        elif r.deadline is not None and r.wcrt > r.deadline:
            sink.emit("E316", f"the response-time bound of `{task.id}` on core `{r.core}`, {fmt_time(r.wcrt)}, is "
                      f"above its deadline {fmt_time(r.deadline)} ({r.deadline_rule}): the bound does not prove the "
                      "deadline", task.span, "deadline not proved by the bound", secondary=interferers,
                      notes=tuple(notes), help="`verify prove` decides it (it shows a run that misses it, or "
                      "proves it); or give the task a higher priority or relax its deadline")
