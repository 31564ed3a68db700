"""What every trace reader gives: the callbacks seen, each identified as CARET identifies callbacks
(node, type, period or topic, symbol, construction order), and the jobs each ran (specs/trace.md §1).

Times are whole nanoseconds (the trace's clock); a job is (start, end, write): ``write`` is when its
last output left (a publish inside the job, else its end), for the hops of a chain. Job records add
the release, the job's number, what it read and the CPU time its thread spent on it.
"""
from __future__ import annotations

from array import array
from collections import Counter
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Callback:
    """A recorded callback. ``kind``: "timer", "subscription" or "task" (a job record names its task);
    ``order``: its rank among the callbacks of its node alike in kind, period or topic and symbol, in
    the order they were registered (CARET's ``construction_order``)."""

    key: str
    node: str | None
    kind: str  # "timer" | "subscription" | "task" | "topic" (a bag's: its messages)
    period_ns: int | None = None
    topic: str | None = None
    symbol: str = ""
    order: int = 0
    task: str | None = None  # a job record's task name
    registered: int = 0  # its rank among all callbacks of the recording, in registration order

    def describe(self) -> str:
        if self.kind == "topic":
            return f"topic `{self.topic}`"
        what = {"timer": f"timer callback ({_period(self.period_ns)})",
                "subscription": f"subscription callback on `{self.topic}`"}.get(self.kind, f"task `{self.task}`")
        return f"{what} of node `{self.node or '?'}`" + (f", construction order {self.order}" if self.order else "")


def _period(ns: int | None) -> str:
    from fractions import Fraction

    from ..model.units import fmt_time

    return "period unknown" if ns is None else "period " + fmt_time(Fraction(ns, 10**9))


@dataclass
class Jobs:
    """The jobs of one callback, in the order they started (three columns of nanoseconds: 24 bytes a job)."""

    starts: array[int] = field(default_factory=lambda: array("q"))
    ends: array[int] = field(default_factory=lambda: array("q"))
    writes: array[int] = field(default_factory=lambda: array("q"))
    releases: array[int] = field(default_factory=lambda: array("q"))  # job records only: when it was released
    seqs: array[int] = field(default_factory=lambda: array("q"))  # job records only: each job's number
    #: job records only: the CPU time each job's thread spent on it (ns), −1 where its record says none
    cpus: array[int] = field(default_factory=lambda: array("q"))
    #: job records that hold what each job read: per ``PORT\tWRITER`` (WRITER the writing task, "" when
    #: the record does not name it) the writer's job number each job read there, 0 for none; None: the
    #: records do not say what was read
    reads: dict[str, array[int]] | None = None

    def add(self, start: int, end: int, write: int) -> None:
        self.starts.append(start)
        self.ends.append(end)
        self.writes.append(write)

    def read(self, port: str, writer: str, seq: int) -> None:
        """The job added last read on ``port`` the output of ``writer``'s job number ``seq``."""
        if self.reads is None:
            self.reads = {}
        column = self.reads.setdefault(f"{port}\t{writer}", array("q"))
        column.extend(array("q", [0]) * (len(self) - 1 - len(column)))
        column.append(seq)

    def read_on(self, port: str, writer: str) -> array[int] | None:
        """The writer's job number each job read on ``port`` (0: none), or None when the records do not
        say what was read: ``writer``'s column, else the column of records that name no writer."""
        if self.reads is None:
            return None
        column = self.reads.get(f"{port}\t{writer}", self.reads.get(f"{port}\t"))
        out = array("q", column or ())
        out.extend(array("q", [0]) * (len(self) - len(out)))
        return out

    def execution_times(self) -> list[int]:
        """Each job's execution time: the CPU time its record gives, else end − start."""
        if len(self.cpus) != len(self):
            return [e - s for s, e in zip(self.starts, self.ends, strict=True)]
        return [c if c >= 0 else e - s for s, e, c in zip(self.starts, self.ends, self.cpus, strict=True)]

    def cpu_measured(self) -> int:
        """How many jobs' execution times are CPU times."""
        return sum(1 for c in self.cpus if c >= 0)

    def __len__(self) -> int:
        return len(self.starts)


@dataclass
class Link:
    """The messages of one topic from one publishing node to one subscribing node, each linked from its
    publish to its receipt by its source timestamp (specs/trace.md §1.1): ``delays``, receipt − publish
    in nanoseconds, in the order they were received (8 bytes a message)."""

    topic: str
    publisher: str  # node, "/ns/name"
    subscriber: str  # node
    delays: array[int] = field(default_factory=lambda: array("q"))


@dataclass
class Recording:
    """One trace (or several of one run) as read: its callbacks by key, their jobs, what the reader could
    not use, and the messages linked from publish to receipt (``links``, LTTng traces only). ``partial``
    says why the recording is incomplete (a truncated trace, a job without its end, a message not
    linked); ``ignored`` counts the events of kinds the reader does not use, by name."""

    paths: tuple[str, ...]
    source: str  # "lttng" | "job records" | "bag"
    callbacks: dict[str, Callback] = field(default_factory=dict)
    jobs: dict[str, Jobs] = field(default_factory=dict)
    events: int = 0
    ignored: Counter[str] = field(default_factory=Counter)
    partial: list[str] = field(default_factory=list)
    links: dict[tuple[str, str, str], Link] = field(default_factory=dict)  # (topic, publisher, subscriber)

    def jobs_of(self, key: str) -> Jobs:
        return self.jobs.get(key) or Jobs()
