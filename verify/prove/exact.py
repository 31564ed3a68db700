"""Exact worst cases by enumeration, and a falsifying search (specs/proof.md §3–§6).

* ``exact_class(model)``: whether the exactness theorem of the proof spec applies (constant
  execution times and delays, no sporadic source, a hyperperiod); otherwise a reason.
* ``representatives(model)``: the finite scenario set of the theorem — every phase vector
  ``u·tick + w·h`` (``u`` integer, ``w`` the rank vector of a weak order, ``h = tick/(2m+1)``), shift
  normalised — times every prescaler counter phase.
* ``enumerate_exact(model, targets, budget)``: evaluates every representative with the reference
  simulator (``measure_periodic``) and returns, per target, the exact supremum (and infimum), the
  scenario reaching it, and whether the enumeration was complete.
* ``approach``: from a representative towards a vertex of its region, a concrete scenario whose
  latency exceeds a threshold below the supremum (the suprema need not be attained).
* ``search(model, goals, budget)``: random and hill-climbing scenarios for systems outside the
  exact class. It can only find violations; it never proves.
"""
from __future__ import annotations

import itertools
import math
import random
import time
from dataclasses import dataclass, field
from fractions import Fraction
from collections.abc import Generator, Iterable
from collections.abc import Callable, Iterator

from ..model.system import SystemModel, TaskModel
from .sim import Sample, SimulationError
from .parallel import ordered_map, resolve_workers
from ..core.timebase import TimeBase, ceil_to, floor_to
from .measure import measure, measure_periodic
from .scenario import ConcreteScenario, Measured, ResponseSample, Target, hyperperiod

ZERO = Fraction(0)


class Budget:
    """A deterministic budget: a number of simulated scenarios, plus an optional wall-clock deadline
    (only when the user asked for ``--timeout``)."""

    def __init__(self, scenarios: int, deadline: float | None = None):
        self.left = scenarios
        self.used = 0
        self.deadline = deadline

    def take(self, n: int = 1) -> bool:
        if self.left < n or self.expired():
            return False
        self.left -= n
        self.used += n
        return True

    def expired(self) -> bool:
        return self.deadline is not None and time.monotonic() > self.deadline

    def spend(self, n: int) -> None:
        """Record ``n`` scenarios used elsewhere (a search on its own share of this budget)."""
        self.left -= n
        self.used += n


# ------------------------------------------------------------------ the exact class


def exact_class(model: SystemModel) -> str | None:
    """None when the exactness theorem (proof spec §4) applies to ``model``, else why not."""
    for t in model.tasks:
        if t.activation.irregular:
            return f"`{t.id}` is {t.activation.kind}: its releases have no hyperperiod"
    for t in model.tasks:
        if t.bcet != t.wcet:
            return (f"`{t.id}` has execution times in [bcet, wcet] with bcet < wcet: exactness is only "
                    "established for constant execution times (proof spec §4.4)")
    for lk in model.links:
        if lk.delay_min != lk.delay_max:
            return f"the connection `{lk.source} -> {lk.target}` has a delay range: exactness needs constant delays"
    if hyperperiod(model) is None:
        return "a task lies on a trigger cycle: the system has no hyperperiod"
    return None


def tick_of(model: SystemModel) -> Fraction:
    """The model's tick: the gcd of every period, fixed phase, execution time and delay."""
    values = []
    for t in model.tasks:
        values += [t.wcet, t.bcet]
        act = t.activation
        if act.strict_period is not None:
            values += [act.strict_period, act.fixed_phase or ZERO]
    for lk in model.links:
        values += [lk.delay_min, lk.delay_max]
    return TimeBase.gcd_of(values).unit


def free_timers(model: SystemModel) -> list[TaskModel]:
    return [t for t in model.tasks if t.activation.strict_period is not None and t.activation.fixed_phase is None]


def counter_tasks(model: SystemModel) -> list[TaskModel]:
    return [t for t in model.tasks if t.activation.release_every > 1]


