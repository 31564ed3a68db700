"""Concrete scenarios and their evaluation by the reference simulator (specs/proof.md §2, §5).

A ``ConcreteScenario`` fixes every free choice of one run in a form that can be written to JSON and
replayed: phases, prescaler counter phases, and per task / per connection *patterns* of execution
times, delays and sporadic inter-arrival times (job or message ``i`` takes ``pattern[i % len]``).
``to_sim`` turns it into a ``verify.prove.sim.Scenario``: ``replay`` runs it in the reference simulator,
which every counterexample is checked against. The searches evaluate scenarios with the integer
simulator of ``intsim.py`` (and ``rigid.py`` on top of it, both through ``measure.py``), which the
tests hold to the reference paths here.

Targets name what is measured: a chain latency (``reaction_time``, ``data_age`` — reduced —,
``data_age_nonreduced``; the kinds of ``verify.prove.sim.KINDS``) or a task's response time
(``response``). ``measure_reference`` runs a scenario to a fixed horizon; ``measure_periodic_reference``
(rigid systems only, §4.3 of the proof spec) runs until the timing state repeats and the samples are
provably complete, so that its maxima are those of the infinite run.
"""
from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, TypeAlias, TypeVar

from ..model.system import SystemModel, TaskModel
from ..core.timebase import frac_lcm
from .sim import DEFAULT_MAX_EVENTS, Sample, Scenario, SimJob, Simulator, Trace, chain_latencies, simulate

ZERO = Fraction(0)
CHAIN_KINDS = ("reaction_time", "data_age", "data_age_nonreduced")

_K = TypeVar("_K")
#: a time: ticks (``rigid``) or seconds (``measure_periodic_reference``)
_T = TypeVar("_T", int, Fraction)
#: what decides the timing of a run's future (``timing_state``): six sorted tuples, compared for equality
TimingState: TypeAlias = "tuple[tuple[object, ...], ...]"


# ------------------------------------------------------------------ targets and samples


@dataclass(frozen=True, order=True)
class Target:
    """What one verdict measures: ``kind`` in CHAIN_KINDS (``name`` a chain) or "response" (a task)."""

    kind: str
    name: str


@dataclass(frozen=True)
class ResponseSample:
    """One job's response time ``value = finish − release`` (``finish`` None: not finished by the
    horizon, ``value`` then a lower bound)."""

    value: Fraction
    task: str
    index: int
    release: Fraction
    finish: Fraction | None


def _chain_samples(trace: Trace, model: SystemModel, target: Target) -> tuple[Sample, ...]:
    chain = next(c for c in model.chains if c.name == target.name)
    samples: tuple[Sample, ...] = getattr(chain_latencies(trace, chain), target.kind)
    return samples


def _response_samples(trace: Trace, target: Target, with_open: bool = False) -> list[ResponseSample]:
    out = []
    for j in trace.jobs[target.name]:
        if j.finish is not None:
            out.append(ResponseSample(j.finish - j.release, j.task, j.index, j.release, j.finish))
        elif with_open:
            out.append(ResponseSample(trace.horizon - j.release, j.task, j.index, j.release, None))
    return out


@dataclass(frozen=True)
class Extremes:
    """The largest and smallest sample of one target in one run (None: no sample)."""

    worst: Sample | ResponseSample | None
    best: Sample | ResponseSample | None


def extremes(trace: Trace, model: SystemModel, target: Target, with_open: bool = False) -> Extremes:
    samples: Sequence[Sample | ResponseSample]
    if target.kind == "response":
        samples = _response_samples(trace, target, with_open)
    else:
        samples = list(_chain_samples(trace, model, target))
    if not samples:
        return Extremes(None, None)
    # deterministic tie-break: the earliest sample of equal value
    worst = max(samples, key=lambda s: (s.value, -_when(s)))
    best = min(samples, key=lambda s: (s.value, _when(s)))
    return Extremes(worst, best)


def _when(s: Sample | ResponseSample) -> Fraction:
    return s.begin if isinstance(s, Sample) else s.release


# ------------------------------------------------------------------ scenarios


def _pattern(values: Iterable[Fraction | int | str]) -> tuple[Fraction, ...]:
    return tuple(Fraction(v) for v in values)


