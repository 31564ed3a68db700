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

from dataclasses import dataclass, field
from fractions import Fraction

import z3

from ..diagnostics import Diagnostic, DiagnosticSink, Label
from ..model import SystemModel
from ..resolve import SystemScope
from ..source import NO_SPAN, Span
from ..units import fmt_rate, fmt_time
from .problem import Config, Problem, build_problem
from .solve import Budget, Engine, Objective
from .statements import Statement


@dataclass
class Explanation:
    status: str  # "unsat" | "sat" (the tracked problem found an accepted configuration) | "unknown"
    core: tuple[Statement, ...] = ()
    minimal: bool = False
    witnesses: dict[str, Config] = field(default_factory=dict)  # key -> configuration without it
    hints: tuple[str, ...] = ()
    smallest: dict[str, Fraction] = field(default_factory=dict)  # spec key -> smallest feasible bound
    problem: Problem | None = None
    engine: Engine | None = None
    sat_config: Config | None = None


def explain_unsat(model: SystemModel, scope: SystemScope | None, budget: Budget, *, hints: bool = True) -> Explanation:
    problem = build_problem(model, scope, tracked=True)
    ctx = z3.Context()
    enc = problem.encoding(ctx)
    engine = Engine(problem, enc, budget)
    by_key = {st.key: st for st in sorted(problem.statements, key=lambda st: st.key)}
    lits = {key: enc.lit(key) for key in by_key}
    out = engine.run([], [lits[k] for k in by_key])
    if out.status == "sat":
        return Explanation("sat", problem=problem, engine=engine, sat_config=out.config)
    if out.status != "unsat":
        return Explanation("unknown", problem=problem, engine=engine)
    core, witnesses, minimal = _minimise(engine, lits, by_key, set(out.core))
    ordered = tuple(sorted((by_key[k] for k in core), key=Statement.order_key))
    expl = Explanation("unsat", ordered, minimal, witnesses, problem=problem, engine=engine)
    if hints:
        _hints(expl, engine, lits)
    return expl


def deletion_order(statements) -> list[Statement]:
    """By kind (ranks of ``statements.RANKS``), then by key: names, not positions, so that
    reordering declarations does not change the core."""
    return sorted(statements, key=lambda st: (st.rank, st.key))


def _minimise(engine: Engine, lits: dict, by_key: dict[str, Statement], core: set[str]):
    witnesses: dict[str, Config] = {}
    minimal = True
    for st in deletion_order(by_key[k] for k in core):
        if st.key not in core:
            continue
        trial = sorted(core - {st.key})
        out = engine.run([], [lits[k] for k in trial])
        if out.status == "unsat":
            core = set(out.core) & set(trial) if out.core else set(trial)
        elif out.status == "sat":
            witnesses[st.key] = out.config
        else:
            minimal = False
            break
    return core, {k: w for k, w in witnesses.items() if k in core}, minimal


# ================================================================== repair hints


def _hints(expl: Explanation, engine: Engine, lits: dict) -> None:
    enc, out = engine.enc, []
    for st in expl.core:
        others = [lit for key, lit in sorted(lits.items()) if key != st.key]
        if engine.budget.exhausted():
            break
        if st.kind == "spec":
            out.insert(sum(1 for h in out if h.startswith("relax `")), _spec_hint(expl, st, engine, lits))
        elif st.kind in ("min_rate", "max_rate"):
            out.append(_rate_hint(st, engine, others))
        elif st.kind == "range":
            out.append(_range_hint(st, engine, others))
    expl.hints = tuple(h for h in out if h)


def _spec_hint(expl: Explanation, st: Statement, engine: Engine, lits: dict) -> str:
    """The smallest bound any configuration meets, with every other statement in force, or failing
    that with the other spec bounds relaxed as well (other conflicts remain then)."""
    enc = engine.enc
    objective = Objective(f"hint {st.key}", "min", enc.latency[(st.chain, st.spec_kind)], _spec_real(st, enc))
    others = [lit for key, lit in sorted(lits.items()) if key != st.key]
    res = engine.run([objective], others)
    caveat = ""
    if res.status == "unsat":
        others = [lit for key, lit in sorted(lits.items()) if key != st.key and not key.startswith("spec:")]
        res = engine.run([objective], others)
        caveat = " (once the other conflicting specs are relaxed too)"
    if res.status == "unsat" or not res.values or res.values[0] is None:
        return f"relaxing `{st.text}` of `{st.chain}` alone is not enough"
    value = res.values[0] * enc.tick
    if res.status != "optimal":
        return f"relax `{st.text}` of `{st.chain}` to {fmt_time(value)}{caveat} (not proven the smallest)"
    if not caveat:
        expl.smallest[st.key] = value
    return f"relax `{st.text}` of `{st.chain}` to at least {fmt_time(value)}{caveat}"


def _spec_real(st: Statement, enc):
    def real(config, ev):
        chain = ev.result.chain(st.chain)
        value = {"reaction_time": chain.reaction_time.worst, "data_age": chain.data_age_reduced.worst,
                 "jitter": chain.data_age_reduced.jitter}[st.spec_kind]
        return None if value is None else enc.ticks(value)
    return real


