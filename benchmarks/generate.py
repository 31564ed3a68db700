"""Realistic benchmark systems as DSL text, following the WATERS 2015 automotive benchmark.

    text = generate_system(1000, seed=1)                       # configured, feasible (tightness 3/2)
    text = generate_system(500, seed=2, hole_share=Fraction(1, 5))   # holes for `synth`
    text = generate_system(500, seed=3, infeasible=True)       # specs that cannot hold
    text = generate_chain_system(10, seed=1)                   # one chain for prove's exact search
    text = generate_pipeline_system(300, seed=1)               # a trigger pipeline at one priority

    python -m benchmarks.generate --tasks 1000 --seed 1 -o out.vfy

Everything is drawn from one ``random.Random(seed)`` with integer draws only, and every number in the
text is exact (integers and terminating decimals), so the same arguments give the same text on every
machine. The numbers come from S. Kramer, D. Ziegenbein, A. Hamann, *Real World Automotive Benchmarks
For Free*, WATERS 2015 (the tables below); the chain shapes are those used by the cause-effect-chain
evaluations built on it (Günzel et al., RTAS 2021 / TECS 2023).

How a system is made (``draw_system``; ``render`` turns it into text):

1. **Tasks**: one component per task (instance ``tK`` of component ``CK``, task ``Run``). The period is
   drawn with the WATERS shares, the angle-synchronous share folded into 20 ms. The ACET is a
   triangular(min, avg, max) draw from the per-period table, in whole nanoseconds; BCET = ACET·f_b and
   WCET = ACET·f_w with f_b, f_w uniform (in hundredths) in the per-period ranges.
2. **Chains**: 30–60 per system (scaled down below 200 tasks), each of 1 (70 %), 2 (20 %) or 3 (10 %)
   distinct periods with 2 (30 %), 3 (40 %), 4 (20 %) or 5 (10 %) tasks of each period, shuffled: 2–15
   tasks. Every hop ``a -> b`` becomes a connection ``ta.o -> tb.iA`` (in-port ``iA`` of ``tb`` is fed
   by ``ta``; message type ``MA``).
3. **Activation** (robotics-style variety): a task fed by a task decided before it whose period divides
   its own by 1, 2, 5 or 10 may be data-triggered on that in-port with that prescaler (so its rate is
   the WATERS rate); a task fed by two such tasks of equal period may trigger on an AND compound of
   both. Trigger edges always point from a lower to a higher task number, so they form no cycle. Every
   other task runs on a timer (a quarter of them with a phase in [0, T)); a few timer tasks have a
   `fixed` rate (sensors).
4. **Cores**: tasks are spread round-robin over ``cores`` cores (shuffled), each core gets a
   utilisation target in [0.5, 0.7] (in hundredths) and its execution times are scaled to meet it;
   priorities are rate-monotonic and unique per core (larger number = shorter period).
5. **Delays**: half of the links between cores and a tenth of the others carry a delay
   (``delay D`` or ``delay D1 .. D2``, 10 us .. 500 us).
6. **Specs**: each chain gets ``reaction_time`` and/or ``data_age`` bounds equal to ``tightness`` times
   its *reference bound* (rounded to microseconds: up when tightness ≥ 1, down below 1), the
   Davare-style sum Σ(Wᵢ + R̂ᵢ) + Σ d⁺ᵢ over its tasks and hops (Davare et al., DAC 2007). R̂ᵢ is the
   closed-form response-time bound of Bini, Nguyen, Richard and Baruah (IEEE TC 2009) with release
   jitter; Wᵢ, the longest wait for the next activation, is Tᵢ for a timer task and, for a
   data-triggered one, follows the CPA event model of specs/timing.md (the writer's output jitter,
   the prescaler, the latest first activation). See ``_reference_timing``. It is a reference, not a
   proof, but it was never below the worst case of ``verify.timing.analyze`` on hundreds of chains,
   so tightness ≥ 1 gives specs the analysis proves.
7. **Holes** (``hole_share`` of the tasks whose rate is not fixed, chosen exactly): a timer task gets
   ``timer ? in T/2 .. 2T step T/2`` (or ``timer ? in F/2 Hz .. 2F Hz``, or a bare ``timer ?``), a
   data-triggered one ``trigger p every ? in 1 .. 10``, and some ``activation ?``. The drawn (reference)
   value always lies within the hole and the task's activation constraint, so a system feasible for its
   reference configuration stays feasible for ``synth``.
8. **Infeasible on purpose** (``infeasible=True``): a tenth of the chains (at least one) start with a
   timer task of `fixed` rate and get ``reaction_time <= T₁/2``, below its own period (the worst-case
   reaction time is at least T₁), so no configuration can meet it. A ``tightness`` well below 1 makes
   the other specs likely infeasible too.

``generate_chain_system`` (``draw_chain``, ``render_chain``) makes a different kind of system, for the
exact worst-case search of ``prove``: one chain of ``n_tasks`` tasks in prove's exact class (constant
execution times and delays), one free phase, a hyperperiod of up to ``1000 · n_tasks`` jobs, and specs
below the analysis' own bound so that only the exact search can decide them (see its docstring).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass, field
from fractions import Fraction
from math import gcd, isqrt
from random import Random

# --------------------------------------------------------------------------- WATERS 2015 constants
# S. Kramer, D. Ziegenbein, A. Hamann, "Real World Automotive Benchmarks For Free", WATERS 2015.
# Periods in ms and their share of runnables in percent; the 15 % angle-synchronous share is folded
# into 20 ms (10 + 15 = 25 + 15 -> 40).
PERIOD_SHARES: tuple[tuple[int, int], ...] = (
    (1, 3), (2, 2), (5, 2), (10, 25), (20, 40), (50, 3), (100, 20), (200, 1), (1000, 4),
)
# ACET per period (min, avg, max), in nanoseconds (the paper's table is in microseconds, 2 decimals).
ACET_NS: dict[int, tuple[int, int, int]] = {
    1: (340, 5000, 30110),
    2: (320, 4200, 40690),
    5: (360, 11040, 83380),
    10: (210, 10090, 309870),
    20: (250, 8740, 291420),
    50: (290, 17560, 92980),
    100: (210, 10530, 420430),
    200: (220, 2560, 21950),
    1000: (370, 430, 460),
}
# BCET = ACET * f_b, WCET = ACET * f_w; f uniform in the range, here in hundredths.
FACTORS: dict[int, tuple[tuple[int, int], tuple[int, int]]] = {
    1: ((19, 92), (130, 2911)),
    2: ((12, 89), (154, 1904)),
    5: ((17, 94), (113, 1844)),
    10: ((5, 99), (106, 3003)),
    20: ((11, 98), (106, 1561)),
    50: ((32, 95), (113, 776)),
    100: ((9, 99), (102, 888)),
    200: ((45, 98), (103, 490)),
    1000: ((68, 80), (184, 475)),
}
# Cause-effect chains: 30-60 per system; distinct periods per chain (1: 70 %, 2: 20 %, 3: 10 %);
# tasks per period (2: 30 %, 3: 40 %, 4: 20 %, 5: 10 %).
CHAINS_PER_SYSTEM = (30, 60)
PERIODS_PER_CHAIN: tuple[tuple[int, int], ...] = ((1, 70), (2, 20), (3, 10))
TASKS_PER_PERIOD: tuple[tuple[int, int], ...] = ((2, 30), (3, 40), (4, 20), (5, 10))

# ------------------------------------------------------------------------------- other choices
PRESCALERS = (1, 2, 5, 10)
CORE_UTILISATION = (50, 70)  # per-core target, hundredths, uniform
FULL_SIZE = 200  # below this many tasks the WATERS chain count is scaled down proportionally
TRIGGER_SHARE = Fraction(1, 2)  # of the tasks that could be data-triggered
AND_SHARE = Fraction(1, 2)  # of the triggered tasks with two compatible sources
FIXED_SHARE = Fraction(1, 20)  # of the timer tasks without a hole
PHASE_SHARE = Fraction(1, 4)  # of the timer tasks without a hole
OPTIONAL_SHARE = Fraction(1, 5)  # of the reads that are not trigger reads
DELAY_SHARE_REMOTE, DELAY_SHARE_LOCAL = Fraction(1, 2), Fraction(1, 10)
CONFLICT_SHARE = Fraction(1, 10)  # of the chains, when infeasible=True

NS_PER_MS = 10**6


def _pick(rng: Random, table: tuple[tuple[int, int], ...]) -> int:
    """A value drawn with integer weights."""
    r = rng.randrange(sum(w for _, w in table))
    for value, weight in table:
        if r < weight:
            return value
        r -= weight
    raise AssertionError("unreachable")


def _chance(rng: Random, p: Fraction) -> bool:
    return rng.randrange(p.denominator) < p.numerator


def _triangular(rng: Random, low: int, mode: int, high: int) -> int:
    """An integer triangular(low, mode, high) draw by the inverse CDF, in integer arithmetic only."""
    bits = 48
    u = rng.getrandbits(bits)  # u / 2**bits is uniform in [0, 1)
    span = high - low
    if u * span < (mode - low) << bits:  # u < (mode - low) / span
        return low + isqrt((u * span * (mode - low)) >> bits)
    return high - isqrt((((1 << bits) - u) * span * (high - mode)) >> bits)


def _exact(value: Fraction) -> Fraction:
    if isinstance(value, Fraction):
        return value
    return Fraction(str(value)) if isinstance(value, float) else Fraction(value)


# ------------------------------------------------------------------------------------ the model


@dataclass
class Task:
    index: int
    period_ms: int
    bcet_ns: int
    wcet_ns: int
    core: int = 0
    priority: int = 0
    sources: list[int] = field(default_factory=list)  # writers of this task's in-ports, in order
    trigger: tuple[int, ...] = ()  # the writers whose in-ports trigger it (1, or 2 for AND)
    prescaler: int = 1
    phase_us: int | None = None
    constraint: str = "range"  # "range" F/2..2F, "max" 2F, "none", "fixed"
    hole: str | None = None  # "grid", "freq", "bare", "prescaler", "unknown"
    optional: set[int] = field(default_factory=set)  # sources read optionally
    wcrt_bound: Fraction = Fraction(0)  # R-hat, seconds (reference configuration)
    a_max: Fraction = Fraction(0)  # longest time between activations, seconds
    first: Fraction = Fraction(0)  # latest first activation, seconds
    wait: Fraction = Fraction(0)  # W = max(a_max, first): the longest wait for the next activation

    @property
    def period(self) -> Fraction:
        return Fraction(self.period_ms, 1000)


@dataclass
class Link:
    source: int
    target: int
    delay_ns: tuple[int, int] | None = None


@dataclass
class Chain:
    name: str
    tasks: list[int]
    reference: Fraction = Fraction(0)  # seconds
    reaction_time: Fraction | None = None
    data_age: Fraction | None = None
    conflict: bool = False


@dataclass
class System:
    """A drawn benchmark system; ``render`` gives its text. Times in ``Fraction`` seconds."""

    name: str
    seed: int
    cores: int
    tightness: Fraction
    hole_share: Fraction
    infeasible: bool
    tasks: list[Task]
    links: dict[tuple[int, int], Link]
    chains: list[Chain]
    utilisation: list[Fraction]


# ------------------------------------------------------------------------------------ drawing


def draw_system(n_tasks: int, seed: int, *, cores: int = 4, chains: int | None = None,
                tightness: Fraction = Fraction(3, 2), hole_share: Fraction = Fraction(0),
                infeasible: bool = False) -> System:
    """Draw a benchmark system (see the module docstring for how)."""
    if n_tasks < 1:
        raise ValueError("a system needs at least one task")
    if cores < 1:
        raise ValueError("a system needs at least one core")
    tightness, hole_share = _exact(tightness), _exact(hole_share)
    if tightness <= 0:
        raise ValueError("tightness must be positive")
    if not 0 <= hole_share <= 1:
        raise ValueError("hole_share must lie in [0, 1]")
    rng = Random(seed)

    tasks = [_draw_task(rng, i) for i in range(n_tasks)]
    chain_list = _draw_chains(rng, tasks, chains)
    links: dict[tuple[int, int], Link] = {}
    for chain in chain_list:
        for a, b in zip(chain.tasks, chain.tasks[1:]):
            if (a, b) not in links:
                links[(a, b)] = Link(a, b)
                tasks[b].sources.append(a)
    conflict_heads: set[int] = set()
    if infeasible and chain_list:
        count = max(1, len(chain_list) * CONFLICT_SHARE.numerator // CONFLICT_SHARE.denominator)
        for chain in rng.sample(chain_list, count):
            chain.conflict = True
            conflict_heads.add(chain.tasks[0])
    _draw_activations(rng, tasks, conflict_heads)
    _draw_holes_and_constraints(rng, tasks, hole_share, conflict_heads)
    utilisation = _draw_cores(rng, tasks, cores)
    for link in links.values():
        _draw_delay(rng, link, tasks)
    _reference_timing(tasks, links, cores)
    for chain in chain_list:
        _specs(rng, chain, tasks, links, tightness)
    return System(f"Waters{n_tasks}s{seed}", seed, cores, tightness, hole_share, infeasible, tasks, links,
                  chain_list, utilisation)


def _draw_task(rng: Random, index: int) -> Task:
    period = _pick(rng, PERIOD_SHARES)
    acet = _triangular(rng, *ACET_NS[period])
    (b_lo, b_hi), (w_lo, w_hi) = FACTORS[period]
    f_b, f_w = rng.randint(b_lo, b_hi), rng.randint(w_lo, w_hi)
    # kept in hundredths of a nanosecond until the per-core scaling
    return Task(index, period, acet * f_b, acet * f_w)


def _draw_chains(rng: Random, tasks: list[Task], count: int | None) -> list[Chain]:
    n = len(tasks)
    if n < 2:
        return []
    if count is None:
        count = rng.randint(*CHAINS_PER_SYSTEM)
        if n < FULL_SIZE:
            count = max(1, -(-count * n // FULL_SIZE))
    by_period: dict[int, list[int]] = {}
    for t in tasks:
        by_period.setdefault(t.period_ms, []).append(t.index)
    periods = sorted(by_period)
    result = []
    for k in range(count):
        members: list[int] = []
        wanted = min(_pick(rng, PERIODS_PER_CHAIN), len(periods))
        for period in rng.sample(periods, wanted):
            pool = by_period[period]
            members += rng.sample(pool, min(_pick(rng, TASKS_PER_PERIOD), len(pool)))
        if len(members) < 2:  # too few tasks of the drawn period: add one of another
            members.append(rng.choice([i for i in rng.sample(range(n), min(n, 3)) if i not in members]))
        rng.shuffle(members)
        result.append(Chain(f"c{k}", members))
    return result


def _draw_activations(rng: Random, tasks: list[Task], forced_timers: set[int]) -> None:
    """Trigger on in-ports fed by lower-numbered tasks whose period divides by a prescaler."""
    for t in tasks:  # in index order: the sources of a trigger are always decided already
        if t.index in forced_timers:
            continue
        fits = [a for a in t.sources if a < t.index and t.period_ms % tasks[a].period_ms == 0
                and t.period_ms // tasks[a].period_ms in PRESCALERS]
        if not fits or not _chance(rng, TRIGGER_SHARE):
            continue
        first = rng.choice(fits)
        partners = [a for a in fits if a != first and tasks[a].period_ms == tasks[first].period_ms]
        if partners and _chance(rng, AND_SHARE):
            t.trigger = tuple(sorted((first, rng.choice(partners))))
        else:
            t.trigger = (first,)
        t.prescaler = t.period_ms // tasks[first].period_ms
    for t in tasks:
        t.optional = {a for a in t.sources if a not in t.trigger and _chance(rng, OPTIONAL_SHARE)}


def _draw_holes_and_constraints(rng: Random, tasks: list[Task], hole_share: Fraction,
                                fixed: set[int]) -> None:
    eligible = [t for t in tasks if t.index not in fixed]
    count = len(eligible) * hole_share.numerator // hole_share.denominator
    for t in rng.sample(eligible, count):
        if t.trigger:
            t.hole = "prescaler" if rng.randrange(4) else "unknown"
        else:
            t.hole = ("grid", "grid", "grid", "freq", "bare", "unknown")[rng.randrange(6)]
    for t in tasks:
        if t.index in fixed or not t.trigger and t.hole is None and _chance(rng, FIXED_SHARE):
            t.constraint = "fixed"
        elif t.hole == "bare":
            t.constraint = "range"  # a bare `timer ?` takes its candidates from the constraint
        else:
            t.constraint = ("range", "range", "range", "max", "none")[rng.randrange(5)]
        if not t.trigger and t.hole is None and _chance(rng, PHASE_SHARE):
            t.phase_us = rng.randrange(t.period_ms * 1000)


def _draw_cores(rng: Random, tasks: list[Task], cores: int) -> list[Fraction]:
    """Round-robin over shuffled tasks, scale to a utilisation target, rate-monotonic priorities."""
    order = list(range(len(tasks)))
    rng.shuffle(order)
    on: list[list[Task]] = [[] for _ in range(cores)]
    for k, i in enumerate(order):
        tasks[i].core = k % cores
        on[k % cores].append(tasks[i])
    result = []
    for members in on:
        target = Fraction(rng.randint(*CORE_UTILISATION), 100)
        if not members:
            result.append(Fraction(0))
            continue
        # raw WCETs are in hundredths of a ns; periods in ms
        raw = sum(Fraction(t.wcet_ns, 100 * t.period_ms * NS_PER_MS) for t in members)
        scale = target / raw
        for t in members:
            wcet = max(1, round(Fraction(t.wcet_ns, 100) * scale))
            t.bcet_ns = min(wcet, int(Fraction(t.bcet_ns, 100) * scale))
            t.wcet_ns = wcet
        result.append(sum(Fraction(t.wcet_ns, t.period_ms * NS_PER_MS) for t in members))
        members.sort(key=lambda t: (t.period_ms, t.index))  # rate-monotonic, unique priorities
        for rank, t in enumerate(members):
            t.priority = len(members) - rank
    return result


def _draw_delay(rng: Random, link: Link, tasks: list[Task]) -> None:
    remote = tasks[link.source].core != tasks[link.target].core
    if not _chance(rng, DELAY_SHARE_REMOTE if remote else DELAY_SHARE_LOCAL):
        return
    low = rng.randint(1, 50) * 10_000  # 10 us .. 500 us
    high = low if rng.randrange(2) else rng.randint(low // 10_000, 50) * 10_000
    link.delay_ns = (low, high)


MAX_ROUNDS = 50  # of the fixed point between response-time bounds and trigger jitter


def _reference_timing(tasks: list[Task], links: dict[tuple[int, int], Link], cores: int) -> None:
    """Response-time bounds R-hat and sampling waits W of every task in the reference configuration.

    R-hat is the closed-form bound of Bini et al. 2009 with release jitter,
    (C·(1 + ⌈J/T⌉) + Σ_hp (Cⱼ(1 − Uⱼ) + Uⱼ·Jⱼ)) / (1 − Σ_hp Uⱼ) (the ⌈J/T⌉ term: own jobs released
    late that may still be queued), by priority order on each core (running sums), rounded up to ns.
    Timer tasks have no jitter and wait at most W = T; a data-triggered task inherits the event model
    of its writers' outputs (CPA, specs/timing.md §5.2): jitter J = J_writer + (R-hat − bcet) + (d⁺ − d⁻),
    longest gap A⁺ = k·T_writer + J (an AND compound: k·max of its members' gaps), and waits at most
    W = max(A⁺, latest first activation). The two depend on each other; iterate to a fixed point.
    """
    n = len(tasks)
    by_core = [sorted((t for t in tasks if t.core == k), key=lambda t: -t.priority) for k in range(cores)]
    jitter = [Fraction(0)] * n  # J used for interference (the event model's minimum-distance jitter)
    zero = Fraction(0)
    for _ in range(MAX_ROUNDS):
        for members in by_core:
            carried, load = zero, zero
            for t in members:
                c = Fraction(t.wcet_ns, 10**9)
                backlog = -(-jitter[t.index] // t.period)  # own earlier jobs released up to J late
                t.wcrt_bound = _ceil_ns((c * (1 + backlog) + carried) / (1 - load))  # keeps numbers small
                u = c / t.period
                carried += c * (1 - u) + u * jitter[t.index]
                load += u
        new = list(jitter)
        for t in tasks:  # trigger sources have lower numbers: one pass in index order
            if not t.trigger:
                t.a_max, t.first, new[t.index] = t.period, (Fraction(t.phase_us, 10**6) if t.phase_us is not None
                                                            else t.period), zero
                continue
            arrivals = []  # (period, jitter, first) of the arrivals on each trigger member
            for a in t.trigger:
                src, d = tasks[a], links[(a, t.index)].delay_ns or (0, 0)
                out = src.wcrt_bound - Fraction(src.bcet_ns, 10**9) + Fraction(d[1] - d[0], 10**9)
                arrivals.append((src.period, new[a] + out, src.first + src.wcrt_bound + Fraction(d[1], 10**9)))
            k = t.prescaler
            if len(arrivals) == 1:
                period, j, first = arrivals[0]
                t.a_max, new[t.index] = k * period + j, j
                t.first = first + (k - 1) * period + j if k > 1 else first
            else:  # AND: the next event once every member has a new arrival
                gap = max(p + j for p, j, _ in arrivals)
                t.a_max, new[t.index] = k * gap, max(p + j for p, j, _ in arrivals)
                t.first = max(f for _, _, f in arrivals) + (k - 1) * gap
        if new == jitter:
            break
        jitter = new
    for t in tasks:
        t.wait = max(t.a_max, t.first)


def _specs(rng: Random, chain: Chain, tasks: list[Task], links, tightness: Fraction) -> None:
    """Davare-style reference Σ(Wᵢ + R-hatᵢ) + Σ d⁺ (Wᵢ = Tᵢ for timer tasks) and specs from it."""
    ref = sum((tasks[i].wait + tasks[i].wcrt_bound for i in chain.tasks), Fraction(0))
    for a, b in zip(chain.tasks, chain.tasks[1:]):
        d = links[(a, b)].delay_ns
        if d is not None:
            ref += Fraction(d[1], 10**9)
    chain.reference = ref
    us = Fraction(1, 10**6)
    scaled = tightness * ref / us
    ticks = -(-scaled.numerator // scaled.denominator) if tightness >= 1 else scaled.numerator // scaled.denominator
    bound = max(us, ticks * us)
    which = rng.randrange(3)  # both, reaction time only, data age only
    if which in (0, 1):
        chain.reaction_time = bound
    if which in (0, 2):
        chain.data_age = bound
    if chain.conflict:  # below the first task's own (fixed) period: impossible
        chain.reaction_time = tasks[chain.tasks[0]].period / 2


# ------------------------------------------------------------------------------------ rendering


def _decimal(value: Fraction) -> str:
    """Exact: an integer, a terminating decimal, or ``p/q``."""
    value = Fraction(value)
    if value.denominator == 1:
        return str(value.numerator)
    den, digits = value.denominator, 0
    for prime in (2, 5):
        count = 0
        while den % prime == 0:
            den //= prime
            count += 1
        digits = max(digits, count)
    if den != 1:
        return f"{value.numerator}/{value.denominator}"
    whole, frac = divmod(abs(value.numerator) * 10**digits // value.denominator, 10**digits)
    return ("-" if value < 0 else "") + f"{whole}.{str(frac).rjust(digits, '0')}".rstrip("0")


def _time(seconds: Fraction) -> str:
    """In the largest unit in which the amount is at least 1."""
    for scale, unit in ((Fraction(1), "s"), (Fraction(1, 1000), "ms"), (Fraction(1, 10**6), "us")):
        if seconds >= scale:
            return f"{_decimal(seconds / scale)} {unit}"
    return f"{_decimal(seconds * 10**9)} ns"


def _ns(ns: int) -> str:
    return _time(Fraction(ns, 10**9))


def _hz(hertz: Fraction) -> str:
    return f"{_decimal(hertz)} Hz"


def _component(t: Task) -> list[str]:
    i = t.index
    lines = [f"component C{i} {{"]
    lines += [f"  in i{a} : M{a}" for a in t.sources]
    if len(t.trigger) == 2:
        lines.append(f"  in both = i{t.trigger[0]} & i{t.trigger[1]}")
    lines.append(f"  out o : M{i}")
    lines.append("  task Run {")
    for a in t.sources:
        option = " oversampling forbidden" if a in t.trigger else " optional" if a in t.optional else ""
        lines.append(f"    reads i{a}{option}")
    lines.append("    produces o")
    lines.append(f"    bcet {_ns(t.bcet_ns)}")
    lines.append(f"    wcet {_ns(t.wcet_ns)}")
    rate = 1 / t.period
    if t.constraint == "fixed":
        lines.append(f"    activation {_hz(rate)} fixed")
    elif t.constraint == "range":
        lines.append(f"    activation {_hz(rate / 2)} .. {_hz(rate * 2)}")
    elif t.constraint == "max":
        lines.append(f"    activation max {_hz(rate * 2)}")
    lines += ["  }", "}"]
    return lines


def _activation(t: Task) -> str:
    if t.hole == "unknown":
        return "activation ?"
    if t.trigger:
        port = "both" if len(t.trigger) == 2 else f"i{t.trigger[0]}"
        if t.hole == "prescaler":
            return f"trigger {port} every ? in 1 .. 10"
        return f"trigger {port}" + (f" every {t.prescaler}" if t.prescaler != 1 else "")
    period = t.period
    if t.hole == "grid":
        return f"timer ? in {_time(period / 2)} .. {_time(period * 2)} step {_time(period / 2)}"
    if t.hole == "freq":
        return f"timer ? in {_hz(1 / period / 2)} .. {_hz(2 / period)}"
    if t.hole == "bare":
        return "timer ?"
    text = f"timer {_time(period)}"
    if t.phase_us is not None:
        text += f" phase {_time(Fraction(t.phase_us, 10**6))}" if t.phase_us else " phase 0 ms"
    return text


def render(system: System) -> str:
    """The DSL text of a drawn system: the components, then the system."""
    n = len(system.tasks)
    triggered = sum(1 for t in system.tasks if t.trigger)
    holes = sum(1 for t in system.tasks if t.hole)
    out = [
        "// Generated by benchmarks.generate from the WATERS 2015 automotive benchmark",
        "// (Kramer, Ziegenbein, Hamann, \"Real World Automotive Benchmarks For Free\").",
        f"// tasks {n}, seed {system.seed}, cores {system.cores}, chains {len(system.chains)}, "
        f"tightness {_decimal(system.tightness)}, hole share {_decimal(system.hole_share)}, "
        f"infeasible {'yes' if system.infeasible else 'no'}",
        f"// data-triggered tasks {triggered}, holes {holes}, links {len(system.links)}; core utilisation "
        + ", ".join(f"~{_decimal(Fraction(round(u * 1000), 1000))}" for u in system.utilisation),
        "",
    ]
    for t in system.tasks:
        out += _component(t)
    out += ["", f"system {system.name} {{"]
    out += [f"  core cpu{k}" for k in range(system.cores)]
    for t in system.tasks:
        out.append(f"  instance t{t.index} : C{t.index} on cpu{t.core} {{ task Run priority {t.priority} "
                   f"{_activation(t)} }}")
    for link in system.links.values():
        text = f"  connect t{link.source}.o -> t{link.target}.i{link.source}"
        if link.delay_ns is not None:
            low, high = link.delay_ns
            text += f" delay {_ns(low)}" + (f" .. {_ns(high)}" if high != low else "")
        out.append(text)
    for chain in system.chains:
        specs = []
        if chain.reaction_time is not None:
            specs.append(f"reaction_time <= {_time(chain.reaction_time)}")
        if chain.data_age is not None:
            specs.append(f"data_age <= {_time(chain.data_age)}")
        note = "; infeasible: reaction time below the fixed period of its first task" if chain.conflict else ""
        out.append(f"  // reference bound {_time(_ceil_ns(chain.reference))}{note}")
        out.append(f"  chain {chain.name}: " + " -> ".join(f"t{i}.o" for i in chain.tasks)
                   + " { " + " ".join(specs) + " }")
    out += ["}", ""]
    return "\n".join(out)


def _ceil_ns(seconds: Fraction) -> Fraction:
    scaled = seconds * 10**9
    return Fraction(-(-scaled.numerator // scaled.denominator), 10**9)


def generate_system(n_tasks: int, seed: int, *, cores: int = 4, chains: int | None = None,
                    tightness: Fraction = Fraction(3, 2), hole_share: Fraction = Fraction(0),
                    infeasible: bool = False) -> str:
    """The DSL text of a WATERS-2015-like system of ``n_tasks`` tasks (see the module docstring).

    ``tightness`` multiplies each chain's reference bound to give its specs (3/2: 50 % slack; below 1:
    likely infeasible); ``hole_share`` is the share of (non-fixed) tasks left as holes for ``synth``;
    ``infeasible`` adds chains whose reaction-time spec contradicts a fixed rate.
    """
    return render(draw_system(n_tasks, seed, cores=cores, chains=chains, tightness=tightness,
                              hole_share=hole_share, infeasible=infeasible))


# ------------------------------------------------------------------------ one chain for the exact search

CHAIN_TIMER_SHARE = Fraction(2, 5)  # of the tasks after the head that run on their own (fixed-phase) timer (at least 1)
CHAIN_DELAY_SHARE = Fraction(1, 4)  # of the hops that carry a constant 1 ms delay
CHAIN_HEAD_PERIODS = (4, 5, 6, 8, 10)  # ms: the free-phase head timer (its period sets the phase search)
CHAIN_PERIODS = tuple(range(4, 41))  # ms: the other timers
CHAIN_MAX_UTILISATION = Fraction(4, 5)  # per core


@dataclass
class ChainTask:
    index: int
    period_ms: int | None  # None: data-triggered by its predecessor (prescaler 1)
    phase_ms: int | None  # None: a free phase (only the head)
    wcet_ms: int
    core: int = 0
    priority: int = 0
    delay_ms: int = 0  # constant delay of the connection into this task


@dataclass
class ChainSystem:
    """One chain of ``len(tasks)`` tasks in the exact class of ``prove`` (constant execution times and
    delays, one free phase); ``jobs`` jobs in one hyperperiod of ``hyperperiod_ms``."""

    name: str
    seed: int
    tasks: list[ChainTask]
    hyperperiod_ms: int
    jobs: int
    reaction_time: Fraction | None = None  # seconds
    data_age: Fraction | None = None


def _chain_periods(tasks: list[ChainTask]) -> list[int]:
    """The effective period of every task (a data-triggered task runs at its predecessor's rate)."""
    out: list[int] = []
    for t in tasks:
        out.append(t.period_ms if t.period_ms is not None else out[-1])
    return out


def draw_chain(n_tasks: int, seed: int, *, jobs: int | None = None, cores: int = 2) -> ChainSystem:
    """A chain ``t0 -> t1 -> … -> t(n-1)`` for the exact worst-case search (no specs yet).

    ``t0`` is a timer with a free phase (period 4–10 ms); after it a share of the tasks run on timers of
    their own with a fixed phase (periods 4–40 ms), the others are triggered by their predecessor's
    output. Execution times are constant (1–2 ms, ``bcet = wcet``), a quarter of the hops carry a
    constant 1 ms delay, cores are drawn, priorities rate-monotonic and unique per core. The timer
    periods are drawn (20,000 tries up to 10 tasks, fewer for longer chains; stopping at the first
    within 10 % below ``jobs``) so that one hyperperiod holds as many jobs as possible but at most
    ``jobs`` (default ``1000 · n_tasks``: 10,000 for ten tasks) and no core is loaded above 80 %.
    Every number is a whole millisecond, so the tick is a whole millisecond and the exact search has
    at most ``3 · T₀ / 1 ms`` (≤ 30) phase representatives."""
    if n_tasks < 1:
        raise ValueError("a chain needs at least one task")
    if cores < 1:
        raise ValueError("a system needs at least one core")
    jobs = 1000 * n_tasks if jobs is None else jobs
    if jobs < n_tasks:
        raise ValueError("a hyperperiod holds at least one job per task")
    rng = Random(seed)
    own = (n_tasks - 1) * CHAIN_TIMER_SHARE.numerator // CHAIN_TIMER_SHARE.denominator
    timers = [0] + sorted(rng.sample(range(1, n_tasks), max(own, min(1, n_tasks - 1))))
    shape = [ChainTask(i, 0 if i in timers else None, None, 1,
                       delay_ms=1 if i and _chance(rng, CHAIN_DELAY_SHARE) else 0) for i in range(n_tasks)]
    for t in shape:
        t.wcet_ms = 1 + rng.randrange(2)
        t.core = rng.randrange(cores)
    best: tuple[int, list[int], int] | None = None  # (jobs, timer periods, hyperperiod)
    for _ in range(min(20_000, max(500, 200_000 // n_tasks))):  # 20,000 tries up to 10 tasks
        periods = [rng.choice(CHAIN_HEAD_PERIODS)] + [rng.choice(CHAIN_PERIODS) for _ in timers[1:]]
        for i, p in zip(timers, periods):
            shape[i].period_ms = p
        eff = _chain_periods(shape)
        hyper = 1
        for p in eff:
            hyper = hyper * p // gcd(hyper, p)
        count = sum(hyper // p for p in eff)
        if count > jobs or (best is not None and count <= best[0]):
            continue
        load = [Fraction(0)] * cores
        for t, p in zip(shape, eff):
            load[t.core] += Fraction(t.wcet_ms, p)
        if max(load) > CHAIN_MAX_UTILISATION:
            continue
        best = (count, periods, hyper)
        if 10 * count >= 9 * jobs:
            break
    if best is None:
        raise ValueError(f"no periods found for a {n_tasks}-task chain within {jobs} jobs per hyperperiod")
    count, periods, hyper = best
    for i, p in zip(timers, periods):
        shape[i].period_ms = p
    for i in timers[1:]:
        shape[i].phase_ms = rng.randrange(shape[i].period_ms)
    eff = _chain_periods(shape)
    for core in range(cores):
        on = sorted((t for t in shape if t.core == core), key=lambda t: (eff[t.index], t.index))
        for rank, t in enumerate(on):
            t.priority = len(on) - rank
    return ChainSystem(f"Chain{n_tasks}s{seed}", seed, shape, hyper, count)


def render_chain(system: ChainSystem) -> str:
    n, cores = len(system.tasks), 1 + max(t.core for t in system.tasks)
    out = ["// Generated by benchmarks.generate.generate_chain_system: one chain in the exact class of `prove`",
           f"// tasks {n}, seed {system.seed}, hyperperiod {system.hyperperiod_ms} ms with {system.jobs} jobs",
           ""]
    for t in system.tasks:
        out.append(f"component C{t.index} {{")
        if t.index:
            out.append(f"  in i : M{t.index - 1}")
        out += [f"  out o : M{t.index}", "  task Run {"]
        if t.index:
            out.append("    reads i")
        out += ["    produces o", f"    bcet {t.wcet_ms} ms", f"    wcet {t.wcet_ms} ms", "  }", "}"]
    out += ["", f"system {system.name} {{"]
    out += [f"  core cpu{k}" for k in range(cores)]
    for t in system.tasks:
        if t.period_ms is None:
            act = "trigger i"
        else:
            act = f"timer {t.period_ms} ms" + (f" phase {t.phase_ms} ms" if t.phase_ms is not None else "")
        out.append(f"  instance t{t.index} : C{t.index} on cpu{t.core} {{ task Run priority {t.priority} {act} }}")
    for t in system.tasks[1:]:
        out.append(f"  connect t{t.index - 1}.o -> t{t.index}.i" + (f" delay {t.delay_ms} ms" if t.delay_ms else ""))
    specs = []
    if system.reaction_time is not None:
        specs.append(f"reaction_time <= {_time(system.reaction_time)}")
    if system.data_age is not None:
        specs.append(f"data_age <= {_time(system.data_age)}")
    if n > 1:
        out.append("  chain c0: " + " -> ".join(f"t{t.index}.o" for t in system.tasks) + " { " + " ".join(specs) + " }")
    out += ["}", ""]
    return "\n".join(out)


def generate_chain_system(n_tasks: int, seed: int, *, jobs: int | None = None, cores: int = 2,
                          tightness: Fraction = Fraction(9, 10)) -> str:
    """The DSL text of one chain (``draw_chain``) whose ``reaction_time`` and ``data_age`` specs are
    ``tightness`` times the bounds of verify's own analysis (``verify.timing.analyze``), rounded down to
    a millisecond: with ``tightness`` < 1 the bound cannot prove them, so ``prove`` must decide them by
    its exact search over the hyperperiod (proved when the exact worst case is below the spec,
    violated with a counterexample otherwise)."""
    tightness = _exact(tightness)
    if tightness <= 0:
        raise ValueError("tightness must be positive")
    system = draw_chain(n_tasks, seed, jobs=jobs, cores=cores)
    text = render_chain(system)
    if n_tasks < 2:
        return text
    import verify  # only here: the specs are set from the analysis' own bounds
    from verify.timing import analyze

    loaded = verify.load_text(text)
    if loaded.diagnostics:
        first = loaded.diagnostics[0]
        raise AssertionError(f"generated chain does not load: {first.code} {first.message}")
    bounds = analyze(loaded.system()).chain("c0")
    ms = Fraction(1, 1000)

    def spec(bound):
        if bound is None:
            return None
        scaled = tightness * bound / ms
        return max(ms, scaled.numerator // scaled.denominator * ms)

    system.reaction_time = spec(bounds.reaction_time.worst)
    system.data_age = spec(bounds.data_age_reduced.worst)
    return render_chain(system)


def generate_pipeline_system(n_tasks: int, seed: int) -> str:
    """The DSL text of a processing pipeline as one ROS single-threaded executor runs it: ``n_tasks``
    tasks on one core at one priority, the first on a 100 ms timer, each other one triggered by its
    predecessor's output (execution times drawn in [1 us, 2 us], bcet half of wcet, in whole
    nanoseconds), and one chain through all of them, without a spec. Every task lies on a causal
    path from each task before it, so the response-time analysis holds n²/2 causal caps
    (specs/timing.md §6.2) and its CPA iteration runs many rounds: the worst case of the analysis'
    cost, not a typical system. (With 600 tasks, seed 1, the analysis finds no WCRT bound: E312
    for every task.)"""
    rng = Random(seed)
    out = ["// Generated by benchmarks.generate.generate_pipeline_system: a trigger pipeline at one priority",
           f"// tasks {n_tasks}, seed {seed}", ""]
    for k in range(n_tasks):
        wcet = rng.randint(1_000, 2_000)
        out.append(f"component P{k} {{")
        if k:
            out.append("  in i : M")
        out += ["  out o : M", "  task Run {"]
        if k:
            out.append("    reads i")
        out += ["    produces o", f"    bcet {wcet // 2} ns", f"    wcet {wcet} ns", "  }", "}"]
    out += ["", "system Pipeline {", "  core cpu0"]
    for k in range(n_tasks):
        act = "trigger i" if k else "timer 100 ms"
        out.append(f"  instance p{k} : P{k} on cpu0 {{ task Run priority 1 {act} }}")
    out += [f"  connect p{k - 1}.o -> p{k}.i" for k in range(1, n_tasks)]
    out += ["  chain pipeline: " + " -> ".join(f"p{k}.o" for k in range(n_tasks)), "}", ""]
    return "\n".join(out)


def generate_executor_system(n_tasks: int, seed: int, kind: str = "single_threaded", per_executor: int = 100) -> str:
    """The DSL text of ``n_tasks`` ROS 2 callbacks on executors of ``per_executor`` callbacks each
    (specs/timing.md §9), every executor on a core of its own (a ``multi_threaded`` one on two): pipelines
    of ten callbacks, the first on a timer of 100, 200 or 500 ms, each other triggered by the one before
    (execution times drawn in [100 us, 300 us], bcet half of wcet, in whole microseconds), one chain
    through the first pipeline of each executor, without a spec. Each node is a callback of its own
    (in its default group)."""
    rng = Random(seed)
    out = ["// Generated by benchmarks.generate.generate_executor_system: callbacks on ROS 2 executors",
           f"// callbacks {n_tasks}, seed {seed}, {kind} executors of {per_executor}", "",
           "component Source {", "  out o : M", "  task Run {", "    produces o", "    bcet 50 us", "    wcet 100 us",
           "  }", "}"]
    costs = sorted({rng.randint(100, 300) for _ in range(8)})
    for c in costs:
        out += [f"component Stage{c} {{", "  in i : M", "  out o : M", "  task Run {", "    reads i", "    produces o",
                f"    bcet {c // 2} us", f"    wcet {c} us", "  }", "}"]
    executors = max(1, -(-n_tasks // per_executor))
    out += ["", "system Executors {"]
    for e in range(executors):
        if kind == "multi_threaded":
            out += [f"  core c{e}", f"  core d{e}", f"  executor e{e} multi_threaded on c{e}, d{e} priority 10"]
        else:
            out += [f"  core c{e}", f"  executor e{e} {kind} on c{e} priority 10"]
    connects, chains = [], []
    for k in range(n_tasks):
        e = k // per_executor
        if k % 10 == 0:
            out.append(f"  instance n{k} : Source {{ task Run executor e{e} timer {rng.choice([100, 200, 500])} ms }}")
        else:
            out.append(f"  instance n{k} : Stage{rng.choice(costs)} {{ task Run executor e{e} trigger i }}")
            connects.append(f"  connect n{k - 1}.o -> n{k}.i")
        if k % per_executor == 9 or k == n_tasks - 1 and k % per_executor < 9:
            first = k - k % 10
            chains.append(f"  chain p{e}: " + " -> ".join(f"n{j}.o" for j in range(first, k + 1)))
    out += connects + chains + ["}", ""]
    return "\n".join(out)


# ------------------------------------------------------------------------------------ CLI


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.generate",
                                description="Write a WATERS-2015-like benchmark system as DSL text.")
    p.add_argument("--tasks", type=int, required=True, help="number of tasks")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--cores", type=int, default=4)
    p.add_argument("--chains", type=int, default=None, help="number of chains (default: 30-60, fewer when small)")
    p.add_argument("--tightness", type=Fraction, default=Fraction(3, 2),
                   help="spec = tightness x reference bound (exact, e.g. 3/2 or 1.2; default 3/2)")
    p.add_argument("--hole-share", type=Fraction, default=Fraction(0), help="share of tasks with holes (e.g. 1/5)")
    p.add_argument("--infeasible", action="store_true", help="add specs that contradict a fixed rate")
    p.add_argument("-o", "--output", help="write here instead of standard output")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")
    args = p.parse_args(argv)
    if args.tasks < 1 or args.cores < 1 or (args.chains is not None and args.chains < 0):
        p.error("--tasks and --cores must be at least 1, --chains at least 0")
    if not 0 <= args.hole_share <= 1 or args.tightness <= 0:
        p.error("--hole-share must lie in [0, 1] and --tightness be positive")
    if args.output and os.path.exists(args.output) and not args.force:
        print(f"{args.output} exists; not overwriting it (use --force)", file=sys.stderr)
        return 2
    start = time.perf_counter()
    text = generate_system(args.tasks, args.seed, cores=args.cores, chains=args.chains, tightness=args.tightness,
                           hole_share=args.hole_share, infeasible=args.infeasible)
    if args.output:
        with open(args.output, "w", encoding="utf-8") as f:
            f.write(text)
        print(f"{args.output}: {args.tasks} tasks, {text.count(chr(10))} lines "
              f"({time.perf_counter() - start:.2f} s)", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
