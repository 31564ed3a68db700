"""``prove(model)``: every spec of a configured system proved, refuted with a concrete run, or
undecided within the budget (specs/proof.md).

Order of work: the compositional analysis decides everything its bounds meet ("bound"). The
obligations left over are measured by one exact search over the scenario space of the exactness
theorem — enumeration through the reference simulator when the representatives fit in the budget,
else the Z3 encoding where it applies — and otherwise by a falsifying search, which can show a
violation but never proves.
"""
from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from contextlib import closing
from dataclasses import dataclass
from functools import partial
from fractions import Fraction
from typing import cast

from ..core.diagnostics import Diagnostic, DiagnosticSink, Label
from ..core.gcpause import paused_gc
from ..model.arrivals import with_arrivals
from ..model.system import SystemModel
from .sim import Sample, ScenarioError, SimulationError, SimulationTimeout, Trace
from ..timing import TaskResponse, response_and_chain_bounds
from ..model.units import fmt_time
from . import bound as bound_mod
from .bound import Obligation
from .cone import Replays, SliceMismatch, check_all_carry_over, restrict, slices
from .dominant import exact_system
from .refine import refine, verdict as refined_verdict
from .exact import (SEARCH_EVENTS, Budget, ExactResult, Extreme, Goal, approach, count_representatives,
                    enumerate_exact, SearchResult, exact_class, first_scenarios, grid_of, search, search_horizon)
from .parallel import ordered_map, resolve_workers
from .measure import measure
from .scenario import ConcreteScenario, Measured, ResponseSample, Target, replay
from .verdict import Counterexample, ProofResult, Verdict
from ..core.budgets import PROVE_BUDGET, PROVE_RLIMIT

DEFAULT_BUDGET = PROVE_BUDGET  # simulated scenarios
DEFAULT_RLIMIT = PROVE_RLIMIT  # Z3 resource units (deterministic), per query


def prove(model: SystemModel, *, budget: int = DEFAULT_BUDGET, rlimit: int = DEFAULT_RLIMIT,
          timeout: float | None = None, data_age: str = "reduced", use_z3: bool = True,
          jobs: int | None = None) -> ProofResult:
    """Prove every chain spec and task deadline of ``model`` (which must have no synthesis holes).

    ``budget`` bounds the number of simulated scenarios, ``rlimit`` the resources of the Z3 search (all
    its queries together);
    ``timeout`` (seconds, wall clock) is off unless given; ``jobs`` processes may share a large
    exact enumeration or a batch of large falsifying searches (None: every available CPU).
    Deterministic for fixed arguments other than ``jobs``, which never changes the result."""
    if model.holes:
        raise ValueError("prove needs a configured system: use verify.api.require_configured first")
    model = with_arrivals(model)  # (the work of taking arrivals, as tasks: specs/timing.md §6.6)
    with paused_gc():  # (the searches below run with the collector as the caller has it)
        variant, responses, chains = response_and_chain_bounds(model, data_age=data_age)
        obs = bound_mod.obligations(model, variant, responses, chains)
        verdicts: dict[int, Verdict] = {}
        open_: list[tuple[int, Obligation]] = []
        for i, ob in enumerate(obs):
            if ob.proved_by_bound:
                verdicts[i] = bound_mod.by_bound(ob)
            else:
                open_.append((i, ob))
    budget_obj = Budget(budget, None if timeout is None else time.monotonic() + timeout)
    if open_:
        verdicts.update(_decide(model, open_, budget_obj, rlimit, use_z3, jobs, (responses, variant)))
    with paused_gc():
        ordered = tuple(verdicts[i] for i in range(len(obs)))
        found = diagnostics(model, ordered) + unbounded(model, responses, budget_obj)
        return ProofResult(model.name, ordered, tuple(found), variant, budget_obj.used, budget)


