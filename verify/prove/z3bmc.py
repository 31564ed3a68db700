"""Exact worst cases with Z3: bounded model checking of the job-level semantics (specs/proof.md §5).

The encoding is time-indexed on the grid of the exactness theorem (unit ``h = tick/(2m+1)``, so
every event of every scenario of the search space falls on an instant): per task and instant the
number of pending jobs and the remaining work of the oldest, whether it runs in the next unit, its
completions; timers release when ``phase ≡ t (mod T)`` — periods are constants, so everything is
linear integer arithmetic. Free choices are the phases (integers in [0, T/h), one of them 0 when
no phase is fixed: only relative phases matter) and the prescaler counter phases.

It covers the subclass (``z3_applicable``): the exact class of ``exact.exact_class``, preemptive
tasks only, single-port data triggers, distinct priorities on each core, execution times > 0.

The window is justified by a query that must be unsatisfiable (in *no* scenario do the timing states at
``t_s`` and ``t_s + H`` differ, so the timing repeats from ``t_s`` in all of them) and by the analysis'
bounds, which say by when every sample class has completed (``W``). Then the supremum is found by asking for a
sample above the best value so far; every model is replayed in the reference simulator (``measure_periodic``),
whose value becomes the new best, until the query is unsatisfiable. All queries share one resource limit in Z3
``rlimit`` units (deterministic) and stop at the caller's deadline; an exhausted limit gives no result (the
caller reports "undecided").
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from fractions import Fraction
from typing import TypeAlias

import z3

from ..model.system import ChainModel, SystemModel
from .exact import Budget, Extreme, ExactResult, Grid, exact_class, grid_of, scenario_of
from ..core.timebase import ceil_to, floor_to
from .measure import measure_periodic
from .scenario import Measured, Target

MAX_CELLS = 2_500  # instants × tasks: beyond, bit-blasting alone can outlast any resource limit
MAX_PERIODS = 8  # hyperperiods tried for the start of the repetition

#: provenance at one position and instant: (stamp, previous read, valid, previous valid)
_Quad: TypeAlias = "tuple[z3.BitVecRef, z3.BitVecRef, z3.BoolRef, z3.BoolRef]"


class EncodingMismatch(AssertionError):
    """A Z3 model that the reference simulator does not confirm (a bug in the encoding)."""


def z3_applicable(model: SystemModel) -> str | None:
    """None when the encoding covers ``model``, else why not."""
    reason = exact_class(model)
    if reason:
        return reason
    for t in model.tasks:
        if t.kind != "preemptive":
            return f"`{t.id}` is cooperative"
        if t.executor is not None:
            return f"`{t.id}` is a callback of ROS 2 executor `{t.executor}`"
        act = t.activation
        if act.trigger_port is not None and act.single_port is None:
            return f"`{t.id}` is triggered by a compound port"
        if t.wcet <= 0:
            return f"`{t.id}` has a zero execution time"
    seen: dict[tuple[str, int], str] = {}
    for t in model.tasks:
        if (t.core, t.priority) in seen:
            return f"`{t.id}` and `{seen[(t.core, t.priority)]}` share a priority on `{t.core}`"
        seen[(t.core, t.priority)] = t.id
    grid = grid_of(model)
    cells = (MAX_PERIODS + 3) * int(grid.hyper / grid.h) * len(model.tasks)
    if cells > MAX_CELLS:
        return f"its unrolling would have {cells} cells (instants × tasks), more than {MAX_CELLS}"
    return None


class Encoding:
    """The unrolled semantics over instants 0..W (extended on demand)."""

    def __init__(self, model: SystemModel, grid: Grid, chains: list[str], width: int = 16):
        self.model, self.grid = model, grid
        self.width = width
        self.h = grid.h
        self.units: Callable[[Fraction], int] = lambda x: int(Fraction(x) / self.h)
        self.tasks = list(model.tasks)
        self.ids: list[str] = [t.id for t in self.tasks]
        self.C: dict[str, int] = {t.id: self.units(t.wcet) for t in self.tasks}
        self.hp: dict[str, list[str]] = {
            t.id: [u.id for u in self.tasks if u.core == t.core and u.priority > t.priority] for t in self.tasks}
        self.phi: dict[str, z3.BitVecRef | int] = {}
        self.cons: list[z3.BoolRef] = []
        for t in self.tasks:
            act = t.activation
            if act.strict_period is not None:
                period = self.units(act.strict_period)
                if act.fixed_phase is None:
                    v = z3.BitVec(f"phi_{t.id}", width)
                    self.cons += [z3.ULT(v, period)]
                    self.phi[t.id] = v
                else:
                    self.phi[t.id] = self.units(act.fixed_phase)
        if grid.normalise and grid.timers:
            self.cons.append(z3.Or([self.phi[a] == 0 for a in grid.timers]))
        self.c0: dict[str, z3.BitVecRef] = {}
        for tid, k in grid.counters:
            v = z3.BitVec(f"c0_{tid}", width)
            self.cons += [z3.ULT(v, k)]
            self.c0[tid] = v
        self.trigger: dict[str, tuple[str, int, int] | None] = {}  # writer, delay (units), prescaler
        for t in self.tasks:
            act = t.activation
            if act.trigger_port is not None:
                lk = model.link_into(f"{t.instance}.{act.trigger_members[0]}")
                self.trigger[t.id] = None if lk is None else (lk.writer, self.units(lk.delay_max), act.release_every)
        self.q: dict[str, list[z3.BitVecRef]] = {i: [] for i in self.ids}
        self.rem: dict[str, list[z3.BitVecRef]] = {i: [] for i in self.ids}
        self.rel: dict[str, list[z3.BoolRef]] = {i: [] for i in self.ids}
        self.comp: dict[str, list[z3.BoolRef]] = {i: [] for i in self.ids}
        self.run: dict[str, list[z3.BoolRef]] = {i: [] for i in self.ids}
        self.cnt: dict[str, list[z3.BitVecRef]] = {i: [] for i in self.trigger}
        self.rc: dict[str, list[z3.BitVecRef]] = {i: [] for i in self.ids}
        self.fc: dict[str, list[z3.BitVecRef]] = {i: [] for i in self.ids}
        self.chains: dict[str, _ChainVars] = {
            name: _ChainVars(self, next(c for c in model.chains if c.name == name)) for name in chains}
        self.W = -1

    def extend(self, W: int) -> None:
        for t in range(self.W + 1, W + 1):
            self._instant(t)
            for cv in self.chains.values():
                cv.instant(t)
        self.W = max(self.W, W)

    def _instant(self, t: int) -> None:
        B = z3.BoolVal
        for i in self.ids:  # completions first: they depend on the previous instant only
            if t == 0:
                self.comp[i].append(B(False))
            else:
                c = z3.Bool(f"comp_{i}_{t}")
                self.cons.append(c == z3.And(self.run[i][t - 1], self.rem[i][t - 1] == 1))
                self.comp[i].append(c)
        for tsk in self.tasks:
            i, act = tsk.id, tsk.activation
            if act.strict_period is not None:
                period = self.units(act.strict_period)
                phi = self.phi[i]
                rel = (phi == t % period) if isinstance(phi, z3.BitVecRef) else B(phi == t % period)
            elif i in self.trigger:
                src = self.trigger[i]
                arr = B(False) if src is None or t < src[1] else self.comp[src[0]][t - src[1]]
                k = src[2] if src else 1
                prev = self.cnt[i][t - 1] if t > 0 else self.c0.get(i, self.val(0))
                if k == 1:
                    rel = arr
                    self.cnt[i].append(self.val(0))
                else:
                    nxt = prev + 1
                    r = z3.Bool(f"rel_{i}_{t}")
                    self.cons.append(r == z3.And(arr, nxt == k))
                    cv = self.var(f"cnt_{i}_{t}")
                    self.cons.append(cv == z3.If(arr, z3.If(nxt == k, 0, nxt), prev))
                    self.cnt[i].append(cv)
                    rel = r
            else:
                rel = B(False)
            self.rel[i].append(rel)
            q, rem = self.var(f"q_{i}_{t}"), self.var(f"rem_{i}_{t}")
            one = self.one
            if t == 0:
                self.cons += [q == one(rel), rem == self.C[i]]
                self.rc[i].append(one(rel))
                self.fc[i].append(self.val(0))
            else:
                self.cons += [q == self.q[i][t - 1] - one(self.comp[i][t]) + one(rel),
                              rem == z3.If(self.comp[i][t], self.C[i],
                                           self.rem[i][t - 1] - one(self.run[i][t - 1]))]
                rcv, fcv = self.var(f"rc_{i}_{t}"), self.var(f"fc_{i}_{t}")
                self.cons += [rcv == self.rc[i][t - 1] + one(rel), fcv == self.fc[i][t - 1] + one(self.comp[i][t])]
                self.rc[i].append(rcv)
                self.fc[i].append(fcv)
            self.q[i].append(q)
            self.rem[i].append(rem)
        for i in self.ids:
            r = z3.Bool(f"run_{i}_{t}")
            self.cons.append(r == z3.And(z3.UGT(self.q[i][t], 0), *[self.q[j][t] == 0 for j in self.hp[i]]))
            self.run[i].append(r)

    def var(self, name: str) -> z3.BitVecRef:
        return z3.BitVec(name, self.width)

    def val(self, x: int) -> z3.BitVecRef:
        return z3.BitVecVal(x, self.width)

    def one(self, b: z3.BoolRef) -> z3.BitVecRef:
        return z3.If(b, self.val(1), self.val(0))

    def start(self, i: str, t: int) -> z3.BoolRef:
        return z3.And(self.run[i][t], self.rem[i][t] == self.C[i])

    def state(self, t: int) -> list[z3.BitVecRef]:
        """The timing state after instant t (what decides the future, proof spec §4.3)."""
        out = []
        for i in self.ids:
            out += [self.q[i][t], self.rem[i][t]]
        for i, src in self.trigger.items():
            out.append(self.cnt[i][t])
            if src is not None:
                out += [self.one(self.comp[src[0]][t - x]) for x in range(src[1])]
        return out

    def scenario(self, model: z3.ModelRef) -> tuple[dict[str, Fraction], dict[str, int]]:
        phases = {a: model.eval(self.phi[a], model_completion=True).as_long() * self.h for a in self.grid.timers}
        counters = {tid: model.eval(v, model_completion=True).as_long() for tid, v in self.c0.items()}
        return phases, {k: v for k, v in counters.items() if v}


class _ChainVars:
    """Provenance along one chain: per position the stamp (τ₁'s read) and the previous read held by
    the current job, per hop the register, and the stamps held by τₙ's completions."""

    def __init__(self, enc: Encoding, chain: ChainModel):
        self.enc, self.chain = enc, chain
        self.n = len(chain.tasks)
        self.delays = [enc.units(hop.link.delay_max) for hop in chain.hops]
        self.cur: list[list[_Quad]] = [[] for _ in range(self.n)]  # (stamp, previous read, valid, prev. valid)
        self.reg: list[list[_Quad]] = [[] for _ in range(self.n)]
        self.last: list[tuple[z3.BitVecRef, z3.BoolRef]] = []  # τ₁'s latest read so far: (time, valid)
        self.first: list[tuple[z3.BitVecRef, z3.BoolRef]] = []  # τ₁'s first read: (time, valid)
        self.held: list[tuple[z3.BitVecRef, z3.BoolRef]] = []  # latest stamp held by a completion of τₙ

    def instant(self, t: int) -> None:
        enc, tasks = self.enc, self.chain.tasks
        name = self.chain.name
        F = z3.BoolVal(False)
        zero = enc.val(0)
        prev: Callable[[list[_Quad]], _Quad] = ((lambda seq: seq[t - 1]) if t > 0
                                                else (lambda seq: (zero, zero, F, F)))
        s1 = enc.start(tasks[0], t)
        lt_prev, lv_prev = self.last[t - 1] if t > 0 else (zero, F)
        cs, cp, cv, cpv = [enc.var(f"st_{name}_0_{t}"), enc.var(f"pr_{name}_0_{t}"), z3.Bool(f"sv_{name}_0_{t}"),
                           z3.Bool(f"pv_{name}_0_{t}")]
        ps, pp, pv, ppv = prev(self.cur[0])
        enc.cons += [cs == z3.If(s1, enc.val(t), ps), cp == z3.If(s1, lt_prev, pp), cv == z3.Or(s1, pv),
                     cpv == z3.If(s1, lv_prev, ppv)]
        self.cur[0].append((cs, cp, cv, cpv))
        lt, lv = enc.var(f"lt_{name}_{t}"), z3.Bool(f"lv_{name}_{t}")
        enc.cons += [lt == z3.If(s1, enc.val(t), lt_prev), lv == z3.Or(s1, lv_prev)]
        self.last.append((lt, lv))
        ft_prev, fv_prev = self.first[t - 1] if t > 0 else (zero, F)
        ft, fv = enc.var(f"ft_{name}_{t}"), z3.Bool(f"fv_{name}_{t}")
        enc.cons += [ft == z3.If(fv_prev, ft_prev, z3.If(s1, enc.val(t), zero)), fv == z3.Or(fv_prev, s1)]
        self.first.append((ft, fv))
        for pos in range(1, self.n):
            d = self.delays[pos - 1]
            writer = tasks[pos - 1]
            rs, rp, rv, rpv = [enc.var(f"rs_{name}_{pos}_{t}"), enc.var(f"rp_{name}_{pos}_{t}"),
                               z3.Bool(f"rv_{name}_{pos}_{t}"), z3.Bool(f"rpv_{name}_{pos}_{t}")]
            qs, qp, qv, qpv = prev(self.reg[pos])
            if t - d >= 1:
                arr = enc.comp[writer][t - d]
                ws, wp, wv, wpv = self.cur[pos - 1][t - d - 1]
                enc.cons += [rs == z3.If(arr, ws, qs), rp == z3.If(arr, wp, qp), rv == z3.If(arr, wv, qv),
                             rpv == z3.If(arr, wpv, qpv)]
            else:
                enc.cons += [rs == qs, rp == qp, rv == qv, rpv == qpv]
            self.reg[pos].append((rs, rp, rv, rpv))
            st = enc.start(tasks[pos], t)
            cs, cp, cv, cpv = [enc.var(f"st_{name}_{pos}_{t}"), enc.var(f"pr_{name}_{pos}_{t}"),
                               z3.Bool(f"sv_{name}_{pos}_{t}"), z3.Bool(f"pv_{name}_{pos}_{t}")]
            ps, pp, pv, ppv = prev(self.cur[pos])
            enc.cons += [cs == z3.If(st, rs, ps), cp == z3.If(st, rp, pp), cv == z3.If(st, rv, pv),
                         cpv == z3.If(st, rpv, ppv)]
            self.cur[pos].append((cs, cp, cv, cpv))
        hs_prev, hv_prev = self.held[t - 1] if t > 0 else (zero, F)
        hs, hv = enc.var(f"hs_{name}_{t}"), z3.Bool(f"hv_{name}_{t}")
        if t >= 1:
            done = z3.And(enc.comp[tasks[-1]][t], self.cur[-1][t - 1][2])
            enc.cons += [hs == z3.If(done, self.cur[-1][t - 1][0], hs_prev), hv == z3.Or(done, hv_prev)]
        else:
            enc.cons += [hs == hs_prev, hv == hv_prev]
        self.held.append((hs, hv))

    def samples(self, kind: str, t: int) -> tuple[z3.BoolRef, z3.BitVecRef]:
        """(exists, value) of the sample ``kind`` ending with a completion of τₙ at instant t ≥ 1."""
        enc = self.enc
        comp = enc.comp[self.chain.tasks[-1]][t]
        s, p, v, pv = self.cur[-1][t - 1]
        now = enc.val(t)
        if kind == "data_age":
            return z3.And(comp, v), now - s
        if kind == "data_age_nonreduced":
            return z3.And(comp, v, pv), now - p
        hs, hv = self.held[t - 1]
        ft, _fv = self.first[t - 1]
        base = z3.If(hv, hs, ft)
        return z3.And(comp, v, z3.UGT(s, base)), now - base


def _sample_terms(enc: Encoding, target: Target, W: int) -> list[tuple[z3.BoolRef, z3.BitVecRef]]:
    if target.kind == "response":
        raise ValueError("response targets use counts")
    cv = enc.chains[target.name]
    return [cv.samples(target.kind, t) for t in range(1, W + 1)]


def _exceeds(enc: Encoding, target: Target, W: int, threshold_units: Fraction, side: str) -> z3.BoolRef:
    """A formula: some sample of ``target`` within [0, W] is above (below) ``threshold_units``."""
    if target.kind == "response":
        i = target.name
        D = int(threshold_units // 1)  # response (integer units) > threshold ⟺ ≥ D + 1
        return z3.Or([z3.And(enc.rel[i][r], z3.ULT(enc.fc[i][r + D], enc.rc[i][r])) for r in range(0, W - D + 1)]
                     or [z3.BoolVal(False)])
    terms = _sample_terms(enc, target, W)
    bound = enc.val(int(threshold_units))  # sample values are whole units
    if side == "worst":
        return z3.Or([z3.And(e, z3.UGT(val, bound)) for e, val in terms])
    return z3.Or([z3.And(e, z3.ULT(val, bound)) for e, val in terms])


def _solver(enc: Encoding) -> z3.Solver:
    s = z3.SolverFor("QF_BV")
    s.add(enc.cons)
    return s


class _Spend:
    """One resource limit for every query of a search (Z3 ``rlimit`` units, deterministic), and the
    caller's deadline (``--timeout``): a query gets what is left, and none is asked once it is spent
    or the deadline has passed (``unknown``)."""

    def __init__(self, total: int, budget: Budget | None):
        self.left, self.budget = total, budget

    def check(self, solver: z3.Solver) -> z3.CheckSatResult:
        if self.left <= 0 or (self.budget is not None and self.budget.expired()):
            return z3.unknown
        solver.set("rlimit", self.left)
        before = _rlimit_count(solver)
        result = solver.check()
        self.left -= max(0, _rlimit_count(solver) - before)
        return result


def _rlimit_count(solver: z3.Solver) -> int:
    """Z3's resource counter (one per context, cumulative; absent before the context's first query)."""
    stats = solver.statistics()
    return stats.get_key_value("rlimit count") if "rlimit count" in stats.keys() else 0  # noqa: SIM118 (no dict)


def z3_exact(model: SystemModel, targets: list[Target], want_best: Iterable[Target] = frozenset(), *,
             rlimit: int = 20_000_000,
             budget: Budget | None = None, max_periods: int = MAX_PERIODS) -> ExactResult | None:
    """The exact extremes of ``targets`` by the encoding (None when it does not apply, is too large,
    or its queries together exhaust ``rlimit``, or the budget's deadline passes)."""
    if z3_applicable(model) is not None:
        return None
    grid = grid_of(model)
    H = int(grid.hyper / grid.h)
    chains = sorted({t.name for t in targets if t.kind != "response"})
    width = ((max_periods + 4) * H * 2 + 4).bit_length() + 1
    enc = Encoding(model, grid, chains, width)
    spend = _Spend(rlimit, budget)
    # 1. a t_s from which the timing state repeats in every scenario
    ts = None
    for k in range(1, max_periods + 1):
        enc.extend((k + 1) * H)
        s = _solver(enc)
        s.add(z3.Or([a != b for a, b in zip(enc.state(k * H), enc.state((k + 1) * H))]))
        r = spend.check(s)
        if r == z3.unknown:
            return None
        if r == z3.unsat:
            ts = k * H
            break
    if ts is None:
        return None
    # 2. a window W holding every sample class of every target in every scenario (§5.2): the first
    #    τₙ job holding a stamp ≥ t_s + 2H completes within the analysis' reaction-time bound of the
    #    read before it; every job released before t_s + H completes within its WCRT bound
    from ..timing import analyze

    analysis = analyze(model)
    spans = []
    for t in targets:
        if t.kind == "response":
            r = analysis.task(t.name).wcrt
            if r is None:
                return None
            spans.append(H + _ceil_units(r, grid.h))
        else:
            rb = analysis.chain(t.name).reaction_time.worst
            if rb is None:
                return None
            spans.append(2 * H + _ceil_units(rb, grid.h))
    W = ts + max(spans, default=H) + 1
    if W * len(model.tasks) > MAX_CELLS:
        return None
    enc.extend(W)
    result = ExactResult("exact-z3", grid=grid)
    base = _solver(enc)
    for side, chosen in (("worst", targets), ("best", sorted(want_best))):
        for t in chosen:
            ext = _optimise(model, enc, base, grid, t, W, side, budget, result, spend)
            if ext is None:
                return None
            getattr(result, side)[t] = ext
    return result


def _optimise(model: SystemModel, enc: Encoding, solver: z3.Solver, grid: Grid, target: Target, W: int, side: str,
              budget: Budget | None, result: ExactResult, spend: _Spend) -> Extreme | None:
    measured = measure_periodic(model, scenario_of({a: Fraction(0) for a in grid.timers}, {}), [target],
                                grid.hyper)
    result.explored += 1
    best: Measured | None = measured if getattr(measured.values[target], side) is not None else None
    while True:
        solver.push()
        if best is None:
            solver.add(_exists(enc, target, W))
        else:
            value = getattr(best.values[target], side).value
            solver.add(_exceeds(enc, target, W, value / grid.h, side))
        r = spend.check(solver)
        if r == z3.unknown:
            solver.pop()
            return None
        if r == z3.unsat:
            solver.pop()
            break
        phases, counters = enc.scenario(solver.model())
        solver.pop()
        if budget is not None and not budget.take():
            return None
        m = measure_periodic(model, scenario_of(phases, counters), [target], grid.hyper)
        result.explored += 1
        s = getattr(m.values[target], side)
        if s is None or not m.complete:
            return None
        if best is not None:
            old = getattr(best.values[target], side).value
            if (s.value <= old) if side == "worst" else (s.value >= old):
                raise EncodingMismatch(f"the Z3 model for {target} does not replay above {old}")
        best = m
    if best is None:
        return Extreme()
    raw = getattr(best.values[target], side).value
    return Extreme(ceil_to(raw, grid.tick) if side == "worst" else floor_to(raw, grid.tick), raw, best)


def _ceil_units(x: Fraction, h: Fraction) -> int:
    return -(-Fraction(x) // h)


def _exists(enc: Encoding, target: Target, W: int) -> z3.BoolRef:
    if target.kind == "response":
        return z3.Or([r for r in enc.rel[target.name][:W + 1]])
    return z3.Or([e for e, _ in _sample_terms(enc, target, W)])
