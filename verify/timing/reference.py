"""One round of response-time analysis for every task, by the reference statements (specs/timing.md §6,
§9.3, §9.4): a task on a core by ``rta.response_time``, a callback of a ROS 2 executor by
``executors.callback_response``. The CPA iteration computes its rounds with ``fastrta``, which gives the
same results (``tests/test_perf_equivalence.py`` checks it against this module).
"""
from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction

from ..model.system import SystemModel
from .executors import callback_response
from .kernel import TaskResponse
from .rates import EventModel
from .rta import response_time


def response_times(system: SystemModel, events: Mapping[str, EventModel],
                   estimates: Mapping[str, Fraction | None]) -> dict[str, TaskResponse]:
    """One round of RTA for every task (the façade iterates to the CPA fixed point); the callbacks of
    ROS 2 executors by ``executors.callback_response`` (§9.3)."""
    return {t.id: (callback_response(system, t, events, estimates) if t.executor is not None
                   else response_time(system, t, events, estimates)) for t in system.tasks}