def unbounded(model: SystemModel, responses: Mapping[str, TaskResponse],
              budget: Budget | None = None) -> list[Diagnostic]:
    """E312 for every task with neither a response-time bound nor a deadline (its activations are not
    bounded, so neither is ``A⁺``): there is nothing to prove it against, so nothing is proved for it,
    and ``prove`` does not pass (proof spec §1). The run of the first search scenario — every phase
    0, every job at its wcet, every message at its largest delay (§6) — shows how its jobs queue: one
    scenario of ``budget``, run only while its deadline has not passed (else a note says why not)."""
    tasks = [t for t in model.tasks if responses[t.id].wcrt is None and responses[t.id].deadline is None]
    if not tasks:
        return []
    trace, why_not = _first_run(model, budget)
    sink = DiagnosticSink()
    for task in tasks:
        notes = [f"the response-time analysis finds no bound: {responses[task.id].failure or 'not bounded'}",
                 "it has no deadline either (its activations are not bounded), so there is nothing to prove "
                 "it against: nothing is proved for it"]
        if trace is not None:
            notes.append(_queue_text(trace, task.id))
        elif why_not is not None:
            notes.append(why_not)
        sink.emit("E312", f"no response-time bound for `{task.id}`, and no deadline to prove", task.span,
                  "not bounded", notes=notes,
                  help="break what lets its activations grow (a trigger cycle, an unbounded source), or give "
                       "it a deadline: prove then searches for a run that misses it")
    return sink.items


def _first_run(model: SystemModel, budget: Budget | None) -> tuple[Trace | None, str | None]:
    """The run of the first search scenario for E312's note, charged to ``budget`` (one scenario, and
    its deadline); else None and why it was not run (None: it cannot be, or it exceeds its events)."""
    not_run = "the run with every phase 0 and every job at its wcet was not simulated: "
    if budget is not None and not budget.take():
        return None, not_run + ("the timeout (`--timeout`) had passed" if budget.expired() else
                                "the scenario budget (`--budget`) was spent")
    try:
        scenario = first_scenarios(model, search_horizon(model, None))[0]
        return replay(model, scenario, SEARCH_EVENTS, budget.deadline if budget is not None else None), None
    except SimulationTimeout:
        return None, not_run + "the timeout (`--timeout`) passed while it ran"
    except (ScenarioError, SimulationError):
        return None, None


