"""The Z3 encoding: linear integer arithmetic and pseudo-Boolean constraints over integer ticks.

Every choice is a one-hot vector of Bools over its candidates (exactly one true, a PB equality).
Times are integers in *ticks*: the greatest common divisor of every time of the problem (execution
times, delays, candidate periods, phases, deadlines, bounds), so the same problem with every time
scaled gives the same integers. Rates are integers in units of ``1/(M·tick)``, ``M`` the least
common multiple of the denominators every rate can have, so ``k·f_reader = f_writer`` for a
prescaler ``k`` stays integral. A product of two decisions (a prescaler times a period that is itself
decided) never appears: each candidate contributes its own linear equality under its Bool
(``sel → P = k·P_writer``), the classic linearisation of Davare et al., *Period Optimization for Hard
Real-time Distributed Automotive Systems*, DAC 2007.

Per task: the maximum-distance event model ``P⁺, J⁺, F`` of specs/timing.md §5.2 (exact, as the
analysis computes it), the response time ``R`` (an integer with lower bounds only: from ``wcet`` and
from lemmas learnt lazily, specs/synthesis.md §4), the rate interval ``fl, fh``. Chains are sums of
the hop terms of §7 with the same rule choice (the smaller of trigger and register rule); the data age
is the least sum through three ages per task (§7.7), with the start-to-completion time ``E`` and the
same-core trigger pair's ``J`` learnt like ``R`` (lower bounds only, ``C ≤ E ≤ R``). Constraints:
exactly one candidate, no trigger cycle, activation constraints of triggered tasks, sampling
tolerances, utilisation per core, ``R ≤ deadline``, the specs. Tracked statements guard their
constraints with an assumption literal (``guard``).
"""
from __future__ import annotations

import math
from fractions import Fraction
from typing import TypeAlias, cast
from collections.abc import Mapping

import z3

from ..model import syntax as s
from ..model.activations import Activation
from ..model.system import ChainModel, HopModel, LinkModel, SystemModel, TaskModel
from ..core.timebase import TimeBase
from ..timing.chains import cascade_in_time, cascade_links, pair_shape, same_core_reason
from ..timing.rates import tolerance_limit
from ..timing.rta import cooperative_counts
from .candidates import Choice
from .floors import first_job_bounds
from .scale import rate_scale, tick_of
from .statements import Statement, statement_index
from .structure import Structure, activation_options, member_links
from .terms import Cond, Term, Terms, conjunction, disjunction, lt_pair

#: a job's data ages at its release, its read (start) and its completion (specs/timing.md §7.7)
Ages: TypeAlias = "tuple[Term, Term, Term]"


# ================================================================== the encoding


