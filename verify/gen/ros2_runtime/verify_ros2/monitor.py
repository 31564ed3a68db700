"""Chain monitors (specs/codegen.md §5): reaction time, data age and jitter of a chain, computed at its
last task from the stamps its jobs hold, exactly as specs/timing.md §4 defines them. Plain Python: a
hand-written node can feed a ``ChainMonitor`` too."""
from __future__ import annotations

import threading
from dataclasses import dataclass

MAX_SAMPLES = 1_000_000


@dataclass(frozen=True)
class Stamp:
    """A chain's data in a job: ``origin`` the read of the chain's first task it stems from, ``first``
    the start of that task's first job (ns since the epoch)."""

    chain: str
    position: int
    origin: int
    first: int


@dataclass(frozen=True)
class Violation:
    chain: str
    metric: str  # "reaction_time", "data_age" or "jitter"
    value_ns: int
    bound_ns: int
    at_ns: int  # the completion that showed it


class Metric:
    """Count, minimum, maximum and percentiles (nearest rank, over the first MAX_SAMPLES samples)."""

    def __init__(self) -> None:
        self.count = 0
        self.min = 0
        self.max = 0
        self.violations = 0
        self.samples: list[int] = []

    def add(self, value: int) -> None:
        if self.count == 0 or value < self.min:
            self.min = value
        if self.count == 0 or value > self.max:
            self.max = value
        self.count += 1
        if len(self.samples) < MAX_SAMPLES:
            self.samples.append(value)

    def percentile(self, p: int) -> int:
        if not self.samples:
            return 0
        ordered = sorted(self.samples)
        rank = (p * len(ordered) + 99) // 100
        return ordered[max(rank, 1) - 1]

    def summary(self, bound: int) -> dict[str, int]:
        out = {"count": self.count}
        if self.count:
            out.update(min_ns=self.min, max_ns=self.max, p50_ns=self.percentile(50), p90_ns=self.percentile(90),
                       p99_ns=self.percentile(99))
        out["samples_kept"] = len(self.samples)
        if bound > 0:
            out["bound_ns"] = bound
        out["violations"] = self.violations
        return out


class ChainMonitor:
    """The monitor of one chain at its last task: ``on_end`` per completed job holding the chain's stamp.
    A bound of 0 is no spec."""

    def __init__(self, name: str, reaction_time: int = 0, data_age: int = 0, jitter: int = 0) -> None:
        self.name = name
        self.bounds = {"reaction_time": reaction_time, "data_age": data_age, "jitter": jitter}
        self.reaction = Metric()
        self.age = Metric()
        self._last_origin = 0
        self._jitter_reported = 0
        self._jitter_violations = 0
        self._lock = threading.Lock()

    def on_end(self, stamp: Stamp, finish: int) -> list[Violation]:
        with self._lock:
            found: list[Violation] = []
            age = finish - stamp.origin
            self.age.add(age)
            self._check(found, self.age, "data_age", age, finish)
            if stamp.origin > self._last_origin:
                start = self._last_origin or (stamp.first if stamp.first < stamp.origin else 0)
                if start:
                    reaction = finish - start
                    self.reaction.add(reaction)
                    self._check(found, self.reaction, "reaction_time", reaction, finish)
                self._last_origin = stamp.origin
            jitter = self.age.max - self.age.min
            bound = self.bounds["jitter"]
            if bound and jitter > bound and jitter > self._jitter_reported:
                self._jitter_reported = jitter
                self._jitter_violations += 1
                found.append(Violation(self.name, "jitter", jitter, bound, finish))
            return found

    def _check(self, found: list[Violation], metric: Metric, kind: str, value: int, at: int) -> None:
        bound = self.bounds[kind]
        if bound and value > bound:
            metric.violations += 1
            found.append(Violation(self.name, kind, value, bound, at))

    def summary(self) -> dict[str, object]:
        with self._lock:
            jitter: dict[str, int] = {"value_ns": self.age.max - self.age.min if self.age.count else 0}
            if self.bounds["jitter"]:
                jitter["bound_ns"] = self.bounds["jitter"]
            jitter["violations"] = self._jitter_violations
            return {"reaction_time": self.reaction.summary(self.bounds["reaction_time"]),
                    "data_age": self.age.summary(self.bounds["data_age"]), "jitter": jitter}
