"""One CPA round of response-time analysis for every task at once: exactly ``reference.response_times``,
without its quadratic cost.

``rta`` states the analysis task by task: hp(i) is found by scanning the core, and every fixed-point
step sums the demand of each stream of hp(i) in ``Fraction``s — about 10⁸ ``Fraction`` operations per
round at 10,000 tasks (2,500 per core). This module computes the same fixed points by the same
iterations (so with the same step budget, the same failures and the same messages):

* **Integer time.** Every duration of the round (costs, periods, jitters, deadlines, hold times) is an
  integer number of ticks of 1/D s, D the least common multiple of their denominators; everything the
  iterations compute are sums of those, so integers too, and results are converted back exactly.
  Utilisations ``Σ C/P`` are integers in units of 1/U, U the least common multiple of the periods.
* **One sweep per core in priority order.** hp(i) grows by one priority level at a time. The bounded
  streams are kept per period (``_Period``), where the demand of all of them at a window w takes a few
  integer operations whatever their number; unbounded streams and the utilisation are kept alongside.
* **Per-task corrections.** What the sweep holds is corrected for i: i itself when it shares its
  priority (subtracted), the streams with a causal cap on i's busy window (§6.2: what a stream demands
  beyond its cap, ``max(0, count − cap)·C``, subtracted; one term per causal path, its cap computed in
  the same loop), the remote siblings' token streams (§6.3). The causal paths and their carry-ins
  are sums and quotients of ticks too (``_causal_paths``, ``_carry``): a trigger pipeline of n
  tasks at one priority has n²/2 of them.
* **Hold time = first busy window.** ``hold_time`` is the busy window of one job without blocking; for a
  task with no causal caps, no blocking and no remote siblings that is the ``q = 1`` step of its WCRT,
  which reuses it (the same iteration from the same start with a fresh budget).

Tasks with cooperative siblings need the siblings' hold times, so their WCRTs are computed in a second
sweep of their core, once every hold time is known.

``tests/test_perf_equivalence.py`` checks the results against ``reference.response_times`` on random
systems and against digests recorded before this module existed.
"""
from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass
from fractions import Fraction
from math import lcm
from collections.abc import Callable, Sequence
from typing import overload
from collections.abc import Mapping

from ..core.construct import direct_constructor
from ..core.ids import TaskId
from ..model.system import SystemModel
from ..core.timebase import TimeBase
from .pipeline import cases, upstream
from .rates import EventModel
from .executors import executor_responses
from .interferers import CoreOrder, Interferers
from .kernel import MAX_JOBS, MAX_STEPS, ZERO, TaskResponse, bcrt, causes, deadline_of, ratio

_new_response = direct_constructor(TaskResponse)  # (``verify.core.construct``: one per task)

#: what ``Round._lfp`` returns: (the fixed point in ticks or None, why not, the step budget left)
_Run = tuple[int | None, str | None, int]
#: a task's WCRT in ``Round._wcrt``: (R, Q, critical q, failure)
_Wcrt = tuple[Fraction | None, int | None, int | None, str | None]
#: a task's result in ``Round.result``: ``_Wcrt`` and (blocking, remote sibling streams)
_Result = tuple[Fraction | None, int | None, int | None, str | None, Fraction | None, "list[_Stream]"]
#: a stream of hp(i) with a causal cap on i: (stream, Π prescalers, carry-in)
_Capped = tuple["_Stream", int, int]
#: ``Round._interference``'s correction: the extra demand, by the number of jobs q and then window w
_ExtraAt = Callable[[int], Callable[[int], int]]


class Static:
    """What every round needs from the system and that no round changes."""

    def __init__(self, system: SystemModel):
        self.system = system
        tasks = system.tasks
        self.index = {t.id: n for n, t in enumerate(tasks)}
        by_core: dict[str, list[int]] = {}
        for n, t in enumerate(tasks):
            by_core.setdefault(t.core, []).append(n)
        #: per core: priority levels (highest first), each a list of task numbers in declaration order
        self.levels: dict[str, list[list[int]]] = {}
        for core, members in by_core.items():
            levels: dict[int, list[int]] = {}
            for n in members:
                levels.setdefault(tasks[n].priority, []).append(n)
            self.levels[core] = [levels[p] for p in sorted(levels, reverse=True)]
        self.by_core = by_core
        #: the position of each task among the tasks of its core (``SystemModel.tasks_on`` order)
        self.position = {n: k for members in by_core.values() for k, n in enumerate(members)}
        cooperative: dict[str, list[int]] = {}
        for n, t in enumerate(tasks):
            if t.kind == "cooperative":
                cooperative.setdefault(t.instance, []).append(n)
        #: ``kernel.siblings``: the other cooperative tasks of a cooperative task's instance
        self.siblings: list[tuple[int, ...]] = [
            tuple(m for m in cooperative[t.instance] if m != n) if t.kind == "cooperative" else ()
            for n, t in enumerate(tasks)]
        #: ``kernel.causes`` of each task: (prescaler, events without a new arrival, d⁺ of the link, writer)
        self.causes: list[list[tuple[int, int, Fraction, int]]] = [
            [(k, extra, link.delay_max, self.index[link.writer]) for k, extra, link in causes(system, t)]
            for t in tasks]
        #: whether each task's jobs take time (``bcet > 0``: a local causal path may pass it, §6.2)
        self.timed = [t.bcet > 0 for t in tasks]
        self.cores = [t.core for t in tasks]
        self.priorities = [t.priority for t in tasks]
        counts = {instance: len(members) for instance, members in cooperative.items()}
        #: ``pipeline.upstream`` of each task (the pipeline release offsets of §6.2)
        self.upstream = [upstream(system, t, counts) for t in tasks]