def weak_orders(m: int) -> Iterator[tuple[int, ...]]:
    """Rank vectors ``w`` (length m) of every weak order of {zero, 0..m−1}: the block holding the
    zero element has rank 0, the others consecutive ranks below and above it."""
    elems = list(range(m + 1))  # m is the zero element

    def partitions(rest: list[int]) -> Iterator[list[list[int]]]:
        if not rest:
            yield []
            return
        for size in range(1, len(rest) + 1):
            for block in itertools.combinations(rest, size):
                remaining = [e for e in rest if e not in block]
                for tail in partitions(remaining):
                    yield [list(block)] + tail

    for blocks in partitions(elems):
        zero_at = next(i for i, b in enumerate(blocks) if m in b)
        ranks = [0] * m
        for i, block in enumerate(blocks):
            for e in block:
                if e != m:
                    ranks[e] = i - zero_at
        yield tuple(ranks)


@dataclass(frozen=True)
class Grid:
    """The search space of the theorem for one model."""

    tick: Fraction
    h: Fraction
    timers: tuple[str, ...]  # free-phase timers
    periods: tuple[int, ...]  # their periods in ticks
    normalise: bool  # only relative phases matter (no fixed phase)
    counters: tuple[tuple[str, int], ...]  # (task, prescaler) with prescaler > 1
    hyper: Fraction

    @property
    def m(self) -> int:
        return len(self.timers)


def grid_of(model: SystemModel) -> Grid:
    tick = tick_of(model)
    timers = free_timers(model)
    m = len(timers)
    fixed = any(t.activation.fixed_phase is not None for t in model.tasks)
    hyper = hyperperiod(model)
    if hyper is None:
        raise ValueError("a model without a hyperperiod is not of the exact class")
    return Grid(tick, tick / (2 * m + 1), tuple(t.id for t in timers),
                tuple(int(period / tick) for t in timers if (period := t.activation.strict_period) is not None),
                not fixed, tuple((t.id, t.activation.release_every) for t in counter_tasks(model)), hyper)


def _u_ranges(grid: Grid, w: tuple[int, ...]) -> list[range]:
    """Integer parts ``u_a`` that keep ``u_a·tick + w_a·h`` in [0, T_a)."""
    return [range(1 if wa < 0 else 0, (p + 1) if wa < 0 else p) for wa, p in zip(w, grid.periods)]


def count_representatives(grid: Grid, limit: int | None = None) -> int:
    """The size of the theorem's finite set (§4.2). With ``limit``, counting stops once the count
    exceeds it (the result is then some number above ``limit``): every weak order adds at least one
    phase vector, and there are Fubini(m + 1) of them, far too many to walk for many timers."""
    counters = math.prod(k for _, k in grid.counters)
    if grid.m == 0:
        return counters
    phases = 0
    for w in weak_orders(grid.m):
        ranges = _u_ranges(grid, w)
        total = math.prod(len(r) for r in ranges)
        if grid.normalise:
            zero = [a for a, wa in enumerate(w) if wa == 0]
            if not zero:
                continue
            without = math.prod(len(r) - (1 if a in zero and 0 in r else 0) for a, r in enumerate(ranges))
            total -= without
        phases += total
        if limit is not None and phases * counters > limit:
            break
    return phases * counters


def representatives(grid: Grid) -> Iterator[tuple[dict[str, Fraction], dict[str, int]]]:
    """Every (phases, counter phases) of the theorem's finite set, in a fixed order."""
    counter_space = list(itertools.product(*(range(k) for _, k in grid.counters)))
    phase_space: Iterator[tuple[Fraction, ...]]
    if grid.m == 0:
        phase_space = iter([()])
    else:
        def gen() -> Iterator[tuple[Fraction, ...]]:
            for w in weak_orders(grid.m):
                if grid.normalise and 0 not in w:
                    continue
                for u in itertools.product(*_u_ranges(grid, w)):
                    if grid.normalise and not any(ua == 0 and wa == 0 for ua, wa in zip(u, w)):
                        continue
                    yield tuple(ua * grid.tick + wa * grid.h for ua, wa in zip(u, w))
        phase_space = gen()
    for phases in phase_space:
        for counters in counter_space:
            yield (dict(zip(grid.timers, phases)),
                   {tid: c for (tid, _), c in zip(grid.counters, counters) if c})


