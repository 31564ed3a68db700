"""Explaining an unsatisfiable problem: a minimal unsat core of user statements, and repair hints.

Only when the untracked problem is unsatisfiable is it rebuilt with every user statement behind an
assumption literal (specs/synthesis.md §5). The solver's unsat core (over those literals) is then
minimised by deletion in a fixed order — hole ranges, execution times, core assignments, sampling
tolerances, activation constraints, fixed rates, spec bounds, each by name — so that what
remains is what a user most likely wants to see. A statement stays only if the core without it is
satisfiable; that is shown by a configuration the analysis accepts (the *witness*), so the core is
minimal: removing any one member makes the rest satisfiable.

Repair hints, each with every other statement in force: for a spec bound in the core, the smallest
bound any configuration meets; for a relaxable range in the core (an end of an activation
constraint, a hole's range), the rate or value it would need to admit.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from fractions import Fraction
from typing import cast, overload

import z3

from ..core.diagnostics import Diagnostic, DiagnosticSink, Label
from ..model.system import SystemModel
from ..frontend.resolve import SystemScope
from ..core.source import NO_SPAN, Span
from ..timing import RateInterval
from ..model.units import fmt_rate, fmt_time
from .candidates import Candidate
from .encode import Encoding
from .problem import Config, Evaluation, Problem, build_problem, relaxed_problem
from .prune import ChainLowerBound, Pruner
from .repair import fastest_chain
from .solve import Budget, Engine, Objective, Outcome, quick_answer
from .statements import Statement

# A spec statement (``kind`` "spec") names its chain and its spec kind (``Statement.chain`` and
# ``Statement.spec_kind`` are None only for the other kinds): hence ``cast(str, st.chain)`` below.


@dataclass
class Explanation:
    status: str  # "unsat" | "sat" (the tracked problem found an accepted configuration) | "unknown"
    core: tuple[Statement, ...] = ()
    minimal: bool = False
    witnesses: dict[str, Config] = field(default_factory=dict)  # key -> configuration without it
    hints: tuple[str, ...] = ()
    smallest: dict[str, Fraction] = field(default_factory=dict)  # spec key -> smallest feasible bound
    problem: Problem | None = None
    sat_config: Config | None = None


def explain_unsat(model: SystemModel, scope: SystemScope | None, budget: Budget, *, hints: bool = True,
                  culprit: tuple[tuple[str, ...], tuple[str, ...]] | None = None) -> Explanation:
    """The minimal core and hints of an unsatisfiable problem. ``culprit`` (chains, tasks): what
    pruning blamed; when the statements about those alone cannot hold together, minimisation starts
    from them instead of from the core of a solver run over every statement."""
    problem = build_problem(model, scope, tracked=True)
    by_key = {st.key: st for st in sorted(problem.statements, key=lambda st: st.key)}
    start = seeded_core(problem, culprit, budget) if culprit is not None else None
    if start is None:
        enc = problem.encoding(z3.Context())
        engine = Engine(problem, enc, budget)
        out = engine.run([], [enc.lit(k) for k in by_key])
        if out.status == "sat":
            return Explanation("sat", problem=problem, sat_config=out.config)
        if out.status != "unsat":
            return Explanation("unknown", problem=problem)
        start = set(out.core)
    core, witnesses, minimal = _minimise(problem, by_key, start, budget)
    ordered = tuple(sorted((by_key[k] for k in core), key=Statement.order_key))
    expl = Explanation("unsat", ordered, minimal, witnesses, problem=problem)
    if hints:
        _hints(expl, problem, budget)
    return expl


def seeded_core(problem: Problem, culprit: tuple[tuple[str, ...], tuple[str, ...]], budget: Budget) -> set[str] | None:
    """The statements about the blamed chains and tasks — the chains' specs, and every other
    statement on a task of theirs or on a task that may trigger one — when they alone cannot hold
    together (decided like a deletion trial); None otherwise."""
    chains, tasks = culprit
    involved = set(tasks)
    for chain in problem.model.chains:
        if chain.name in chains:
            involved.update(chain.tasks)
    writers: dict[str, set[str]] = {}
    for writer, reader, _ in problem.structure.trigger_edges:
        writers.setdefault(reader, set()).add(writer)
    stack = list(involved)
    while stack:
        for writer in writers.get(stack.pop(), ()):
            if writer not in involved:
                involved.add(writer)
                stack.append(writer)
    keys = {st.key for st in problem.statements
            if (st.chain in chains if st.kind == "spec" else bool(involved & set(st.tasks)))}
    status, _ = decide_trial(problem, keys, budget)
    return keys if status == "unsat" else None


def deletion_order(statements: Iterable[Statement]) -> list[Statement]:
    """By kind (ranks of ``statements.RANKS``), then by key: names, not positions, so that
    reordering declarations does not change the core."""
    return sorted(statements, key=lambda st: (st.rank, st.key))


def _minimise(problem: Problem, by_key: dict[str, Statement], core: set[str], budget: Budget
              ) -> tuple[set[str], dict[str, Config], bool]:
    """Deletion in ``deletion_order``, in chunks: the next ``size`` statements are dropped together
    when the rest is still unsatisfiable (``size`` doubles after each such drop); when it is not, the
    chunk is halved, and a single statement that cannot go stays, with its witness. Unsatisfiability
    is monotone (more statements in force never make a problem satisfiable), so dropping a chunk
    drops exactly what one-by-one deletion in the same order would — the same core, in fewer trials."""
    witnesses: dict[str, Config] = {}
    minimal = True
    order = [st.key for st in deletion_order(by_key[k] for k in core)]
    pos, size = 0, 1
    while pos < len(order):
        chunk = order[pos:pos + size]
        trial = core - set(chunk)
        status, witness = decide_trial(problem, trial, budget)
        if status == "unsat":
            core, pos, size = set(trial), pos + len(chunk), size * 2
        elif status == "sat" and len(chunk) > 1:
            size = len(chunk) // 2
        elif status == "sat":
            assert witness is not None  # (a satisfiable trial comes with its witness)
            witnesses[chunk[0]] = witness
            pos += 1
        else:
            minimal = False
            break
    return core, {k: w for k, w in witnesses.items() if k in core}, minimal


def decide_trial(problem: Problem, in_force: set[str], budget: Budget) -> tuple[str, Config | None]:
    """Whether the statements ``in_force`` can hold together with every other statement relaxed —
    relaxing only removes a constraint or widens a choice, so that is the most permissive case. Decided
    on the trial's own untracked problem (``relaxed_problem``), where exact pruning often settles it
    before the solver runs. ``("sat", witness)`` gives a configuration of ``problem`` that the analysis
    accepts; ``("unsat", None)``; ``("unknown", None)`` when the budget ran out."""
    off = frozenset(st.key for st in problem.statements if st.key not in in_force)
    sub = relaxed_problem(problem, off)
    if sub.infeasible is not None:
        return "unsat", None
    found = quick_answer(sub)
    if found is None:
        out = Engine(sub, sub.encoding(z3.Context()), budget).run([])
        if out.status != "sat":
            problem.analyses += sub.analyses
            return out.status, None
        assert out.config is not None and out.evaluation is not None  # (a "sat" outcome has its configuration)
        found = (out.config, out.evaluation)
    problem.analyses += sub.analyses
    picked = sub.candidates(found[0])
    choice = tuple((tid, problem.choices[tid].candidates.index(picked[tid])) for tid in problem.choices)
    return "sat", Config(choice, off)


# ================================================================== repair hints

HINT_RLIMIT = 2_000_000  # Z3 resource units per hint: a hint never costs more than a few seconds


def _hints(expl: Explanation, problem: Problem, budget: Budget) -> None:
    out: list[str] = []
    for st in expl.core:
        if budget.exhausted():
            break
        if st.kind == "spec":
            out.insert(sum(1 for h in out if h.startswith("relax `")), _spec_hint(expl, st, problem, budget))
        elif st.kind in ("min_rate", "max_rate"):
            out.append(_rate_hint(st, problem, budget))
        elif st.kind == "range":
            out.append(_range_hint(st, problem, budget))
    expl.hints = tuple(h for h in out if h)


def _relaxed_run(problem: Problem, off: set[str], budget: Budget, objective: Callable[[Encoding], Objective]
                 ) -> tuple[Outcome, Problem] | None:
    """The best configuration by ``objective(encoding)`` of ``problem`` with ``off`` relaxed and every
    other statement in force (its own pruned problem, at most ``HINT_RLIMIT``); None if pruning shows
    there is none."""
    sub = relaxed_problem(problem, frozenset(off))
    if sub.infeasible is not None:
        return None
    enc = sub.encoding(z3.Context())
    own = Budget(min(HINT_RLIMIT, budget.remaining) if budget.remaining is not None else HINT_RLIMIT)
    own.deadline = budget.deadline
    res = Engine(sub, enc, own).run([objective(enc)])
    budget.charge(own.used)
    problem.analyses += sub.analyses
    return None if res.status == "unsat" else (res, sub)


def _spec_hint(expl: Explanation, st: Statement, problem: Problem, budget: Budget) -> str:
    """The smallest bound any configuration meets, with every other statement in force, or failing
    that with the other spec bounds relaxed as well (other conflicts remain then)."""
    def objective(enc: Encoding) -> Objective:
        return Objective(f"hint {st.key}", "min", enc.latency[(cast(str, st.chain), cast(str, st.spec_kind))],
                         _spec_real(st, enc))

    found, caveat = _relaxed_run(problem, {st.key}, budget, objective), ""
    if found is None:  # other conflicts remain: the chain at its fastest with every spec relaxed
        caveat = " (once the other conflicting specs are relaxed too)"
        return _fastest_chain_hint(st, problem, caveat)
    if found is None or not found[0].values or found[0].values[0] is None:
        return f"relaxing `{st.text}` of `{st.chain}` alone is not enough"
    res, sub = found
    assert res.config is not None and res.evaluation is not None  # (an outcome with values has its configuration)
    value = _spec_real(st, None)(res.config, res.evaluation)
    if res.status != "optimal":
        return f"relax `{st.text}` of `{st.chain}` to {fmt_time(value)}{caveat} (not proven the smallest)"
    if not caveat:
        assert value is not None  # (the same latency as ``values[0]``, in seconds)
        expl.smallest[st.key] = value
    return f"relax `{st.text}` of `{st.chain}` to at least {fmt_time(value)}{caveat}"


def _fastest_chain_hint(st: Statement, problem: Problem, caveat: str) -> str:
    """With every spec bound relaxed: the latency of the chain run as fast as the rest allows (a
    configuration the analysis accepts reaches it), against the lower bound of pruning."""
    sub = relaxed_problem(problem, frozenset(key.key for key in problem.statements if key.kind == "spec"))
    found = None
    if sub.infeasible is None:
        found = fastest_chain(sub, cast(str, st.chain)) or (sub.seed() if sub.seed()[1].accepted else None)
    problem.analyses += sub.analyses
    value = _spec_real(st, None)(*found) if found is not None else None
    if value is None:
        return f"relaxing `{st.text}` of `{st.chain}` alone is not enough"
    lower = None
    if st.spec_kind in ("reaction_time", "data_age"):
        pruner = Pruner(sub.model, sub.choices, sub.structure.order, sub.structure.cyclic)
        chain = next(c for c in sub.model.chains if c.name == st.chain)
        kind = "reaction" if st.spec_kind == "reaction_time" else "age"
        lower = ChainLowerBound(pruner, chain, kind, *pruner.bounds()).total
    if lower is not None and lower >= value:
        return f"relax `{st.text}` of `{st.chain}` to at least {fmt_time(value)}{caveat}"
    below = f"; none gets below {fmt_time(lower)}" if lower is not None else ""
    return (f"relax `{st.text}` of `{st.chain}` to {fmt_time(value)}{caveat} (a configuration reaches it"
            f"{below})")


@overload
def _spec_real(st: Statement, enc: Encoding) -> Callable[[Config, Evaluation], int | None]: ...
@overload
def _spec_real(st: Statement, enc: None) -> Callable[[Config, Evaluation], Fraction | None]: ...


def _spec_real(st: Statement, enc: Encoding | None) -> Callable[[Config, Evaluation], Fraction | int | None]:
    """The analysed latency a spec bounds: in ticks of ``enc``, in seconds when ``enc`` is None."""
    def real(config: Config, ev: Evaluation) -> Fraction | int | None:
        chain = ev.result.chain(cast(str, st.chain))
        value = {"reaction_time": chain.reaction_time.worst, "data_age": chain.data_age_reduced.worst,
                 "jitter": chain.data_age_reduced.jitter}[cast(str, st.spec_kind)]
        return value if value is None or enc is None else enc.ticks(value)
    return real


def _rate_hint(st: Statement, problem: Problem, budget: Budget) -> str:
    """The rate the constraint end would need to admit (every other statement in force)."""
    high = st.kind == "max_rate"

    def real_rate(ev: Evaluation) -> Fraction | None:
        rates = [ev.result.task(t).rate for t in st.tasks]
        if any(r is None for r in rates):
            return None
        values = [r.high if high else r.low for r in cast("list[RateInterval]", rates)]  # (no None: above)
        return max(values) if high else min(values)

    def objective(enc: Encoding) -> Objective:
        z = z3.Int(f"hint|{st.key}", enc.ctx)
        for tid in st.tasks:
            fl, fh = enc.rates.get(tid, (None, None))
            if fl is not None:
                enc.add(z >= enc.t.lift(fh) if high else z <= enc.t.lift(fl))

        def real(config: Config, ev: Evaluation) -> int | None:
            rate = real_rate(ev)
            return None if rate is None else int(rate * enc.tick * enc.M)
        return Objective(f"hint {st.key}", "min" if high else "max", z, real)

    found = _relaxed_run(problem, {st.key}, budget, objective)
    who = ", ".join(f"`{t}`" for t in st.tasks)
    if found is None:
        return f"widening `{st.text}` of {who} alone is not enough"
    if found[0].evaluation is None:  # the hint's own budget ran out before any configuration
        return ""
    rate = real_rate(found[0].evaluation)
    if rate is None:
        return ""
    return f"{who} would need to run at {'up to' if high else 'down to'} {fmt_rate(rate)} ({st.label} now)"


def _range_hint(st: Statement, problem: Problem, budget: Budget) -> str:
    """The candidate outside a hole's range that the problem would need (every other statement in force)."""
    tid = st.tasks[0]
    choice = problem.choices[tid]
    outside = {choice.candidates[i] for i, ex in enumerate(choice.excluded) if st.key in ex}
    inside = [c for c in choice.candidates if c not in outside]
    if not inside:
        return ""
    lo, hi = min(c.speed for c in inside), max(c.speed for c in inside)

    def distance(c: Candidate) -> Fraction:
        v = c.speed
        return lo - v if v < lo else (v - hi if v > hi else Fraction(0))

    def objective(enc: Encoding) -> Objective:
        cands = enc.choices[tid].candidates

        def scale(c: Candidate) -> int:
            return int(distance(c) / enc.tick) if c.activation.strict_period is not None else int(distance(c))

        term = enc.t.add(*(enc.t.ite(enc.sel[tid][i], scale(c), 0) for i, c in enumerate(cands) if c in outside))
        return Objective(f"hint {st.key}", "min", term, lambda config, ev: scale(cands[config.index(tid)]))

    found = _relaxed_run(problem, {st.key}, budget, objective)
    if found is None:
        return f"widening `{st.text}` of `{tid}` alone is not enough"
    res, sub = found
    if res.config is None:
        return ""
    chosen = sub.choices[tid].candidates[res.config.index(tid)]
    return f"`{tid}` would need `{chosen.text()}`, outside `{st.text}`"


