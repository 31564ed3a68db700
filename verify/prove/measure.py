"""What the searches of ``prove`` measure a scenario with (specs/proof.md §4.3, §5): the integer
evaluators of ``intsim.py`` and ``rigid.py``, which give the same run, samples and extremes as the
reference paths of ``scenario.py`` (``measure_reference``, ``measure_periodic_reference``) by the
reference simulator; ``tests/test_intsim.py`` and ``tests/test_prove.py`` compare them.
"""
from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction

from ..model.system import SystemModel
from .intsim import measure_prefix
from .rigid import measure_rigid, rigid_scenario
from .scenario import ConcreteScenario, Measured, Target, measure_periodic_reference
from .sim import DEFAULT_MAX_EVENTS


def measure_periodic(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target],
                     hyper: Fraction, max_periods: int = 64,
                     max_events: int = DEFAULT_MAX_EVENTS) -> Measured:
    """``scenario.measure_periodic_reference``, by the integer evaluator of ``rigid.py`` whenever the
    scenario is rigid (the same run, samples and extremes; tests/test_prove.py compares the two)."""
    if rigid_scenario(model, scenario):
        return measure_rigid(model, scenario, targets, hyper, max_periods, max_events)
    return measure_periodic_reference(model, scenario, targets, hyper, max_periods, max_events)


def measure(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target],
            max_events: int = DEFAULT_MAX_EVENTS, event_budget: int | None = None) -> Measured:
    """The extremes of every target in the run of ``scenario`` up to its horizon (no completeness
    claim: what a falsifying search uses), by the integer simulator of ``intsim.py`` (the same run,
    samples and extremes as ``scenario.measure_reference``; tests/test_intsim.py compares the two). With
    ``event_budget`` the run ends at the first instant reached with that many events processed, if
    that comes before the horizon (the result holds the scenario with the shorter horizon)."""
    return measure_prefix(model, scenario, tuple(targets), max_events, event_budget)
