"""Response-time lower bounds every configuration respects (specs/synthesis.md §2, "schedulability").

``first_job_bounds`` is the first job of the level-i busy window over all candidates: pruning drops a
timer candidate whose period is below it, and the encoding bounds every ``R`` below by it.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from fractions import Fraction

from ..model.system import SystemModel, TaskModel
from .candidates import Choice
from .structure import activation_options


def first_job_bounds(model: SystemModel, choices: Mapping[str, Choice], *,
                     relaxed: bool = False) -> dict[str, Fraction]:
    """A response-time lower bound per task, valid in every configuration: the first job of the
    level-i busy window (specs/timing.md §6.2), ``w = C + Σ_{hp} η·C`` with ``η = ⌈w / T_max⌉`` for
    an interferer that is a timer in every configuration (``T_max`` its longest candidate period) and
    1 otherwise (every interferer is activated at least once in a window, and a causal cap is at
    least 1), and 0 for a task on its pipeline path in some configuration (``_possible_upstream``:
    the pipeline release offsets of §6.2 may leave it no job in the window). For a callback of an
    executor, every bound of §9.3 counts each other callback of its executor and each higher thread at
    least once: ``C + Σ C``; of a multi-threaded one, ``multi_threaded_floor``. ``relaxed`` (tracked
    problems): an execution time may fall to ``bcet`` and a task may leave its core, so only the
    task's own ``bcet`` is certain."""
    if relaxed:
        return {t.id: t.bcet for t in model.tasks}
    out: dict[str, Fraction] = {}
    by_core: dict[str, list[TaskModel]] = {}
    for t in model.tasks:
        by_core.setdefault(t.core, []).append(t)
    for tasks in by_core.values():
        cost = [t.bcet if relaxed else t.wcet for t in tasks]
        periods = []
        for t in tasks:
            acts = [a for _, a in activation_options(t, choices.get(t.id))]
            strict = [a.strict_period for a in acts]
            known = [p for p in strict if p is not None]
            periods.append(max(known) if len(known) == len(strict) else None)
        scale = 1
        for x in cost + [p for p in periods if p is not None]:
            scale = math.lcm(scale, x.denominator)
        c = [int(x * scale) for x in cost]
        per = [int(p * scale) if p is not None else None for p in periods]
        limit = max([p for p in per if p is not None], default=scale) * 1000
        for n, t in enumerate(tasks):
            if t.executor is not None and model.executor(t.executor).multi_threaded:
                out[t.id] = multi_threaded_floor(model, t)
                continue
            if t.executor is not None:  # a callback (§9.3): each other callback and higher thread once
                others = [m for m, o in enumerate(tasks) if m != n and (o.priority > t.priority
                                                                      or o.executor == t.executor)]
                out[t.id] = Fraction(c[n] + sum(c[m] for m in others), scale)
                continue
            # (a task upstream of t on a pipeline may have no job in the window: timing.pipeline)
            ahead = _possible_upstream(model, choices, t)
            hp = [m for m, o in enumerate(tasks) if m != n and o.priority >= t.priority and o.id not in ahead]
            w = c[n] + sum(c[m] for m in hp)
            for _ in range(1000):
                new = c[n] + sum(c[m] * _jobs(w, per[m]) for m in hp)
                if new == w or new > limit:
                    break
                w = new
            out[t.id] = Fraction(max(w, c[n]), scale)
    return out


def _jobs(window: int, period: int | None) -> int:
    """The jobs of a task of ``period`` ticks in a window of ``window`` ticks (one without a period)."""
    return -(-window // period) if period else 1


def multi_threaded_floor(model: SystemModel, task: TaskModel) -> Fraction:
    """A lower bound of the bound of §9.4 for a callback of a multi-threaded executor, in every
    configuration: ``Cᵢ + B + (the m largest C)/m`` (the jobs of the window's other callbacks are not
    certain: a callback may be silent)."""
    from ..timing.multithreaded import carry_in, group_blocking

    name = task.executor
    assert name is not None  # (a callback)
    executor = model.executor(name)
    blocking, _ = group_blocking(model, task, executor)
    workers = len(executor.workers)
    return task.wcet + (blocking or Fraction(0)) + carry_in(model, model.callbacks(executor.name), workers) / workers


def _possible_upstream(model: SystemModel, choices: Mapping[str, Choice], task: TaskModel) -> set[str]:
    """The tasks that are on ``task``'s pipeline path (``verify.timing.pipeline.upstream``) in some
    configuration: writers reached back through single-port triggers of any candidate, without delay,
    on ``task``'s core at a higher priority (a superset: tokens and the depth limit are ignored)."""
    found: set[str] = set()
    todo = [task]
    while todo:
        reader = todo.pop()
        for _, act in activation_options(reader, choices.get(reader.id)):
            port = act.single_port
            link = None if port is None else model.link_into(f"{reader.instance}.{port}")
            if link is None or link.delay_max != 0 or link.writer in found:
                continue
            writer = model.task(link.writer)
            if writer.core == task.core and writer.priority > task.priority:
                found.add(writer.id)
                todo.append(writer)
    return found