def scenario_of(phases: dict[str, Fraction], counters: dict[str, int], horizon: Fraction = ZERO) -> ConcreteScenario:
    return ConcreteScenario(horizon, tuple(sorted(phases.items())), tuple(sorted(counters.items())))


# ------------------------------------------------------------------ enumeration


@dataclass
class Extreme:
    """The exact supremum (``kind`` "worst") or infimum ("best") of one target over a search space,
    with the measurement that reached it."""

    value: Fraction | None = None  # rounded to the tick: the supremum / infimum
    raw: Fraction | None = None  # the value in the reaching scenario itself
    measured: Measured | None = None


@dataclass
class ExactResult:
    """Per target: ``worst``/``best`` extremes; ``complete`` False if some scenario could not be
    evaluated completely (no periodic state within the window); ``explored`` scenarios."""

    method: str
    worst: dict[Target, Extreme] = field(default_factory=dict)
    best: dict[Target, Extreme] = field(default_factory=dict)
    complete: bool = True
    explored: int = 0
    reason: str = ""
    grid: Grid | None = None


PARALLEL_EVENTS = 200_000  # simulator events left to do above which the enumeration forks workers


def enumerate_exact(model: SystemModel, targets: list[Target], budget: Budget,
                    want_best: frozenset[Target] = frozenset(), max_periods: int = 64,
                    jobs: int | None = None) -> ExactResult | None:
    """The exact extremes of ``targets`` by evaluating every representative (None when the model is
    outside the exact class or the representatives do not fit in the budget).

    The representatives are independent: once the first has run, if the events still to simulate
    (its event count times the scenarios left) exceed ``PARALLEL_EVENTS``, the rest run in ``jobs``
    processes (None: every available CPU). Results are taken in order, so the outcome does not
    depend on ``jobs``."""
    if exact_class(model) is not None:
        return None
    grid = grid_of(model)
    n = count_representatives(grid, budget.left)
    if n > budget.left:
        return None
    result = ExactResult("exact-enumeration", {t: Extreme() for t in targets},
                         {t: Extreme() for t in want_best}, grid=grid)
    scenarios = [scenario_of(phases, counters) for phases, counters in representatives(grid)]

    def evaluate(i: int) -> Measured | None:
        try:
            return measure_periodic(model, scenarios[i], targets, grid.hyper, max_periods)
        except SimulationError:
            return None

    def measurements() -> Generator[Measured | None, None, None]:
        first = evaluate(0)
        yield first
        events = first.events if first is not None else 0
        workers = resolve_workers(jobs) if events * (n - 1) > PARALLEL_EVENTS else 1
        yield from ordered_map(evaluate, range(1, n), workers)

    results = measurements()
    try:
        for _ in scenarios:
            if not budget.take():
                result.complete = False
                result.reason = "the budget ran out"
                return result
            m = next(results)
            if m is None:
                result.complete = False
                result.reason = "a scenario exceeded the simulator's event budget (a zero-time loop?)"
                continue
            result.explored += 1
            if not m.complete:
                result.complete = False
                result.reason = (f"a scenario did not reach a periodic state within {max_periods} hyperperiods"
                                 if m.periodic_from is None else "a chain stopped delivering new values")
            _account(result, m, grid.tick, targets, want_best)
    finally:
        results.close()
    return result