# ================================================================== the diagnostic


def unsat_diagnostic(system: SystemModel, expl: Explanation | None, reason: str | None,
                     holes: tuple[Label, ...] = (), rejected: tuple[str, ...] = ()) -> Diagnostic:
    """E401: primary label on a violated spec of the core, secondary labels on the other members. Without
    a core (no tracked statement is to blame: the conflict lies in what is not a statement, e.g. a
    deadline or a priority) it stands on the ``holes`` — no value of theirs is accepted — with the
    analysis' ``rejected`` reasons of the slowest configuration as notes."""
    sink = DiagnosticSink()
    core = expl.core if expl is not None else ()
    if not core and holes:
        return _holes_diagnostic(system, holes, reason, rejected, expl is not None and expl.status == "unsat")
    specs = [st for st in core if st.kind == "spec"]
    primary = specs[0] if specs else (core[0] if core else None)
    where = primary.span if primary is not None else system.span
    if primary is not None and primary.kind == "spec":
        message = (f"no configuration of `{system.name}` meets `{primary.text}` of chain `{primary.chain}`"
                   + (" together with the statements below" if len(core) > 1 else ""))
        label = "cannot hold"
    elif primary is not None:
        message = (f"no configuration of `{system.name}` satisfies these statements together" if len(core) > 1
                   else f"no configuration of `{system.name}` satisfies this statement")
        label = primary.label
    else:
        message = f"no configuration of `{system.name}` meets every constraint" + (f": {reason}" if reason else "")
        label = ""
    secondary = tuple(Label(st.span, _label(st)) for st in core if st is not primary)
    notes = []
    if core:
        assert expl is not None  # (a core comes with its explanation)
        if len(core) == 1:
            notes.append("this statement cannot hold: without it a configuration exists (every other statement "
                         "was relaxed)")
        else:
            notes.append(f"these {len(core)} statements cannot hold together"
                         + (": without any one of them a configuration exists (a minimal unsatisfiable core; "
                            "every other statement was relaxed)" if expl.minimal else
                            " (the search budget ran out before the core was minimal)"))
        for st in core:
            if not _real(st.span):
                notes.append(f"{_who(st)}: {st.text}")
    elif reason:
        notes.append(reason)
    for key, value in (expl.smallest.items() if expl is not None else ()):
        st = next(s for s in core if s.key == key)
        notes.append(f"the smallest {cast(str, st.spec_kind).replace('_', ' ')} of `{st.chain}` any configuration "
                     f"allows is {fmt_time(value)}")
    help_ = "; ".join(expl.hints) if expl is not None and expl.hints else (
        "relax a spec bound, a fixed rate or an activation constraint" if core else None)
    sink.emit("E401", message, where, label, secondary=secondary, notes=tuple(notes), help=help_)
    return sink.items[0]


