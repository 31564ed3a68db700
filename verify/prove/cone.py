"""The cone of an obligation: the tasks whose choices can change its samples (specs/proof.md §4.0).

A job of task ``x`` is released by its own timer or sporadic source, or by arrivals on its trigger
ports, whose messages come from the writers of those ports; it is scheduled on its core against the
jobs of equal or higher priority (a lower-priority job never delays it under preemptive
fixed-priority scheduling); if it is cooperative, it waits for the token of its instance, held by the
cooperative siblings. A chain's samples follow values along its hops, whose writers are chain tasks.
The **cone** of an obligation is the least set of tasks holding the obligation's own tasks (the
chain's tasks, or the task of a deadline) and closed under these three dependencies. The run of the
cone's tasks depends only on the choices (phases, execution times, delays, counters) of the cone:
every run of the system restricted to the cone is a run of the cone's subsystem (``restrict``), and
every run of the subsystem is the restriction of runs of the system — whatever the tasks outside do.
Extremes over the subsystem's runs are therefore those over the system's: the exact search, the
falsifying search and the exact class (a sporadic task, an execution-time range, a trigger cycle)
only look at the cone.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from fractions import Fraction
from typing import TYPE_CHECKING

from ..model.system import SystemModel, TaskModel
from .intsim import IntSimulator, samples_at
from .scenario import ConcreteScenario, ResponseSample, Target
from .sim import DEFAULT_MAX_EVENTS, Sample

if TYPE_CHECKING:
    from .verdict import Counterexample


class ConeIndex:
    """What ``cone`` needs of a system, built once for all of its obligations: per core its tasks by
    priority, highest first; per instance its cooperative tasks; per task its trigger writers."""

    def __init__(self, model: SystemModel):
        self.by_core: dict[str, list[TaskModel]] = {}
        self.siblings: dict[str, list[str]] = {}
        self.writers: dict[str, list[str]] = {}
        for t in model.tasks:
            self.by_core.setdefault(t.core, []).append(t)
            if t.kind == "cooperative":
                self.siblings.setdefault(t.instance, []).append(t.id)
            act = t.activation
            if act.trigger_port is not None:
                links = (model.link_into(f"{t.instance}.{m}") for m in act.trigger_members)
                self.writers[t.id] = [lk.writer for lk in links if lk is not None]
        for tasks in self.by_core.values():
            tasks.sort(key=lambda t: -t.priority)  # (stable: system order among equals)
        self.tasks: dict[str, TaskModel] = {t.id: t for t in model.tasks}

    def cone(self, roots: list[str]) -> frozenset[str]:
        found = set(roots)
        todo = list(roots)
        reached = dict.fromkeys(self.by_core, 0)  # per core: how many of its tasks (a prefix) are in
        while todo:
            task = self.tasks[todo.pop()]
            depends = list(self.writers.get(task.id, ()))
            if task.kind == "cooperative":
                depends += self.siblings[task.instance]
            # the tasks of equal or higher priority on the core: a prefix of its list, taken once
            on_core, k = self.by_core[task.core], reached[task.core]
            while k < len(on_core) and on_core[k].priority >= task.priority:
                depends.append(on_core[k].id)
                k += 1
            reached[task.core] = k
            for other in depends:
                if other not in found:
                    found.add(other)
                    todo.append(other)
        return frozenset(found)


def cone(model: SystemModel, roots: list[str], index: ConeIndex | None = None) -> frozenset[str]:
    """The least set of task ids holding ``roots`` and closed under trigger writers, same-core tasks
    of equal or higher priority, and cooperative siblings."""
    return (index or ConeIndex(model)).cone(roots)


def restrict(model: SystemModel, tasks: frozenset[str], chains: set[str]) -> SystemModel:
    """The subsystem of ``tasks`` (in system order) with the connections between them and the chains
    named in ``chains``. A connection from outside into one of its tasks is left out: by the closure
    of ``cone`` it ends on a port that triggers nothing and carries no chain, so it changes no
    timing and no sample."""
    kept = [t for t in model.tasks if t.id in tasks]
    links = []
    for lk in model.links:
        readers = tuple(r for r in lk.readers if r in tasks)
        if lk.writer in tasks and readers:
            links.append(lk if readers == lk.readers else type(lk)(lk.source, lk.target, lk.writer, readers,
                                                                   lk.delay_min, lk.delay_max, lk.span,
                                                                   lk.message_type))
    instances = {t.instance for t in kept}
    executors = tuple(e for e in model.executors if any(t.executor == e.name for t in kept))
    cores = {t.core for t in kept} | {c for e in executors for c in e.workers}
    used = tuple(i for i in model.instances if i.name in instances)
    components = {i.component for i in used}
    return SystemModel(model.name, tuple(c for c in model.cores if c.name in cores), tuple(kept), tuple(links),
                       tuple(c for c in model.chains if c.name in chains), model.span,
                       tuple(c for c in model.compounds if c.instance in instances), used,
                       tuple(c for c in model.components if c.name in components),
                       tuple(p for p in model.ports if p.instance in instances),
                       executors, tuple(g for g in model.groups if g.executor in {e.name for e in executors}))


def slices(model: SystemModel, targets: list[Target]) -> list[tuple[SystemModel, list[Target]]]:
    """The targets grouped by cone, each group with its subsystem (groups in the order of their first
    target; the whole model itself when a cone is the whole system)."""
    groups: dict[frozenset[str], list[Target]] = {}
    index = ConeIndex(model)
    chains = {c.name: c for c in model.chains}
    for t in targets:
        roots: list[str] = [t.name] if t.kind == "response" else list(chains[t.name].tasks)
        groups.setdefault(index.cone(roots), []).append(t)
    out = []
    for tasks, members in groups.items():
        if len(tasks) == len(model.tasks):
            out.append((model, members))
        else:
            out.append((restrict(model, tasks, {t.name for t in members if t.kind != "response"}), members))
    return out


class SliceMismatch(AssertionError):
    """A run of a cone's subsystem whose sample the whole system does not reproduce (a bug)."""