def _account(result: ExactResult, m: Measured, tick: Fraction, targets: Iterable[Target],
             want_best: Iterable[Target]) -> None:
    for t in targets:
        sample = m.values[t].worst
        if sample is None:
            continue
        value = ceil_to(sample.value, tick)
        cur = result.worst[t]
        if cur.value is None or cur.raw is None or value > cur.value or (value == cur.value and sample.value > cur.raw):
            result.worst[t] = Extreme(value, sample.value, m)
    for t in want_best:
        sample = m.values[t].best
        if sample is None:
            continue
        value = floor_to(sample.value, tick)
        cur = result.best[t]
        if cur.value is None or cur.raw is None or value < cur.value or (value == cur.value and sample.value < cur.raw):
            result.best[t] = Extreme(value, sample.value, m)


def approach(model: SystemModel, grid: Grid, measured: Measured, target: Target,
             accept: Callable[[Fraction], bool], gap: Fraction, side: str = "worst",
             budget: Budget | None = None, max_periods: int = 64) -> Measured | None:
    """A concrete scenario on the segment from the representative of ``measured`` towards a vertex
    of its region whose value is accepted (proof spec §4.5). ``gap`` is how far the threshold lies
    inside the extreme (e.g. supremum − spec); the step ``λ < gap / (2·tick)`` suffices."""
    phases = dict(measured.scenario.phases)
    counters = dict(measured.scenario.counters)
    sample = getattr(measured.values[target], side)
    if sample is not None and accept(sample.value):
        return measured
    lam = min(Fraction(1), gap / (2 * grid.tick)) / 2
    corners = [sorted({floor_to(phases[a], grid.tick), ceil_to(phases[a], grid.tick)}) for a in grid.timers]
    periods = {a: p * grid.tick for a, p in zip(grid.timers, grid.periods)}
    for vertex in itertools.product(*corners):
        x = {a: v + lam * (phases[a] - v) for a, v in zip(grid.timers, vertex)}
        if any(not (0 <= x[a] < periods[a]) for a in x):
            continue
        if budget is not None and not budget.take():
            return None
        m = measure_periodic(model, scenario_of(x, counters), [target], grid.hyper, max_periods)
        s = getattr(m.values[target], side)
        if s is not None and accept(s.value):
            return m
    return None


# ------------------------------------------------------------------ falsifying search


@dataclass
class Goal:
    """What the search tries to exhibit for one target: a sample above ``above`` (worst side) or
    below ``below`` (best side); None: just push the extreme."""

    target: Target
    above: Fraction | None = None
    below: Fraction | None = None
    spread: Fraction | None = None  # jitter: the largest sample of one run minus the smallest of another


@dataclass
class SearchResult:
    worst: dict[Target, Measured] = field(default_factory=dict)  # target -> Measured with the largest sample
    best: dict[Target, Measured] = field(default_factory=dict)
    explored: int = 0


def search_horizon(model: SystemModel, span: Fraction | None) -> Fraction:
    """How long each search run simulates: two hyperperiods plus the latency bound, capped at 60
    times the longest period or inter-arrival (the search proves nothing, so the window only needs
    to be long enough to show a violation)."""
    longest = max([t.activation.gaps[1] for t in model.tasks if t.activation.gaps is not None]
                  + [Fraction(1, 1000)])
    hyper = hyperperiod(model)
    base = 2 * hyper if hyper is not None else 10 * longest
    return min(base + (span or 2 * longest), 60 * longest)


