"""Exact pruning of candidates before the solver runs, and the cheap necessary checks.

Every rule removes only candidates that no accepted configuration can use (specs/synthesis.md §3),
from bounds over *all* remaining configurations:

* rate bounds per task, propagated through triggers (a writer's range divided by the prescaler,
  AND: minimum of the members, OR: sum) — a triggered candidate whose rate can never lie within the
  task's activation constraint goes (E305/E306 would reject it);
* sampling tolerances (E310): a candidate that over- or undersamples beyond the tolerance whatever
  the other side does goes;
* utilisation (E311): a candidate that puts its core above 1 even with every other task at its
  slowest goes; if a core is above 1 at the slowest candidates, the problem is infeasible;
* latency: a candidate whose chain lower bound (periods, WCETs and delays that every rule of
  specs/timing.md §7 must add) already exceeds a spec goes.

The rules are applied until nothing changes. Only untracked problems are pruned: an unsat-core
problem must keep every candidate a relaxed statement could allow.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from fractions import Fraction
from typing import TypeAlias
from collections.abc import Callable, Mapping

from ..model.activations import Activation
from ..model.system import ChainModel, HopModel, SystemModel, TaskModel
from ..timing.chains import same_core_reason
from ..timing.rates import exact_sum, tolerance_limit
from .candidates import Choice, make_choice
from .structure import activation_options, member_links

ZERO = Fraction(0)

#: a range (least, greatest) of a rate
Range: TypeAlias = tuple[Fraction, Fraction]


@dataclass(frozen=True)
class Bounds:
    """Over all remaining configurations: the range of the lower and upper activation rate (Hz) and
    a lower bound on the longest distance between activations (``p_min``, seconds). None: unknown."""

    fl: tuple[Fraction, Fraction] | None
    fh: tuple[Fraction, Fraction] | None
    p_min: Fraction


UNKNOWN = Bounds(None, None, ZERO)


def _hull(items: list[Bounds]) -> Bounds:
    if not items:
        return UNKNOWN
    if len(items) == 1:
        return items[0]
    return Bounds(_range_hull([b.fl for b in items]), _range_hull([b.fh for b in items]), min(b.p_min for b in items))


def _known(ranges: list[Range | None]) -> list[Range] | None:
    """``ranges`` when none is unknown, else None."""
    known = [r for r in ranges if r is not None]
    return known if len(known) == len(ranges) else None


def _range_hull(ranges: list[Range | None]) -> Range | None:
    known = _known(ranges)
    return None if known is None else (min(r[0] for r in known), max(r[1] for r in known))


@functools.lru_cache(maxsize=4096)
def _timed_bounds(gaps: tuple[Fraction, Fraction]) -> Bounds:
    lo, hi = 1 / gaps[1], 1 / gaps[0]
    return Bounds((lo, lo), (hi, hi), gaps[1])


def activation_bounds(model: SystemModel, task: TaskModel, act: Activation, known: Mapping[str, Bounds]) -> Bounds:
    """The bounds of one activation of ``task`` given its writers' bounds (specs/timing.md §5.1)."""
    gaps = act.gaps
    if gaps is not None:  # released by time
        return _timed_bounds(gaps)
    mode = act.trigger_mode
    if mode is None:
        return UNKNOWN
    members = [known.get(link.writer, UNKNOWN) for _, link in member_links(model, task, act) if link is not None]
    if not members:
        return UNKNOWN
    k = act.release_every
    if mode == "and":
        fl = _combine([m.fl for m in members], min)
        fh = _combine([m.fh for m in members], min)
        p_min = max(m.p_min for m in members)
    elif mode == "or":
        fl = _combine([m.fl for m in members], sum)
        fh = _combine([m.fh for m in members], sum)
        p_min = min(m.p_min for m in members)
    else:
        fl, fh, p_min = members[0].fl, members[0].fh, members[0].p_min

    def div(r: Range | None) -> Range | None:
        return None if r is None else (r[0] / k, r[1] / k)

    return Bounds(div(fl), div(fh), k * p_min)