class Replays:
    """Runs of the whole ``model`` by the integer simulator, one per scenario, each made as far as the
    samples asked of it need and taken further when a later question needs more: a scenario that
    several cones' counterexamples share (the first scenarios of their searches, run on the union of
    the cones) is run on the whole system once, not once per cone."""

    def __init__(self, model: SystemModel):
        self.model = model
        self.runs: dict[ConcreteScenario, IntSimulator] = {}

    def samples(self, scenario: ConcreteScenario, targets: Iterable[Target],
                end: Fraction | None) -> dict[Target, list[ResponseSample] | list[Sample]]:
        """The samples of ``targets`` in the run of ``scenario`` up to its horizon, or with ``end`` up to
        just after ``end`` (the run then holds every sample that ends by ``end``, as ``target_samples``
        of the scenario cut there gives them)."""
        sim = self.runs.get(scenario)
        if sim is None:
            sim = IntSimulator.of(self.model, scenario, DEFAULT_MAX_EVENTS, (scenario.horizon,))
        horizon = sim.base.ticks(scenario.horizon)
        until = horizon if end is None else min(horizon, math.floor(end / sim.unit) + 1)
        self.runs.pop(scenario, None)  # (a run that fails on the way is not kept)
        if until > sim.now:
            sim.run_to(until)
        self.runs[scenario] = sim
        return samples_at(sim, self.model, targets, max(until, sim.now))


def check_all_carry_over(model: SystemModel, cexs: Iterable[Counterexample], replays: Replays | None = None) -> None:
    """Replay counterexamples found on a subsystem on the whole ``model``: the same scenario (tasks
    outside the cone take the simulator's defaults) must hold the same sample(s). One run of the
    whole system per distinct scenario, up to the last sample it must hold, by the integer simulator
    (``intsim``: the samples the reference simulator's trace gives, at a fraction of its cost on a
    large system), kept in ``replays`` (of ``model``) for the counterexamples of other cones;
    ``SliceMismatch`` if a sample is missing."""
    replays = replays if replays is not None else Replays(model)
    wanted: dict[ConcreteScenario, list[tuple[Target, object]]] = {}  # scenario -> [(target, sample)]
    for cex in cexs:
        for scenario, sample in ((cex.scenario, cex.sample), (cex.best_scenario, cex.best_sample)):
            if scenario is not None:
                wanted.setdefault(scenario, []).append((cex.target, sample))
    for scenario, pairs in wanted.items():
        ends = [_end(sample) for _target, sample in pairs]
        last = max(end for end in ends if end is not None) if None not in ends else None
        samples = replays.samples(scenario, sorted({t for t, _ in pairs}), last)
        for target, sample in pairs:
            if sample not in samples[target]:
                raise SliceMismatch(f"the run of the cone of {target} does not carry over to `{model.name}`")


def _end(sample: object) -> Fraction | None:
    """The last event of a counterexample's ``sample``: a chain sample's end, a response sample's finish."""
    if isinstance(sample, ResponseSample):
        return sample.finish
    return sample.end if isinstance(sample, Sample) else None
