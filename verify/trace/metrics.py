"""What a recording measures of the model's tasks and chains (specs/trace.md §3). Exact: nanoseconds
as recorded, seconds as fractions; quantiles by nearest rank.

- a task's **execution time**: per job, the CPU time its thread spent on it where its record gives
  one (the generated nodes' ``cpu``), else end − start (what a callback's start and end events, or a
  job record's start and finish, enclose: preemptions included); beside it, end − start (**elapsed**)
  and, for job records, finish − release (**response**);
- its **activation**: the time between consecutive starts (job records: releases), their least and
  greatest, and the mean period (last − first) / (n − 1); a timer callback's configured period;
- a chain's **data age** and **reaction time** by specs/timing.md §4, on the jobs: a job of the
  chain's first task holds its own start as the stamp; a job of a later task holds the stamp of the
  writer's job it read — the one its record names where job records say what each job read, else
  the writer's latest job whose output left (its last publish, else its end) at or before the job
  started; data age = end − stamp per job of the last task holding one; reaction time, as the
  generated nodes' monitors keep it, one per stamp newer than every one that reached the last task
  before: the end of the first job holding it minus the newest of those earlier stamps (before any,
  the first task's first start) — the worst of the stimuli it stands for; jitter = greatest − least
  data age.
"""
from __future__ import annotations

import bisect
from array import array
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from ..model.activations import Periodic
from ..model.system import ChainModel, SystemModel
from .match import Matching
from .recording import Jobs, Recording

NS = 10**9