@dataclass
class _Stream:
    """A stream of demand in ticks (``kernel.Interferer``): None fields are unbounded."""

    task: int
    cost: int
    period: int | None
    jitter: int | None
    silent: bool
    load: int | None  # cost/period in units of 1/U (0 if silent), None: not bounded


class _Period:
    """The bounded streams of one period P on a core, as far as the sweep has come.

    With ``J = a·P + r`` (0 ≤ r < P) and ``w = m·P + s`` (0 ≤ s < P), a stream's count is
    ``⌈(w + J)/P⌉ = m + a + [s + r > 0] + [s + r > P]``, so the demand of all of them is
    ``m·ΣC + Σa·C + (ΣC if s > 0 else Σ_{r>0} C) + Σ_{r > P−s} C``: a few operations, plus a
    suffix sum over the sorted residues when some residue is large enough (jitter close to a period,
    which is rare); ``Round._lfp`` computes it. Timers (no jitter) are r = a = 0."""

    __slots__ = ("period", "cost", "offset", "positive", "residues", "costs")

    def __init__(self, period: int):
        self.period = period
        self.cost = 0  # ΣC
        self.offset = 0  # Σ a·C
        self.positive = 0  # Σ C over r > 0
        self.residues: list[int] = []  # the r > 0, sorted
        self.costs: list[int] = []  # their C, in the same order

    def add(self, jitter: int, cost: int) -> None:
        a, r = divmod(jitter, self.period)
        self.cost += cost
        self.offset += a * cost
        if r:
            self.positive += cost
            k = bisect_right(self.residues, r)
            self.residues.insert(k, r)
            self.costs.insert(k, cost)


class _Core:
    """The streams of one core added so far in the sweep (hp of the next priority level)."""

    def __init__(self, position: Mapping[int, int]) -> None:
        self.periods: dict[int, _Period] = {}
        self.groups: list[_Period] = []  # the values of ``periods``
        self.load = 0  # Σ cost/period over the streams with a bounded rate, in units of 1/U
        self.unrated: list[int] = []  # streams whose rate is not bounded
        self.unbounded: list[int] = []  # streams whose demand is not bounded
        self.first_unbounded: int | None = None  # the first of them in system order
        self.position = position

    def add(self, s: _Stream) -> None:
        if s.silent:
            pass
        elif s.period is None or s.jitter is None:
            self.unbounded.append(s.task)
            if self.first_unbounded is None or self.position[s.task] < self.position[self.first_unbounded]:
                self.first_unbounded = s.task
        else:
            group = self.periods.get(s.period)
            if group is None:
                group = self.periods[s.period] = _Period(s.period)
                self.groups.append(group)
            group.add(s.jitter, s.cost)
        if s.load is None:
            self.unrated.append(s.task)
        else:
            self.load += s.load


