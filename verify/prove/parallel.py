"""Independent evaluations spread over processes, results in input order (specs/proof.md §4.6).

The exact enumeration evaluates each representative scenario on its own, so the scenarios can run
side by side. Workers are forked: they inherit the model and the evaluation function, and only the
index goes out and the (picklable) result comes back. Results are yielded in input order, so the
caller's accounting, and hence every output, is the same for any number of workers.
"""
from __future__ import annotations

import multiprocessing
import os
from typing import TypeVar
from collections.abc import Callable, Generator

R = TypeVar("R")

_WORK: Callable[[int], object] | None = None  # the function the forked workers call


def available_workers() -> int:
    """The CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def resolve_workers(jobs: int | None) -> int:
    """``jobs`` as given (at least 1, at most four per available CPU: more processes only compete),
    or every available CPU for None / 0."""
    cpus = available_workers()
    return cpus if not jobs else max(1, min(jobs, 4 * cpus))


def _run(i: int) -> object:
    assert _WORK is not None
    return _WORK(i)


def ordered_map(work: Callable[[int], R], indices: range, workers: int) -> Generator[R, None, None]:
    """``work(i)`` for every ``i`` in ``indices``, in order; with ``workers`` > 1 and more than one
    index, in that many forked processes. Stopping the iteration early stops the workers.
    Where processes cannot be forked (no ``fork`` start method, or inside a daemonic worker), the
    work runs here, one index after another."""
    global _WORK
    pool = None
    if workers > 1 and len(indices) > 1 and "fork" in multiprocessing.get_all_start_methods() \
            and not multiprocessing.current_process().daemon:
        _WORK = work
        try:
            pool = multiprocessing.get_context("fork").Pool(min(workers, len(indices)))
        except OSError:  # no processes left, say: run here
            _WORK, pool = None, None
    if pool is None:
        for i in indices:
            yield work(i)
        return
    try:
        yield from pool.imap(_run, indices)
    finally:
        pool.terminate()
        pool.join()
        _WORK = None
