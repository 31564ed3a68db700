"""Exhaustive enumeration: the ground truth of small problems (specs/synthesis.md §7).

Every combination of the (pruned) candidates is analysed by ``Problem.evaluate`` — the analysis itself
— and the best accepted one by a key is kept. ``brute_force`` (the baseline of the property tests and
the benchmarks) enumerates the unpruned problem; ``synthesize`` enumerates the pruned one when the
solver has not decided it (its budget ran out) or answered that no configuration exists, and the
space holds at most ``EXHAUSTIVE_LIMIT`` configurations: a small problem is always decided, and an
"unsat" answer on it is the analysis' own verdict on every configuration.
"""
from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

from .problem import Config, Evaluation, Problem

#: the most candidate configurations ``synthesize`` enumerates when the solver leaves a problem open
EXHAUSTIVE_LIMIT = 10_000

#: a configuration's key (smaller is better), or None when it is no answer (e.g. an unbounded objective)
Key = Callable[[Evaluation], "tuple[Fraction, ...] | None"]


@dataclass(frozen=True)
class Enumerated:
    """The best accepted configuration found (None: none), how many were analysed, and whether every
    combination was (else the best is only the best seen, and none found proves nothing)."""

    config: Config | None
    evaluation: Evaluation | None
    evaluated: int
    complete: bool


def space(problem: Problem) -> int:
    """The number of candidate configurations of ``problem``: the product of its choices' sizes."""
    return math.prod(len(ch.candidates) for ch in problem.choices.values())


def enumerate_best(problem: Problem, key: Key, *, first: bool = False, limit: int | None = None,
                   deadline: float | None = None) -> Enumerated:
    """Analyse every combination of candidates in ``itertools.product`` order and keep the accepted one
    with the least ``key`` (the first among equals); ``first``: stop at the first accepted one. At most
    ``limit`` combinations, and none after the wall-clock ``deadline`` (``time.monotonic``)."""
    names = list(problem.choices)
    ranges = [range(len(problem.choices[n].candidates)) for n in names]
    best: tuple[tuple[Fraction, ...], Config, Evaluation] | None = None
    count, complete = 0, True
    for combo in itertools.product(*ranges):
        if (limit is not None and count >= limit) or (deadline is not None and time.monotonic() >= deadline):
            complete = False
            break
        count += 1
        config = Config(tuple(zip(names, combo)))
        ev = problem.evaluate(config)
        if not ev.accepted:
            continue
        value = key(ev)
        if value is None:
            continue
        if best is None or value < best[0]:
            best = (value, config, ev)
            if first:
                break
    if best is None:
        return Enumerated(None, None, count, complete)
    return Enumerated(best[1], best[2], count, complete)