def _random_scenario(model: SystemModel, rng: random.Random, horizon: Fraction) -> ConcreteScenario:
    tick = tick_of(model)
    phases: list[tuple[str, Fraction]] = []
    for t in model.tasks:
        act = t.activation
        if act.offset_window is not None:
            phases.append((t.id, _grid_pick(rng, act.offset_window, tick)))
    counters = tuple((t.id, rng.randrange(t.activation.release_every)) for t in counter_tasks(model))
    mode = rng.random()
    execs: list[tuple[str, tuple[Fraction, ...]]] = []
    for t in model.tasks:
        if t.bcet == t.wcet or mode < 0.45:
            continue
        if mode < 0.55:
            execs.append((t.id, (t.bcet,)))
        elif mode < 0.75:
            execs.append((t.id, (rng.choice([t.bcet, t.wcet]),)))
        else:
            mid = (t.bcet + t.wcet) / 2
            execs.append((t.id, tuple(rng.choice([t.bcet, t.wcet, t.wcet, mid]) for _ in range(rng.choice([3, 5, 7])))))
    dmode = rng.random()
    delays: list[tuple[tuple[str, str], tuple[Fraction, ...]]] = []
    for lk in model.links:
        if lk.delay_min == lk.delay_max:
            continue
        if dmode < 0.6:
            delays.append(((lk.source, lk.target), (lk.delay_max,)))
        elif dmode < 0.75:
            continue
        else:
            delays.append(((lk.source, lk.target),
                           tuple(rng.choice([lk.delay_min, lk.delay_max]) for _ in range(rng.choice([2, 3, 5])))))
    gaps: list[tuple[str, tuple[Fraction, ...]]] = []
    for t in model.tasks:
        act = t.activation
        if act.gaps is not None and act.gaps[0] != act.gaps[1]:
            low, high = act.gaps
            choice = rng.random()
            if choice < 0.4:
                gaps.append((t.id, (high,)))
            elif choice < 0.7:
                gaps.append((t.id, tuple(_range_pick(rng, low, high)
                                         for _ in range(rng.choice([2, 3, 5])))))
    return ConcreteScenario(horizon, tuple(phases), counters, tuple(execs), tuple(delays), tuple(gaps))


def _grid_pick(rng: random.Random, length: Fraction, tick: Fraction) -> Fraction:
    """A phase in [0, length): a multiple of tick/4, often just below a multiple of the tick."""
    steps = max(1, int(length / (tick / 4)))
    value = (tick / 4) * rng.randrange(steps)
    if rng.random() < 0.3 and value > 0:
        value -= tick / 1000
    return value


def _range_pick(rng: random.Random, lo: Fraction, hi: Fraction) -> Fraction:
    return lo + (hi - lo) * Fraction(rng.randint(0, 8), 8)


def _mutate(model: SystemModel, sc: ConcreteScenario, rng: random.Random) -> ConcreteScenario:
    """A neighbour: one phase moved (a little or anywhere), or one execution pattern flipped."""
    tick = tick_of(model)
    phases = dict(sc.phases)
    if phases and rng.random() < 0.7:
        task = rng.choice(sorted(phases))
        act = model.task(task).activation
        gaps = act.gaps
        assert gaps is not None, "a task with a phase is released by time"
        length = gaps[1]  # (its phase lies in [0, its greatest gap))
        if rng.random() < 0.5:
            step = tick * Fraction(rng.choice([-4, -2, -1, 1, 2, 4]), rng.choice([1, 4, 16]))
            phases[task] = (phases[task] + step) % length
        else:
            phases[task] = _grid_pick(rng, length, tick)
        return ConcreteScenario(sc.horizon, tuple(sorted(phases.items())), sc.counters, sc.exec_times, sc.delays,
                                sc.interarrivals)
    execs = dict(sc.exec_times)
    varying = [t for t in model.tasks if t.bcet != t.wcet]
    if varying:
        t = rng.choice(varying)
        execs[t.id] = (rng.choice([t.bcet, t.wcet]),)
    counters = dict(sc.counters)
    for t in counter_tasks(model):
        if rng.random() < 0.3:
            counters[t.id] = rng.randrange(t.activation.release_every)
    return ConcreteScenario(sc.horizon, sc.phases, tuple(sorted(counters.items())), tuple(sorted(execs.items())),
                            sc.delays, sc.interarrivals)


#: events after which a search run ends (at the next instant: the shorter run)
SEARCH_EVENTS = 400_000


def first_scenarios(model: SystemModel, horizon: Fraction) -> list[ConcreteScenario]:
    """The extremes every search starts with: every phase 0 with wcet and d⁺, then with bcet and d⁻."""
    return [ConcreteScenario(horizon, (), (), (), tuple(((lk.source, lk.target), (lk.delay_max,))
                                                        for lk in model.links if lk.delay_min != lk.delay_max)),
            ConcreteScenario(horizon, (), (), tuple((t.id, (t.bcet,)) for t in model.tasks if t.bcet != t.wcet))]


