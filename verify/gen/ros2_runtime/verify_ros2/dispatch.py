"""Which job runs next, and when timers release (specs/codegen.md §2, specs/timing.md §1 and §9).

A process runs its jobs on one thread, in the order of its policy:

- ``fp``: the highest priority first, FIFO among equals (a task's thread, or an instance's cooperative
  tasks); every release is queued;
- ``single_threaded`` / ``static_single_threaded`` / ``multi_threaded`` (one worker): a wait-set executor:
  when its snapshot is empty it polls, and the snapshot becomes every pending job ordered by kind (timers
  first; subscriptions first for ``static_single_threaded``), then system order;
- ``events``: release order, FIFO.

On an executor a callback with a pending job absorbs further releases (timing §9.1), except a timer
of the events executor.
"""
from __future__ import annotations

import heapq
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction


@dataclass
class Job:
    task: str  # "instance.Task"
    seq: int  # the task's job number, from 1
    event: int  # the activation that released it: the timer's k, the trigger's count, the release's number
    release: int  # ns since the epoch
    start: int = 0
    finish: int = 0
    cpu: int = 0  # the CPU time its thread spent from its start to its finish (ns, the thread's CPU clock)


@dataclass(frozen=True)
class Callback:
    """How a task takes part in the order: its priority, its kind (timer or not), its system order."""

    priority: int
    timer: bool
    order: int


class Dispatcher:
    def __init__(self, policy: str, callbacks: dict[str, Callback], run: Callable[[Job], None]) -> None:
        self.policy = policy
        self.callbacks = callbacks
        self.run_job = run
        self._pending: list[Job] = []
        self._snapshot: list[Job] = []
        self._seq = {task: 0 for task in callbacks}
        self._cond = threading.Condition()
        self._stopping = False
        self.thread = threading.Thread(target=self._loop, name="verify-jobs", daemon=True)

    @property
    def executor(self) -> bool:
        return self.policy != "fp"

    def _absorbs(self, task: str) -> bool:
        if not self.executor or (self.policy == "events" and self.callbacks[task].timer):
            return False
        return any(j.task == task for j in self._pending) or any(j.task == task for j in self._snapshot)

    def release(self, task: str, event: int, at: int) -> Job | None:
        """Release a job of ``task`` (None: absorbed by a pending one, or stopping)."""
        with self._cond:
            if self._stopping or self._absorbs(task):
                return None
            self._seq[task] += 1
            job = Job(task, self._seq[task], event, at)
            self._pending.append(job)
            self._cond.notify()
            return job

    def _rank(self, job: Job) -> tuple[int, int]:
        cb = self.callbacks[job.task]
        if self.policy == "static_single_threaded":
            return (int(cb.timer), cb.order)
        return (int(not cb.timer), cb.order)

    def take(self) -> Job | None:
        """The job to start now, by the policy (None: nothing pending); the caller holds the lock."""
        if self.policy == "fp":
            if not self._pending:
                return None
            best = min(range(len(self._pending)), key=lambda i: (-self.callbacks[self._pending[i].task].priority, i))
            return self._pending.pop(best)
        if self.policy == "events":
            return self._pending.pop(0) if self._pending else None
        if not self._snapshot:  # a wait-set executor polls
            self._snapshot = sorted(self._pending, key=self._rank)
            self._pending = []
        return self._snapshot.pop(0) if self._snapshot else None

    def _loop(self) -> None:
        while True:
            with self._cond:
                job = self.take()
                while job is None and not self._stopping:
                    self._cond.wait()
                    job = self.take()
                if job is None:
                    return
            self.run_job(job)

    def start(self, setup: Callable[[], None] | None = None) -> None:
        """Start the jobs' thread, which first runs ``setup`` (its scheduling)."""
        def body() -> None:
            if setup is not None:
                setup()
            self._loop()
        self.thread = threading.Thread(target=body, name="verify-jobs", daemon=True)
        self.thread.start()

    def stop(self) -> None:
        """No new release; the running job completes; pending jobs are dropped."""
        with self._cond:
            self._stopping = True
            self._pending.clear()
            self._snapshot.clear()
            self._cond.notify_all()
        if self.thread.is_alive():
            self.thread.join()


@dataclass(frozen=True)
class Timer:
    task: str
    period: Fraction  # ns
    phase: Fraction  # ns


def first_after(timer: Timer, instant: int) -> int:
    """The least k ≥ 1 with φ + k·T > ``instant``."""
    k = (Fraction(instant) - timer.phase) // timer.period + 1
    return max(int(k), 1)


def instant(timer: Timer, k: int) -> int:
    """φ + k·T in ns, rounded up to a whole ns."""
    value = timer.phase + k * timer.period
    return -((-value.numerator) // value.denominator)


class Timers:
    """Releases every timer task at φ + k·T ns since the epoch (CLOCK_REALTIME), from ``start`` on."""

    def __init__(self, timers: list[Timer], release: Callable[[str, int, int], object],
                 setup: Callable[[], None] | None = None) -> None:
        self.timers = timers
        self._release = release
        self._setup = setup
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._loop, name="verify-timers", daemon=True)
        self._start = 0

    def start(self, start: int) -> None:
        self._start = start
        if self.timers:
            self.thread.start()

    def _loop(self) -> None:
        if self._setup is not None:
            self._setup()
        heap = [(instant(t, first_after(t, self._start - 1)), first_after(t, self._start - 1), i)
                for i, t in enumerate(self.timers)]
        heapq.heapify(heap)
        while heap and not self._stop.is_set():
            at, k, i = heap[0]
            while (remaining := at - time.time_ns()) > 0:
                if self._stop.wait(remaining / 1e9):
                    return
            heapq.heapreplace(heap, (instant(self.timers[i], k + 1), k + 1, i))
            self._release(self.timers[i].task, k, at)

    def stop(self) -> None:
        self._stop.set()
        if self.thread.is_alive():
            self.thread.join()
