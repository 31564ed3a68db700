"""``synthesize``: the whole pipeline behind ``synth``, and the brute-force baseline.

    result = synthesize(verify.load("examples/navigation/navigation-holes.vfy"))
    result.status            # "sat" | "unsat" | "undecided"
    result.choices           # task id -> Candidate, for every hole
    result.model             # the configured SystemModel; result.analysis its analysis

Pipeline (specs/synthesis.md): build the problem and prune it; answer from the cheap necessary checks
if they already decide; otherwise solve with lazy refinement and the objective; only when that is
unsatisfiable, rebuild with tracked statements and explain (unsat core and repair hints).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import cast

import z3

from ..api import LoadResult
from ..core.diagnostics import Diagnostic, DiagnosticSink, Label
from ..model.arrivals import with_arrivals
from ..model.system import SystemModel
from ..frontend.resolve import SystemScope
from ..core.source import Span
from ..timing import AnalysisResult
from ..model.units import fmt_time
from .candidates import Candidate
from .core import Explanation, explain_unsat, unsat_diagnostic
from .encode import Encoding
from .exhaust import EXHAUSTIVE_LIMIT, Enumerated, Key, enumerate_best, space
from .problem import Config, Evaluation, Problem, build_problem
from .solve import Budget, Engine, Objective, Outcome, lex_better, quick_answer
from .statements import Statement
from ..core.budgets import SYNTH_RLIMIT

DEFAULT_RLIMIT = SYNTH_RLIMIT  # Z3 resource units for one run (deterministic); --rlimit changes it
OBJECTIVES = ("utilisation", "slack", "latency:CHAIN", "age:CHAIN", "none")


class ObjectiveError(ValueError):
    """An ``--objective`` that names no known objective or chain."""


@dataclass(frozen=True)
class Goal:
    """One objective as the user asked for it: ``kind`` utilisation | slack | latency | age."""

    kind: str
    chain: str | None = None

    @property
    def name(self) -> str:
        return self.kind if self.chain is None else f"{self.kind}:{self.chain}"

    @property
    def sense(self) -> str:
        return "max" if self.kind == "slack" else "min"


def parse_objective(text: str | None, model: SystemModel) -> list[Goal]:
    """``utilisation`` (default), ``slack``, ``latency:CHAIN``, ``age:CHAIN``, comma-separated for a
    lexicographic combination; ``none`` for any feasible configuration."""
    from ..core.diagnostics import suggest

    goals: list[Goal] = []
    chains = [c.name for c in model.chains]
    for part in (text or "utilisation").split(","):
        part = part.strip()
        kind, _, chain = part.partition(":")
        if part == "none":
            continue
        if kind in ("utilisation", "utilization", "slack") and not chain:
            goals.append(Goal("utilisation" if kind.startswith("utili") else "slack"))
        elif kind in ("latency", "age") and chain:
            if chain not in chains:
                hint = suggest(chain, chains)
                raise ObjectiveError(f"no chain `{chain}` in system `{model.name}`"
                                     + (f"; did you mean `{hint}`?" if hint
                                        else f" (chains: {', '.join(chains) or 'none'})"))
            goals.append(Goal(kind, chain))
        else:
            raise ObjectiveError(f"unknown objective `{part}`; use one of {', '.join(OBJECTIVES)}, "
                                 "comma-separated for a lexicographic combination")
    specs = any(c.reaction_time or c.data_age or c.jitter for c in model.chains)
    if any(g.kind == "slack" for g in goals) and not specs:
        raise ObjectiveError("objective `slack` needs at least one spec")
    return goals


def objectives_for(goals: list[Goal], enc: Encoding) -> list[Objective]:
    out = []
    for g in goals:
        if g.kind == "utilisation":
            out.append(Objective(g.name, "min", enc.utilisation,
                                 lambda c, ev: int(_utilisation(ev.result) * enc.M), enc.utilisation_floor()))
        elif g.kind == "slack":
            slack = z3.Int("objective|slack", enc.ctx)
            for _, term, bound in enc.specs:
                enc.add(slack <= bound - enc.t.lift(term))
            # (the configurations measured are accepted ones: every spec holds, so no margin is None)
            out.append(Objective(g.name, "max", slack,
                                 lambda c, ev: enc.ticks(cast(Fraction, min_margin(ev.result)))))
        else:
            kind = "reaction_time" if g.kind == "latency" else "data_age"
            chain = cast(str, g.chain)  # (a latency or age goal names its chain)

            def latency(c: Config, ev: Evaluation, ch: str = chain, k: str = kind) -> int:
                value = _latency(ev.result, ch, k)
                assert value is not None  # (an accepted configuration's latency is bounded)
                return enc.ticks(value)
            out.append(Objective(g.name, "min", enc.latency[(chain, kind)], latency))
    return out


def _utilisation(result: AnalysisResult) -> Fraction:
    # (of a configuration the analysis accepts: no core has an unbounded utilisation)
    return sum((cast(Fraction, c.utilisation) for c in result.cores), Fraction(0))


def min_margin(result: AnalysisResult) -> Fraction | None:
    margins = [s.margin for c in result.chains for s in c.specs]
    return min(cast("list[Fraction]", margins)) if margins and None not in margins else None


def _latency(result: AnalysisResult, chain: str, kind: str) -> Fraction | None:
    bounds = result.chain(chain)
    return bounds.reaction_time.worst if kind == "reaction_time" else bounds.data_age_reduced.worst


def goal_value(goal: Goal, result: AnalysisResult) -> Fraction | None:
    """The natural value of an objective for an analysed configuration (a fraction, or seconds)."""
    if goal.kind == "utilisation":
        return _utilisation(result)
    if goal.kind == "slack":
        return min_margin(result)
    return _latency(result, cast(str, goal.chain), "reaction_time" if goal.kind == "latency" else "data_age")


# ================================================================== result


@dataclass
class SynthResult:
    status: str  # "sat" | "unsat" | "undecided"
    system: str
    goals: tuple[Goal, ...] = ()
    values: tuple[Fraction | None, ...] = ()
    optimal: bool = False
    choices: dict[str, Candidate] = field(default_factory=dict)
    model: SystemModel | None = None
    analysis: AnalysisResult | None = None
    explanation: Explanation | None = None
    reason: str | None = None
    established: tuple[str, ...] = ()
    diagnostics: tuple[Diagnostic, ...] = ()
    stats: dict[str, int] = field(default_factory=dict)
    problem: Problem | None = None

    @property
    def core(self) -> tuple[Statement, ...]:
        return self.explanation.core if self.explanation is not None else ()

    @property
    def ok(self) -> bool:
        return self.status == "sat"


def _inputs(source: LoadResult | SystemModel, system: str | None, scope: SystemScope | None
            ) -> tuple[SystemModel, SystemScope | None]:
    if isinstance(source, LoadResult):
        model = source.system(system)
        resolution = source.resolution
        return model, resolution.systems.get(model.name) if resolution is not None else None
    return source, scope


def synthesize(source: LoadResult | SystemModel, system: str | None = None, *,
               objective: str | list[Goal] | None = "utilisation",
               rlimit: int | None = DEFAULT_RLIMIT, timeout: float | None = None, explain: bool = True,
               scope: SystemScope | None = None) -> SynthResult:
    """Fill the holes of a system: a ``LoadResult`` (with ``system`` naming one of its systems) or a
    ``SystemModel`` (with an optional ``scope`` for source spans). Raises ``ObjectiveError`` for an
    unknown objective and ``candidates.TooManyCandidates`` for a hole with too fine a grid."""
    model, scope = _inputs(source, system, scope)
    model = with_arrivals(model)  # (the work of taking arrivals, as tasks: specs/timing.md §6.6)
    goals = objective if isinstance(objective, list) else parse_objective(objective, model)
    budget = Budget(rlimit, timeout)
    problem = build_problem(model, scope)
    stats = {"candidates": sum(len(c.candidates) for c in problem.choices.values()), "pruned": problem.pruned}
    reason = problem.infeasible
    quick = quick_answer(problem) if reason is None and not goals else None
    if quick is not None:  # any accepted configuration will do: found without the solver
        stats.update(solver_calls=0, analyses=problem.analyses, lemmas=0, rejected=0, rlimit_used=0)
        return _answer(model, problem, goals, *quick, True, stats)
    if reason is None:
        enc = problem.encoding(z3.Context())
        engine = Engine(problem, enc, budget)
        out = engine.run(objectives_for(goals, enc))
        stats.update(_engine_stats(engine, problem, budget))
        if out.status in ("sat", "optimal"):
            assert out.config is not None and out.evaluation is not None  # (a found configuration)
            return _answer(model, problem, goals, out.config, out.evaluation, not goals or out.status == "optimal",
                           stats)
        size = space(problem)
        found = _exhaust(problem, goals, budget) if size <= EXHAUSTIVE_LIMIT else None
        if found is not None:  # small: the analysis of every configuration decides it (specs/synthesis.md §7)
            stats["enumerated"] = found.evaluated
            stats["analyses"] = problem.analyses
            if found.config is not None:
                assert found.evaluation is not None  # (set with the configuration)
                return _answer(model, problem, goals, found.config, found.evaluation, True, stats)
            reason = f"the analysis rejects every one of the {size} candidate configurations"
        elif out.status == "unknown":
            where = scope.system.name.span if scope is not None else model.span
            return _undecided(model, problem, goals, out, budget, stats, where)
        else:
            reason = "no configuration meets every constraint"
    return _unsat(model, scope, problem, goals, reason, budget, stats, explain)


def goal_key(goals: Sequence[Goal]) -> Key:
    """A configuration's objective values as a key, smaller is better (a "max" goal negated); None when
    one is unbounded (no answer, as in ``Engine.run``)."""
    def key(ev: Evaluation) -> tuple[Fraction, ...] | None:
        values = [goal_value(g, ev.result) for g in goals]
        if any(v is None for v in values):
            return None
        return tuple(cast(Fraction, v) if g.sense == "min" else -cast(Fraction, v) for g, v in zip(goals, values))
    return key


def _exhaust(problem: Problem, goals: Sequence[Goal], budget: Budget) -> Enumerated | None:
    """Every configuration of the pruned ``problem`` analysed: the best accepted one by the objectives
    (its ``config`` None when there is none); None when the wall-clock limit stopped it first."""
    found = enumerate_best(problem, goal_key(goals), first=not goals, deadline=budget.deadline)
    return found if found.complete else None


def _engine_stats(engine: Engine, problem: Problem, budget: Budget) -> dict[str, int]:
    return {"solver_calls": engine.stats.checks, "analyses": problem.analyses, "lemmas": engine.stats.lemmas,
            "rejected": engine.stats.rejected, "rlimit_used": budget.used}


def _answer(model: SystemModel, problem: Problem, goals: Sequence[Goal], config: Config, ev: Evaluation,
            optimal: bool, stats: dict[str, int]) -> SynthResult:
    values = tuple(goal_value(g, ev.result) for g in goals)
    return SynthResult("sat", model.name, tuple(goals), values, optimal, problem.candidates(config), ev.model,
                       ev.result, stats=stats, problem=problem)


def _undecided(model: SystemModel, problem: Problem, goals: Sequence[Goal], out: Outcome, budget: Budget,
               stats: dict[str, int], where: Span) -> SynthResult:
    kept = sum(len(c.candidates) for c in problem.choices.values())
    established = [f"pruning kept {kept} of {kept + problem.pruned} candidate values "
                   f"({len(problem.choices)} hole{'s' * (len(problem.choices) != 1)})"]
    if out.config is not None:
        assert out.evaluation is not None  # (set with the configuration)
        values = tuple(goal_value(g, out.evaluation.result) for g in goals)
        shown = ", ".join(f"{g.name} {_show(g, v)}" for g, v in zip(goals, values))
        established.append(f"a configuration meeting every spec was found ({shown}); it is printed, but no "
                           "better one has been ruled out")
    else:
        established.append("no configuration meeting every spec has been found yet, and none has been ruled out")
    rejected = stats.get("rejected", 0)
    established.append("no configuration was rejected by the analysis" if not rejected else
                       f"{rejected} configuration{'s' * (rejected != 1)} that the solver proposed "
                       f"{'were' if rejected != 1 else 'was'} rejected by the analysis and excluded")
    sink = DiagnosticSink()
    sink.emit("E402", f"synthesis of `{model.name}` is undecided: {out.reason or budget.reason}", where,
              "undecided", notes=tuple(f"established: {e}" for e in established),
              help="raise the budget with `--rlimit N` (deterministic) or allow more time with `--timeout S`")
    result = SynthResult("undecided", model.name, tuple(goals), reason=out.reason or budget.reason,
                         established=tuple(established), diagnostics=tuple(sink.items), stats=stats, problem=problem)
    if out.config is not None:
        assert out.evaluation is not None
        result.values = tuple(goal_value(g, out.evaluation.result) for g in goals)
        result.choices, result.model, result.analysis = problem.candidates(out.config), out.evaluation.model, \
            out.evaluation.result
    return result


def _show(goal: Goal, value: Fraction | None) -> str:
    if value is None:
        return "unbounded"
    return f"{float(value) * 100:.2f} %" if goal.kind == "utilisation" else fmt_time(value)


def _unsat(model: SystemModel, scope: SystemScope | None, problem: Problem, goals: Sequence[Goal], reason: str,
           budget: Budget, stats: dict[str, int], explain: bool) -> SynthResult:
    expl = explain_unsat(model, scope, budget, culprit=problem.culprit) if explain else None
    if expl is not None and expl.status == "sat":  # the tracked search found what the untracked one missed
        assert expl.problem is not None and expl.sat_config is not None  # (a "sat" explanation has both)
        ev = expl.problem.evaluate(expl.sat_config)
        result = SynthResult("sat", model.name, tuple(goals), tuple(goal_value(g, ev.result) for g in goals), False,
                             expl.problem.candidates(expl.sat_config), ev.model, ev.result, stats=stats,
                             problem=problem)
        result.choices = {k: v for k, v in result.choices.items() if k in problem.choices}
        return result
    if expl is not None:
        assert expl.problem is not None  # (every explanation has its problem)
        stats["core_analyses"] = expl.problem.analyses
        stats["rlimit_used"] = budget.used
    found = expl if expl is not None and expl.status == "unsat" else None
    diag = unsat_diagnostic(model, found, reason, *(_holes(model, problem) if found is None or not found.core
                                                    else ((), ())))
    return SynthResult("unsat", model.name, tuple(goals), explanation=expl, reason=reason, diagnostics=(diag,),
                       stats=stats, problem=problem)


def _holes(model: SystemModel, problem: Problem) -> tuple[tuple[Label, ...], tuple[str, ...]]:
    """Labels on the holes (source order) and why the analysis rejects them all at their slowest, for an
    E401 that no statement is blamed for (``core.unsat_diagnostic``)."""
    holes = sorted(((ch.hole.span.file, ch.hole.span.line, ch.hole.span.column), tid, ch.hole.span)
                   for tid, ch in problem.choices.items() if ch.hole is not None)
    labels = tuple(Label(span, f"no value accepted (`{tid}`)") for _, tid, span in holes)
    if not labels or any(not ch.candidates for ch in problem.choices.values()):
        return labels, ()
    return labels, problem.seed()[1].reasons


# ================================================================== baseline


@dataclass
class BruteResult:
    status: str  # "sat" | "unsat" (every combination rejected) | "limit" (stopped at the limit, none accepted)
    choices: dict[str, Candidate] | None
    values: tuple[Fraction | None, ...]
    evaluated: int
    complete: bool = True  # every combination was evaluated (else the best is only the best seen)


def brute_force(source: LoadResult | SystemModel, system: str | None = None, *,
                objective: str | list[Goal] | None = "utilisation", scope: SystemScope | None = None,
                prune: bool = False, limit: int | None = None) -> BruteResult:
    """Enumerate every combination of candidates (unpruned by default), analyse each, keep the best
    accepted one by the objective (the first in enumeration order among equals). The naive baseline.
    With ``limit``, at most that many combinations are evaluated: stopping there with none accepted
    is status "limit", not "unsat", and a best found is marked ``complete=False``."""
    model, scope = _inputs(source, system, scope)
    model = with_arrivals(model)  # (the work of taking arrivals, as tasks: specs/timing.md §6.6)
    goals = objective if isinstance(objective, list) else parse_objective(objective, model)
    problem = build_problem(model, scope, prune=prune)
    found = enumerate_best(problem, goal_key(goals), first=not goals, limit=limit)
    if found.config is None:
        return BruteResult("unsat" if found.complete else "limit", None, (), found.evaluated, found.complete)
    assert found.evaluation is not None  # (set with the configuration)
    values = tuple(goal_value(g, found.evaluation.result) for g in goals)
    return BruteResult("sat", problem.candidates(found.config), values, found.evaluated, found.complete)


__all__ = ["BruteResult", "DEFAULT_RLIMIT", "Goal", "ObjectiveError", "SynthResult", "brute_force",
           "lex_better", "parse_objective", "synthesize"]