class Round:
    """``reference.response_times(system, events, estimates)`` computed in one sweep per core."""

    def __init__(self, static: Static, events: Mapping[str, EventModel], estimates: Mapping[str, Fraction | None],
                 previous: Round | None = None):
        """``previous``: last CPA round, whose per-task data is reused where a task's event model is
        the same object (``rates.event_models`` with a memo keeps it when nothing changed)."""
        self.static = static
        system = static.system
        tasks = self.tasks = system.tasks
        # callbacks of ROS 2 executors have their own analysis (specs/timing.md §9.3); the sweeps treat
        # them as tasks of their executor's priority, which is how every other task of the core sees them
        self.callbacks = executor_responses(system, events, estimates) if system.executors else {}
        self.events = [events[t.id] for t in tasks]
        self.estimates = [estimates.get(t.id) for t in tasks]
        kept = ([e is previous.events[n] for n, e in enumerate(self.events)]
                if previous is not None else [False] * len(tasks))
        self.deadlines: list[tuple[Fraction | None, str]] = [
            previous.deadlines[n] if previous is not None and kept[n] else deadline_of(t, self.events[n])
            for n, t in enumerate(tasks)]
        self.base = self._time_base(previous, kept)
        self.scale = self.base.scale
        if previous is None or previous.scale != self.scale:
            kept = [False] * len(tasks)
        periods = [previous.streams[n].period if previous is not None and kept[n] else self.ticks(e.period_min)
                   for n, e in enumerate(self.events)]
        #: U: utilisations are kept as integers in units of 1/U (U: lcm of the periods in ticks)
        self.unit = lcm(*{p for p in periods if p is not None})
        if previous is None or previous.unit != self.unit:
            kept = [False] * len(tasks)
        siblings = static.siblings
        self.streams: list[_Stream] = [
            previous.streams[n] if previous is not None and kept[n]
            and (not siblings[n] or self.estimates[n] == previous.estimates[n])
            else self._stream(n) for n in range(len(tasks))]
        self.capped = self._causal_paths()
        self._hold_run: list[_Run | None] = [None] * len(tasks)  # (ticks or None, failure, steps left)
        self.result: list[_Result | None] = [None] * len(tasks)  # (computed, q, critical, failure, blocking, remote)
        # last round, if its ticks are these (then a stream of the same object is the same stream)
        self.previous = previous if previous is not None and previous.scale == self.scale and \
            previous.unit == self.unit else None
        later = {core: self._sweep(levels) for core, levels in static.levels.items()}
        for core, pending in later.items():
            if pending:  # the siblings' hold times are known now
                self._sweep(static.levels[core], pending)

    # ------------------------------------------------------------------ ticks
    def _time_base(self, previous: Round | None, kept: list[bool]) -> TimeBase:
        """1/D seconds (``verify.core.timebase``): every duration of the round is a multiple of 1/D seconds. Any
        multiple of the least such D would do as well; after the first round D grows only by what tasks with
        new event models bring (last round's D covers the others, and the execution times)."""
        dens = {1 if previous is None else previous.scale}
        if previous is None:  # what no round changes: execution times and the delays of trigger links
            dens.update(t.wcet.denominator for t in self.tasks)
            dens.update(t.bcet.denominator for t in self.tasks)
            dens.update(cause[2].denominator for causes in self.static.causes for cause in causes)
        for n, e in enumerate(self.events):
            if not kept[n]:
                for v in (e.period_min, e.jitter_min, self.deadlines[n][0]):
                    if v is not None:
                        dens.add(v.denominator)
        dens.update(r.denominator for r in self.estimates if r is not None)
        return TimeBase.per_second(dens)

    @overload
    def ticks(self, value: Fraction) -> int: ...
    @overload
    def ticks(self, value: Fraction | None) -> int | None: ...

    def ticks(self, value: Fraction | None) -> int | None:
        # (``self.base.ticks`` for a base of 1/D s, inlined: a round converts some 10⁴ values)
        return None if value is None else value.numerator * (self.scale // value.denominator)

    @overload
    def seconds(self, ticks: int) -> Fraction: ...
    @overload
    def seconds(self, ticks: int | None) -> Fraction | None: ...

    def seconds(self, ticks: int | None) -> Fraction | None:
        return None if ticks is None else Fraction(ticks, self.scale)

    def _stream(self, n: int) -> _Stream:
        """Task n as an interferer (``kernel.interferer``): its jitter grows by ``R − C`` if it is
        cooperative with siblings (it may wait for the token)."""
        task, events = self.tasks[n], self.events[n]
        jitter = events.jitter_min
        if jitter is not None and self.static.siblings[n]:
            r = self.estimates[n]
            jitter = None if r is None else jitter + max(ZERO, r - task.wcet)
        cost, period = self.ticks(task.wcet), self.ticks(events.period_min)
        load = 0 if events.silent else None if period is None else cost * (self.unit // period)
        return _Stream(n, cost, period, self.ticks(jitter), events.silent, load)

    def _causal_paths(self) -> dict[int, list[tuple[int, int, int, int, int | None]]]:
        """target -> [(source, Π prescalers, L⁺ in ticks, E, E of the local path or None)] for every
        ``rta.causal_path(source,
        target)`` that ``_capped_into`` can use (source on target's core at no lower priority): one
        walk per source, in ``rta.causal_path``'s order (depth first, members in order, each task
        entered once), keeps the first path to each task it meets. The nested ceilings of the cap,
        ⌈(n + e)/k⌉ at each hop from the target, are one: ⌈(n + E)/Π⌉, where walking out from the
        source each hop makes Π ← Π·k and E ← e + E·k (⌈(⌈x/a⌉ + e)/b⌉ = ⌈(x + e·a)/(ab)⌉ for
        integers), so a path is a few integers, not a tuple per hop (a trigger chain of n tasks has
        n²/2 paths). L⁺ is a sum of delays and WCRT estimates, all multiples of the tick
        (``_time_base``), so it is summed in ticks. A local path (no delay, every task in between on
        the core with ``C⁻ > 0`` and a priority at least the target's; specs/timing.md §6.2) has its
        own E, one more at every hop from a task in between, used with the carry of L⁺ = 0."""
        capped: dict[int, list[tuple[int, int, int, int, int | None]]] = {}
        tasks = self.tasks
        causes = [[(k, extra, self.ticks(delay), writer) for k, extra, delay, writer in c]
                  for c in self.static.causes]
        estimates = [self.ticks(e) for e in self.estimates]
        timed = self.static.timed
        cores, priorities = self.static.cores, self.static.priorities
        readers: list[list[int]] = [[] for _ in tasks]
        for reader, reader_causes in enumerate(causes):
            for cause in reader_causes:
                readers[cause[3]].append(reader)
        upstream: dict[str, dict[int, int]] = {}  # per core: ``_least_upstream``
        for source in range(len(tasks)):
            if self.static.siblings[source] and estimates[source] is None:
                continue  # (its suspension jitter is not bounded: rta.causally_capped caps nothing then)
            core, priority = cores[source], priorities[source]
            least_upstream = upstream.get(core)
            if least_upstream is None:
                least_upstream = upstream[core] = self._least_upstream(core, readers, estimates)
            visited, found = {source}, set()
            # per task on the path: (causes not yet tried, Π, E, L⁺, E of the local path or None, the least
            # priority of the tasks in between)
            start: int | None = 0
            stack = [(iter(causes[source]), 1, 0, 0, start, priority)]
            while stack:
                pending, product, extras, latency, local, least = stack[-1]
                step = next(pending, None)
                if step is None:
                    stack.pop()
                    continue
                k, extra, delay, writer = step
                here = (product * k, extra + extras * k, latency + delay)
                near = None if local is None or delay else extra + local * k
                mine = cores[writer] == core
                if mine and writer not in found and priority >= priorities[writer]:
                    found.add(writer)
                    alt = near if near is not None and least >= priorities[writer] else None
                    capped.setdefault(writer, []).append((source, here[0], here[2], here[1], alt))
                estimate = estimates[writer]
                if writer in visited or estimate is None or least_upstream.get(writer, priority + 1) > priority:
                    continue  # (the last: no task the walk would meet beyond it is one it keeps a path to)
                visited.add(writer)
                through = near + 1 if near is not None and mine and timed[writer] else None
                stack.append((iter(causes[writer]), here[0], here[1], here[2] + estimate, through,
                              min(least, priorities[writer])))
        return capped

    def _least_upstream(self, core: str, readers: list[list[int]], estimates: list[int | None]) -> dict[int, int]:
        """task -> the least priority of the tasks of ``core`` that a walk of ``_causal_paths`` entering
        the task may meet (itself included; absent: none). A walk from a source of ``core`` goes on
        past a task only when one of them is at no higher priority than the source's, so a walk costs
        what it finds, not all that lies upstream of its source (a trigger chain of n tasks over the
        cores at falling priorities: n walks of none instead of n²/2 steps). One pass forward from the
        tasks of the core, the lowest priority first: each task is labelled once."""
        static = self.static
        least: dict[int, int] = {}
        for priority, seed in sorted((static.priorities[n], n) for n in static.by_core[core]):
            if seed in least:
                continue
            least[seed] = priority
            todo = [seed]
            while todo:
                for reader in readers[todo.pop()]:
                    if reader not in least and estimates[reader] is not None:  # (a walk goes past it)
                        least[reader] = priority
                        todo.append(reader)
        return least

    # ------------------------------------------------------------------ the sweep
    def _sweep(self, levels: list[list[int]], pending: set[int] | None = None) -> set[int]:
        """Sweep one core, highest priority first: hold times, and the WCRTs of the tasks without
        cooperative siblings (returned: the others); with ``pending``, only those WCRTs. A task alone
        on its level is analysed before it is added; the tasks of a shared level after the whole level
        has been added, each less itself.

        As long as every stream added so far is last round's (the same object), the core holds what it
        held then, and a task whose own inputs are last round's too has last round's results: they are
        taken over (``_unchanged``). Late CPA rounds change few streams, most of them low on their core."""
        core = _Core(self.static.position)
        later: set[int] = set()
        previous = self.previous if pending is None else None
        for members in levels:
            if len(members) == 1:
                self._analyse(members[0], core, False, pending, later, previous)
            for n in members:
                core.add(self.streams[n])
                if previous is not None and self.streams[n] is not previous.streams[n]:
                    previous = None
            if len(members) > 1:
                for n in members:
                    self._analyse(n, core, True, pending, later, previous)
        return later

    def _analyse(self, n: int, core: _Core, with_self: bool, pending: set[int] | None, later: set[int],
                 previous: Round | None) -> None:
        if pending is not None:
            if n in pending:
                self.result[n] = self._response(n, core, with_self)
            return
        if previous is not None and self._unchanged(n, previous):
            self._hold_run[n] = previous._hold_run[n]
            self.result[n] = previous.result[n]
            return
        self._hold(n, core, with_self)
        if self.static.siblings[n]:
            later.add(n)
        else:
            self.result[n] = self._response(n, core, with_self)

    def _unchanged(self, n: int, previous: Round) -> bool:
        """Task n's own inputs are last round's: its stream and event model (the same objects, so the
        same deadline), its WCRT estimate, its causal caps; and no cooperative sibling."""
        index = self.static.index
        return (self.streams[n] is previous.streams[n] and not self.static.siblings[n]
                and self.estimates[n] == previous.estimates[n] and self.capped.get(n) == previous.capped.get(n)
                and all(self.estimates[index[t.id]] == previous.estimates[index[t.id]]
                        and self.streams[index[t.id]] is previous.streams[index[t.id]]
                        for t, _ in self.static.upstream[n]))

    def _interference(self, n: int, core: _Core, with_self: bool, capped: Sequence[_Capped] = (),
                      remote: Sequence[_Stream] = ()
                      ) -> tuple[list[_Period], _ExtraAt | None, int | None, int | None]:
        """n's interfering streams for ``_lfp``: the core's period groups, ``extra_at`` (``extra_at(q)``
        is the demand, for w > 0 in ticks, to add to theirs in the busy window of q jobs; None:
        nothing), the first stream whose demand is not bounded, and the utilisation of the uncapped
        ones (None: not bounded). ``core`` holds hp(n) (and n itself if ``with_self``); ``capped``:
        (stream, Π prescalers, carry-in) for the streams of hp(n) with a causal cap (``_cap``);
        ``remote``: the remote siblings' token streams."""
        if not with_self and not capped and not remote:  # the common case: hp(n) is what the core holds
            return core.groups, None, core.first_unbounded, None if core.unrated else core.load
        exclude = [s for s, _, _ in capped]  # in the core's sums, but not (or not so) among n's streams
        if with_self:
            exclude.append(self.streams[n])
        # a capped stream counted in the core's sums demands min(count, cap)·C instead of count·C: it
        # takes away max(0, count − cap)·C; an unbounded one is not in the sums and adds cap·C
        over = [(s.jitter, s.period, s.cost, product, carry) for s, product, carry in capped
                if not s.silent and s.period is not None and s.jitter is not None]
        fixed = [(s.cost, product, carry) for s, product, carry in capped
                 if not s.silent and (s.period is None or s.jitter is None)]
        own = self.streams[n]
        minus = ((own.jitter, own.period, own.cost),) if (with_self and not own.silent and own.period is not None
                                                          and own.jitter is not None) else ()
        tokens = [s for s in remote if not s.silent]
        # (used only when every token is bounded: ``first_bad`` stops ``_lfp`` before it asks ``extra``)
        plus = [(s.jitter, s.period, s.cost) for s in tokens if s.period is not None and s.jitter is not None]

        def extra_at(q: int) -> Callable[[int], int]:
            base = sum(_cap(product, carry, q) * cost for cost, product, carry in fixed)
            before = 1 - q  # the cap of a path is ⌈(q − 1 + carry)/Π⌉ (``_cap``, inlined)

            def extra(w: int) -> int:
                total = base
                for jitter, period, cost, product, carry in over:
                    count = -((-w - jitter) // period)
                    cap = -((before - carry) // product)
                    if count > cap:
                        total -= (count - cap) * cost
                for jitter, period, cost in minus:
                    total += ((-w - jitter) // period) * cost
                for jitter, period, cost in plus:
                    total -= ((-w - jitter) // period) * cost
                return total

            return extra

        excluded = {s.task for s in exclude}
        bad = [m for m in core.unbounded if m not in excluded]
        bad_tokens = [s for s in tokens if s.period is None or s.jitter is None]
        first_bad = (min(bad, key=self.static.position.__getitem__) if bad
                     else bad_tokens[0].task if bad_tokens else None)
        load = core.load
        unrated = [m for m in core.unrated if m not in excluded]
        for s in exclude:
            if s.load is not None:
                load -= s.load
        for s in remote:
            if s.load is None:
                unrated.append(s.task)
            else:
                load += s.load
        return core.groups, extra_at, first_bad, None if unrated else load

    def _lfp(self, base: int, start: int, groups: list[_Period], extra: Callable[[int], int] | None,
             first_bad: int | None, load: int | None, left: int) -> _Run:
        """``kernel.least_fixed_point`` in ticks (``load`` in units of 1/U) for the streams that
        ``_interference`` describes; ``left`` is the step budget, returned as used."""
        if load is None:
            return None, "the interference is not bounded", left
        if load is not None and load >= self.unit and base > 0:
            return None, f"the interfering utilisation is {ratio(Fraction(load, self.unit))} (at least 1)", left
        w = start
        while True:
            left -= 1
            if left < 0:
                return None, f"no fixed point within {MAX_STEPS} iteration steps", left
            if w > 0:
                if first_bad is not None:
                    return None, f"the activations of `{self.tasks[first_bad].id}` are not bounded", left
                new = base
                for g in groups:  # _Period.demand, inlined: the innermost loop of the analysis
                    period = g.period
                    m, r = divmod(w, period)
                    if r:
                        new += (m + 1) * g.cost + g.offset
                        residues = g.residues
                        if residues and residues[-1] > period - r:
                            new += sum(g.costs[bisect_right(residues, period - r):])
                    else:
                        new += m * g.cost + g.offset + g.positive
                if extra is not None:
                    new += extra(w)
            else:  # an empty window: no stream demands anything
                new = base
            if new == w:
                return w, None, left
            w = new

    def _hold(self, n: int, core: _Core, with_self: bool) -> None:
        """``rta.hold_time``: the busy window of one job of n, no blocking, no caps (§6.3)."""
        cost = self.streams[n].cost
        groups, extra_at, first_bad, load = self._interference(n, core, with_self)
        self._hold_run[n] = self._lfp(cost, cost, groups, extra_at and extra_at(1), first_bad, load,
                                      MAX_STEPS)

    def hold(self, n: int) -> Fraction | None:
        """Eᵢ, the hold time of task n."""
        run = self._hold_run[n]
        assert run is not None, "the first sweep of n's core runs (or takes over) its hold time"
        return self.seconds(run[0])

    # ------------------------------------------------------------------ one task
    def _response(self, n: int, core: _Core, with_self: bool) -> _Result:
        """``rta.response_time`` less what ``responses`` assembles: (R, Q, critical q, failure,
        blocking, remote sibling streams)."""
        blocking, once, remote = self._blocking(n)
        if blocking is None or once is None:
            return None, None, None, "a cooperative sibling's hold time is not bounded", None, remote
        capped: list[_Capped] = []
        paths = self._capped_into(n)
        if paths:
            carry = self._carry(n)
            if carry is not None:
                streams = self.streams
                local = carry(0)
                capped = [(streams[source], product, extra + carry(latency) if alt is None
                           else min(extra + carry(latency), alt + local))
                          for source, product, latency, extra, alt in paths]
        return self._wcrt(n, core, with_self, blocking, once, capped, remote) + (max(blocking, once), remote)

    def _carry(self, n: int) -> Callable[[int], int] | None:
        """``rta.carry_in`` of task n as a function of the path latency L⁺ in ticks: the least of
        ``(L⁺ + J⁻ + R − B) // P⁻ + 1`` (where the event model and R are bounded) and ``L⁺ // C⁻ + 1``
        (where C⁻ > 0); 0 for a silent task; None where both are unknown (no cap)."""
        events, response = self.events[n], self.estimates[n]
        if events.silent:
            return lambda latency: 0
        gap = self.ticks(self.tasks[n].bcet)
        if events.period_min is None or events.jitter_min is None or response is None:
            return None if gap == 0 else (lambda latency: latency // gap + 1)
        base = self.ticks(events.jitter_min) + self.ticks(response) - self.ticks(bcrt(self.tasks[n]))
        period = self.ticks(events.period_min)
        if gap == 0:
            return lambda latency: (latency + base) // period + 1
        return lambda latency: min((latency + base) // period, latency // gap) + 1

    def _capped_into(self, n: int) -> list[tuple[int, int, int, int, int | None]]:
        """The causal paths into n from streams of hp(n) (``_causal_paths`` keeps no others)."""
        return self.capped.get(n, [])

    def _blocking(self, n: int) -> tuple[Fraction | None, Fraction | None, list[_Stream]]:
        """``rta.cooperative_blocking``: β per job and β once per window (seconds), and the remote
        siblings' token streams."""
        sibs = self.static.siblings[n]
        if not sibs:
            return ZERO, ZERO, []
        task = self.tasks[n]

        def most(values: list[Fraction | None]) -> Fraction | None:
            known = [v for v in values if v is not None]
            return max(known, default=ZERO) if len(known) == len(values) else None

        blocking = most([self.hold(s) for s in sibs if self.tasks[s].core != task.core])
        once = most([self.hold(s) for s in sibs
                     if self.tasks[s].core == task.core and self.tasks[s].priority < task.priority])
        remote = []
        for s in sibs:
            if self.tasks[s].core == task.core:
                continue
            events, response = self.events[s], self.estimates[s]
            jitter = None if events.jitter_min is None or response is None else events.jitter_min + response
            run = self._hold_run[s]
            assert run is not None, "a sibling's hold time is run in the first sweep"
            # (a hold time that is not bounded makes a stream whose demand is not: no period)
            cost, period = (0, None) if run[0] is None else (run[0], self.ticks(events.period_min))
            load = 0 if events.silent else None if period is None else cost * (self.unit // period)
            remote.append(_Stream(s, cost, period, self.ticks(jitter), events.silent, load))
        return blocking, once, remote

    def _wcrt(self, n: int, core: _Core, with_self: bool, blocking: Fraction, once: Fraction,
              capped: Sequence[_Capped], remote: Sequence[_Stream]) -> _Wcrt:
        """``rta.wcrt`` in ticks: (R, Q, critical q, failure)."""
        own = self.events[n]
        if not own.silent and (own.period_min is None or own.jitter_min is None):
            return None, None, None, ("its activations are not bounded" if own.period_min is None else
                                      "its activation jitter is not bounded (a writer upstream has no WCRT bound)")
        stream = self.streams[n]
        # δ⁻(q) = max(0, (q−1)·P − J) in ticks (a silent task never has a second job: q = 1 only, and
        # neither P nor J enters)
        period = 1 if own.silent else stream.period
        jitter = 0 if own.silent else self.ticks(own.jitter_min) if self.static.siblings[n] else stream.jitter
        assert period is not None and jitter is not None, "bounded (checked above)"
        total = self._all_loads(n, core, with_self, remote)  # (whether the busy window closes: §6.2)
        if total is not None and not own.silent:  # (blocking is left out: it may come once per window)
            total += stream.cost * (self.unit // period)
        if total is not None and total >= self.unit:
            return None, None, None, "the utilisation of its level is 1 or more"
        blocking_ticks = self.ticks(blocking) if blocking else 0
        once_ticks = self.ticks(once) if once else 0
        cost = stream.cost + blocking_ticks
        reuse = not capped and not remote and not blocking_ticks and not once_ticks
        best: int | None = None
        best_q: int | None = None
        w: int | None = 0
        left = MAX_STEPS
        groups, extra_at, first_bad, load = self._interference(n, core, with_self, capped, remote)
        for q in range(1, MAX_JOBS + 1):
            offset = 0 if q == 1 else max(0, (q - 1) * period - jitter)
            if q == 1 and reuse:  # the same iteration as the hold time's
                run = self._hold_run[n]
                assert run is not None, "n's hold time is run before its WCRT"
                w, why, left = run
            else:
                assert w is not None, "(a failed iteration returns)"
                w, why, left = self._lfp(q * cost + once_ticks, w + cost, groups, extra_at and extra_at(q),
                                         first_bad, load, left)
            if w is None:
                return None, q, None, why
            if best is None or w - offset > best:
                best, best_q = w - offset, q
            if own.silent or w <= max(0, q * period - jitter):  # the busy window closes before job q + 1
                if self.static.upstream[n]:
                    refined = self._pipeline(n, q, cost, once_ticks, period, jitter, groups, extra_at, first_bad,
                                             load, capped)
                    if refined is not None and refined[0] < best:
                        best, best_q = refined
                return self.seconds(best), q, best_q, None
        return None, MAX_JOBS, None, f"the busy window does not close within {MAX_JOBS} jobs"

    def _pipeline(self, n: int, jobs: int, cost: int, once: int, period: int, jitter: int, groups: list[_Period],
                  extra_at: _ExtraAt | None, first_bad: int | None, load: int | None, capped: Sequence[_Capped]
                  ) -> tuple[int, int] | None:
        """``rta.pipeline_response`` in ticks: (R, critical q), or None when a fixed point is not found.
        A path task whose cascade job was released up to X before the window counts
        ``min(η⁺(w), ⌈(w + X + J)/P⌉ − 1, cap)`` jobs: ``extra`` takes the excess over what the core's
        sums and the causal caps count away."""
        index = self.static.index
        estimates: dict[str, Fraction | None] = {t.id: self.estimates[index[t.id]] for t, _ in self.static.upstream[n]}
        caps = {st.task: (product, carry) for st, product, carry in capped}
        best: tuple[int, int] | None = None
        for case in cases(self.static.upstream[n], estimates):
            reduced = []
            for tid, before in case.before.items():
                st = self.streams[index[TaskId(tid)]]
                if not st.silent and st.period is not None and st.jitter is not None:
                    reduced.append((st.jitter, st.period, st.cost, self.ticks(before), caps.get(st.task)))
            w: int | None = 0
            left = MAX_STEPS
            for q in range(1, jobs + 1):
                extra = _reduced_extra(extra_at and extra_at(q), reduced, q)
                assert w is not None, "(a failed iteration returns)"
                w, _, left = self._lfp(q * cost + once, w + cost, groups, extra, first_bad, load, left)
                if w is None:
                    return None
                low = 0 if q == 1 else max(0, (q - 1) * period - jitter)
                value = w - self.ticks(case.gone(q, self.seconds(low)))
                if best is None or value > best[0]:
                    best = (value, q)
        return best

    def _all_loads(self, n: int, core: _Core, with_self: bool, remote: Sequence[_Stream]) -> int | None:
        """Σ cost/period (units of 1/U) over all of n's streams (capped ones included) and its remote
        token streams."""
        if any(m != n for m in core.unrated) or any(s.load is None for s in remote):
            return None
        load = core.load + sum(s.load or 0 for s in remote)  # (none is None)
        own = self.streams[n].load
        if with_self and own is not None:
            load -= own
        return load

    # ------------------------------------------------------------------ results
    def wcrts(self) -> dict[str, Fraction | None]:
        """The WCRT every later step uses, per task (the user's bound if given)."""
        return {t.id: (t.wcrt_bound if t.wcrt_bound is not None else
                       self.callbacks[t.id].wcrt if t.id in self.callbacks else self._computed(n))
                for n, t in enumerate(self.tasks)}

    def _computed(self, n: int) -> Fraction | None:
        result = self.result[n]
        assert result is not None, "every task's result is computed (or taken over) in its core's sweeps"
        return result[0]

    def responses(self) -> dict[str, TaskResponse]:
        """The ``TaskResponse`` of every task, in system order. Each one's hp(i) is a view of its core's
        tasks (``interferers.Interferers``), not a copy: memory linear in the tasks of a core."""
        out: dict[int, TaskResponse] = {}
        static = self.static
        for core, members in static.by_core.items():
            level_of = {n: k for k, level in enumerate(static.levels[core]) for n in level}
            order = CoreOrder([self.tasks[n].id for n in members], [level_of[n] for n in members])
            for n in members:
                out[n] = self._task_response(n, order, level_of[n])
        return {t.id: self.callbacks.get(t.id) or out[n] for n, t in enumerate(self.tasks)}

    def _task_response(self, n: int, order: CoreOrder, level: int) -> TaskResponse:
        task = self.tasks[n]
        result = self.result[n]
        assert result is not None, "every task's result is computed (or taken over) in its core's sweeps"
        computed, q, crit, failure, blocking, remote = result
        names = Interferers(order, level, task.id, tuple(self.tasks[s.task].id for s in remote))
        if task.activation.unknown:
            failure = "its activation is an unresolved synthesis hole (run `synth` first)"
        used: Fraction | None
        if task.wcrt_bound is not None:
            used, rule = task.wcrt_bound, "user bound"
        else:
            used = computed
            rule = f"busy window, {q} job{'s' if q != 1 else ''}" if computed is not None else "unbounded"
        deadline, deadline_rule = self.deadlines[n]
        return _new_response(task.id, task.core, task.priority, task.bcet, used, computed, rule, deadline,
                             deadline_rule, blocking, self.hold(n), q, crit, names, failure)


def _reduced_extra(extra: Callable[[int], int] | None, reduced: list[tuple[int, int, int, int, tuple[int, int] | None]],
                   q: int) -> Callable[[int], int] | None:
    """``extra`` less, per stream (J, P, C, X, causal cap or None) of a path task whose cascade job was
    released up to X before the window, the jobs ``⌈(w + X + J)/P⌉ − 1`` does not allow beyond what
    the core's sums (η⁺) and its cap count (``Round._pipeline``)."""
    if not reduced:
        return extra

    def less(w: int) -> int:
        total = extra(w) if extra is not None else 0
        for jitter, period, cost, before, cap in reduced:
            count = -((-w - jitter) // period)
            if cap is not None:
                count = min(count, _cap(cap[0], cap[1], q))
            allowed = -((-w - before - jitter) // period) - 1
            if count > allowed:
                total -= (count - allowed) * cost
        return total

    return less


def _cap(product: int, carry: int, q: int) -> int:
    """``kernel.Interferer.causal_cap``, with the product of the path's prescalers."""
    return -((-(q - 1 + carry)) // product)


def response_times(system: SystemModel, events: Mapping[str, EventModel],
                   estimates: Mapping[str, Fraction | None], static: Static | None = None) -> dict[str, TaskResponse]:
    """The same as ``reference.response_times``."""
    return Round(static or Static(system), events, estimates).responses()