@dataclass(frozen=True)
class Distribution:
    """Measured values (seconds): how many, least, median, 99th percentile, greatest."""

    count: int
    min: Fraction
    p50: Fraction
    p99: Fraction
    max: Fraction

    @staticmethod
    def of(values_ns: Sequence[int]) -> Distribution | None:
        if not values_ns:
            return None
        ordered = sorted(values_ns)
        n = len(ordered)

        def rank(p: int) -> Fraction:
            return Fraction(ordered[max(-(-p * n // 100) - 1, 0)], NS)

        return Distribution(n, Fraction(ordered[0], NS), rank(50), rank(99), Fraction(ordered[-1], NS))


@dataclass(frozen=True)
class TaskMeasure:
    task: str
    callback: str  # the recorded callback, in words
    jobs: int
    execution: Distribution | None
    intervals: Distribution | None  # between consecutive activations
    mean_period: Fraction | None
    configured_period: Fraction | None  # a timer callback's period as registered
    overruns: tuple[tuple[int, Fraction], ...] = ()  # (job index, execution time) above the wcet: the first few
    overrun_count: int = 0  # how many jobs ran longer than the wcet
    cpu_jobs: int = 0  # how many jobs' execution times are the CPU time their thread spent (job records' `cpu`)
    elapsed: Distribution | None = None  # end − start of each job (the execution time where no CPU time is given)
    response: Distribution | None = None  # finish − release of each job (job records only)


@dataclass(frozen=True)
class ChainMeasure:
    chain: str
    data_age: Distribution | None
    reaction_time: Distribution | None
    missing: str | None = None  # why it is not measured

    @property
    def jitter(self) -> Fraction | None:
        return None if self.data_age is None else self.data_age.max - self.data_age.min


@dataclass(frozen=True)
class Measurements:
    tasks: tuple[TaskMeasure, ...]
    chains: tuple[ChainMeasure, ...]

    def task(self, task_id: str) -> TaskMeasure | None:
        return next((t for t in self.tasks if t.task == task_id), None)


#: how many overrunning jobs a task's measure names
SHOWN_OVERRUNS = 5


def measure(model: SystemModel, recording: Recording, matching: Matching) -> Measurements:
    tasks = tuple(_task(task.id, task.wcet, recording, key) for task in model.tasks
                  if (key := matching.pairs.get(task.id)) is not None)
    chains = tuple(_chain(model, chain, recording, matching) for chain in model.chains)
    return Measurements(tasks, chains)


def _task(task_id: str, wcet: Fraction, recording: Recording, key: str) -> TaskMeasure:
    """What the jobs of the callback ``key`` measure of the task ``task_id``."""
    jobs = recording.jobs_of(key)
    callback = recording.callbacks[key]
    released = len(jobs.releases) == len(jobs) and len(jobs) > 0
    activations = jobs.releases if released else jobs.starts
    intervals = [b - a for a, b in zip(activations, activations[1:], strict=False)]
    mean = Fraction(activations[-1] - activations[0], (len(activations) - 1) * NS) if len(activations) > 1 else None
    configured = Fraction(callback.period_ns, NS) if callback.period_ns else None
    if callback.kind == "topic":  # (a bag's: when messages were written, not how long jobs ran)
        return TaskMeasure(task_id, callback.describe(), len(jobs), None, Distribution.of(intervals), mean, configured)
    execution = jobs.execution_times()
    limit = wcet * NS
    above = [(k, Fraction(x, NS)) for k, x in enumerate(execution) if x > limit]
    elapsed = [e - s for s, e in zip(jobs.starts, jobs.ends, strict=True)]
    response = [e - r for r, e in zip(jobs.releases, jobs.ends, strict=True)] if released else []
    return TaskMeasure(task_id, callback.describe(), len(jobs), Distribution.of(execution), Distribution.of(intervals),
                       mean, configured, tuple(above[:SHOWN_OVERRUNS]), len(above), jobs.cpu_measured(),
                       Distribution.of(elapsed), Distribution.of(response))


def _chain(model: SystemModel, chain: ChainModel, recording: Recording, matching: Matching) -> ChainMeasure:
    if recording.source == "bag":
        return ChainMeasure(chain.name, None, None, "a bag records when messages were written, not when jobs ran")
    missing = [t for t in chain.tasks if t not in matching.pairs]
    if missing:
        return ChainMeasure(chain.name, None, None, f"task `{missing[0]}` is not in the trace")
    first = recording.jobs_of(matching.pairs[chain.tasks[0]])
    stamps: array[int] = array("q", first.starts)
    previous = first
    for hop in chain.hops:
        reader = recording.jobs_of(matching.pairs[hop.reader])
        read = reader.read_on(hop.link.target.split(".", 1)[1], hop.writer)
        numbered = read is not None and any(previous.seqs)
        stamps = _read(previous, stamps, read) if read is not None and numbered else _held(previous, stamps, reader)
        previous = reader
    last = previous
    ages = [end - s for end, s in zip(last.ends, stamps, strict=True) if s >= 0]
    reactions = _reactions(first.starts[0] if len(first) else 0, last.ends, stamps)
    return ChainMeasure(chain.name, Distribution.of(ages), Distribution.of(reactions))


def _held(writer: Jobs, writer_stamps: array[int], reader: Jobs) -> array[int]:
    """The stamp each reader job holds, inferred from the times: that of the writer's latest job whose
    output left at or before the reader job started (−1: none yet)."""
    out = array("q")
    writes = writer.writes
    for start in reader.starts:
        k = bisect.bisect_right(writes, start) - 1
        out.append(writer_stamps[k] if k >= 0 else -1)
    return out


def _read(writer: Jobs, writer_stamps: array[int], read: array[int]) -> array[int]:
    """The stamp each reader job holds, as recorded: that of the writer's job whose number it read
    (−1: it read none, or a job not in the records)."""
    seqs = writer.seqs
    order: Sequence[int] = range(len(seqs))
    if any(a >= b for a, b in zip(seqs, seqs[1:], strict=False)):  # (records out of order: sorted, as indices)
        order = array("q", sorted(order, key=seqs.__getitem__))
        seqs = array("q", (seqs[k] for k in order))
    out = array("q")
    for seq in read:
        k = bisect.bisect_left(seqs, seq)
        out.append(writer_stamps[order[k]] if seq > 0 and k < len(seqs) and seqs[k] == seq else -1)
    return out


def _reactions(first: int, ends: Sequence[int], stamps: Sequence[int]) -> list[int]:
    """One reaction per stamp newer than every stamp that reached the last task before (its jobs in the
    order they ended): the end of the first job holding it minus the newest earlier stamp (before any:
    ``first``, the first task's first start), as the generated nodes' monitors keep it (specs/codegen.md
    §5). Each is the worst reaction of the stimuli between those two reads, so the greatest is timing
    §4's reaction time."""
    out = []
    newest = first
    for end, stamp in sorted(zip(ends, stamps, strict=True)):
        if stamp > newest:
            out.append(end - newest)
            newest = stamp
    return out


def period_of(model: SystemModel, task_id: str) -> Fraction | None:
    activation = model.task(task_id).activation
    return activation.period if isinstance(activation, Periodic) else None
