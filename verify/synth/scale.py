"""The integer scale of one problem: the tick (times) and the rate unit ``M`` (specs/synthesis.md §3).

Times are integers in *ticks*: the greatest common divisor of every time of the problem, so that the
same problem with every time scaled gives the same integers. Rates are integers in units of
``1/(M·tick)``, ``M`` a common multiple of the denominators every rate can have (propagated through
triggers), so that ``k·f_reader = f_writer`` for a prescaler ``k`` stays integral.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from fractions import Fraction

from ..model.system import SystemModel, TaskModel
from ..core.timebase import TimeBase
from .candidates import Choice
from .structure import Structure, activation_options, member_links


def problem_times(model: SystemModel, choices: Mapping[str, Choice]) -> list[Fraction]:
    times: list[Fraction | None] = []
    for t in model.tasks:
        times += [t.wcet, t.bcet, t.deadline, t.wcrt_bound]
        act = t.activation
        if act.gaps is not None:
            times += [*act.gaps, act.fixed_phase]
    for lk in model.links:
        times += [lk.delay_min, lk.delay_max]
    for ch in model.chains:
        times += [ch.reaction_time, ch.data_age, ch.jitter]
    for ex in model.executors:  # (a multi-threaded executor's bounds divide work by its workers, §9.4)
        if ex.multi_threaded:
            times += [c / len(ex.workers) for t in model.callbacks(ex.name) for c in (t.wcet, t.bcet)]
    for choice in choices.values():
        for c in choice.candidates:
            times += [c.activation.strict_period, c.activation.fixed_phase]
    return [x for x in times if x]


def tick_of(model: SystemModel, choices: Mapping[str, Choice]) -> Fraction:
    """The largest time of which every time of the problem is a whole multiple."""
    return TimeBase.gcd_of(problem_times(model, choices), default=Fraction(1, 1000)).unit


def rate_scale(model: SystemModel, choices: Mapping[str, Choice], structure: Structure, tick: Fraction) -> int:
    """M: a common multiple of the denominators of every possible rate (per tick)."""
    den: dict[str, int] = {}

    def of(task: TaskModel) -> int:
        value = 1
        for _, act in activation_options(task, choices.get(task.id)):
            if act.gaps is not None:
                d = math.lcm(int(act.gaps[0] / tick), int(act.gaps[1] / tick))
            elif act.trigger_port is not None:
                d = act.release_every
                for _, link in member_links(model, task, act):
                    if link is not None:
                        d = math.lcm(d, den.get(link.writer, 1) * act.release_every)
            else:
                d = 1
            value = math.lcm(value, d)
        return value

    rounds = {tid: (len(structure.cyclic) + 1 if tid in structure.cyclic else 1) for tid in structure.order}
    for _ in range(max(rounds.values(), default=1)):
        for tid in structure.order:
            if rounds[tid] > 0:
                den[tid] = math.lcm(den.get(tid, 1), of(model.task(tid)))
                rounds[tid] -= 1
    scale = 1
    for d in den.values():
        scale = math.lcm(scale, d)
    return scale