@dataclass(frozen=True)
class ConcreteScenario:
    """Every free choice of one run, replayable and serialisable (see the module docstring).

    Missing entries take the simulator's defaults (phase 0, counter 0, ``wcet``, ``delay_min``,
    ``min_interarrival``)."""

    horizon: Fraction
    phases: tuple[tuple[str, Fraction], ...] = ()
    counters: tuple[tuple[str, int], ...] = ()
    exec_times: tuple[tuple[str, tuple[Fraction, ...]], ...] = ()
    delays: tuple[tuple[tuple[str, str], tuple[Fraction, ...]], ...] = ()
    interarrivals: tuple[tuple[str, tuple[Fraction, ...]], ...] = ()

    def with_horizon(self, horizon: Fraction) -> ConcreteScenario:
        return ConcreteScenario(Fraction(horizon), self.phases, self.counters, self.exec_times, self.delays,
                                self.interarrivals)

    def to_sim(self, model: SystemModel) -> Scenario:
        """The ``verify.prove.sim.Scenario`` of these choices; entries without a pattern take the
        simulator's defaults for ``model``."""
        wcet: dict[str, Fraction] = {t.id: t.wcet for t in model.tasks}
        dmin: dict[tuple[str, str], Fraction] = {(lk.source, lk.target): lk.delay_min for lk in model.links}
        amin: dict[str, Fraction] = {t.id: t.activation.gaps[0] for t in model.tasks
                if t.activation.gaps is not None and t.activation.gaps[0] != t.activation.gaps[1]}
        execs, delays, gaps = dict(self.exec_times), dict(self.delays), dict(self.interarrivals)

        def exec_time(task: str, index: int) -> Fraction:
            pattern = execs.get(task)
            return wcet[task] if pattern is None else pattern[index % len(pattern)]

        def delay(source: str, target: str, index: int) -> Fraction:
            pattern = delays.get((source, target))
            return dmin[(source, target)] if pattern is None else pattern[index % len(pattern)]

        def gap(task: str, index: int) -> Fraction:
            pattern = gaps.get(task)
            return amin[task] if pattern is None else pattern[index % len(pattern)]

        return Scenario(self.horizon, dict(self.phases), exec_time if execs else None,
                        delay if delays else None, gap if gaps else None, dict(self.counters))

    def to_json(self) -> dict[str, Any]:
        from ..timing.report import exact

        return {
            "horizon": exact(self.horizon),
            "phases": {t: exact(v) for t, v in self.phases},
            "counter_phases": dict(self.counters),
            "execution_times": {t: [exact(v) for v in p] for t, p in self.exec_times},
            "delays": {f"{s} -> {d}": [exact(v) for v in p] for (s, d), p in self.delays},
            "interarrivals": {t: [exact(v) for v in p] for t, p in self.interarrivals},
            "pattern_rule": "job, message or release i takes pattern[i mod len(pattern)]",
        }

    @classmethod
    def from_json(cls, doc: dict[str, Any]) -> ConcreteScenario:
        def q(x: Any) -> Fraction:
            return Fraction(x["exact"])

        return cls(
            q(doc["horizon"]),
            tuple((t, q(v)) for t, v in doc.get("phases", {}).items()),
            tuple((t, int(v)) for t, v in doc.get("counter_phases", {}).items()),
            tuple((t, tuple(q(v) for v in p)) for t, p in doc.get("execution_times", {}).items()),
            tuple((tuple(k.split(" -> ")), tuple(q(v) for v in p)) for k, p in doc.get("delays", {}).items()),
            tuple((t, tuple(q(v) for v in p)) for t, p in doc.get("interarrivals", {}).items()),
        )

    def summary(self, model: SystemModel) -> str:
        """One line for a diagnostic note: the phases and how execution times and delays were chosen."""
        from ..model.units import fmt_time

        parts = []
        free = [t.id for t in model.tasks if t.activation.offset_window is not None]
        given = dict(self.phases)
        if free:
            if any(given.get(t, ZERO) for t in free):
                parts.append("phases " + ", ".join(f"{t} {fmt_time(given.get(t, ZERO))}" for t in free))
            else:
                parts.append("all phases 0")
        if self.counters:
            parts.append("counters " + ", ".join(f"{t} {c}" for t, c in self.counters))
        execs = _policy_text(self.exec_times, {t.id: (t.bcet, t.wcet) for t in model.tasks}, "wcet")
        parts.append("execution times " + (execs or "constant (bcet = wcet)"))
        delays = _policy_text(self.delays, {(lk.source, lk.target): (lk.delay_min, lk.delay_max)
                                            for lk in model.links}, "d⁻")
        if delays:
            parts.append("delays " + delays)
        return "; ".join(parts)