def _holes_diagnostic(system: SystemModel, holes: tuple[Label, ...], reason: str | None,
                      rejected: tuple[str, ...], blameless: bool) -> Diagnostic:
    """E401 on the holes, when no statement is blamed (``unsat_diagnostic``): ``blameless`` when relaxing
    every statement was shown not to help, else the search for the core did not finish."""
    sink = DiagnosticSink()
    notes = ["relaxing every tracked statement does not help: what conflicts is not a statement synth relaxes "
              "(a deadline, a priority, a delay, a sporadic source)" if blameless else
              "the search for the statements that conflict ran out of its budget"]
    notes += [f"with every hole at its slowest value: {why}" for why in rejected[:5]]
    message = (f"no configuration of `{system.name}` meets every constraint: {reason}" if reason else
               f"no value of the holes of `{system.name}` gives a configuration the analysis accepts")
    sink.emit("E401", message, holes[0].span, holes[0].message, secondary=holes[1:], notes=tuple(notes),
              help="widen a hole's range, or change the deadlines, priorities or delays the notes name")
    return sink.items[0]


def _label(st: Statement) -> str:
    return st.label if st.kind == "spec" or len(st.tasks) != 1 or st.kind == "core" else f"{st.label} ({st.tasks[0]})"


def _who(st: Statement) -> str:
    return f"chain `{st.chain}`" if st.kind == "spec" else ", ".join(f"`{t}`" for t in st.tasks)


def _real(span: Span) -> bool:
    return span is not None and span != NO_SPAN and span.line > 0
