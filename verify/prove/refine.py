"""The compositional bound with exact response times (specs/proof.md §4.8).

An obligation the exact methods cannot decide on its cone (ranges in a chain's cone, say) may still
be proved by the analysis once it builds on better response times. Every task in the cones of such
obligations whose own deadline cone has an exact system (the cone itself in the exact class, or a
dominating rigid system, §4.7) gets its exact worst-case response time by enumeration; where that is
below the analysis' WCRT it enters the analysis as a user bound does (timing.md §6.2: a promise every
bound builds on — here a proved one), and the analysis is run again. An obligation whose recomputed
bound meets its spec is *proved* by method ``refined-bound``.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction

from ..model.system import SystemModel
from ..timing import TaskResponse, response_and_chain_bounds
from ..model.units import fmt_time
from . import bound as bound_mod
from .bound import Obligation
from .cone import ConeIndex, slices
from .dominant import Dominant, exact_system
from .exact import Budget, enumerate_exact
from .scenario import Target
from .verdict import Verdict


@dataclass(frozen=True)
class Refinement:
    """Exact worst-case response times below the analysis' (``exact``: task id -> value) and the
    bound of every obligation recomputed with them (``bounds``: (name, kind) -> bound or None)."""

    exact: dict[str, Fraction]
    bounds: dict[tuple[str, str], Fraction | None]


def refine(model: SystemModel, open_: Sequence[Obligation], responses: Mapping[str, TaskResponse], variant: str,
           budget: Budget, jobs: int | None = None) -> Refinement | None:
    """The bounds of ``open_`` recomputed with the exact response times of the tasks in their cones,
    spending at most half of the ``budget`` left on the enumerations (None: no response time improved).
    Only the obligations that the bound could prove if every such task responded within its ``wcet``
    have their cones enumerated: a smaller response time is never found, so the others stay open."""
    eligible = {tid: sub for tid, sub in exact_cones(model, in_cones(model, open_)).items()
                if _above_wcet(responses[tid].wcrt, model.task(tid).wcet)}
    if not eligible:
        return None
    optimistic = _bounds(with_responses(model, {tid: model.task(tid).wcet for tid in eligible}), variant)
    hopeful = [ob for ob in open_ if (b := optimistic.get((ob.name, ob.kind))) is not None and b <= ob.spec]
    wanted = in_cones(model, hopeful)
    exact = exact_responses({tid: sub for tid, sub in eligible.items() if tid in wanted}, responses, budget, jobs)
    if not exact:
        return None
    return Refinement(exact, _bounds(with_responses(model, exact), variant))


def _above_wcet(wcrt: Fraction | None, wcet: Fraction) -> bool:
    """A response-time bound an exact value might improve: one at the ``wcet`` cannot be, since a job
    may run for its ``wcet``."""
    return wcrt is None or wcet < wcrt


def _bounds(model: SystemModel, variant: str) -> dict[tuple[str, str], Fraction | None]:
    variant, responses, chains = response_and_chain_bounds(model, data_age=variant)
    return {(ob.name, ob.kind): ob.bound for ob in bound_mod.obligations(model, variant, responses, chains)}


def in_cones(model: SystemModel, obligations: Sequence[Obligation]) -> frozenset[str]:
    """The tasks in the cones of ``obligations`` (a chain's, or a deadline's task's)."""
    index = ConeIndex(model)
    chains = {c.name: c for c in model.chains}
    wanted: set[str] = set()
    for ob in obligations:
        wanted |= index.cone([ob.name] if ob.subject == "task" else list(chains[ob.name].tasks))
    return frozenset(wanted)


def with_responses(model: SystemModel, exact: Mapping[str, Fraction]) -> SystemModel:
    """``model`` with the response times ``exact`` as the tasks' user bounds (timing.md §6.2)."""
    return replace(model, tasks=tuple(replace(t, wcrt_bound=exact[t.id]) if t.id in exact else t
                                      for t in model.tasks))


def exact_cones(model: SystemModel, tasks: frozenset[str]) -> dict[str, Dominant]:
    """Task id -> the exact system of its deadline cone (§4.1, §4.7), for those of ``tasks`` that
    have one (in system order)."""
    targets = [Target("response", t.id) for t in model.tasks if t.id in tasks]
    out: dict[str, Dominant] = {}
    for sub, members in slices(model, targets):
        system = exact_system(sub, members)
        if system is not None:
            out.update((t.name, system) for t in members)
    return {t.id: out[t.id] for t in model.tasks if t.id in out}


def exact_responses(cones: Mapping[str, Dominant], responses: Mapping[str, TaskResponse], budget: Budget,
                    jobs: int | None = None) -> dict[str, Fraction]:
    """Task id -> exact worst-case response time, for the tasks of ``cones`` (id -> the exact system
    of its deadline cone) whose exact value is below the analysis' WCRT (a user bound included),
    spending at most half of the ``budget`` left; tasks sharing a system share its enumeration."""
    groups: dict[int, tuple[Dominant, list[Target]]] = {}
    for tid, system in cones.items():
        groups.setdefault(id(system), (system, []))[1].append(Target("response", tid))
    own = Budget(budget.left // 2, budget.deadline)
    out: dict[str, Fraction] = {}
    for system, members in groups.values():
        found = enumerate_exact(system.model, members, own, jobs=jobs)
        if found is None or not found.complete:
            continue
        for target in members:
            value = found.worst[target].value
            known = responses[target.name].wcrt
            if value is not None and (known is None or value < known):
                out[target.name] = value
    budget.spend(own.used)
    return {tid: out[tid] for tid in cones if tid in out}


def verdict(ob: Obligation, refinement: Refinement) -> Verdict | None:
    """The obligation proved by its recomputed bound, or None."""
    bound = refinement.bounds.get((ob.name, ob.kind))
    if bound is None or bound > ob.spec:
        return None
    shown = [f"`{t}` {fmt_time(v)}" for t, v in refinement.exact.items()]
    used = ", ".join(shown[:4]) + (f" and {len(shown) - 4} more" if len(shown) > 4 else "")
    return ob.verdict("proved", "refined-bound", refined=bound,
                      note=f"the compositional bound with the exact worst-case response times {used} "
                           "(proof spec §4.8)")