def _queue_text(trace: Trace, task: str) -> str:
    """How the jobs of ``task`` queue in ``trace``: the responses of its finished jobs at four points,
    and its jobs still pending at the end."""
    jobs = trace.jobs.get(task, ())
    done = [j for j in jobs if j.finish is not None]
    pending = len(jobs) - len(done)
    if not done:
        return f"in the run with every phase 0 and every job at its wcet, no job of it completes within " \
               f"{fmt_time(trace.horizon)} ({pending} released)"
    picks = sorted({done[(len(done) - 1) * k // 3] for k in range(4)}, key=lambda j: j.index)
    shown = ", ".join(f"job #{j.index} (released at {fmt_time(j.release)}) in "
                      f"{fmt_time(finish - j.release)}" for j in picks if (finish := j.finish) is not None)
    return (f"in the run with every phase 0 and every job at its wcet, its jobs respond: {shown}; "
            f"{pending} still pending at {fmt_time(trace.horizon)}")


# ------------------------------------------------------------------ deciding what the bound left open


#: the falsifying searches of this many cones get their shares of the budget together (and may run
#: side by side): what one of them leaves goes to the cones after the batch; the batch is fixed, so
#: verdicts do not depend on ``jobs``
SEARCH_BATCH = 4
#: a batch whose shares (plus one) times cone sizes reach this many task-scenarios is spread over
#: ``jobs`` processes (below it, forking would cost more than it saves)
PARALLEL_TASK_SCENARIOS = 2000
#: events after which a run of the first scenarios shared by all searches ends (the union of the
#: cones can be the whole system, and its runs go to the longest horizon)
SHARED_EVENTS = 4 * SEARCH_EVENTS


def _decide(model: SystemModel, open_: list[tuple[int, Obligation]], budget: Budget, rlimit: int,
            use_z3: bool, jobs: int | None = None,
            analysis: tuple[dict[str, TaskResponse], str] | None = None) -> dict[int, Verdict]:
    """Decide the obligations the bound left open, cone by cone (proof spec §3, §4.0): first the
    exact methods, each group of obligations with the same cone on the subsystem of its cone; then,
    with ``analysis`` (the responses and the data-age variant of the bound), the bound refined by the
    exact response times (§4.8); then the falsifying searches of what they left (``_search_all``).
    Every counterexample found on a subsystem is replayed on the whole system; if one did not carry
    over (a bug), its obligations are decided again on the whole system."""
    out: dict[int, Verdict] = {}
    pending: list[tuple[SystemModel, list[_Left]]] = []
    replays = Replays(model)
    for sub, targets in slices(model, sorted({ob.target for _, ob in open_})):
        members = set(targets)
        items = [(i, ob) for i, ob in open_ if ob.target in members]
        decided, rest = _decide_exactly(sub, items, budget, rlimit, use_z3, jobs)
        if sub is not model and not _carries_over(model, decided, replays=replays):
            decided, rest = _decide_exactly(model, items, budget, rlimit, use_z3, jobs)
            sub = model
        out.update(decided)
        if rest:
            pending.append((sub, rest))
    if pending and analysis is not None:
        pending = _refined(model, pending, budget, jobs, analysis, out)
    out.update(_search_all(model, pending, budget, jobs, replays))
    return out


def _refined(model: SystemModel, pending: list[tuple[SystemModel, list[_Left]]], budget: Budget,
             jobs: int | None, analysis: tuple[dict[str, TaskResponse], str],
             out: dict[int, Verdict]) -> list[tuple[SystemModel, list[_Left]]]:
    """The obligations the exact methods left that the bound refined by exact response times proves
    (verdicts into ``out``), and what is left for the searches."""
    refinement = refine(model, [r.ob for _, rest in pending for r in rest], *analysis, budget, jobs)
    if refinement is None:
        return pending
    left = []
    for sub, rest in pending:
        keep = []
        for r in rest:
            v = refined_verdict(r.ob, refinement)
            if v is None:
                keep.append(r)
            else:
                out[r.i] = v
        if keep:
            left.append((sub, keep))
    return left


@dataclass(frozen=True)
class _Left:
    """An obligation the exact methods of its cone left to the falsifying search, and why."""

    i: int
    ob: Obligation
    reason: str
    explored: int  # scenarios the exact search of its cone simulated


def _carries_over(model: SystemModel, decided: dict[int, Verdict],
                  known: Mapping[ConcreteScenario, Measured] | None = None, replays: Replays | None = None) -> bool:
    """Every counterexample of ``decided`` (found on a subsystem) holds on the whole ``model``; one
    whose samples come from ``known`` runs (scenario -> ``Measured``, made on the whole ``model``
    itself) needs no replay, and the replays of ``model`` made for other cones are reused."""
    cexs = [v.counterexample for v in decided.values()
            if v.counterexample is not None and not _measured_on(v.counterexample, known or {})]
    try:
        check_all_carry_over(model, cexs, replays)
    except SliceMismatch:
        return False
    return True


def _measured_on(cex: Counterexample, known: Mapping[ConcreteScenario, Measured]) -> bool:
    """The counterexample's samples are those of runs in ``known``."""
    worst = known.get(cex.scenario)
    if worst is None or worst.values.get(cex.target) is None or worst.values[cex.target].worst != cex.sample:
        return False
    if cex.best_scenario is None:
        return True
    best = known.get(cex.best_scenario)
    return (best is not None and best.values.get(cex.target) is not None
            and best.values[cex.target].best == cex.best_sample)


def _search_all(model: SystemModel, pending: list[tuple[SystemModel, list[_Left]]], budget: Budget,
                jobs: int | None, replays: Replays | None = None) -> dict[int, Verdict]:
    """One falsifying search per cone, in batches of ``SEARCH_BATCH``: each search of a batch gets
    an equal share of the budget left with the cones from the batch on (what it does not use, because
    it refuted everything, goes to the cones after the batch). Budget left after the last batch goes
    to further rounds over the cones with undecided obligations, each search resuming from its best
    runs with a new seed, until the budget is used or nothing is undecided. The counterexamples found
    on cones are replayed on the whole system in ``replays`` (a scenario once for all cones)."""
    out: dict[int, Verdict] = {}
    replays = replays if replays is not None else Replays(model)
    horizons = [search_horizon(sub, max((r.ob.bound for r in rest if r.ob.bound is not None), default=None))
                for sub, rest in pending]
    firsts, on_model = ((), False) if len(pending) < 2 else _shared_firsts(model, pending, max(horizons), budget,
                                                                            jobs)
    cones = [_Cone(sub, rest, horizon, firsts if all(m.horizon >= horizon for m in firsts) else ())
             for (sub, rest), horizon in zip(pending, horizons)]
    known = {m.scenario: m for m in firsts} if on_model else {}  # runs made on the whole system
    todo, round_ = list(range(len(cones))), 0
    while todo:
        before = budget.used
        _search_round(model, cones, todo, round_, budget, jobs, known, out, replays)
        if budget.used == before or budget.left <= 0 or budget.expired():
            break
        todo = [k for k in todo if any(out[r.i].status == "undecided" for r in cones[k].items)]
        round_ += 1
    return out


@dataclass
class _Cone:
    """A cone's falsifying search across rounds: its subsystem, the obligations the exact methods
    left, its horizon, its first runs made on the union of the cones, and its search so far."""

    sub: SystemModel
    items: list[_Left]
    horizon: Fraction
    given: tuple[Measured, ...]
    found: SearchResult | None = None


def _search_round(model: SystemModel, cones: list[_Cone], todo: list[int], round_: int, budget: Budget,
                  jobs: int | None, known: Mapping[ConcreteScenario, Measured], out: dict[int, Verdict],
                  replays: Replays) -> None:
    """One round of the searches of cones ``todo`` (their undecided obligations after round 0), in
    batches: verdicts into ``out``, each cone's search kept for the next round. The counterexamples of
    a cone are replayed on the whole system here, in ``replays``, where those of other cones are."""
    for start in range(0, len(todo), SEARCH_BATCH):
        batch = todo[start:start + SEARCH_BATCH]
        parts = len(todo) - start
        shares = {k: budget.left // parts + (j < budget.left % parts) for j, k in enumerate(batch)}
        size = sum((shares[k] + 1) * len(cones[k].sub.tasks) for k in batch)
        workers = resolve_workers(jobs) if size >= PARALLEL_TASK_SCENARIOS else 1
        items = {k: [r for r in cones[k].items if round_ == 0 or out[r.i].status == "undecided"] for k in batch}

        work = partial(_search_batch_member, cones, batch, items, shares, budget, round_)
        with closing(ordered_map(work, range(len(batch)), workers)) as runs:
            for k, (verdicts, used, found) in zip(batch, runs):  # (closing stops the workers)
                budget.spend(used)
                cones[k].found = found
                if cones[k].sub is not model and not _carries_over(model, verdicts, known, replays):
                    # a bug in the cone: search the whole system instead
                    cones[k].sub = model
                    found, used = _search_cone(model, items[k], budget.left // parts, budget.deadline,
                                               cones[k].horizon)
                    budget.spend(used)
                    cones[k].found = found
                    verdicts = _search_verdicts(items[k], found, budget)
                out.update(verdicts)


def _shared_firsts(model: SystemModel, pending: list[tuple[SystemModel, list[_Left]]], horizon: Fraction,
                   budget: Budget, jobs: int | None) -> tuple[tuple[Measured, ...], bool]:
    """The two scenarios every search starts with (``first_scenarios``: all phases 0, all wcet and
    d⁺, or all bcet and d⁻) run once, on the union of the cones and up to the longest horizon, for all
    of them: a run of the union is a run of each cone (§4.0), so two scenarios of the budget stand for
    two per cone. (The runs, and whether the union is the whole ``model``; no runs when the budget
    has less than two left or a run fails.)"""
    if budget.left < 2 or budget.expired():
        return (), False
    tasks = frozenset(t.id for sub, _ in pending for t in sub.tasks)
    targets = sorted({r.ob.target for _, rest in pending for r in rest})
    union = model if len(tasks) == len(model.tasks) else restrict(
        model, tasks, {t.name for t in targets if t.kind != "response"})
    scenarios = first_scenarios(union, horizon)
    budget.take(len(scenarios))

    def run(k: int) -> Measured | None:
        try:
            return measure(union, scenarios[k], targets, 2 * SHARED_EVENTS, event_budget=SHARED_EVENTS)
        except (ScenarioError, SimulationError):
            return None

    workers = resolve_workers(jobs) if len(union.tasks) * len(scenarios) >= PARALLEL_TASK_SCENARIOS else 1
    runs = tuple(ordered_map(run, range(len(scenarios)), workers))
    if any(m is None for m in runs):
        return (), False
    return cast("tuple[Measured, ...]", runs), union is model  # (no run is None: checked above)


def _search_batch_member(cones: list[_Cone], batch: list[int], items: dict[int, list[_Left]],
                         shares: dict[int, int], budget: Budget, round_: int, j: int
                         ) -> tuple[dict[int, Verdict], int, SearchResult | None]:
    """The search of cone ``batch[j]`` (in a worker when the batch is spread): (verdicts, scenarios
    used, search)."""
    cone = cones[batch[j]]
    found, used = _search_cone(cone.sub, items[batch[j]], shares[batch[j]], budget.deadline, cone.horizon, cone.given,
                               cone.found, round_)
    return _search_verdicts(items[batch[j]], found, budget), used, found


def _search_cone(model: SystemModel, items: list[_Left], share: int, deadline: float | None, horizon: Fraction,
                 given: tuple[Measured, ...] = (), resume: SearchResult | None = None,
                 round_: int = 0) -> tuple[SearchResult | None, int]:
    """The falsifying search for ``items`` on ``model`` within ``share`` scenarios (``given``: its
    first runs, made on the union of the cones; ``resume``: its search of the rounds before, which
    round ``round_`` continues): (its result or None, the scenarios it used)."""
    goals = []
    for r in items:
        ob = r.ob
        goals.append(Goal(ob.target, spread=ob.spec) if ob.kind == "jitter" else Goal(ob.target, above=ob.spec))
    own = Budget(share, deadline)
    if own.expired():
        return None, 0
    if round_ == 0:
        return search(model, goals, own, horizon, given=given), own.used
    return search(model, goals, own, horizon, seed=f"verify-prove/round {round_}", resume=resume), own.used


def _search_verdicts(items: list[_Left], found: SearchResult | None, budget: Budget) -> dict[int, Verdict]:
    out: dict[int, Verdict] = {}
    for r in items:
        ob = r.ob
        cex = _search_cex(ob, found) if found is not None else None
        explored = (found.explored if found else 0) + r.explored
        if cex is not None:
            out[r.i] = ob.verdict("violated", "search", counterexample=cex, explored=explored)
        else:
            why = r.reason or "no exact method applies"
            if budget.expired():
                why += "; the time limit was reached"
            out[r.i] = ob.verdict("undecided", "search", explored=explored, note=why)
    return out


def _decide_exactly(model: SystemModel, open_: list[tuple[int, Obligation]], budget: Budget, rlimit: int,
                    use_z3: bool, jobs: int | None = None) -> tuple[dict[int, Verdict], list[_Left]]:
    """The obligations of one cone that an exact method decides (it may use all the budget that is
    left), and the others with the reason they are not decided exactly. Outside the exact class the
    exact methods search the cone's dominating rigid system where one applies (§4.7); its
    counterexamples must replay on the cone itself."""
    targets = sorted({ob.target for _, ob in open_})
    want_best = frozenset(ob.target for _, ob in open_ if ob.kind == "jitter")
    system = exact_system(model, targets)
    reason = exact_class(model) if system is None else None
    exact: ExactResult | None = None
    if system is not None:
        exact = enumerate_exact(system.model, targets, budget, want_best, jobs=jobs)
        if exact is None and use_z3:
            from .z3bmc import EncodingMismatch, z3_applicable, z3_exact

            try:
                exact = z3_exact(system.model, targets, want_best, rlimit=rlimit, budget=budget)
            except EncodingMismatch:  # a bug: the encoding and the simulator disagree; decide nothing by it
                exact = None
        if exact is None:
            allowed, shown = budget.left + budget.used, max(10 * (budget.left + budget.used), 100_000)
            n = count_representatives(grid_of(system.model), shown)
            reason = (f"the exact search space has {n if n <= shown else f'more than {shown}'} "
                      f"phase representatives, more than the budget of {allowed} scenarios (raise --budget)")
            if use_z3:
                why_not = z3_applicable(system.model)
                reason += (", and the Z3 search did not decide within its resource limit"
                           + (" and the time limit" if budget.deadline is not None else "")
                           if why_not is None else f", and the Z3 search does not apply: {why_not}")
        elif not exact.complete:
            reason = exact.reason
    out: dict[int, Verdict] = {}
    leftover: list[_Left] = []
    for i, ob in open_:
        v = None if exact is None or system is None else _from_exact(system.model, ob, exact, budget, system.what)
        if v is None:
            leftover.append(_Left(i, ob, reason or "", exact.explored if exact else 0))
        else:
            out[i] = v
    if system is not None and system.model is not model and not _carries_over(model, out):
        return {}, [_Left(i, ob, "a run of the dominating rigid system did not replay on the system (a bug)",
                          exact.explored if exact else 0) for i, ob in open_]
    return out, leftover


def _from_exact(model: SystemModel, ob: Obligation, exact: ExactResult, budget: Budget,
                note: str = "") -> Verdict | None:
    """The verdict an exact result gives, or None when it gives none (incomplete and no violation);
    ``note`` says which system the exact search ran on when it was not the cone itself."""
    worst: Extreme | None = exact.worst.get(ob.target)
    best: Extreme | None = exact.best.get(ob.target) if ob.kind == "jitter" else None
    if worst is None or worst.value is None or (ob.kind == "jitter" and (best is None or best.value is None)):
        return None
    if ob.kind == "jitter":
        assert best is not None and best.value is not None  # (checked above)
        value = worst.value - best.value
    else:
        value = worst.value
    if value <= ob.spec:
        if not exact.complete:
            return None
        return ob.verdict("proved", exact.method, exact=value, exact_best=best.value if best else None,
                          explored=exact.explored, note=note)
    cex = _concrete(model, ob, exact, budget, value)
    if cex is None:
        return None
    if not exact.complete:  # a real violation, but the supremum is not established
        return ob.verdict("violated", exact.method, counterexample=cex, explored=exact.explored,
                          note="; ".join(filter(None, (note, "the exact search was incomplete (" + exact.reason
                                                       + "); the run shown is real"))))
    return ob.verdict("violated", exact.method, exact=value, exact_best=best.value if best else None,
                      counterexample=cex, explored=exact.explored, note=note)


def _concrete(model: SystemModel, ob: Obligation, exact: ExactResult, budget: Budget,
              value: Fraction) -> Counterexample | None:
    """A concrete run exceeding the spec, found by approaching the extreme (proof spec §4.5)."""
    grid = exact.grid or grid_of(model)
    t = ob.target
    # (``_from_exact`` found the extremes' values, and an extreme with a value has the run that reached it)
    worst = exact.worst[t].measured
    assert worst is not None
    if ob.kind != "jitter":
        m = approach(model, grid, worst, t, lambda x: x > ob.spec, value - ob.spec, "worst", budget)
        return None if m is None else Counterexample.of(t, m)
    best = exact.best[t].measured
    worst_value, best_value = exact.worst[t].value, exact.best[t].value
    assert best is not None and worst_value is not None and best_value is not None
    gap = (value - ob.spec) / 2
    hi = worst_value - gap
    lo = best_value + gap
    mw = approach(model, grid, worst, t, lambda x: x > hi, gap, "worst", budget)
    mb = approach(model, grid, best, t, lambda x: x < lo, gap, "best", budget)
    if mw is None or mb is None:
        return None
    return Counterexample.of(t, mw, mb)


def _search_cex(ob: Obligation, found: SearchResult) -> Counterexample | None:
    t = ob.target
    w: Measured | None = found.worst.get(t)
    if ob.kind == "jitter":
        b: Measured | None = found.best.get(t)
        if w is None or b is None:
            return None
        worst, best = w.values[t].worst, b.values[t].best  # (a run kept in a search result has its sample)
        if worst is not None and best is not None and worst.value - best.value > ob.spec:
            return Counterexample.of(t, w, b)
        return None
    if w is None:
        return None
    sample = w.values[t].worst
    if sample is None or not sample.value > ob.spec:
        return None
    return Counterexample.of(t, w)


# ------------------------------------------------------------------ diagnostics


def _spec_text(v: Verdict) -> str:
    if v.kind == "deadline":
        return f"deadline {fmt_time(v.spec)}"
    return f"`{v.kind} <= {fmt_time(v.spec)}`"


def _method_text(method: str) -> str:
    return {"bound": "the compositional bound", "refined-bound": "the bound with exact response times",
            "exact-enumeration": "exact enumeration",
            "exact-z3": "the exact Z3 search", "search": "a falsifying search"}[method]


def diagnostics(model: SystemModel, verdicts: Sequence[Verdict]) -> list[Diagnostic]:
    """E501 (violated spec), E503 (deadline miss), E502 (undecided), in verdict order."""
    sink = DiagnosticSink()
    undecided = sorted({_subject_target(v) for v in verdicts if v.status == "undecided"})
    # whether an exact search applies to the cone of each undecided subject (§4.0), all cones at once
    exact_applies = {t: exact_system(sub, members) is not None for sub, members in slices(model, undecided)
                     for t in members}
    for v in verdicts:
        if v.status == "proved":
            continue
        notes = []
        if v.bound is not None:
            notes.append(f"the compositional bound is {fmt_time(v.bound)}")
        elif v.subject == "task":
            notes.append("the response-time analysis finds no bound (E312)")
        else:
            notes.append("the compositional analysis gives no bound")
        if v.status == "violated":
            cex = v.counterexample
            assert cex is not None  # (every violation comes with its run)
            notes.append(f"established by {_method_text(v.method)}; the run replays in the reference "
                         "simulator (verify.sim)")
            if v.exact is not None:
                notes.append(f"exact worst case: {fmt_time(v.exact)}"
                             + (" (a supremum, approached by runs like this one)" if v.exact != cex.latency else ""))
            notes.append("scenario: " + cex.scenario.summary(model))
            notes.append(_sample_text(model, v, cex))
            if v.note:
                notes.append(v.note)
            if v.subject == "chain":
                sink.emit("E501", f"chain `{v.name}` violates {_spec_text(v)}: a run reaches {fmt_time(cex.latency)}",
                          v.span, f"{fmt_time(cex.latency)} > {fmt_time(v.spec)}",
                          secondary=[Label(span, text) for span, text in v.related], notes=notes,
                          help="see the run with `--trace-svg FILE` or `--format json`; relax the spec, "
                               "or shorten the periods or execution times along the chain")
            else:
                sink.emit("E503", f"`{v.name}` can miss its {_spec_text(v)}: a job responds after "
                          f"{fmt_time(cex.latency)}", v.span, f"responds after {fmt_time(cex.latency)}",
                          notes=notes, help="give it a higher priority, move interfering tasks to another "
                                            "core, or relax the deadline")
        else:
            notes.append(f"searched {v.explored} scenario{'s' * (v.explored != 1)} without a violation; "
                         f"not exact because {v.note}")
            what = f"chain `{v.name}`: {_spec_text(v)}" if v.subject == "chain" else f"`{v.name}`: {_spec_text(v)}"
            if exact_applies[_subject_target(v)]:  # an exact search applies to the cone, it did not finish
                sink.emit("E502", f"cannot decide {what} within the budget", v.span,
                          "neither proved nor refuted", notes=notes,
                          help="raise `--budget` (or `--timeout`), or tighten the model (constant execution "
                               "times and delays make the exact search apply)")
            else:  # outside the exact class: more budget only searches longer for a violation
                sink.emit("E502", f"cannot decide {what}: no exact method applies and no run violates it",
                          v.span, "neither proved nor refuted", notes=notes,
                          help="make the execution times and delays constant in the cone of this spec (its "
                               "tasks, the writers that trigger them, equal or higher priorities on their "
                               "cores, cooperative siblings: proof spec §4.0), and the exact search decides "
                               "it; or shorten periods and response times until the bound proves it")
    return sink.items


def _subject_target(v: Verdict) -> Target:
    """A target with the cone of the verdict's subject (any chain kind stands for its chain)."""
    return Target("response" if v.subject == "task" else "data_age", v.name)


def _sample_text(model: SystemModel, v: Verdict, cex: Counterexample) -> str:
    if v.subject == "task":
        r = cast(ResponseSample, cex.sample)  # (see ``Counterexample.of``: a task's sample is a response)
        end = "still running at the end of the run" if r.finish is None else f"completes at {fmt_time(r.finish)}"
        return f"job {r.task}#{r.index} is released at {fmt_time(r.release)} and {end}"
    s = cast(Sample, cex.sample)  # (a chain's sample is a ``verify.prove.sim.Sample``)
    chain = next(c for c in model.chains if c.name == v.name)
    first, last = chain.tasks[0], chain.tasks[-1]
    text = (f"from the read of {first}#{s.origin} at {fmt_time(s.begin)} to the completion of {last}#{s.last} "
            f"at {fmt_time(s.end)}: {fmt_time(s.value)}")
    if v.kind == "jitter":
        b = cast(Sample, cex.best_sample)  # (a jitter counterexample has a second run)
        text = (f"data age {fmt_time(s.value)} in one run and {fmt_time(b.value)} in another: jitter "
                f"{fmt_time(cex.latency)}")
    return text
