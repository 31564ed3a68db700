"""The lazy refinement loop: solve, analyse the answer, learn, repeat (specs/synthesis.md §4).

Response times are not encoded exactly: each task's ``R`` is an integer bounded below by lemmas.
After every answer of the solver the configuration is analysed by ``verify.timing.analyze`` (the
independent analysis, specs/timing.md §5–§7). For every task whose analysed WCRT exceeds the value
the solver assumed, a lemma ``(every decision in its cone at least as fast as now) → R ≥ r`` is
added: the response-time analysis is monotone (a shorter period or prescaler of an interferer, or of
a source of jitter, never shortens a response time), so the lemma holds for every such configuration.
A configuration the analysis rejects is also blocked exactly. Only configurations the analysis
accepts are ever returned. The space is finite and every round cuts the current answer off, so the
loop ends; the solver budget (Z3 ``rlimit``) and an optional wall clock bound it.

Objectives are optimised lexicographically by strengthening with the same incremental solver (``_best``). An
accepted configuration becomes the incumbent, and the next question is "is there one strictly better than
it?"; the optimum is proven when that is unsatisfiable. Encoded objective values are optimistic (response
times are lower bounds), so a proven optimum of the encoding that the analysis confirms is the true optimum.
Period optimization in this style follows Davare et al., DAC 2007.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, cast
from collections.abc import Callable, Sequence

import z3

from ..timing import TaskResponse, timing_of
from ..timing.chains import pair_fixed_point, pair_qualifies
from .encode import Encoding
from .problem import Config, Evaluation, Problem
from .repair import repair
from .statements import statement_index

RANDOM_SEED = 0
ARITH_SOLVER = 2


# ================================================================== budget


class Budget:
    """A deterministic solver budget (Z3 resource units, shared by every check of one run) and an
    optional wall-clock limit in seconds."""

    def __init__(self, rlimit: int | None, timeout: float | None = None):
        self.rlimit, self.timeout = rlimit, timeout
        self.used = 0
        self.deadline = None if timeout is None else time.monotonic() + timeout
        self.reason: str | None = None

    @property
    def remaining(self) -> int | None:
        return None if not self.rlimit else self.rlimit - self.used

    def exhausted(self) -> bool:
        if self.remaining is not None and self.remaining <= 0:
            self.reason = self.reason or f"the solver budget (rlimit {self.rlimit}) ran out"
        elif self.deadline is not None and time.monotonic() >= self.deadline:
            self.reason = self.reason or f"the time limit of {self.timeout:g} s ran out"
        return self.reason is not None

    def arm(self, obj: z3.Solver) -> None:
        if self.remaining is not None:
            obj.set("rlimit", max(1, self.remaining))
        if self.deadline is not None:
            obj.set("timeout", max(1, int((self.deadline - time.monotonic()) * 1000)))

    def charge(self, spent: int) -> None:
        self.used += spent


def implies(parts: list[z3.BoolRef], fact: z3.BoolRef) -> z3.BoolRef:
    """``(∧ parts) → fact`` built directly (z3py's ``And`` coerces every argument, which is slow for
    the long antecedents of lemmas)."""
    if not parts:
        return fact
    ctx = fact.ctx
    ref = ctx.ref()
    # the negations through the C API (z3py's ``Not`` coerces each argument); each is referenced by a
    # BoolRef until Z3 has built the disjunction
    terms = [z3.BoolRef(z3.Z3_mk_not(ref, p.as_ast()), ctx) for p in parts] + [fact]
    args = (z3.Ast * len(terms))()
    for n, term in enumerate(terms):
        args[n] = term.as_ast()
    return z3.BoolRef(z3.Z3_mk_or(ref, len(terms), args), ctx)


def _rlimit_count(obj: z3.Solver) -> int:
    stats = obj.statistics()
    for key in stats.keys():  # noqa: SIM118 (z3's Statistics is no dict: iterating it gives (key, value) pairs)
        if key == "rlimit count":
            return int(stats.get_key_value(key))
    return 0


# ================================================================== objectives


@dataclass(frozen=True)
class Objective:
    """``term`` in encoding units; ``real`` gives the same quantity from an analysed configuration."""

    name: str
    sense: str  # "min" | "max"
    term: object  # an int or a z3 term
    real: Callable[[Config, Evaluation], int | None]
    floor: int | None = None  # for "min": a value no configuration's ``term`` lies below (None: unknown)

    def better(self, a: int, b: int) -> bool:
        return a < b if self.sense == "min" else a > b


def lex_better(objectives: Sequence[Objective], a: Sequence[int | None], b: Sequence[int | None]) -> bool:
    for obj, x, y in zip(objectives, a, b):
        # ``Objective.real`` says None for unbounded; the configurations compared here are accepted ones,
        # whose objective values are bounded (``better`` compares ints)
        assert x is not None and y is not None
        if obj.better(x, y):
            return True
        if x != y:
            return False
    return False


def strictly_better(enc: Encoding, objectives: Sequence[Objective], values: Sequence[int | None]) -> z3.BoolRef:
    """The encoded objectives lexicographically better than ``values``."""
    t = enc.t
    cases = []
    for n, obj in enumerate(objectives):
        term = t.lift(obj.term)
        strict = term < values[n] if obj.sense == "min" else term > values[n]
        cases.append(z3.And(*[t.lift(o.term) == values[m] for m, o in enumerate(objectives[:n])], strict))
    return z3.Or(*cases)


def failing_checks(problem: Problem, ev: Evaluation) -> set[str] | None:
    """The statements whose checks reject ``ev`` (spec bounds, activation-constraint ends, sampling
    tolerances); an empty set when some failure needs no statement (E311, E312, E316); None when a failure
    cannot be attributed (then the whole configuration is blocked)."""
    from ..timing.rates import tolerance_violation

    slots = statement_index(problem.statements)
    checks: set[str | None]  # (None: a failure no statement asks for)
    result, checks = ev.result, set()
    for d in result.diagnostics:
        if d.code in ("E311", "E312", "E316"):
            return set()
    for chain in result.chains:
        checks |= {f"spec:{chain.name}:{s.kind}" for s in chain.specs if not s.ok}
    for info in result.tasks:
        task, rate = problem.model.task(info.id), info.rate
        if info.activation.trigger_port is None or rate is None:
            continue
        mine = slots.get(info.id, {})
        if task.min_rate is not None and rate.low < task.min_rate:
            checks.add(mine.get("min_rate") or mine.get("rate"))
        if task.max_rate is not None and rate.high > task.max_rate:
            checks.add(mine.get("max_rate") or mine.get("rate"))
    for s in result.links:
        read = next((r for r in problem.model.task(s.reader).reads if r.port == s.target.split(".", 1)[1]), None)
        if read is None:
            continue
        for direction, tol, flagged, factor in (("over", read.oversampling, s.oversampled, s.oversampling),
                                                ("under", read.undersampling, s.undersampled, s.undersampling)):
            if tolerance_violation(tol, flagged, factor) is not None:
                checks.add(slots.get(s.reader, {}).get(f"tolerance:{read.port}:{direction}"))
    if None in checks or not checks:
        return None
    return cast("set[str]", checks)  # (None is not in it: checked above)


# ================================================================== the loop


def quick_answer(problem: Problem) -> tuple[Config, Evaluation] | None:
    """An accepted configuration found without the solver, if a cheap one exists: the seed (every
    choice at its slowest, often good enough), else the seed with its failing chains sped up."""
    config, ev = problem.seed()
    if ev.accepted:
        return config, ev
    return repair(problem, config, ev)


@dataclass
class Outcome:
    status: str  # "sat" | "optimal" | "unsat" | "unknown"
    config: Config | None = None
    evaluation: Evaluation | None = None
    values: tuple[int | None, ...] | None = None
    core: tuple[str, ...] = ()  # statement keys (tracked, unsat)
    reason: str | None = None


@dataclass
class Stats:
    checks: int = 0
    lemmas: int = 0
    blocked: int = 0
    rejected: int = 0


class Engine:
    def __init__(self, problem: Problem, enc: Encoding, budget: Budget):
        self.problem, self.enc, self.budget = problem, enc, budget
        self.stats = Stats()
        self.solver = z3.Solver(ctx=enc.ctx)
        self.solver.set("random_seed", RANDOM_SEED)
        # the legacy simplex: on generated 500-task problems it proved optima the default arithmetic
        # solver ran out of budget on (specs/synthesis.md §7)
        self.solver.set("smt.arith.solver", ARITH_SOLVER)
        self._assert(enc.take_new())
        self._bounds = 0
        if problem.choices or problem.tracked:
            self.learn(*problem.seed(), None)

    # -------------------------------------------------------------- z3 plumbing

    def _assert(self, terms: list[z3.BoolRef]) -> None:
        """``Solver.add`` through the C API: the same assertions in the same order, without z3py's
        per-term sort check (a tenth of the time of a 500-task run)."""
        ref, solver = self.enc.ctx.ref(), self.solver.solver
        for term in terms:
            z3.Z3_solver_assert(ref, solver, term.as_ast())

    def _sync(self) -> None:
        self._assert(self.enc.take_new())

    def _check(self, assumptions: Sequence[z3.BoolRef]) -> tuple[str, Any]:
        """(status, the model when "sat", the unsat core when "unsat", else None)"""
        self._sync()
        if self.budget.exhausted():
            return "unknown", None
        self.budget.arm(self.solver)
        before = _rlimit_count(self.solver)
        result = self.solver.check(*assumptions)
        self.budget.charge(_rlimit_count(self.solver) - before)
        self.stats.checks += 1
        if result == z3.sat:
            return "sat", self.solver.model()
        if result == z3.unsat:
            return "unsat", self.solver.unsat_core()
        self.budget.exhausted()
        self.budget.reason = self.budget.reason or f"the solver gave up ({self.solver.reason_unknown()})"
        return "unknown", None

    def _fresh(self, prefix: str) -> z3.BoolRef:
        self._bounds += 1
        return z3.Bool(f"{prefix}|{self._bounds}", self.enc.ctx)

    def _value(self, model: z3.ModelRef, term: object) -> int:
        return term if isinstance(term, int) else model.eval(term, model_completion=True).as_long()

    def _best(self, objectives: Sequence[Objective], assumptions: list[z3.BoolRef]) -> tuple[str, Any, bool]:
        """The encoded lexicographic optimum under ``assumptions``, by strengthening, and whether it
        is proven (every objective's last question unsatisfiable, or its answer at its ``floor``).
        First ask for a value better than the last answer by a step (a sixteenth of it at first) that
        doubles while answers come; once a value is known impossible (found so, or below the floor),
        alternately bisect between the best answer and it and ask for anything better than the best
        answer at all (which often ends the search at once)."""
        status, answer = self._check(assumptions)
        if status != "sat" or not objectives:
            return status, answer, status == "sat"
        fixed: list[z3.BoolRef] = []
        for obj in objectives:
            sign = 1 if obj.sense == "min" else -1
            best = self._value(answer, obj.term)
            floor = obj.floor if obj.floor is not None and sign > 0 else None
            bound = floor - 1 if floor is not None and best == floor else None
            step, probe = max(1, abs(best) // 16), False
            while bound is None or abs(best - bound) > 1:
                if bound is None:
                    target = best - sign * step
                    if floor is not None and target < floor:  # known impossible: bisect down to the floor
                        bound = floor - 1
                        continue
                else:  # alternate: bisect the gap; is anything better than the incumbent at all?
                    target = best - sign if probe else (best + bound) // 2
                    probe = not probe
                lit = self._fresh("goal")
                term = self.enc.t.lift(obj.term)
                self.enc.add(z3.Implies(lit, term <= target if sign > 0 else term >= target))
                status, found = self._check(assumptions + fixed + [lit])
                if status == "unknown":
                    return "sat", answer, False  # the best so far; the caller finds the budget exhausted
                if status == "sat":
                    answer, best, step = found, self._value(found, obj.term), step * 2
                else:
                    bound = target
            lit = self._fresh("fix")
            self.enc.add(z3.Implies(lit, self.enc.t.lift(obj.term) == best))
            fixed.append(lit)
        return "sat", answer, True

    # -------------------------------------------------------------- configurations

    def config_of(self, model: z3.ModelRef) -> Config:
        choice = []
        for tid, sels in self.enc.sel.items():
            index = next((i for i, b in enumerate(sels) if z3.is_true(model.eval(b, model_completion=True))), 0)
            choice.append((tid, index))
        off = frozenset(key for key, lit in self.enc.lits.items()
                        if not z3.is_true(model.eval(lit, model_completion=True)))
        return Config(tuple(choice), off)

    def _config_literals(self, config: Config) -> list[z3.BoolRef]:
        lits = [self.enc.sel[tid][i] for tid, i in config.choice]
        for key, lit in sorted(self.enc.lits.items()):
            lits.append(z3.Not(lit) if key in config.off else lit)
        return lits

    def block(self, config: Config, ev: Evaluation | None = None) -> None:
        """Exclude a rejected configuration. With tracked statements only what the verdict depends on
        is named: the choices, the execution times in force (a larger ``C`` only makes the timing
        worse, so one rejected with a ``wcet`` relaxed stays rejected with it in force), the core
        assignments, and — when every failure is a check a statement asks for — that one of those
        statements is in force. Other statements (ranges, fixed rates) do not change the model."""
        lits = [self.enc.sel[tid][i] for tid, i in config.choice]
        checks = None if ev is None else failing_checks(self.problem, ev)
        if not self.problem.tracked or checks is None:
            lits += [z3.Not(lit) if key in config.off else lit for key, lit in sorted(self.enc.lits.items())]
        else:
            for key, lit in sorted(self.enc.lits.items()):
                if key.startswith("wcet:") and key not in config.off:
                    lits.append(lit)
                elif key.startswith("core:"):
                    lits.append(z3.Not(lit) if key in config.off else lit)
            if checks:
                lits.append(z3.Or(*[self.enc.lit(k) for k in sorted(checks)]))
        self.enc.add(z3.Not(z3.And(*lits)) if lits else False)
        self.stats.blocked += 1

    # -------------------------------------------------------------- lemmas

    def ladder(self, tid: str, index: int) -> z3.BoolRef | None:
        """"The choice of ``tid`` is in the group of candidate ``index`` and at least as fast" (the
        candidates of a group are sorted fastest first), or the exact candidate for an AND feeder."""
        sels = self.enc.sel[tid]
        if tid in self.problem.structure.exact_only:
            return sels[index]
        cands = self.problem.choices[tid].candidates
        group = cands[index].group
        start = index
        while start > 0 and cands[start - 1].group == group:
            start -= 1
        if start == 0 and index == len(cands) - 1:
            return None  # every candidate qualifies
        if index == start:
            return sels[index]
        lads = self.enc.ladders.setdefault(tid, [None] * len(cands))
        if lads[index] is None:
            previous = self.ladder(tid, index - 1)
            lads[index] = z3.Bool(f"lad|{tid}|{index}", self.enc.ctx)
            self.enc.add(lads[index] == z3.Or(previous, sels[index]))
        return lads[index]

    def antecedent(self, tid: str, config: Config) -> list[z3.BoolRef]:
        bits = self.problem.structure.cones.get(tid, 0)
        choice = dict(config.choice)
        parts = []
        while bits:
            low = bits & -bits
            kind, key = self.problem.atoms[low.bit_length() - 1]
            bits ^= low
            if kind == "choice":
                lit = self.ladder(key, choice[key])
                if lit is not None:
                    parts.append(lit)
            elif kind == "wcet":
                if key not in config.off:
                    parts.append(self.enc.lit(key))
            else:
                lit = self.enc.lit(key)
                parts.append(z3.Not(lit) if key in config.off else lit)
        return parts

    def learn(self, config: Config, ev: Evaluation, model: z3.ModelRef | None) -> int:
        """Lemmas ``antecedent → R ≥ r`` for every task whose analysed WCRT exceeds the solver's, and
        the same for the start-to-completion times ``E`` and the same-core trigger pairs' ``J`` of
        specs/timing.md §7.7 (fixed points over the same interferers as ``R``, so monotone alike)."""
        facts: list[tuple[list[str], z3.ArithRef, int | None]] = []
        for tid in sorted(self.enc.R):
            var = self.enc.R[tid]
            if not isinstance(var, int):
                facts.append(([tid], var, self._lower_bound(ev.result.task(tid).response)))
        if any(not isinstance(v, int) for v in self.enc.E.values()) or self.enc.J:
            timing = timing_of(ev.result, ev.model)
            for tid in sorted(self.enc.E):
                span = self.enc.E[tid]
                if not isinstance(span, int):
                    e = timing.E(tid)
                    facts.append(([tid], span, None if e is None else self.enc.ticks_above(e)))
            for key in sorted(self.enc.J):
                hop, pair = self.enc.J[key]
                value = pair_fixed_point(timing, hop) if pair_qualifies(timing, hop) else None
                facts.append(([hop.writer, hop.reader], pair,
                              None if value is None else self.enc.ticks_above(value)))
        added = 0
        for tasks, var, bound in facts:
            if bound is None:
                continue
            if model is not None and model.eval(var, model_completion=True).as_long() >= bound:
                continue
            if bound <= self._static_floor(tasks, var):
                continue
            parts = [lit for tid in tasks for lit in self.antecedent(tid, config)]
            self.enc.add(implies(parts, self.enc.t.at_least(var, bound)))
            added += 1
        self.stats.lemmas += added
        return added

    def _static_floor(self, tasks: list[str], var: z3.ArithRef) -> int:
        """What the encoding already asks of ``var`` in every configuration (a lemma at most that adds
        nothing): the first-job bound of an ``R``, ``C⁺`` of an ``E``, ``C⁺ₚ + C⁺ᵢ`` of a ``J``, where
        the execution times are constants (untracked)."""
        if len(tasks) == 1 and var is self.enc.R.get(tasks[0]):
            return self.enc.floor(tasks[0])
        costs = [self.enc.C[tid] for tid in tasks]
        return sum(cast("list[int]", costs)) if all(isinstance(c, int) for c in costs) else -1

    def _lower_bound(self, response: TaskResponse) -> int | None:
        """The analysed WCRT in ticks; for a task without a bound (the load of its level reached 1) the
        least number of ticks above the deadline."""
        if response.wcrt is not None:
            return self.enc.ticks_above(response.wcrt)
        why = response.failure or ""
        if response.deadline is not None and "utilisation" in why:
            return self.enc.ticks_above(response.deadline, strictly=True)
        return None

    # -------------------------------------------------------------- search

    def start(self) -> tuple[Config, Evaluation] | None:
        return quick_answer(self.problem)

    def run(self, objectives: Sequence[Objective] = (), assumptions: Sequence[z3.BoolRef] = ()) -> Outcome:
        """The best accepted configuration under ``assumptions`` (any one without objectives)."""
        objectives = list(objectives)
        best: Outcome | None = None
        guard = None
        start = self.start() if not assumptions and not self.problem.tracked else None
        if start is not None and objectives and any(o.real(*start) is None for o in objectives):
            start = None  # (unbounded where no statement in force asks for a bound: no incumbent, below)
        if start is not None:
            if not objectives:
                return Outcome("sat", *start)
            values = tuple(o.real(*start) for o in objectives)
            if len(objectives) == 1 and values[0] == objectives[0].floor:  # nothing lies below the floor
                return Outcome("optimal", *start, values)
            best = Outcome("sat", *start, values)
            guard = self._fresh("better")
            self.enc.add(z3.Implies(guard, strictly_better(self.enc, objectives, values)))
        scope = self._fresh("run")  # run-local exclusions hang on it
        seen: set[Config] = set()
        while True:
            assume = list(assumptions) + [scope] + ([guard] if guard is not None else [])
            status, answer, proven = self._best(objectives, assume)
            if status == "unknown":
                return Outcome("unknown", *(best.config, best.evaluation, best.values) if best else (None,) * 3,
                               reason=self.budget.reason)
            if status == "unsat":
                if best is not None:
                    return Outcome("optimal", best.config, best.evaluation, best.values)
                core = tuple(sorted(str(x.decl().name())[len("stmt|"):] for x in answer
                                    if str(x.decl().name()).startswith("stmt|")))
                return Outcome("unsat", core=core)
            config = self.config_of(answer)
            ev = self.problem.evaluate(config)
            self.learn(config, ev, answer)
            if not ev.accepted:
                self.stats.rejected += 1
                self.block(config, ev)
                continue
            if not objectives:
                return Outcome("sat", config, ev)
            values = tuple(o.real(config, ev) for o in objectives)
            if any(v is None for v in values):  # (unbounded where no statement in force asks for a bound,
                # e.g. a chain through an overlapping reentrant callback, §9.4: no incumbent)
                self.enc.add(z3.Implies(scope, z3.Not(z3.And(*self._config_literals(config)))))
                continue
            if proven and values == tuple(self._value(answer, o.term) for o in objectives):
                # the encoded optimum, and its true values are the encoded ones: every accepted
                # configuration lies in the encoding with true values no better than its encoded ones
                return Outcome("optimal", config, ev, values)
            # (an incumbent always has its values)
            if best is None or lex_better(objectives, values, cast("tuple[int | None, ...]", best.values)):
                best = Outcome("sat", config, ev, values)
                guard = self._fresh("better")
                self.enc.add(z3.Implies(guard, strictly_better(self.enc, objectives, values)))
            if config in seen:  # the encoding still overrates it: exclude it from this run
                self.enc.add(z3.Implies(scope, z3.Not(z3.And(*self._config_literals(config)))))
            seen.add(config)