def search(model: SystemModel, goals: list[Goal], budget: Budget, horizon: Fraction, seed: str = "verify-prove",
           max_events: int = SEARCH_EVENTS, given: tuple[Measured, ...] = (),
           resume: SearchResult | None = None) -> SearchResult:
    """Random scenarios, then hill climbing from the best one per goal, until every goal has a
    violating scenario or the budget is used. Deterministic for a given seed and budget. ``given``:
    the runs of ``first_scenarios`` made elsewhere — on a system of which this one's tasks are a cone,
    at least ``horizon`` long — taken instead of simulating them here. ``resume``: an earlier search
    of this system and horizon (with another seed), continued: its best runs are where the climbing
    starts, its scenarios count on, and the first scenarios are not run again."""
    rng = random.Random(seed)
    targets = sorted({g.target for g in goals})
    result = SearchResult() if resume is None else SearchResult(dict(resume.worst), dict(resume.best),
                                                                resume.explored)

    def done() -> bool:
        for g in goals:
            w, b = result.worst.get(g.target), result.best.get(g.target)
            if g.above is not None and not _beyond(w, g.target, "worst", g.above):
                return False
            if g.below is not None and not _beyond(b, g.target, "best", g.below):
                return False
            if g.spread is not None and not _spread_over(w, b, g.target, g.spread):
                return False
        return True

    def consider(m: Measured) -> bool:
        improved = False
        for t in targets:
            w, b = m.values[t].worst, m.values[t].best
            cur = result.worst.get(t)
            kept = None if cur is None else cur.values[t].worst  # (a run is kept with its sample)
            if w is not None and (kept is None or w.value > kept.value):
                result.worst[t] = m
                improved = True
            cur = result.best.get(t)
            kept = None if cur is None else cur.values[t].best
            if b is not None and (kept is None or b.value < kept.value):
                result.best[t] = m
                improved = True
        return improved

    from .sim import ScenarioError, SimulationError

    def run(sc: ConcreteScenario) -> Measured | None:
        try:  # a run with max_events events ends at the next instant (a shorter run, as real as any)
            m = measure(model, sc, targets, 2 * max_events, event_budget=max_events)
        except (ScenarioError, SimulationError):  # (past twice that within one instant: a zero-time loop)
            return None
        result.explored += 1
        return m

    m: Measured | None
    for m in given:
        result.explored += 1
        consider(m)
    for sc in () if given or resume is not None else first_scenarios(model, horizon):
        if done() or not budget.take():
            return result
        m = run(sc)
        if m is not None:
            consider(m)
    explore = max(1, budget.left * 2 // 5)
    for _ in range(explore):
        if done() or not budget.take():
            return result
        m = run(_random_scenario(model, rng, horizon))
        if m is not None:
            consider(m)
    while not done() and budget.take():
        g = goals[rng.randrange(len(goals))]
        side = "worst" if g.above is not None else "best" if g.below is not None else rng.choice(["worst", "best"])
        base = (result.worst if side == "worst" else result.best).get(g.target)
        sc = (_random_scenario(model, rng, horizon) if base is None
              else _mutate(model, base.scenario.with_horizon(horizon), rng))
        m = run(sc)
        if m is not None:
            consider(m)
    return result


def _spread_over(worst: Measured | None, best: Measured | None, target: Target, spread: Fraction) -> bool:
    """Whether the worst sample of ``worst`` and the best of ``best`` are more than ``spread`` apart."""
    if worst is None or best is None:
        return False
    w, b = worst.values[target].worst, best.values[target].best
    return w is not None and b is not None and w.value - b.value > spread


def _beyond(m: Measured | None, target: Target, side: str, threshold: Fraction) -> bool:
    if m is None:
        return False
    s: Sample | ResponseSample | None = getattr(m.values[target], side)
    if s is None:
        return False
    return s.value > threshold if side == "worst" else s.value < threshold
