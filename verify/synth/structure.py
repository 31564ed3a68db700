"""The shape of a synthesis problem: trigger edges over every candidate, and dependency cones.

* The *union trigger graph* has an edge ``w → t`` whenever some activation ``t`` may take (its fixed
  one or any candidate) is triggered by an in-port ``w`` writes. Values flow along it (rates, event
  models); ``order`` lists every task with writers first (ties and cycles broken by task id).
* The *dependency cone* of a task is every decision its response time can depend on (specs/timing.md
  §6): its own event model, the event models of the tasks of higher or equal priority on its core,
  the response times of cooperative tasks it waits for, and, through the event model of a triggered
  task, its writers' event models and response times, transitively. A lemma about a task's response
  time mentions only the decisions in its cone.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TypeAlias
from collections.abc import Mapping

import networkx as nx

from ..model.activations import Activation
from ..model.system import LinkModel, SystemModel, TaskModel
from .candidates import Choice

#: a node of the dependency graph: ("em", task), ("r", task) or ("hp", core, priority)
DepNode: TypeAlias = "tuple[str, str] | tuple[str, str, int]"


def activation_options(task: TaskModel, choice: Choice | None) -> list[tuple[int | None, Activation]]:
    """(candidate index or None, activation model) for every activation ``task`` may take."""
    if choice is None:
        return [(None, task.activation)]
    return list(enumerate(choice.activations))


def member_links(model: SystemModel, task: TaskModel, act: Activation) -> list[tuple[str, LinkModel | None]]:
    """(member in-port, connection into it or None) of a data-triggered activation."""
    return [(m, model.link_into(f"{task.instance}.{m}")) for m in act.trigger_members]


@dataclass(frozen=True)
class Structure:
    order: tuple[str, ...]
    cyclic: frozenset[str]  # tasks on a cycle of the union trigger graph
    trigger_edges: tuple[tuple[str, str, int | None], ...]  # (writer, reader, candidate index or None)
    cones: Mapping[str, int]  # task id -> bitset of atoms (see ``dependency_cones``)
    exact_only: frozenset[str]  # choices whose lemmas must name the exact candidate (AND feeders)


def trigger_graph(model: SystemModel,
                  choices: Mapping[str, Choice]) -> tuple[nx.DiGraph[str], list[tuple[str, str, int | None]]]:
    graph: nx.DiGraph[str] = nx.DiGraph()
    graph.add_nodes_from(sorted(t.id for t in model.tasks))
    edges: list[tuple[str, str, int | None]] = []
    for task in sorted(model.tasks, key=lambda t: t.id):
        for index, act in activation_options(task, choices.get(task.id)):
            for _, link in member_links(model, task, act):
                if link is not None:
                    graph.add_edge(link.writer, task.id)
                    edges.append((link.writer, task.id, index))
    return graph, edges


def topological(graph: nx.DiGraph[str]) -> tuple[tuple[str, ...], frozenset[str]]:
    """Every node, writers before readers; the members of a cycle together, by id."""
    condensed = nx.condensation(graph)
    cyclic: set[str] = set()
    order: list[str] = []
    for scc in nx.lexicographical_topological_sort(condensed, key=lambda n: min(condensed.nodes[n]["members"])):
        members = sorted(condensed.nodes[scc]["members"])
        if len(members) > 1 or graph.has_edge(members[0], members[0]):
            cyclic.update(members)
        order.extend(members)
    return tuple(order), frozenset(cyclic)


def dependency_graph(model: SystemModel, trigger: nx.DiGraph[str]) -> nx.DiGraph[DepNode]:
    """What a response time depends on (specs/timing.md §5.2, §6): nodes ("em", t) for the event model
    of t, ("r", t) for its response time, ("hp", core, priority) for "the event models of every task
    of that core at this priority or higher". Edges: em(w), r(w) → em(t) for every trigger writer w
    of t; em(t) → r(t); hp(core, p(t)) → r(t); em(t) → hp(core, p(t)); hp level → next lower level;
    and r(j) → r(i) where i's analysis reads j's response time: a cooperative sibling, a
    cooperative task of higher priority (its suspension jitter), or a task above the thread of i's
    executor (the polling-round bound of specs/timing.md §9.3). A callback of a multi-threaded
    executor whose bound counts the other callbacks' jobs without their activations (§9.4) depends on
    their execution times alone: ("wc", j) → r(i) for each other callback j instead of hp → r(i)."""
    graph: nx.DiGraph[DepNode] = nx.DiGraph()
    capped = _capped_callbacks(model)
    for w, r in trigger.edges:
        graph.add_edge(("em", w), ("em", r))
        graph.add_edge(("r", w), ("em", r))
    by_core: dict[str, list[TaskModel]] = {}
    for t in model.tasks:
        graph.add_edge(("em", t.id), ("r", t.id))
        by_core.setdefault(t.core, []).append(t)
    for core, tasks in by_core.items():
        levels = sorted({t.priority for t in tasks}, reverse=True)
        for higher, lower in zip(levels, levels[1:]):
            graph.add_edge(("hp", core, higher), ("hp", core, lower))
        for t in tasks:
            graph.add_edge(("em", t.id), ("hp", core, t.priority))
            if t.id in capped:
                graph.add_edges_from((("wc", j.id), ("r", t.id)) for j in capped[t.id])
            else:
                graph.add_edge(("hp", core, t.priority), ("r", t.id))
    for t in model.tasks:
        if t.executor is not None:
            for h in by_core[t.core]:
                if h.priority > t.priority:
                    graph.add_edge(("r", h.id), ("r", t.id))
    coop: dict[str, list[TaskModel]] = {}
    for t in model.tasks:
        if t.kind == "cooperative":
            coop.setdefault(t.instance, []).append(t)
    for sibs in coop.values():
        if len(sibs) < 2:
            continue
        for a in sibs:
            for b in model.tasks_on(a.core):
                if b.priority <= a.priority and b.id != a.id:
                    graph.add_edge(("r", a.id), ("r", b.id))  # suspension jitter of a, seen below it
            for b in sibs:
                if a.id != b.id:
                    graph.add_edge(("r", a.id), ("r", b.id))
                    graph.add_edge(("hp", a.core, a.priority), ("r", b.id))  # a's hold time
    return graph


def _capped_callbacks(model: SystemModel) -> dict[str, tuple[TaskModel, ...]]:
    """The callbacks of multi-threaded executors whose bound (§9.4) does not follow the other callbacks'
    activations, with those other callbacks."""
    from ..timing.multithreaded import group_blocking

    out: dict[str, tuple[TaskModel, ...]] = {}
    for ex in model.executors:
        if not ex.multi_threaded:
            continue
        members = model.callbacks(ex.name)
        for t in members:
            blocking, why = group_blocking(model, t, ex)
            if blocking is not None and why != "siblings":
                out[t.id] = tuple(m for m in members if m.id != t.id)
    return out


def dependency_cones(graph: nx.DiGraph[DepNode], atoms: Mapping[str, int],
                     choice_bits: Mapping[str, int] | None = None) -> dict[str, int]:
    """Per task: the OR of ``atoms`` (attached to the task's event model) over everything its
    response time depends on; a ("wc", t) node carries t's atoms without its choice (``choice_bits``)."""
    condensed = nx.condensation(graph)
    bits: dict[int, int] = {}
    for scc in nx.topological_sort(condensed):
        value = 0
        for m in condensed.nodes[scc]["members"]:
            if m[0] == "em":
                value |= atoms.get(m[1], 0)
            elif m[0] == "wc":
                value |= atoms.get(m[1], 0) & ~(choice_bits or {}).get(m[1], 0)
        for pred in condensed.predecessors(scc):
            value |= bits[pred]
        bits[scc] = value
    mapping = condensed.graph["mapping"]
    return {node[1]: bits[mapping[node]] for node in graph.nodes if node[0] == "r"}


def and_feeders(model: SystemModel, choices: Mapping[str, Choice], trigger: nx.DiGraph[str]) -> frozenset[str]:
    """Choices upstream (inclusive) of a writer into an AND compound: the minimum-distance model of an
    AND join follows its slowest member (specs/timing.md §5.2), which is not monotone in the members'
    periods, so lemmas generalise only to the exact candidate there (specs/synthesis.md §4)."""
    writers: set[str] = set()
    for task in model.tasks:
        for _, act in activation_options(task, choices.get(task.id)):
            if act.all_members:
                writers.update(link.writer for _, link in member_links(model, task, act) if link is not None)
    upstream: set[str] = set(writers)
    for w in writers:
        upstream |= nx.ancestors(trigger, w)
    return frozenset(t for t in upstream if t in choices)


def analyse_structure(model: SystemModel, choices: Mapping[str, Choice], atoms: Mapping[str, int]) -> Structure:
    trigger, edges = trigger_graph(model, choices)
    order, cyclic = topological(trigger)
    choice_bits = {tid: 1 << n for n, tid in enumerate(choices)}  # (``problem._atoms``: choices first)
    cones = dependency_cones(dependency_graph(model, trigger), atoms, choice_bits)
    return Structure(order, cyclic, tuple(edges), cones, and_feeders(model, choices, trigger))