def _rate_hint(st: Statement, engine: Engine, others: list) -> str:
    """The rate the constraint end would need to admit (every other statement in force)."""
    enc = engine.enc
    high = st.kind == "max_rate"
    z = z3.Int(f"hint|{st.key}", enc.ctx)
    for tid in st.tasks:
        fl, fh = enc.rates[tid]
        enc.add(z >= enc.t.lift(fh) if high else z <= enc.t.lift(fl))

    def real(config, ev):
        rates = [ev.result.task(t).rate for t in st.tasks]
        if any(r is None for r in rates):
            return None
        values = [r.high if high else r.low for r in rates]
        return int((max(values) if high else min(values)) * enc.tick * enc.M)

    res = engine.run([Objective(f"hint {st.key}", "min" if high else "max", z, real)], others)
    who = ", ".join(f"`{t}`" for t in st.tasks)
    if res.status == "unsat":
        return f"widening `{st.text}` of {who} alone is not enough"
    if not res.values or res.values[0] is None:
        return ""
    rate = Fraction(res.values[0]) / (enc.tick * enc.M)
    return f"{who} would need to run at {'up to' if high else 'down to'} {fmt_rate(rate)} ({st.label} now)"


def _range_hint(st: Statement, engine: Engine, others: list) -> str:
    """The candidate outside a hole's range that the problem would need (every other statement in force)."""
    enc, tid = engine.enc, st.tasks[0]
    choice = engine.problem.choices[tid]
    outside = [i for i, ex in enumerate(choice.excluded) if st.key in ex]
    inside = [i for i in range(len(choice.candidates)) if i not in outside]
    if not inside:
        return ""
    lo, hi = min(choice.candidates[i].speed for i in inside), max(choice.candidates[i].speed for i in inside)

    def distance(i: int) -> int:
        v = choice.candidates[i].speed
        gap = lo - v if v < lo else (v - hi if v > hi else Fraction(0))
        return int(gap / enc.tick) if choice.candidates[i].kind == "timer" else int(gap)

    term = enc.t.add(*(enc.t.ite(enc.sel[tid][i], distance(i), 0) for i in outside)) if outside else 0
    res = engine.run([Objective(f"hint {st.key}", "min", term, lambda c, ev: distance(c.index(tid)))], others)
    if res.status == "unsat":
        return f"widening `{st.text}` of `{tid}` alone is not enough"
    if res.config is None:
        return ""
    chosen = choice.candidates[res.config.index(tid)]
    return f"`{tid}` would need `{chosen.text()}`, outside `{st.text}`"


# ================================================================== the diagnostic


def unsat_diagnostic(system: SystemModel, expl: Explanation | None, reason: str | None) -> Diagnostic:
    """E401: primary label on a violated spec of the core, secondary labels on the other members."""
    sink = DiagnosticSink()
    core = expl.core if expl is not None else ()
    specs = [st for st in core if st.kind == "spec"]
    primary = specs[0] if specs else (core[0] if core else None)
    where = primary.span if primary is not None else system.span
    if primary is not None and primary.kind == "spec":
        message = (f"no configuration of `{system.name}` meets `{primary.text}` of chain `{primary.chain}`"
                   + (" together with the statements below" if len(core) > 1 else ""))
        label = "cannot hold"
    elif primary is not None:
        message = f"no configuration of `{system.name}` satisfies these statements together"
        label = primary.label
    else:
        message = f"no configuration of `{system.name}` meets every constraint" + (f": {reason}" if reason else "")
        label = ""
    secondary = tuple(Label(st.span, _label(st)) for st in core if st is not primary)
    notes = []
    if core:
        notes.append(f"these {len(core)} statements cannot hold together"
                     + (": without any one of them a configuration exists (a minimal unsatisfiable core; every "
                        "other statement was relaxed)" if expl.minimal else " (the search budget ran out before "
                        "the core was minimal)"))
        for st in core:
            if not _real(st.span):
                notes.append(f"{_who(st)}: {st.text}")
    elif reason:
        notes.append(reason)
    for key, value in (expl.smallest.items() if expl is not None else ()):
        st = next(s for s in core if s.key == key)
        notes.append(f"the smallest {st.spec_kind.replace('_', ' ')} of `{st.chain}` any configuration allows "
                     f"is {fmt_time(value)}")
    help_ = "; ".join(expl.hints) if expl is not None and expl.hints else (
        "relax a spec bound, a fixed rate or an activation constraint" if core else None)
    sink.emit("E401", message, where, label, secondary=secondary, notes=tuple(notes), help=help_)
    return sink.items[0]


def _label(st: Statement) -> str:
    return st.label if st.kind == "spec" or len(st.tasks) != 1 or st.kind == "core" else f"{st.label} ({st.tasks[0]})"


def _who(st: Statement) -> str:
    return f"chain `{st.chain}`" if st.kind == "spec" else ", ".join(f"`{t}`" for t in st.tasks)


def _real(span: Span) -> bool:
    return span is not None and span != NO_SPAN and span.line > 0