def _policy_text(patterns: Iterable[tuple[object, tuple[Fraction, ...]]],
                 ranges: Mapping[_K, tuple[Fraction, Fraction]], default: str) -> str | None:
    """How the choices with a range were made (None: nothing has a range)."""
    chosen = dict(patterns)
    if all(lo == hi for lo, hi in ranges.values()):
        return None
    if not chosen:
        return f"all {default}"
    lows = highs = 0
    for key, (lo, hi) in ranges.items():
        pattern = chosen.get(key)
        if lo == hi:
            continue
        if pattern is None:
            if default == "wcet":
                highs += 1
            else:
                lows += 1
        elif all(v == hi for v in pattern):
            highs += 1
        elif all(v == lo for v in pattern):
            lows += 1
        else:
            return "varying per job (see the JSON output)" if default == "wcet" else "varying per message"
    if lows and highs:
        return "mixed extremes (see the JSON output)"
    if not lows and not highs:
        return "fixed"
    return ("all wcet" if highs else "all bcet") if default == "wcet" else ("all d⁺" if highs else "all d⁻")


def replay(model: SystemModel, scenario: ConcreteScenario, max_events: int = DEFAULT_MAX_EVENTS,
           deadline: float | None = None) -> Trace:
    """The run of ``scenario`` (over ``[0, scenario.horizon)``), by ``verify.prove.sim.simulate`` (which ends
    it with ``SimulationTimeout`` once ``deadline``, a ``time.monotonic()`` instant, has passed)."""
    return simulate(model, scenario.to_sim(model), max_events, deadline)


# ------------------------------------------------------------------ hyperperiod


def hyperperiod(model: SystemModel) -> Fraction | None:
    """The least common multiple of every task's *effective* period: a timer's period, and for a data
    trigger the lcm of its members' writers' effective periods times the prescaler (§4.3). None
    when a task is sporadic or on a trigger cycle."""
    from ..timing.rates import trigger_order

    order, cyclic = trigger_order(model)
    if cyclic:
        return None
    eff: dict[str, Fraction | None] = {}
    for tid in order:
        t = model.task(tid)
        act = t.activation
        if act.strict_period is not None:
            eff[tid] = act.strict_period
        elif act.trigger_port is not None:
            links = [lk for member in act.trigger_members
                     if (lk := model.link_into(f"{t.instance}.{member}")) is not None]
            writers = [w for lk in links if (w := eff.get(lk.writer)) is not None]
            if len(writers) < len(links):
                eff[tid] = None
            else:
                base = frac_lcm(writers)
                eff[tid] = None if base is None else base * act.release_every
        else:
            eff[tid] = None
    if any(v is None for t, v in eff.items() if not _silent(model, t)):
        return None
    return frac_lcm(v for v in eff.values() if v is not None)


def _silent(model: SystemModel, tid: str) -> bool:
    """A triggered task none of whose members is connected never runs."""
    t = model.task(tid)
    act = t.activation
    return act.trigger_port is not None and all(
        model.link_into(f"{t.instance}.{m}") is None for m in act.trigger_members)


# ------------------------------------------------------------------ periodic evaluation (rigid systems)


@dataclass(frozen=True)
class Measured:
    """The outcome of one scenario: per target its extremes; ``complete`` says whether they are
    those of the infinite run (§4.3), ``horizon`` how far the simulator ran, ``periodic_from`` the
    detected start ``t₀`` and ``period`` the detected period of the timing state."""

    scenario: ConcreteScenario
    values: dict[Target, Extremes]
    complete: bool
    horizon: Fraction
    periodic_from: Fraction | None = None
    period: Fraction | None = None
    events: int = 0


def repetition(run_to: Callable[[_T], object], timing_state: Callable[[_T], Hashable], hyper: _T,
               max_periods: int) -> tuple[_T, _T] | None:
    """(t₀, P) of specs/proof.md §4.3: drive a run to the multiples of ``hyper`` until its timing
    state at one equals that at an earlier one; None if none repeats within ``max_periods``."""
    seen: dict[Hashable, int] = {}
    for k in range(max_periods + 1):
        run_to(k * hyper)
        state = timing_state(k * hyper)
        if state in seen:
            return seen[state] * hyper, (k - seen[state]) * hyper
        seen[state] = k
    return None


