"""A cheap repair before the solver: speed up what the failing chains depend on (specs/synthesis.md §4).

When a configuration fails only latency specs and activation constraints, the decisions that can
help are the activations of the chains' own tasks (of the too slow tasks) and of the tasks whose
outputs trigger them. ``repair`` moves
each of those decisions to the fastest candidate of its group (shortest period, prescaler 1) and
analyses the result, for a few rounds (a sped-up writer can make another chain fail). A triggered
task outside its activation constraint gets the largest prescaler that fits its writers' current
rate (a faster writer would speed up every other reader too); only one that cannot fit is sped up
through what triggers it. It is a
heuristic and claims nothing on its own: a configuration it returns was accepted by the
independent analysis like every other answer, and when it finds none the solver decides.
"""
from __future__ import annotations

from collections.abc import Iterable

from ..model.system import SystemModel
from .candidates import Choice
from .problem import Config, Evaluation, Problem
from .structure import member_links

ROUNDS = 6


def rate_misses(problem: Problem, ev: Evaluation) -> tuple[set[str], set[str]]:
    """(tasks activated below their minimum rate, tasks activated above their maximum) in ``ev``."""
    below: set[str]
    above: set[str]
    below, above = set(), set()
    for t in problem.model.tasks:
        rate = ev.result.task(t.id).rate
        if rate is not None and t.min_rate is not None and rate.low < t.min_rate:
            below.add(t.id)
        if rate is not None and t.max_rate is not None and rate.high > t.max_rate:
            above.add(t.id)
    return below, above


def fitted_prescaler(problem: Problem, ev: Evaluation, tid: str, index: int) -> int | None:
    """The candidate of the trigger group of ``index`` with the largest prescaler that puts the task
    within its activation constraint at its writers' current rate; None if there is none."""
    choice, task = problem.choices[tid], problem.model.task(tid)
    current, rate = choice.candidates[index], ev.result.task(tid).rate
    if current.activation.trigger_port is None or rate is None:
        return None
    k = current.activation.release_every
    low, high = rate.low * k, rate.high * k  # the writers' rate
    every = [c.activation.release_every for c in choice.candidates]
    fitting = [i for i, c in enumerate(choice.candidates) if c.group == current.group
               and (task.min_rate is None or low / every[i] >= task.min_rate)
               and (task.max_rate is None or high / every[i] <= task.max_rate)]
    return max(fitting, key=lambda i: every[i]) if fitting else None


def upstream(model: SystemModel, tasks: Iterable[str]) -> set[str]:
    """``tasks`` and every task whose output triggers one of them, transitively, in ``model``."""
    seen, stack = set(), list(tasks)
    while stack:
        tid = stack.pop()
        if tid in seen:
            continue
        seen.add(tid)
        task = model.task(tid)
        if task.activation.trigger_port is not None:
            stack += [link.writer for _, link in member_links(model, task, task.activation) if link is not None]
    return seen


def fastest_in_group(choice: Choice, index: int) -> int:
    """The fastest candidate of the group of ``index`` (candidates of a group are sorted fastest first)."""
    group = choice.candidates[index].group
    while index > 0 and choice.candidates[index - 1].group == group:
        index -= 1
    return index


def repair(problem: Problem, config: Config, ev: Evaluation) -> tuple[Config, Evaluation] | None:
    """An accepted configuration reached from ``config`` by speeding up the failing chains, or None."""
    for _ in range(ROUNDS):
        failing = {c.name for c in ev.result.chains if any(not s.ok for s in c.specs)}
        step = speed_up(problem, config, ev, failing)
        if step is None:
            return None
        config, ev = step
        if ev.accepted:
            return config, ev
    return None


def speed_up(problem: Problem, config: Config, ev: Evaluation, chains: set[str]) -> tuple[Config, Evaluation] | None:
    """One round: the tasks of ``chains`` and what triggers them at their fastest, triggered tasks
    outside their activation constraint refitted; None when nothing changes or speeding up cannot cure
    what ``ev`` failed for."""
    if any(not r.startswith(("chain `", "E305:")) for r in ev.reasons):
        return None  # overload, sampling, a fixed rate: speeding up does not cure those
    choice = dict(config.choice)
    chained = {tid for chain in problem.model.chains if chain.name in chains for tid in chain.tasks}
    for tid in sorted(upstream(ev.model, sorted(chained)) & problem.choices.keys()):
        choice[tid] = fastest_in_group(problem.choices[tid], choice[tid])
    below, above = rate_misses(problem, ev)
    for tid in sorted(below | above):
        fitted = fitted_prescaler(problem, ev, tid, choice[tid]) if tid in choice else None
        if fitted is not None:
            choice[tid] = fitted
        elif tid in above:
            return None
        else:  # a timer or a fixed binding too slow for its constraint: speed up what triggers it
            for up in sorted(upstream(ev.model, [tid]) & problem.choices.keys()):
                choice[up] = fastest_in_group(problem.choices[up], choice[up])
    faster = Config(tuple((tid, choice[tid]) for tid, _ in config.choice), config.off)
    if faster == config:
        return None
    return faster, problem.evaluate(faster)


def fastest_chain(problem: Problem, chain: str) -> tuple[Config, Evaluation] | None:
    """An accepted configuration with ``chain`` as fast as the seed allows: its tasks (and what
    triggers them) at their fastest candidates, the rest at the seed's, refitted for a few rounds."""
    config, ev = problem.seed()
    for n in range(ROUNDS):
        step = speed_up(problem, config, ev, {chain} if n == 0 else set())
        if step is None:
            return None
        config, ev = step
        if ev.accepted:
            return config, ev
    return None