def _combine(ranges: list[Range | None], how: Callable[..., object]) -> Range | None:
    known = _known(ranges)
    if known is None:
        return None
    if how is sum:
        return (sum((r[0] for r in known), ZERO), sum((r[1] for r in known), ZERO))
    return (min(r[0] for r in known), min(r[1] for r in known))


class Pruner:
    """Applies the rules of this module to the choices of an untracked problem until a fixed point."""

    def __init__(self, model: SystemModel, choices: dict[str, Choice], order: tuple[str, ...],
                 cyclic: frozenset[str]):
        self.model, self.choices, self.order, self.cyclic = model, dict(choices), order, cyclic
        self.removed = 0
        self.infeasible: str | None = None
        # what the infeasibility is about, when one rule names it: (chains, tasks)
        self.culprit: tuple[tuple[str, ...], tuple[str, ...]] | None = None

    # -------------------------------------------------------------- bounds

    def bounds(self) -> tuple[dict[str, Bounds], dict[tuple[str, int], Bounds]]:
        """Task bounds, and per (choice, candidate index) the bounds of that candidate."""
        tasks: dict[str, Bounds] = {}
        per_candidate: dict[tuple[str, int], Bounds] = {}
        for tid in self.order:
            task = self.model.task(tid)
            if tid in self.cyclic:
                tasks[tid] = UNKNOWN
                continue
            options = activation_options(task, self.choices.get(tid))
            found = []
            for index, act in options:
                b = activation_bounds(self.model, task, act, tasks)
                if index is not None:
                    per_candidate[(tid, index)] = b
                found.append(b)
            tasks[tid] = _hull(found)
        return tasks, per_candidate

    # -------------------------------------------------------------- rules

    def run(self) -> dict[str, Choice]:
        while self.infeasible is None:
            tasks, per = self.bounds()
            dead = self._dead(tasks, per)
            if not dead:
                break
            self._remove(dead)
        return self.choices

    def _remove(self, dead: set[tuple[str, int]]) -> None:
        for tid in sorted({t for t, _ in dead}):
            choice = self.choices[tid]
            keep = [i for i in range(len(choice.candidates)) if (tid, i) not in dead]
            self.removed += len(choice.candidates) - len(keep)
            if not keep:
                self.infeasible = f"no candidate of `{tid}` can meet the constraints"
            self.choices[tid] = make_choice(tid, tuple(choice.candidates[i] for i in keep),
                                            tuple(choice.excluded[i] for i in keep), choice.hole)

    def _blame(self, why: str, culprit: tuple[tuple[str, ...], tuple[str, ...]]) -> None:
        """Record the first infeasibility found (rules visit tasks, links and chains by name)."""
        if self.infeasible is None:
            self.infeasible, self.culprit = why, culprit

    def _dead(self, tasks: dict[str, Bounds], per: dict[tuple[str, int], Bounds]) -> set[tuple[str, int]]:
        dead: set[tuple[str, int]] = set()
        for (tid, i), b in per.items():
            if not self._rate_ok(self.model.task(tid), self.choices[tid].candidates[i].activation, b):
                dead.add((tid, i))
        for t in sorted(self.model.tasks, key=lambda t: t.id):  # (by name: the blame must not depend on order)
            if t.id not in self.choices and t.activation.trigger_port is not None and not self._rate_ok(
                    t, t.activation, tasks.get(t.id, UNKNOWN)):
                self._blame(f"`{t.id}` is activated outside its activation constraint in every configuration",
                            ((), (t.id,)))
        dead |= self._schedulability()
        dead |= self._sampling(tasks, per)
        dead |= self._utilisation(tasks, per)
        dead |= self._latency(tasks, per)
        return dead

    def _schedulability(self) -> set[tuple[str, int]]:
        """A timer candidate whose period (its default deadline) is below the first-job bound of its
        busy window goes (E312); a task whose given deadline is below it makes the problem infeasible."""
        from .floors import first_job_bounds

        dead: set[tuple[str, int]] = set()
        floors = first_job_bounds(self.model, self.choices)
        for task in sorted(self.model.tasks, key=lambda t: t.id):
            if task.wcrt_bound is not None:
                continue
            floor = floors[task.id]
            if task.deadline is not None:
                if floor > task.deadline and self.infeasible is None:
                    self.infeasible = f"`{task.id}` cannot meet its deadline in any configuration"
                continue
            choice = self.choices.get(task.id)
            for i, c in enumerate(choice.candidates if choice else ()):
                period = c.activation.strict_period
                if period is not None and floor > period:
                    dead.add((task.id, i))
        return dead

    @staticmethod
    def _rate_ok(task: TaskModel, act: Activation, b: Bounds) -> bool:
        if act.trigger_port is None:
            return True  # timer candidates outside the constraint were excluded already
        if task.min_rate is not None and b.fl is not None and b.fl[1] < task.min_rate:
            return False
        return not (task.max_rate is not None and b.fh is not None and b.fh[0] > task.max_rate)

    def _sampling(self, tasks: dict[str, Bounds], per: dict[tuple[str, int], Bounds]) -> set[tuple[str, int]]:
        dead: set[tuple[str, int]] = set()
        for link in sorted(self.model.links, key=lambda lk: (lk.source, lk.target)):
            for reader_id in sorted(link.readers):
                reader = self.model.task(reader_id)
                port = link.target.split(".", 1)[1]
                read = next((r for r in reader.reads if r.port == port), None)
                if read is None:
                    continue
                for direction, tol in (("over", read.oversampling), ("under", read.undersampling)):
                    if tol is None or tol.kind == "ok":
                        continue
                    limit = tolerance_limit(tol)
                    dead |= self._tolerance(link.writer, reader, port, direction, limit, tasks, per)
        return dead

    def _tolerance(self, writer: str, reader: TaskModel, port: str, direction: str, limit: Fraction,
                   tasks: dict[str, Bounds], per: dict[tuple[str, int], Bounds]) -> set[tuple[str, int]]:
        dead: set[tuple[str, int]] = set()
        choice = self.choices.get(reader.id)
        options = activation_options(reader, choice)
        w = tasks.get(writer, UNKNOWN)
        for index, act in options:
            rb = per.get((reader.id, index), tasks.get(reader.id, UNKNOWN)) if index is not None else tasks[reader.id]
            if act.single_port == port:
                bad = direction == "under" and act.release_every > limit
            else:
                bad = _violates(direction, w, rb, limit)
            if bad and index is not None:
                dead.add((reader.id, index))
            elif bad:
                self._blame(f"`{reader.id}` violates its {direction}sampling tolerance on `{port}` in every "
                            "configuration", ((), (reader.id, writer)))
        wchoice = self.choices.get(writer)
        if wchoice is not None and not _triggered_by(reader, choice, port):
            r = tasks.get(reader.id, UNKNOWN)
            for index in range(len(wchoice.candidates)):
                if _violates(direction, per.get((writer, index), UNKNOWN), r, limit):
                    dead.add((writer, index))
        return dead

    def _utilisation(self, tasks: dict[str, Bounds], per: dict[tuple[str, int], Bounds]) -> set[tuple[str, int]]:
        dead: set[tuple[str, int]] = set()
        by_core: dict[str, list[TaskModel]] = {}
        for t in self.model.tasks:
            by_core.setdefault(t.core, []).append(t)
        for core in sorted(by_core):
            demands = []
            for t in by_core[core]:
                b = tasks.get(t.id, UNKNOWN)
                if b.fh is not None:
                    demands.append(t.wcet * b.fh[0])
            floor = exact_sum(demands)
            capacity = self.model.capacity(core)  # (a multi-threaded executor's workers, §9.4)
            if floor > capacity:
                self._blame(f"core `{core}` is above 100 % utilisation even at the slowest candidates"
                            if capacity == 1 else f"the {capacity} workers of core `{core}`'s multi-threaded "
                            "executor are above 100 % utilisation even at the slowest candidates",
                            ((), tuple(t.id for t in by_core[core])))
                return dead
            slack = capacity - floor  # (compared, never added to: its denominator is the core's whole lcm)
            for t in by_core[core]:
                choice = self.choices.get(t.id)
                if choice is None:
                    continue
                fh = tasks[t.id].fh
                own = fh[0] if fh is not None else ZERO
                for i in range(len(choice.candidates)):
                    b = per.get((t.id, i), UNKNOWN)
                    if b.fh is not None and t.wcet * (b.fh[0] - own) > slack:
                        dead.add((t.id, i))
        return dead

    def _latency(self, tasks: dict[str, Bounds], per: dict[tuple[str, int], Bounds]) -> set[tuple[str, int]]:
        dead: set[tuple[str, int]] = set()
        for chain in sorted(self.model.chains, key=lambda c: c.name):
            for bound, kind in ((chain.reaction_time, "reaction"), (chain.data_age, "age")):
                if bound is None:
                    continue
                lower = ChainLowerBound(self, chain, kind, tasks, per)
                if lower.total > bound:
                    self._blame(f"chain `{chain.name}` cannot meet its {kind} bound at any candidate",
                                ((chain.name,), ()))
                    return dead
                for tid in dict.fromkeys(chain.tasks):
                    choice = self.choices.get(tid)
                    for i in range(len(choice.candidates) if choice else 0):
                        if lower.pinned(tid, i) > bound:
                            dead.add((tid, i))
        return dead