class Encoding:
    """All variables and constraints of one problem. ``hard`` lists every constraint so far;
    ``take_new()`` hands out what was added since the last call (lemmas, ladders, blocks)."""

    def __init__(self, model: SystemModel, choices: Mapping[str, Choice], statements: tuple[Statement, ...],
                 structure: Structure, tracked: bool, seed: Mapping[str, Fraction | None], ctx: z3.Context):
        self.model, self.choices, self.statements = model, choices, statements
        self.structure, self.tracked, self.seed = structure, tracked, seed
        self.base = TimeBase(tick_of(model, choices))
        self.M = rate_scale(model, choices, structure, self.tick)
        self.ctx = ctx
        self.t = Terms(ctx)
        self.slots = statement_index(statements)
        self.hard: list[z3.BoolRef] = []
        self._given = 0
        self.lits: dict[str, z3.BoolRef] = {}
        self.sel: dict[str, list[z3.BoolRef]] = {}
        self.R: dict[str, Term] = {}
        self.E: dict[str, Term] = {}  # start to completion (§7.7), for the tasks of chains
        self.J: dict[tuple[str, str], tuple[HopModel, Term]] = {}  # same-core trigger pairs by link (§7.7)
        self.events: dict[str, tuple[Term, Term, Term]] = {}  # (P⁺, J⁺, F)
        self.rates: dict[str, tuple[Term, Term]] = {}  # (k·fl, k·fh)
        self.C: dict[str, Term] = {}
        self.latency: dict[tuple[str, str], Term] = {}
        self.specs: list[tuple[Statement, Term, int]] = []  # (statement, latency term, bound ticks)
        self.ladders: dict[str, list[z3.BoolRef | None]] = {}
        self._floors: dict[str, Fraction] | None = None
        self._cooperative = cooperative_counts(model)
        self._mins = 0
        self._waits: dict[str, Term] = {}
        self._build()

    # -------------------------------------------------------------- basics

    @property
    def tick(self) -> Fraction:
        """The problem's tick in seconds (``tick_of``)."""
        return self.base.unit

    def ticks(self, x: Fraction) -> int:
        """``x`` in ticks of the problem (``verify.core.timebase``)."""
        return self.base.ticks(x)

    def ticks_above(self, x: Fraction, strictly: bool = False) -> int:
        """The least number of ticks at least ``x`` (more than ``x`` when ``strictly``): what an integer
        ``v ≥ x`` (``v > x``) in ticks means, also for an ``x`` that is no whole number of ticks (a lemma's
        value of an analysis whose bound divides by an executor's workers, or the deadline ``A⁺``)."""
        q = x / self.tick
        return math.floor(q) + 1 if strictly else math.ceil(q)

    def add(self, c: Cond) -> None:
        if c is True:
            return
        self.hard.append(z3.BoolVal(False, self.ctx) if c is False else c)

    def floor(self, tid: str) -> int:
        """The static lower bound of R (ticks) every configuration respects."""
        if self._floors is None:
            self._floors = first_job_bounds(self.model, self.choices, relaxed=self.tracked)
        return math.ceil(self._floors[tid] / self.tick)

    def take_new(self) -> list[z3.BoolRef]:
        new = self.hard[self._given:]
        self._given = len(self.hard)
        return new

    def lit(self, key: str | None) -> z3.BoolRef | None:
        """The assumption literal of a tracked statement; None (always on) when untracked."""
        if key is None or not self.tracked:
            return None
        if key not in self.lits:
            self.lits[key] = z3.Bool(f"stmt|{key}", self.ctx)
        return self.lits[key]

    def guard(self, key: str | None, c: Cond, *conds: z3.BoolRef) -> None:
        """Assert ``c`` under the statement ``key`` (tracked) and the candidate literals ``conds``."""
        if c is True:
            return
        pre = [x for x in (self.lit(key), *conds) if x is not None and x is not True]
        if not pre:
            self.add(c)
        else:
            then = z3.BoolVal(False, self.ctx) if c is False else c
            self.add(self.t.implies(pre, then))

    def slot(self, task: str, name: str) -> str | None:
        return self.slots.get(task, {}).get(name)

    # -------------------------------------------------------------- build

    def _build(self) -> None:
        for tid, choice in self.choices.items():
            self.sel[tid] = [z3.Bool(f"sel|{tid}|{i}", self.ctx) for i in range(len(choice.candidates))]
            self.add(z3.PbEq([(b, 1) for b in self.sel[tid]], 1) if self.sel[tid] else False)
            for i, keys in enumerate(choice.excluded):
                for key in keys:
                    self.guard(key, z3.Not(self.sel[tid][i]))
        ordered = sorted(self.model.tasks, key=lambda t: t.id)
        for task in ordered:
            self.C[task.id] = self._cost(task)
            self.R[task.id] = self._response_var(task)
        self._declare_flow_vars()
        for tid in self.structure.order:
            self._task_flow(self.model.task(tid))
        self._no_trigger_cycles()
        for task in ordered:
            self._schedulable(task)
            self._activation_constraint(task)
        self._tolerances()
        self._utilisation()
        self._spec_statements: dict[str | None, list[Statement]] = {}
        for st in self.statements:
            if st.kind == "spec":
                self._spec_statements.setdefault(st.chain, []).append(st)
        for chain in sorted(self.model.chains, key=lambda c: c.name):
            self._chain(chain)

    def _cost(self, task: TaskModel) -> Term:
        wcet, bcet = self.ticks(task.wcet) if task.wcet else 0, self.ticks(task.bcet) if task.bcet else 0
        key = self.slot(task.id, "wcet")
        if not self.tracked or key is None or wcet == bcet:
            return wcet
        return z3.If(self.lit(key), self.t.lift(wcet), self.t.lift(bcet))

    def _response_var(self, task: TaskModel) -> Term:
        if task.wcrt_bound is not None:
            return self.ticks(task.wcrt_bound)
        if not self.structure.cones.get(task.id) and not self.tracked:
            value = self.seed.get(task.id)
            if value is None:
                self.add(False)  # unschedulable whatever synthesis chooses
                return 0
            return self.ticks(value)
        r = z3.Int(f"R|{task.id}", self.ctx)
        self.add(self.t.ge(r, self.C[task.id]))
        self.add(self.t.at_least(r, self.floor(task.id)))
        return r

    def _variable(self, task: TaskModel) -> bool:
        """Whether the event model or rate of ``task`` depends on a decision or a learnt R."""
        if task.id in self.choices or task.id in self.structure.cyclic:
            return True
        act = task.activation
        for _, link in member_links(self.model, task, act):
            if link is not None and (self._varflags[link.writer] or not isinstance(self.R[link.writer], int)):
                return True
        return False

    def _declare_flow_vars(self) -> None:
        self._varflags: dict[str, bool] = {}
        for tid in self.structure.order:
            self._varflags[tid] = self._variable(self.model.task(tid))
        for tid in sorted(self._varflags):
            if self._varflags[tid]:
                self.events[tid] = tuple(z3.Int(f"{n}|{tid}", self.ctx) for n in ("P", "J", "F"))
                self.rates[tid] = tuple(z3.Int(f"{n}|{tid}", self.ctx) for n in ("fl", "fh"))

    # -------------------------------------------------------------- event models and rates (§5)

    def _task_flow(self, task: TaskModel) -> None:
        options = activation_options(task, self.choices.get(task.id))
        for index, act in options:
            events, rates = self._source(task, act)
            if not self._varflags[task.id]:
                self.events[task.id], self.rates[task.id] = events, rates
                return
            cond = self.sel[task.id][index] if index is not None else None
            P, J, F = self.events[task.id]
            fl, fh = self.rates[task.id]
            k = act.release_every
            cs = [self.t.eq(P, events[0]), self.t.eq(J, events[1]), self.t.eq(F, events[2]),
                  self.t.eq(self.t.mul(k, fl), rates[0]), self.t.eq(self.t.mul(k, fh), rates[1])]
            for c in cs:
                self.guard(None, c, *([cond] if cond is not None else []))

    def _source(self, task: TaskModel, act: Activation) -> tuple[tuple[Term, Term, Term], tuple[Term, Term]]:
        """(P⁺, J⁺, F) in ticks and (k·fl, k·fh) in rate units for one activation (§5.2)."""
        gaps, latest = act.gaps, act.first_release_latest
        if gaps is not None and latest is not None:  # released by time: (a⁺, 0, first release at the latest)
            lo, hi = self.ticks(gaps[0]), self.ticks(gaps[1])
            return (hi, 0, self.ticks(latest)), (self.M // hi, self.M // lo)
        mode = act.trigger_mode
        assert mode is not None  # the rest releases by data
        arrivals = [(self.arrival(link), self.rates[link.writer])
                    for _, link in member_links(self.model, task, act) if link is not None]
        stream = self._stream([a for a, _ in arrivals], mode)
        k, t = act.release_every, self.t
        P, J, F = stream
        if k > 1:
            if mode == "or" and len(arrivals) > 1:
                first = None
                for (aP, aJ, aF), _ in arrivals:
                    cand = t.add(aF, t.mul(k - 1, aP), aJ)
                    first = cand if first is None else t.min(first, cand)
                F = first
            else:
                F = t.add(F, t.mul(k - 1, P), J)
        rates = [r for _, r in arrivals]
        fl, fh = rates[0]
        if mode == "and":
            for rl, rh in rates[1:]:
                fl, fh = t.min(fl, rl), t.min(fh, rh)
        elif mode == "or":
            fl, fh = t.add(*(r[0] for r in rates)), t.add(*(r[1] for r in rates))
        if not self._varflags.get(task.id) and isinstance(fl, int) and isinstance(fh, int):
            return (t.mul(k, P), J, F), (fl // k, fh // k)
        return (t.mul(k, P), J, F), (fl, fh)

    def arrival(self, link: LinkModel) -> tuple[Term, Term, Term]:
        """The arrival stream on ``link.target`` (§5.2): the writer's period, its jitter plus the output
        jitter ``R − B + d⁺ − d⁻``, first arrival ``F + R + d⁺``."""
        w = link.writer
        P, J, F = self.events[w]
        R, B = self.R[w], self.ticks(self.model.task(w).bcet) if self.model.task(w).bcet else 0
        dmax = self.ticks(link.delay_max) if link.delay_max else 0
        dmin = self.ticks(link.delay_min) if link.delay_min else 0
        t = self.t
        return P, t.add(J, R, -B, dmax - dmin), t.add(F, R, dmax)

    def _stream(self, arrivals: list[tuple[Term, Term, Term]], mode: str) -> tuple[Term, Term, Term]:
        t = self.t
        if mode == "and":
            P = F = None
            for aP, aJ, aF in arrivals:
                gap = t.add(aP, aJ)
                P = gap if P is None else t.max(P, gap)
                F = aF if F is None else t.max(F, aF)
            return P, 0, F
        if mode == "or" and len(arrivals) > 1:
            bP, bJ, bF = arrivals[0]
            bW = t.max(t.add(bP, bJ), bF)
            for aP, aJ, aF in arrivals[1:]:
                wait = t.max(t.add(aP, aJ), aF)
                better = lt_pair(t, (wait, aP), (bW, bP))
                bP, bJ, bF, bW = (t.ite(better, aP, bP), t.ite(better, aJ, bJ), t.ite(better, aF, bF),
                                  t.ite(better, wait, bW))
            first = None
            for _, _, aF in arrivals:
                first = aF if first is None else t.min(first, aF)
            return bP, t.add(bJ, t.max(0, t.add(bF, t.mul(-1, bP)))), first
        return arrivals[0]

    def _no_trigger_cycles(self) -> None:
        """A configuration whose triggers form a cycle is never synthesized (specs/synthesis.md §2)."""
        cyclic = self.structure.cyclic
        if not cyclic:
            return
        rank = {tid: z3.Int(f"ord|{tid}", self.ctx) for tid in sorted(cyclic)}
        for w, r, index in self.structure.trigger_edges:
            if w in rank and r in rank:
                self.guard(None, rank[w] < rank[r], *([self.sel[r][index]] if index is not None else []))

    # -------------------------------------------------------------- constraints

    def a_max(self, tid: str) -> Term:
        P, J, _ = self.events[tid]
        return self.t.add(P, J)

    def wait(self, tid: str) -> Term:
        """W⁺ = max(A⁺, F)."""
        return self.t.max(self.a_max(tid), self.events[tid][2])

    def late_wait(self, tid: str) -> Term:
        """A term at least ``W⁺`` (one-sided, for latencies: ``greatest``), one per task."""
        if tid not in self._waits:
            self._waits[tid] = self.greatest(self.a_max(tid), self.events[tid][2])
        return self._waits[tid]

    def _schedulable(self, task: TaskModel) -> None:
        """R ≤ deadline (E312): the given deadline, else A⁺."""
        if task.wcrt_bound is not None:
            return
        limit = self.ticks(task.deadline) if task.deadline is not None else self.a_max(task.id)
        self.add(self.t.le(self.R[task.id], limit))

    def _activation_constraint(self, task: TaskModel) -> None:
        """A triggered activation's rate within the task's constraint (E305/E306); timer candidates
        outside it are excluded candidates already."""
        if task.min_rate is None and task.max_rate is None:
            return
        options = [(i, a) for i, a in activation_options(task, self.choices.get(task.id)) if a.trigger_port is not None]
        if not options:
            return
        fl, fh = self.rates[task.id]
        rate_key = self.slot(task.id, "rate") if not task.changeable else None
        for index, _ in options:
            cond = [self.sel[task.id][index]] if index is not None else []
            if task.min_rate is not None:
                low = math.ceil(task.min_rate * self.tick * self.M)
                self.guard(rate_key or self.slot(task.id, "min_rate"), self.t.le(low, fl), *cond)
            if task.max_rate is not None:
                high = math.floor(task.max_rate * self.tick * self.M)
                self.guard(rate_key or self.slot(task.id, "max_rate"), self.t.le(fh, high), *cond)

    def _tolerances(self) -> None:
        """Sampling tolerances (E310, §5.3) for every connection and reader."""
        for link in self.model.links:
            port = link.target.split(".", 1)[1]
            for reader_id in link.readers:
                reader = self.model.task(reader_id)
                read = next((r for r in reader.reads if r.port == port), None)
                if read is None:
                    continue
                for direction, tol in (("over", read.oversampling), ("under", read.undersampling)):
                    if tol is not None and tol.kind != "ok":
                        self._tolerance(link, reader, port, direction, tol)

    def _tolerance(self, link: LinkModel, reader: TaskModel, port: str, direction: str, tol: s.Tolerance) -> None:
        limit = tolerance_limit(tol)
        key = self.slot(reader.id, f"tolerance:{port}:{direction}")
        general = []
        for index, act in activation_options(reader, self.choices.get(reader.id)):
            cond = [self.sel[reader.id][index]] if index is not None else []
            if act.single_port == port:
                if direction == "under" and act.release_every > limit:
                    self.guard(key, False, *cond)
            else:
                general.append(cond)
        if not general:
            return
        w_lo, w_hi = self.rates[link.writer]
        r_lo, r_hi = self.rates[reader.id]
        num, den = limit.numerator, limit.denominator
        t = self.t
        c = (t.le(t.mul(den, r_hi), t.mul(num, w_lo)) if direction == "over"
             else t.le(t.mul(den, w_hi), t.mul(num, r_lo)))
        options = len(activation_options(reader, self.choices.get(reader.id)))
        if len(general) == options:  # every activation reads this port as a register
            self.guard(key, c)
        else:
            for cond in general:
                self.guard(key, c, *cond)

    def _utilisation(self) -> None:
        """Σ C·fh ≤ M per core (E311; ≤ m·M over the m workers of a multi-threaded executor, §9.4); a task
        whose core assignment is relaxed runs alone."""
        by_core: dict[str, list[TaskModel]] = {}
        for t in sorted(self.model.tasks, key=lambda t: t.id):
            by_core.setdefault(t.core, []).append(t)
        self.util_terms: dict[str, Term] = {}
        for core in sorted(by_core):
            parts = []
            for task in by_core[core]:
                demand = self._demand(task)
                key = self.slot(task.id, "core")
                if self.tracked and key is not None:
                    self.add(z3.Implies(z3.Not(self.lit(key)), self.t.lift(demand) <= self.M))
                    parts.append(self.t.ite(self.lit(key), demand, 0))
                else:
                    parts.append(demand)
            total = self.t.add(*parts)
            self.util_terms[core] = total
            self.add(self.t.le(total, self.M * self.model.capacity(core)))
        self.utilisation = self.t.add(*(self._demand(t) for t in sorted(self.model.tasks, key=lambda t: t.id)))

    def utilisation_floor(self) -> int | None:
        """A value no configuration's ``utilisation`` term lies below: ``Σ C·fh`` with every ``fh`` at
        the least rate any of the task's activations can give (rates propagated through triggers as
        in ``_source``; tasks on a trigger cycle start from 0 and rise to a fixed point, each round a
        valid lower bound). None for tracked problems (execution times are decisions there)."""
        if self.tracked:
            return None
        low: dict[str, int] = {}
        for tid in self.structure.order:
            fh = self.rates[tid][1]
            low[tid] = fh if isinstance(fh, int) else 0
        for _ in range(len(self.structure.cyclic) + 1):
            changed = False
            for tid in self.structure.order:
                if isinstance(self.rates[tid][1], int):
                    continue
                value = min(self._least_rate(self.model.task(tid), act, low)
                            for _, act in activation_options(self.model.task(tid), self.choices.get(tid)))
                changed |= value != low[tid]
                low[tid] = value
            if not changed:
                break
        total = 0
        for task in self.model.tasks:
            C = self.C[task.id]
            assert isinstance(C, int)  # (untracked: execution times are constants)
            total += C * low[task.id]
        return total

    def _least_rate(self, task: TaskModel, act: Activation, low: Mapping[str, int]) -> int:
        """The least ``fh`` of ``task`` under ``act`` given lower bounds ``low`` of its writers' ``fh``."""
        if act.gaps is not None:
            return self.M // self.ticks(act.gaps[0])
        mode = act.trigger_mode
        if mode is None:
            return 0
        rates = [low[link.writer] for _, link in member_links(self.model, task, act) if link is not None]
        if not rates:
            return 0
        combined = min(rates) if mode == "and" else sum(rates) if mode == "or" else rates[0]
        return combined // act.release_every

    def _demand(self, task: TaskModel) -> Term:
        C, fh = self.C[task.id], self.rates[task.id][1]
        if isinstance(C, int):
            return self.t.mul(C, fh) if isinstance(fh, int) or C != 0 else 0
        wcet, bcet = self.ticks(task.wcet), self.ticks(task.bcet) if task.bcet else 0
        return z3.If(self.lit(self.slot(task.id, "wcet")), self.t.lift(self.t.mul(wcet, fh)),
                     self.t.lift(self.t.mul(bcet, fh)))

    # -------------------------------------------------------------- chains (§7)

    def _chain(self, chain: ChainModel) -> None:
        t = self.t
        first = chain.tasks[0]
        reaction = [t.add(self.late_wait(first), self.R[first])]
        # the reduced data age counts from τ₁'s read, its stamp: its job's release and read ages are 0
        ages: Ages = (0, 0, self._completion(first, 0, 0))
        for n, hop in enumerate(chain.hops):
            r, ages = self._hop(chain.name, n, hop, ages)
            reaction.append(r)
        best = sum(self.ticks(self.model.task(x).bcet) if self.model.task(x).bcet else 0 for x in chain.tasks)
        best += sum(self.ticks(h.link.delay_min) if h.link.delay_min else 0 for h in chain.hops)
        totals = {"reaction_time": self._named(f"lat|{chain.name}|reaction", t.add(*reaction)),
                  "data_age": self._named(f"lat|{chain.name}|age", ages[2])}
        totals["jitter"] = t.add(totals["data_age"], -best)
        self.latency[(chain.name, "reaction_time")] = totals["reaction_time"]
        self.latency[(chain.name, "data_age")] = totals["data_age"]
        self.latency[(chain.name, "jitter")] = totals["jitter"]
        specs = {"reaction_time": chain.reaction_time, "data_age": chain.data_age, "jitter": chain.jitter}
        for st in self._spec_statements.get(chain.name, ()):
            kind = st.spec_kind  # (a spec statement names its ``spec_kind``)
            spec = specs.get(kind) if kind is not None else None
            if kind is not None and spec is not None:
                bound = self.ticks(spec)
                self.specs.append((st, totals[kind], bound))
                self.guard(st.key, t.le(totals[kind], bound))

    def _named(self, name: str, term: Term) -> Term:
        """A variable at least ``term`` (a latency: only its least value matters, §3)."""
        if isinstance(term, int):
            return term
        var = z3.Int(name, self.ctx)
        self.add(self.t.ge(var, term))
        return var

    def least(self, *terms: Term) -> Term:
        """A term at least the least of ``terms``: a fresh variable ``v`` with ``v ≥ a ∨ v ≥ b ∨ …``
        (specs/synthesis.md §3). Latencies are monotone — a larger term never makes a chain bound
        smaller — so where only the least value of a latency matters (specs, objectives) this one-sided
        minimum keeps every configuration at its exact bound, without the case split of an
        ``if-then-else`` in both directions."""
        numbers = [x for x in terms if isinstance(x, int)]
        alternatives: list[Term] = [x for x in terms if not isinstance(x, int)]
        if numbers:
            alternatives.append(min(numbers))
        if len(alternatives) == 1:
            return alternatives[0]
        self._mins += 1
        var = z3.Int(f"min|{self._mins}", self.ctx)
        self.add(self.t.any_of([cast(z3.BoolRef, self.t.ge(var, x)) for x in alternatives]))  # (of a variable)
        return var

    def greatest(self, *terms: Term) -> Term:
        """A term at least the greatest of ``terms`` (one-sided, as ``least``): ``v ≥ a ∧ v ≥ b ∧ …``."""
        numbers = [x for x in terms if isinstance(x, int)]
        rest: list[Term] = [x for x in terms if not isinstance(x, int)]
        if not rest:
            return max(numbers)
        if len(rest) == 1 and not numbers:
            return rest[0]
        self._mins += 1
        var = z3.Int(f"max|{self._mins}", self.ctx)
        for x in rest + ([max(numbers)] if numbers else []):
            self.add(self.t.ge(var, x))
        return var

    def span(self, tid: str) -> Term:
        """``Eᵢ`` (specs/timing.md §7.7): from a job's start to its completion, ``C⁺ᵢ ≤ E ≤ Rᵢ``; raised by
        lemmas learnt from the analysis like ``R`` (``Engine.learn``)."""
        if tid not in self.E:
            R, C = self.R[tid], self.C[tid]
            if isinstance(R, int) and isinstance(C, int) and R == C:
                self.E[tid] = R
            else:
                e = z3.Int(f"E|{tid}", self.ctx)
                self.add(self.t.ge(e, C))
                self.add(self.t.le(e, R))
                self.E[tid] = e
        return self.E[tid]

    def _pair(self, hop: HopModel) -> Term:
        """``Jₚᵢ`` of a same-core trigger pair (specs/timing.md §7.7, (7.7d)): at least ``C⁺ₚ + C⁺ᵢ``,
        raised by lemmas learnt from the analysis (``Engine.learn``)."""
        key = (hop.link.source, hop.link.target)
        if key not in self.J:
            j = z3.Int(f"J|{hop.link.source}|{hop.link.target}", self.ctx)
            self.add(self.t.ge(j, self.t.add(self.C[hop.writer], self.C[hop.reader])))
            self.J[key] = (hop, j)
        return self.J[key][1]

    def _completion(self, tid: str, release: Term, read: Term, *more: Term) -> Term:
        """The completion age of a job of ``tid`` from its release and read ages (rule (7.7a)), or ``more``."""
        t = self.t
        return self.least(t.add(release, self.R[tid]), t.add(read, self.span(tid)), *more)

    def _hop(self, chain: str, n: int, hop: HopModel, ages: Ages) -> tuple[Term, Ages]:
        """(reaction term, the reader's ages) of one hop, by the reader's activation (§7.3, §7.7)."""
        reader = self.model.task(hop.reader)
        options = activation_options(reader, self.choices.get(reader.id))
        terms = [(index, self._hop_terms(hop, act, ages)) for index, act in options]
        if len(terms) == 1:
            r, out = terms[0][1]
            return r, (self._named(f"age|{chain}|{n}|release", out[0]), self._named(f"age|{chain}|{n}|read", out[1]),
                       self._named(f"age|{chain}|{n}|completion", out[2]))
        hr = z3.Int(f"hop|{chain}|{n}|r", self.ctx)
        names = ("release", "read", "completion")
        new = tuple(z3.Int(f"age|{chain}|{n}|{x}", self.ctx) for x in names)
        for index, (r, out) in terms:  # (several options: the candidates of a choice, each with its index)
            assert index is not None  # several options: the candidates of a choice
            sel = self.sel[reader.id][index]
            self.guard(None, self.t.ge(hr, r), sel)
            for var, value in zip(new, out):
                self.guard(None, self.t.ge(var, value), sel)
        return hr, (new[0], new[1], new[2])

    def _hop_terms(self, hop: HopModel, act: Activation, ages: Ages) -> tuple[Term, Ages]:
        """The reaction term (§7.3, §7.6) and the reader's (release, read, completion) ages (§7.7)."""
        t = self.t
        p, i = hop.writer, hop.reader
        release, read, completion = ages
        d = self.ticks(hop.link.delay_max) if hop.link.delay_max else 0
        register_r = t.add(d, self.late_wait(i), self.R[i])
        register_a = t.add(d, self.a_max(p), self.R[p])
        read_term = register_a
        if same_core_reason(self.model, hop) is None:
            read_term = self.least(register_a, self.a_max(p))
        new_read = t.add(self.least(release, read, completion), read_term)
        new_release = new_read
        member = hop.link.target.split(".", 1)[1]
        if not act.listens_to(member):
            reaction = self._same_core(hop, register_r)
        else:
            k = act.release_every  # (it listens to a member: a data trigger)
            if act.all_members:
                wait = self._and_wait(hop, act)
                trig = t.add(d, wait, self._and_join(hop, act, k), self.R[i])
            else:
                wait = 0
                trig = t.add(d, self._delta_plus(p, k), self.R[i])
            reaction = self._same_core(hop, self.least(trig, register_r))
            if act.trigger_mode != "or":  # the data trigger (7.7b) and the AND join age (7.7c)
                new_release = self.least(new_release, *(t.add(age, d, writer, wait) for age, writer in (
                    (release, self.R[p]), (read, self.span(p)), (completion, 0))))
        pair = []
        if pair_shape(self.model, hop, act, self._cooperative):
            pair.append(t.add(read, self.least(self._pair(hop), t.add(self.span(p), self.R[i]))))
        return reaction, (new_release, new_read, self._completion(i, new_release, new_read, *pair))

    def _same_core(self, hop: HopModel, reaction: Term) -> Term:
        """The same-core priority rule (specs/timing.md §7.6) where it applies, as the analysis chooses
        it: the smaller of the reaction term and ``W⁺ᵢ + Rᵢ − Rₚ`` ((7.6b); its data-age term ``A⁺ₚ``,
        (7.6a), is a read term of ``_hop_terms``)."""
        if same_core_reason(self.model, hop) is not None:
            return reaction
        t, p, i = self.t, hop.writer, hop.reader
        return self.least(reaction, t.add(self.late_wait(i), self.R[i], t.mul(-1, self.R[p])))

    def _delta_plus(self, writer: str, k: int) -> Term:
        """δ⁺ₚ(k) = 0 for k = 1, else (k−1)·P⁺ₚ + J⁺ₚ + Rₚ − Bₚ."""
        if k == 1:
            return 0
        P, J, _ = self.events[writer]
        B = self.ticks(self.model.task(writer).bcet) if self.model.task(writer).bcet else 0
        return self.t.add(self.t.mul(k - 1, P), J, self.R[writer], -B)

    def _and_arrivals(self, hop: HopModel, act: Activation) -> list[tuple[str, tuple[Term, Term, Term]]]:
        reader = self.model.task(hop.reader)
        return [(m, self.arrival(link)) for m, link in member_links(self.model, reader, act) if link is not None]

    def _and_wait(self, hop: HopModel, act: Activation) -> Term:
        """``maxₘ W⁺ₘ`` of the other members, 0 where they are fresh by (7.3e) (``_cascade``)."""
        t = self.t
        member = hop.link.target.split(".", 1)[1]
        waits: list[Term] = []
        for m, (aP, aJ, aF) in self._and_arrivals(hop, act):
            if m != member:
                waits += [t.add(aP, aJ), aF]
        cascade = self._cascade(hop, act)
        if cascade is True or not waits:
            return 0
        if cascade is False:
            return self.greatest(*waits)
        self._mins += 1
        var = z3.Int(f"wait|{self._mins}", self.ctx)
        self.add(self.t.ge(var, 0))
        for x in waits:
            self.add(z3.Or(cascade, self.t.ge(var, x)))
        return var

    def _cascade(self, hop: HopModel, act: Activation) -> Cond:
        """Whether the AND join ``act`` is one of a cascade whose other members are fresh when this hop's
        value arrives (specs/timing.md §7.3, (7.3e)), as the analysis decides it (``cascade_fresh``) for
        each activation the writer ``p`` and the task ``w`` triggering it may take: the shape and the
        delays (``cascade_links``, ``cascade_in_time``), and ``d⁺ + Rₚ + d⁺ < max(C⁻_w, a⁻_w − R_w +
        B_w) + d⁻ₘ``."""
        t, model = self.t, self.model
        p = model.task(hop.writer)
        out: list[Cond] = []
        for pidx, pact in activation_options(p, self.choices.get(p.id)):
            shape = cascade_links(model, hop, act, pact)
            if shape is None or not cascade_in_time(shape[0], hop, shape[1], p.bcet):
                continue
            feed, others = shape
            w = model.task(feed.writer)
            bcet = self.ticks(w.bcet)
            late = t.add(self.ticks(feed.delay_max), self.R[p.id], self.ticks(hop.link.delay_max), 1)
            for widx, wact in activation_options(w, self.choices.get(w.id)):
                if wact.gaps is None:
                    continue
                spacing = t.max(bcet, t.add(self.ticks(wact.gaps[0]), t.mul(-1, self.R[w.id]), bcet))
                conds = [t.le(late, t.add(spacing, self.ticks(lk.delay_min))) for lk in others]
                conds += [self.sel[x.id][i] for x, i in ((p, pidx), (w, widx)) if i is not None]
                out.append(conjunction(conds))
        return disjunction(out)

    def _and_join(self, hop: HopModel, act: Activation, k: int) -> Term:
        if k == 1:
            return 0
        t = self.t
        gap = self.greatest(*(t.add(aP, aJ) for _, (aP, aJ, _) in self._and_arrivals(hop, act)))
        return t.mul(k - 1, gap)