def timing_state(sim: Simulator, at: Fraction) -> TimingState:
    """Everything that decides the *timing* of the future after ``at`` (nothing of provenance):
    pending jobs with their remaining work, cooperative tokens, scheduled releases and arrivals in
    processing order, FIFO back-pressure, prescaler counters and AND freshness — all relative to
    ``at``. Execution times and delays are constants in the systems this is used on."""
    ready = tuple(sorted((core, tuple(sorted((j.task.id, j.release - at, j.remaining, j.start is not None)
                                             for j in jobs + _executor_jobs(sim, core))))
                         for core, jobs in sim.ready.items()))
    holders = tuple(sorted((inst, j.task.id, j.release - at) for inst, j in sim.holder.items()))
    # entries of one instant and phase in canonical order: releases of different timers, and arrivals
    # on different connections, do not interact within an instant (specs/proof.md §4.3); the stable
    # sort keeps the send order of messages on one connection
    entries = sorted(sim.heap, key=lambda e: (e[0], e[1], e[2]))
    # (a release carries its task, an arrival its message)
    heap = tuple(sorted(((time - at, phase, payload.id if isinstance(payload, TaskModel)
                          else (payload.source, payload.target)) for time, phase, _seq, payload in entries),
                        key=lambda e: (e[0], e[1], e[2])))
    back = tuple(sorted((k, v - at) for k, v in sim.last_arrival.items() if v > at))
    counters = tuple(sorted(sim.counter.items()))
    fresh = tuple(sorted((k, tuple(sorted(v))) for k, v in sim.fresh.items()))
    snapshots = tuple(tuple((j.task.id, j.release - at) for j in ex.snapshot) for ex in sim.executors.values())
    return ready, holders, heap, back, counters, fresh, snapshots


def _executor_jobs(sim: Simulator, core: str) -> list[SimJob]:
    """The released, uncompleted jobs of the executors of ``core`` (specs/timing.md §9)."""
    return [j for ex in sim.threads.get(core, ()) for j in ex.jobs_on(core)]


def _covered(trace: Trace, model: SystemModel, target: Target, mark: Fraction, period_end: Fraction) -> bool:
    """Whether every sample class of ``target`` is in ``trace`` (proof spec §4.3)."""
    if target.kind == "response":
        return all(j.finish is not None for j in trace.jobs[target.name] if j.release < period_end)
    chain = next(c for c in model.chains if c.name == target.name)
    return any(s.begin >= mark for s in chain_latencies(trace, chain).data_age)


def measure_periodic_reference(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target],
                               hyper: Fraction, max_periods: int = 64,
                               max_events: int = DEFAULT_MAX_EVENTS) -> Measured:
    """Run a rigid system (constant execution times and delays, no sporadic source) until its timing
    state at a multiple of ``hyper`` repeats, then until every sample class is present; return the
    extremes of every target, which are then those of the infinite run (proof spec §4.3).

    ``complete`` is False when no repetition (or no coverage) shows up within ``max_periods``
    hyperperiods; the extremes are then those of the simulated prefix only."""
    targets = tuple(targets)
    sim = Simulator(model, scenario.with_horizon(hyper * (max_periods + 2)).to_sim(model), max_events)
    found = repetition(sim.run_to, lambda t: timing_state(sim, t), hyper, max_periods)
    horizon = sim.now
    complete = False
    if found is not None:
        t0, period = found
        mark, end = t0 + 2 * period, t0 + period
        horizon = max(horizon, t0 + 3 * period)
        limit = hyper * (max_periods + 1) + 2 * period
        while True:
            sim.run_to(horizon)
            trace = sim.trace(horizon)
            if all(_covered(trace, model, t, mark, end) for t in targets):
                complete = True
                break
            if horizon >= limit:
                break
            horizon += period
    trace = sim.trace(horizon)
    values = {t: extremes(trace, model, t) for t in targets}
    return Measured(scenario.with_horizon(horizon), values, complete, horizon, None if found is None else found[0],
                    None if found is None else found[1], sim.events)


def measure_reference(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target],
                      max_events: int = DEFAULT_MAX_EVENTS) -> Measured:
    """``measure`` by the reference simulator ``verify.prove.sim``."""
    trace = replay(model, scenario, max_events)
    values = {t: extremes(trace, model, t, with_open=True) for t in targets}
    return Measured(scenario, values, False, scenario.horizon)