def _violates(direction: str, w: Bounds, r: Bounds, limit: Fraction) -> bool:
    """Certainly over-/undersampled beyond ``limit`` (§5.3): fastest possible reader vs slowest
    possible writer never meets the tolerance's own worst direction."""
    if w.fl is None or w.fh is None or r.fl is None or r.fh is None:
        return False
    if direction == "over":  # need r.high <= limit * w.low for some configuration
        return r.fh[0] > limit * w.fl[1]
    return w.fh[0] > limit * r.fl[1]


def _triggered_by(reader: TaskModel, choice: Choice | None, port: str) -> bool:
    """Whether some activation of ``reader`` is a single-port trigger on ``port`` (then the writer's
    rate does not matter to that activation's tolerance)."""
    return any(act.single_port == port for _, act in activation_options(reader, choice))


def _r_min(task: TaskModel) -> Fraction:
    return task.wcrt_bound if task.wcrt_bound is not None else task.wcet


class ChainLowerBound:
    """A lower bound on the reaction time or data age of ``chain`` over every remaining
    configuration (``total``), and with one choice pinned to a candidate (``pinned``). Every term of
    §7 is at least the WCET (or user bound) of the task it ends in, plus the delay, plus a sampling
    wait: a register read waits up to ``A⁺ ≥ P⁺`` (reaction: of the reader; data age: of the
    writer), a prescaler-k trigger ``(k−1)·P⁺`` of the writer — except the same-core priority terms
    (§7.6), bounded by ``_same_core_term``. The bound is a sum of terms, each depending on at most two
    tasks, so pinning one task recomputes only its own terms."""

    def __init__(self, p: Pruner, chain: ChainModel, kind: str, tasks: dict[str, Bounds],
                 per: dict[tuple[str, int], Bounds]):
        self.p, self.chain, self.kind, self.tasks, self.per = p, chain, kind, tasks, per
        self.same_core = [same_core_reason(p.model, hop) is None for hop in chain.hops]
        self._options: dict[str, list[tuple[Activation, Fraction]]] = {
            tid: self.options(tid, None) for tid in dict.fromkeys(chain.tasks)}
        self._p_min: dict[str, Fraction] = {tid: min(pm for _, pm in opts) for tid, opts in self._options.items()}
        self.terms = [self.term(n, None) for n in range(len(chain.hops) + 1)]
        self.total = sum(self.terms, ZERO)
        self._involved: dict[str, list[int]] = {}
        for n in range(len(chain.hops) + 1):
            for tid in self.involves(n):
                self._involved.setdefault(tid, []).append(n)

    def options(self, tid: str, fixed: tuple[str, int] | None) -> list[tuple[Activation, Fraction]]:
        p = self.p
        choice = p.choices.get(tid)
        if choice is None:
            return [(p.model.task(tid).activation, self.tasks.get(tid, UNKNOWN).p_min)]
        if fixed is not None and fixed[0] == tid:  # (a pinned task has a choice)
            return [(choice.candidates[fixed[1]].activation, self.per.get(fixed, UNKNOWN).p_min)]
        return [(c.activation, self.per.get((tid, i), UNKNOWN).p_min) for i, c in enumerate(choice.candidates)]

    def involves(self, n: int) -> tuple[str, ...]:
        """The tasks whose choice term ``n`` depends on (0: the first task; n ≥ 1: hop n − 1)."""
        if n == 0:
            return (self.chain.tasks[0],) if self.kind == "reaction" else ()
        hop = self.chain.hops[n - 1]
        return (hop.reader, hop.writer)

    def term(self, n: int, fixed: tuple[str, int] | None) -> Fraction:
        """Term 0: the first task's wait and response (reaction time) or the last task's response
        (data age); term n ≥ 1: hop n − 1."""
        model = self.p.model

        def options(tid: str) -> list[tuple[Activation, Fraction]]:
            return self.options(tid, fixed) if fixed is not None and fixed[0] == tid else self._options[tid]

        def p_min(tid: str) -> Fraction:
            return min(pm for _, pm in options(tid)) if fixed is not None and fixed[0] == tid else self._p_min[tid]

        if n == 0:
            first, last = self.chain.tasks[0], self.chain.tasks[-1]
            if self.kind == "reaction":
                return p_min(first) + _r_min(model.task(first))
            return model.task(last).wcet
        hop = self.chain.hops[n - 1]
        member = hop.link.target.split(".", 1)[1]
        waits, same_core_waits = [], []
        for act, pm in options(hop.reader):
            triggered = act.listens_to(member)
            if self.kind == "reaction":
                if triggered and not act.all_members and act.release_every > 1:
                    waits.append(min(pm, (act.release_every - 1) * p_min(hop.writer)))
                else:
                    waits.append(ZERO if triggered else pm)
                same_core_waits.append(ZERO if act.trigger_port is not None else pm)
            else:  # a data trigger (7.7b) waits for nothing; an AND join (7.7c) may not (7.3e)
                joins_or = act.trigger_mode == "or"
                waits.append(ZERO if triggered and not joins_or else p_min(hop.writer))
        if self.kind == "reaction":
            lower = hop.link.delay_max + _r_min(model.task(hop.reader)) + min(waits)
        else:  # (§7.7: a completion age may count E ≥ C⁺ rather than R from the job's read)
            lower = hop.link.delay_max + model.task(hop.writer).wcet + min(waits)
        if self.same_core[n - 1]:
            lower = min(lower, self._same_core_term(hop, min(same_core_waits) if same_core_waits else ZERO,
                                                    p_min(hop.writer)))
        return lower

    def _same_core_term(self, hop: HopModel, reader_wait: Fraction, writer_p_min: Fraction) -> Fraction:
        """The least value of the same-core priority terms (specs/timing.md §7.6). Data age: ``A⁺ₚ ≥
        P⁺ₚ``. Reaction: ``W⁺ᵢ + Rᵢ − Rₚ``, which alone has no positive lower bound; but the term
        before it always ends in ``+ Rₚ`` (every reaction term ends with the R of the task it
        reaches) and is bounded below with ``_r_min(p)`` in it, so ``W⁺ᵢ + _r_min(i) − _r_min(p)``
        keeps the *sum* of the two bounds below the sum of the two terms — the total is what pruning
        compares."""
        model = self.p.model
        if self.kind == "reaction":
            return reader_wait + _r_min(model.task(hop.reader)) - _r_min(model.task(hop.writer))
        return writer_p_min

    def pinned(self, tid: str, index: int) -> Fraction:
        """The bound with the choice of ``tid`` pinned to candidate ``index``."""
        total = self.total
        for n in self._involved.get(tid, ()):
            total += self.term(n, (tid, index)) - self.terms[n]
        return total
