"""What the two simulators share: the job and the order of events within one instant (specs/timing.md §1–§3).

The reference simulator ``sim`` runs in ``Fraction`` seconds with tasks and cores by model and name; the
integer one ``intsim`` in ticks with tasks and cores by index. Both keep their jobs as ``Job``s, typed by
what they use for a task, a time, the reads and a core, and both process the events of one instant in
the same rounds: completions, then arrivals (``ARRIVAL``), then timed releases (``RELEASE``), then
dispatch. An event queue entry is ``(time, phase, sequence number, payload)``, so that at one instant
the heap yields every arrival before any release, each phase in the order the events were scheduled.
"""
from __future__ import annotations

from typing import Generic, TypeVar

ARRIVAL, RELEASE = 1, 2  # heap phases: arrivals before releases at one instant

TaskT = TypeVar("TaskT")
TimeT = TypeVar("TimeT")
ReadsT = TypeVar("ReadsT")
CoreT = TypeVar("CoreT")


class Job(Generic[TaskT, TimeT, ReadsT, CoreT]):
    """One job (§1): of ``task``, the ``index``-th, released at ``release`` with execution time ``cost``
    (``remaining`` of it still to run); ``start`` and ``finish`` once they happened; ``reads``, the
    values its in-ports held at its start; ``core``, the worker core of a callback once started.
    ``key`` is its dispatch rank (§1): ``(−priority, release, task position, index)``, lowest first."""

    __slots__ = ("task", "index", "release", "cost", "remaining", "start", "finish", "reads", "key", "core")

    task: TaskT
    index: int
    release: TimeT
    cost: TimeT
    remaining: TimeT
    start: TimeT | None
    finish: TimeT | None
    reads: ReadsT
    key: tuple[int, TimeT, int, int]
    core: CoreT

    def __init__(self, task: TaskT, index: int, release: TimeT, cost: TimeT, key: tuple[int, TimeT, int, int],
                 reads: ReadsT, core: CoreT):
        self.task, self.index, self.release, self.cost, self.remaining = task, index, release, cost, cost
        self.start = self.finish = None
        self.key, self.reads, self.core = key, reads, core

    @property
    def order(self) -> int:
        """The position of its task in the system (the third entry of its rank)."""
        return self.key[2]
