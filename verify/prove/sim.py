"""An independent job-level discrete-event reference simulator (specs/timing.md §1–§4).

This is the oracle the analytic bounds are tested against, so it is kept literal and small and it
imports nothing from the analysis. All times are exact ``Fraction`` seconds; there are no floats.

* ``Scenario`` fixes every free choice the semantics leaves open (phases, execution times, delays,
  sporadic inter-arrival times, prescaler counters). ``simulate`` checks each choice against its legal
  range and raises ``ScenarioError`` otherwise, so a trace is always one the semantics allows.
* ``random_scenario`` draws every choice within its legal range, reproducibly from one ``rng``.
* ``simulate`` runs the system over the half-open window ``[0, horizon)``: events at or after the
  horizon are not processed; a job still running then has ``finish`` None.
* ``chain_latencies`` derives the §4 quantities of a chain from a trace, each sample naming its jobs.

Job indices are 0-based per task (job 0 is the first release); the spec's "j ≥ 2" is index ≥ 1.

Events at one instant are processed in rounds, each round in this order (specs/timing.md §2,
"Simultaneous events"):

1. **completions**: every running job whose remaining time is 0 completes (in system task order)
   and writes its outputs; each message is scheduled at ``max(write + d, previous arrival)``;
2. **arrivals** due now, in send order (zero-delay messages of step 1 included): each stores its
   value in the in-port register and is an activation event; data-triggered releases happen here;
3. **releases** of timers and sporadic sources due now;
4. **dispatch**: every core picks its job (§1); a job that starts now reads its inputs now, so it
   sees everything that arrived at this instant.

A task bound to a ROS 2 executor (specs/timing.md §9) is a callback: its jobs wait in the executor,
whose thread competes on its core at the executor's priority with the job it runs or would run next.
A wait-set executor (``single_threaded``, ``static_single_threaded``) takes a snapshot of its pending
callbacks when its thread gets the core with none left (a polling point) and runs them in the order
of kinds, then system order; the ``events`` executor runs its jobs in release order (FIFO, ties in
system order). A callback with a pending job absorbs a further activation (no job), except a timer on
the events executor.

A job with execution time 0 that starts at ``t`` completes at ``t`` in a further round at the same
instant; jobs started in the earlier round have already read their inputs by then.

Decisions where the spec is silent: an AND compound starts with no member fresh; when the model
fixes a timer's phase the scenario may omit or repeat it (a different value is an error); messages
and registers carry the writer job's identity, from which ``chain_latencies`` computes the §4
provenance stamps afterwards; the non-reduced data age of a value stamped by the first job of ``τ₁``
(which has no previous read) is not sampled, just as reaction time skips that job.
"""
from __future__ import annotations

import heapq
import random
import time
from bisect import bisect_left
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, TypeAlias, cast
from collections.abc import Callable, Mapping

from ..model.system import Activation, ChainModel, ExecutorModel, LinkModel, SystemModel, TaskModel
from .jobs import ARRIVAL, RELEASE, Job

ZERO = Fraction(0)
GRID = 1000  # random choices lie on a grid of GRID steps across their range
DEFAULT_MAX_EVENTS = 2_000_000

ExecTime = Callable[[str, int], Fraction]  # (task id, job index) -> execution time
Delay = Callable[[str, str, int], Fraction]  # (link source, link target, message index) -> delay
Interarrival = Callable[[str, int], Fraction]  # (task id, i) -> gap between releases i and i+1


class ScenarioError(ValueError):
    """A scenario choice outside its legal range (or a system the simulator cannot run)."""


class SimulationError(RuntimeError):
    """The simulation exceeded its event budget (e.g. a zero-time activation loop); ``at`` is the
    instant at which it did (every event before it was processed)."""

    def __init__(self, message: str, at: Fraction | None = None):
        super().__init__(message)
        self.at = at


class SimulationTimeout(SimulationError):
    """The simulation passed its wall-clock deadline (``simulate(..., deadline=...)``: a caller's
    ``--timeout``); every event before ``at`` was processed."""


#: events between two looks at the clock when a simulation has a deadline
CLOCK_EVERY = 1024


# ------------------------------------------------------------------ scenarios


@dataclass(frozen=True)
class Scenario:
    """The free choices of one run. Missing entries take documented defaults:

    ``phases``: timer phase in [0, T) (ignored when the model fixes the phase) or the first release of
    a sporadic task in [0, a⁺); default 0. ``exec_time``: default ``wcet``. ``delay``: default the
    link's ``delay_min``. ``interarrival``: default ``min_interarrival``. ``counter_phase``: the
    number of trigger events already counted at time 0, in 0..k−1; default 0.
    """

    horizon: Fraction
    phases: Mapping[str, Fraction] = field(default_factory=dict)
    exec_time: ExecTime | None = None
    delay: Delay | None = None
    interarrival: Interarrival | None = None
    counter_phase: Mapping[str, int] = field(default_factory=dict)


def pick_in(rng: random.Random, lo: Fraction, hi: Fraction) -> Fraction:
    """A value in [lo, hi] on a grid; each extreme comes up with probability 1/8 on its own."""
    roll = rng.randrange(8)
    if roll == 0:
        return Fraction(lo)
    if roll == 1:
        return Fraction(hi)
    return lo + (hi - lo) * Fraction(rng.randint(0, GRID), GRID)


@dataclass(frozen=True)
class Draw:
    """A reproducible per-key choice: ``Draw(seed, bounds)(*name, index)`` picks within
    ``bounds[name]`` and always returns the same Fraction for the same seed, name and index."""

    seed: int
    bounds: Mapping[tuple[str, ...], tuple[Fraction, Fraction]]

    def __call__(self, *key: object) -> Fraction:
        lo, hi = self.bounds[cast("tuple[str, ...]", key[:-1])]  # (the names: ids, all str)
        return pick_in(random.Random(f"{self.seed}|{'|'.join(map(str, key))}"), lo, hi)


def _offset(rng: random.Random, length: Fraction) -> Fraction:
    """A value in [0, length) on a grid, 0 with probability about 1/8."""
    return ZERO if rng.randrange(8) == 0 else length * Fraction(rng.randrange(GRID), GRID)


def random_scenario(system: SystemModel, rng: random.Random, horizon: Fraction) -> Scenario:
    """A scenario drawing every free choice of ``system`` within its legal range (§1–§3)."""
    phases: dict[str, Fraction] = {}
    counters: dict[str, int] = {}
    gaps: dict[tuple[str, ...], tuple[Fraction, Fraction]] = {}
    for t in system.tasks:
        act = t.activation
        if act.offset_window is not None:
            phases[t.id] = _offset(rng, act.offset_window)
        if act.gaps is not None and act.gaps[0] != act.gaps[1]:
            gaps[(t.id,)] = act.gaps
        if act.trigger_port is not None:
            counters[t.id] = rng.randrange(act.release_every)
    execs: dict[tuple[str, ...], tuple[Fraction, Fraction]] = {(t.id,): (t.bcet, t.wcet) for t in system.tasks}
    delays: dict[tuple[str, ...], tuple[Fraction, Fraction]] = {
        (lk.source, lk.target): (lk.delay_min, lk.delay_max) for lk in system.links}
    return Scenario(Fraction(horizon), phases, Draw(rng.getrandbits(64), execs),
                    Draw(rng.getrandbits(64), delays), Draw(rng.getrandbits(64), gaps), counters)


# ------------------------------------------------------------------ traces


@dataclass(frozen=True)
class Message:
    """One value sent over connection ``source → target``: the ``index``-th on that connection,
    written by job ``job`` of task ``writer`` at ``written``, arriving at ``arrival`` (§2)."""

    source: str
    target: str
    index: int
    writer: str
    job: int
    written: Fraction
    arrival: Fraction


@dataclass(frozen=True)
class JobRecord:
    """One job (§1). ``reads`` holds, per in-port read (``inst.port``), the message seen at start
    (None: no value yet). ``start``/``finish`` are None if the horizon came first."""

    task: str
    index: int
    release: Fraction
    exec_time: Fraction
    start: Fraction | None
    finish: Fraction | None
    reads: tuple[tuple[str, Message | None], ...]

    def read(self, port: str) -> Message | None:
        return dict(self.reads).get(port)


@dataclass(frozen=True)
class Trace:
    """The outcome of one run: jobs per task (by index) and all arrived messages in arrival order."""

    horizon: Fraction
    jobs: Mapping[str, tuple[JobRecord, ...]]
    messages: tuple[Message, ...]

    def job(self, task: str, index: int) -> JobRecord:
        return self.jobs[task][index]

    def finished(self, task: str) -> tuple[JobRecord, ...]:
        return tuple(j for j in self.jobs[task] if j.finish is not None)


# ------------------------------------------------------------------ the simulator


#: a job of this simulator: its task, times in seconds, its reads by port (filled at its start), its core
SimJob: TypeAlias = Job[TaskModel, Fraction, dict[str, Message | None], str]


def new_job(task: TaskModel, index: int, order: int, release: Fraction, exec_time: Fraction) -> SimJob:
    """Job ``index`` of ``task`` (at position ``order`` in the system), ranked (§1) by higher priority,
    then earlier release, then task order."""
    return Job(task, index, release, exec_time, (-task.priority, release, order, index), {}, "")


def record(job: SimJob) -> JobRecord:
    """The ``JobRecord`` of ``job`` so far."""
    return JobRecord(job.task.id, job.index, job.release, job.cost, job.start, job.finish, tuple(job.reads.items()))


def rank(job: SimJob) -> tuple[int, Fraction, int, int]:
    """The dispatch rank of ``job`` (§1): higher priority, then earlier release, then task order."""
    return job.key


def absorbs(task: TaskModel, executor: ExecutorModel) -> bool:
    """A callback with a pending job releases no job for a further activation (§9): rcl's timer
    skips missed periods, a subscription's history of depth 1 keeps only the newest message; the
    events executor queues one event per timer expiry."""
    return executor.polls or not task.activation.timer_callback


def executor_cores(system: SystemModel) -> list[str]:
    """The cores of the tasks and of the executors' workers, in order of first use (tasks first)."""
    return list(dict.fromkeys([t.core for t in system.tasks] + [c for e in system.executors for c in e.workers]))


def exclusive_groups(system: SystemModel, executor: ExecutorModel) -> dict[str, str]:
    """The callbacks of a multi-threaded ``executor`` in a mutually exclusive group, with the group
    (§9.4; on the other kinds one thread runs one callback at a time anyway)."""
    if not executor.multi_threaded:
        return {}
    exclusive = {g.id for g in system.groups if g.exclusive}
    return {t.id: t.group for t in system.callbacks(executor.name) if t.group in exclusive}


def snapshot_rank(task: TaskModel, executor: ExecutorModel) -> int:
    """``ExecutorModel.kind_rank``: a callback's kind's place in a snapshot (§9.2)."""
    return executor.kind_rank(task)


@dataclass(eq=False)
class _Executor:
    """One executor's jobs: released and not started (``pending``, in release order), the snapshot of
    its last polling point still to run, and per worker core the job it started and has not completed
    (one core for every kind but ``multi_threaded``, §9.4). ``exclusive``: the tasks whose callback
    group is mutually exclusive, by group."""

    model: ExecutorModel
    exclusive: dict[str, str] = field(default_factory=dict)  # task id -> its mutually exclusive group
    pending: list[SimJob] = field(default_factory=list)
    snapshot: list[SimJob] = field(default_factory=list)
    running: dict[str, SimJob | None] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.running = dict.fromkeys(self.model.workers)

    def head(self, core: str) -> SimJob | None:
        """The job the worker of ``core`` runs when it gets its core: its started one, else the first
        takeable entry of the snapshot, else the first of a new snapshot (a polling point)."""
        current = self.running[core]
        if current is not None:
            return current
        if not self.model.polls:
            return min(self.pending, key=lambda j: (j.release, j.order, j.index), default=None)
        return next((j for j in self.snapshot if self.takeable(j)), None) or min(
            (j for j in self.pending if self.takeable(j)), key=self._rank, default=None)

    def takeable(self, job: SimJob) -> bool:
        """Not held back by its mutually exclusive group, which has a started job (§9.4)."""
        group = self.exclusive.get(job.task.id)
        return group is None or not any(j is not None and self.exclusive.get(j.task.id) == group
                                        for j in self.running.values())

    def _rank(self, job: SimJob) -> tuple[int, int, int]:
        return snapshot_rank(job.task, self.model), job.order, job.index

    def start(self, job: SimJob, core: str) -> None:
        if self.model.polls and job not in self.snapshot:  # the polling point
            self.snapshot = sorted((j for j in self.pending if self.takeable(j)), key=self._rank)
        if self.model.polls:
            self.snapshot.remove(job)
        self.pending.remove(job)
        self.running[core] = job
        job.core = core

    def settle(self) -> None:
        """After dispatch: a free worker with nothing to take polls and finds nothing, so the snapshot
        keeps no entry held back by a busy group (§9.4; a worker always has its core there, E224)."""
        if self.snapshot and any(self.running[c] is None and self.head(c) is None for c in self.running):
            self.snapshot = []

    def worker_for(self, job: SimJob, choice: dict[str, SimJob | None]) -> str:
        """The worker that starts ``job``: the first free one in the executor's core order that chose it."""
        return next(c for c in self.model.workers if self.running[c] is None and choice.get(c) is job)

    def jobs_on(self, core: str) -> list[SimJob]:
        """Its released, uncompleted jobs on ``core``: the pending ones with its first core."""
        current = self.running[core]
        return (self.pending if core == self.model.workers[0] else []) + ([current] if current is not None else [])


def _check(ok: bool, what: str) -> None:
    if not ok:
        raise ScenarioError(what)


class Simulator:
    """One run of ``system`` under ``scenario`` (``simulate``); ``run_to`` and ``trace`` let a caller
    drive it in steps (``scenario.measure_periodic_reference``)."""

    def __init__(self, system: SystemModel, scenario: Scenario, max_events: int, deadline: float | None = None):
        if system.holes:
            raise ScenarioError(f"cannot simulate unresolved holes: {[t.id for t in system.holes]}")
        self.system, self.sc, self.max_events = system, scenario, max_events
        self.deadline = deadline
        self.now, self.events, self.seq = ZERO, 0, 0
        self.heap: list[tuple[Fraction, int, int, TaskModel | Message]] = []
        self.order = {t.id: i for i, t in enumerate(system.tasks)}
        self.jobs: dict[str, list[SimJob]] = {t.id: [] for t in system.tasks}
        self.ready: dict[str, list[SimJob]] = {c: [] for c in executor_cores(system)}
        self.running: dict[str, SimJob | None] = dict.fromkeys(self.ready)
        self.holder: dict[str, SimJob] = {}  # instance -> started, uncompleted cooperative job
        self.executors = {e.name: _Executor(e, exclusive_groups(system, e)) for e in system.executors}
        self.threads: dict[str, list[_Executor]] = {}
        for ex in self.executors.values():
            for core in ex.model.workers:
                self.threads.setdefault(core, []).append(ex)
        self.releases: dict[str, int] = {t.id: 0 for t in system.tasks}
        self.registers: dict[str, Message] = {}
        self.messages: list[Message] = []
        self.links_from: dict[str, list[LinkModel]] = {}
        for lk in system.links:
            self.links_from.setdefault(lk.source, []).append(lk)
        self.sent: dict[tuple[str, str], int] = {}
        self.last_arrival: dict[tuple[str, str], Fraction] = {}
        self.triggered: dict[str, list[tuple[TaskModel, str]]] = {}
        self.counter: dict[str, int] = {}
        self.fresh: dict[str, set[str]] = {}
        for t in system.tasks:
            self._init_activation(t)

    # -------------------------------------------------------------- setup (§3)

    def _init_activation(self, t: TaskModel) -> None:
        act, phase = t.activation, self.sc.phases.get(t.id)
        if act.gaps is not None:  # released by time
            if act.fixed_phase is not None:
                _check(phase is None or phase == act.fixed_phase, f"{t.id}: phase is fixed to {act.fixed_phase}")
                phase = act.fixed_phase
            else:
                assert act.offset_window is not None, "a released-by-time kind without a fixed phase has a window"
                phase = ZERO if phase is None else phase
                _check(0 <= phase < act.offset_window,
                       f"{t.id}: {act.offset_name} {phase} outside [0, {act.offset_window})")
            self._push(phase, RELEASE, t)
        elif act.trigger_port is not None:
            c = self.sc.counter_phase.get(t.id, 0)
            _check(0 <= c < act.release_every, f"{t.id}: counter phase {c} outside 0..{act.release_every - 1}")
            self.counter[t.id], self.fresh[t.id] = c, set()
            for member in act.trigger_members:
                self.triggered.setdefault(f"{t.instance}.{member}", []).append((t, member))

    # -------------------------------------------------------------- scenario choices

    def _exec_time(self, t: TaskModel, index: int) -> Fraction:
        c = t.wcet if self.sc.exec_time is None else self.sc.exec_time(t.id, index)
        _check(t.bcet <= c <= t.wcet, f"{t.id}#{index}: execution time {c} outside [{t.bcet}, {t.wcet}]")
        return Fraction(c)

    def _delay(self, lk: LinkModel, index: int) -> Fraction:
        d = lk.delay_min if self.sc.delay is None else self.sc.delay(lk.source, lk.target, index)
        _check(lk.delay_min <= d <= lk.delay_max,
               f"{lk.source}->{lk.target}#{index}: delay {d} outside [{lk.delay_min}, {lk.delay_max}]")
        return Fraction(d)

    def _gap(self, t: TaskModel, act: Activation, index: int) -> Fraction:
        """The time from release ``index`` of ``t`` (released by time) to the next one."""
        assert act.gaps is not None, "only a task released by time has gaps"
        low, high = act.gaps
        if low == high:
            return low
        a = low if self.sc.interarrival is None else self.sc.interarrival(t.id, index)
        _check(low <= a <= high, f"{t.id}#{index}: inter-arrival {a} outside [{low}, {high}]")
        return Fraction(a)

    # -------------------------------------------------------------- the event loop

    def _push(self, time: Fraction, phase: int, payload: TaskModel | Message) -> None:
        self.seq += 1
        heapq.heappush(self.heap, (Fraction(time), phase, self.seq, payload))

    def _count(self) -> None:
        self.events += 1
        if self.events > self.max_events:
            raise SimulationError(f"more than {self.max_events} events by t={self.now} "
                                  "(a zero-time activation loop, or raise max_events)", self.now)
        if self.deadline is not None and self.events % CLOCK_EVERY == 0 and time.monotonic() > self.deadline:
            raise SimulationTimeout(f"the deadline passed after {self.events} events, at t={self.now}", self.now)

    def _next_time(self) -> Fraction | None:
        times = [self.now + j.remaining for j in self.running.values() if j is not None]
        if self.heap:
            times.append(self.heap[0][0])
        return min(times, default=None)

    def run(self) -> Trace:
        self._process_before(self.sc.horizon)
        return self.trace(self.sc.horizon)

    def run_to(self, until: Fraction) -> None:
        """Process every event strictly before ``until`` exactly as ``run`` does, then let time pass up
        to ``until`` (events at ``until`` itself are left for later)."""
        self._process_before(until)
        if self.now < until:
            self._advance(until)

    def trace(self, horizon: Fraction) -> Trace:
        """The run so far as the ``Trace`` of a run over ``[0, horizon)``."""
        jobs = {tid: tuple(record(j) for j in js) for tid, js in self.jobs.items()}
        return Trace(horizon, jobs, tuple(self.messages))

    def _process_before(self, until: Fraction) -> None:
        """The rounds of every instant before ``until``: completions, arrivals, releases, dispatch."""
        while (t := self._next_time()) is not None and t < until:
            self._advance(t)
            self._complete_due()
            self._pop_due(ARRIVAL, self._arrive)
            self._pop_due(RELEASE, self._timed_release)
            self._dispatch()

    def _advance(self, t: Fraction) -> None:
        for job in self.running.values():
            if job is not None:
                job.remaining -= t - self.now
        self.now = t

    def _pop_due(self, phase: int, handle: Callable[[Any], None]) -> None:
        while self.heap and self.heap[0][0] == self.now and self.heap[0][1] == phase:
            self._count()
            handle(heapq.heappop(self.heap)[3])

    # -------------------------------------------------------------- completion and messages (§2)

    def _complete_due(self) -> None:
        due = [j for j in self.running.values() if j is not None and j.remaining == 0]
        for job in sorted(due, key=lambda j: (j.order, j.index)):
            self._count()
            self._complete(job)

    def _complete(self, job: SimJob) -> None:
        t = job.task
        job.finish = self.now
        if t.executor is not None:
            self.executors[t.executor].running[job.core] = None
            self.running[job.core] = None
        else:
            self.ready[t.core].remove(job)
            self.running[t.core] = None
        if self.holder.get(t.instance) is job:
            del self.holder[t.instance]
        for port in t.produces:
            for lk in self.links_from.get(f"{t.instance}.{port}", ()):
                self._send(job, lk)

    def _send(self, job: SimJob, lk: LinkModel) -> None:
        """Schedule one message; FIFO: never before the previous message on the connection (§2)."""
        key = (lk.source, lk.target)
        index = self.sent.get(key, 0)
        self.sent[key] = index + 1
        arrival = self.now + self._delay(lk, index)
        arrival = max(arrival, self.last_arrival.get(key, arrival))
        self.last_arrival[key] = arrival
        self._push(arrival, ARRIVAL, Message(lk.source, lk.target, index, job.task.id, job.index,
                                              self.now, arrival))

    def _arrive(self, msg: Message) -> None:
        """Store in the in-port register (last is best) and count as an activation event (§2, §3)."""
        self.registers[msg.target] = msg
        self.messages.append(msg)
        for task, member in self.triggered.get(msg.target, ()):
            self._trigger_event(task, member)

    # -------------------------------------------------------------- activation (§3)

    def _trigger_event(self, t: TaskModel, member: str) -> None:
        act = t.activation
        if act.all_members:
            fresh = self.fresh[t.id]
            fresh.add(member)
            if not fresh.issuperset(act.trigger_members):
                return
            fresh.clear()  # the event consumes the freshness
        self.counter[t.id] += 1
        if self.counter[t.id] >= act.release_every:
            self.counter[t.id] = 0
            self._release(t)

    def _timed_release(self, t: TaskModel) -> None:
        index = self.releases[t.id]
        self._release(t)
        self._push(self.now + self._gap(t, t.activation, index), RELEASE, t)

    def _release(self, t: TaskModel) -> None:
        self.releases[t.id] += 1
        ex = self.executors[t.executor] if t.executor is not None else None
        if ex is not None and absorbs(t, ex.model) and any(j.task is t for j in ex.pending):
            return  # absorbed by the pending job (§9)
        index = len(self.jobs[t.id])
        c = self._exec_time(t, index)
        job = new_job(t, index, self.order[t.id], self.now, c)
        self.jobs[t.id].append(job)
        (self.ready[t.core] if ex is None else ex.pending).append(job)

    # -------------------------------------------------------------- scheduling (§1)

    def _eligible(self, job: SimJob) -> bool:
        """A cooperative job may start only while no other cooperative job of its instance holds."""
        t = job.task
        return t.kind != "cooperative" or job.start is not None or t.instance not in self.holder

    def _pick(self, core: str) -> SimJob | None:
        """The best eligible task job, or the job an executor thread of the core runs (§9)."""
        heads = [h for ex in self.threads.get(core, ()) if (h := ex.head(core)) is not None]
        return min([j for j in self.ready[core] if self._eligible(j)] + heads, key=rank, default=None)

    def _dispatch(self) -> None:
        """Every core runs its best eligible job. Jobs about to start are started one at a time in
        rank order, so among cooperative jobs of one instance the highest-ranked one wins (§1)."""
        while True:
            choice = {core: self._pick(core) for core in self.ready}
            starting = [j for j in choice.values() if j is not None and j.start is None]
            if not starting:
                self.running = choice
                for ex in self.executors.values():
                    ex.settle()
                return
            self._start(min(starting, key=rank), choice)

    def _start(self, job: SimJob, choice: dict[str, SimJob | None]) -> None:
        """Read all inputs at start (§2) and take the instance's cooperative token (§1)."""
        t = job.task
        job.start = self.now
        if t.executor is not None:
            ex = self.executors[t.executor]
            ex.start(job, ex.worker_for(job, choice))
        for r in t.reads:
            port = f"{t.instance}.{r.port}"
            job.reads[port] = self.registers.get(port)
        if t.kind == "cooperative":
            self.holder[t.instance] = job


def simulate(system: SystemModel, scenario: Scenario, max_events: int = DEFAULT_MAX_EVENTS,
             deadline: float | None = None) -> Trace:
    """Run ``system`` under ``scenario`` over ``[0, scenario.horizon)`` (specs/timing.md §1–§3); with
    ``deadline`` (a ``time.monotonic()`` instant), ``SimulationTimeout`` once it has passed."""
    return Simulator(system, scenario, max_events, deadline).run()


# ------------------------------------------------------------------ chains (§4)


@dataclass(frozen=True)
class Sample:
    """One observed latency ``value = end − begin``. ``begin`` is the read time of job ``origin`` of
    τ₁; ``end`` the completion of job ``last`` of τₙ, which holds the stamp of τ₁'s job ``stamp``."""

    value: Fraction
    begin: Fraction
    end: Fraction
    origin: int
    stamp: int
    last: int

    def explain(self, chain: ChainModel) -> str:
        first, final = chain.tasks[0], chain.tasks[-1]
        return (f"{self.value}: from read of {first}#{self.origin} at {self.begin} to completion of "
                f"{final}#{self.last} at {self.end} (holding the stamp of {first}#{self.stamp})")


KINDS = ("reaction_time", "reaction_time_reduced", "data_age", "data_age_nonreduced")


@dataclass(frozen=True)
class ChainLatencies:
    """All samples of one chain in one trace (§4). ``reaction_time`` is non-reduced and ``data_age``
    reduced, the defaults of the spec."""

    chain: str
    reaction_time: tuple[Sample, ...]
    reaction_time_reduced: tuple[Sample, ...]
    data_age: tuple[Sample, ...]
    data_age_nonreduced: tuple[Sample, ...]

    def worst(self, kind: str = "data_age") -> Sample | None:
        return max(self._samples(kind), key=lambda s: s.value, default=None)

    def best(self, kind: str = "data_age") -> Sample | None:
        return min(self._samples(kind), key=lambda s: s.value, default=None)

    def _samples(self, kind: str) -> tuple[Sample, ...]:
        if kind not in KINDS:
            raise ValueError(f"unknown latency kind {kind!r}; one of {KINDS}")
        samples: tuple[Sample, ...] = getattr(self, kind)
        return samples


def _stamp(trace: Trace, chain: ChainModel, pos: int, job: JobRecord,
           memo: dict[tuple[int, str, int], tuple[int, Fraction] | None]) -> tuple[int, Fraction] | None:
    """The provenance (τ₁ job index, its read time) held by ``job`` at chain position ``pos``."""
    if pos == 0:
        assert job.start is not None
        return job.index, job.start
    key = (pos, job.task, job.index)
    if key not in memo:
        msg = job.read(chain.hops[pos - 1].link.target)
        memo[key] = None if msg is None else _stamp(trace, chain, pos - 1, trace.job(msg.writer, msg.job), memo)
    return memo[key]


def chain_latencies(trace: Trace, chain: ChainModel) -> ChainLatencies:
    """Reaction times and data ages of ``chain`` observed in ``trace`` (specs/timing.md §4). Only
    τₙ jobs completed before the horizon count; the first job of τ₁ opens no reaction sample."""
    first, n = chain.tasks[0], len(chain.tasks)
    reads = {j.index: j.start for j in trace.jobs[first] if j.start is not None}
    memo: dict[tuple[int, str, int], tuple[int, Fraction] | None] = {}
    holders: list[tuple[Fraction, int, JobRecord]] = []  # (stamp time, stamp index, τn job)
    for job in trace.finished(chain.tasks[-1]):
        st = _stamp(trace, chain, n - 1, job, memo)
        if st is not None:
            holders.append((st[1], st[0], job))
    age, age_nr = [], []
    for s, k, job in holders:
        assert job.finish is not None, "trace.finished gives finished jobs"
        age.append(Sample(job.finish - s, s, job.finish, k, k, job.index))
        if k >= 1:
            age_nr.append(Sample(job.finish - reads[k - 1], reads[k - 1], job.finish, k - 1, k, job.index))
    react, react_r = _reactions(reads, holders)
    return ChainLatencies(chain.name, tuple(react), tuple(react_r), tuple(age), tuple(age_nr))


def _reactions(reads: dict[int, Fraction], holders: list[tuple[Fraction, int, JobRecord]]
               ) -> tuple[list[Sample], list[Sample]]:
    """For τ₁ job j ≥ 1 at s_j: the earliest-completing τₙ job holding a stamp ≥ s_j ends both
    the reaction from s_{j−1} (non-reduced) and from s_j (reduced)."""
    holders = sorted(holders, key=lambda h: h[0])
    stamps = [h[0] for h in holders]
    best_from: list[tuple[Fraction, int, int]] = []  # (built backwards, then reversed)
    running: tuple[Fraction, int, int] | None = None
    for _stamp_time, stamp_index, job in reversed(holders):  # suffix minimum of (finish, τn index, stamp index)
        assert job.finish is not None, "holders are finished jobs"
        cand = (job.finish, job.index, stamp_index)
        running = cand if running is None or cand < running else running
        best_from.append(running)
    best_from.reverse()
    react, react_r = [], []
    for j in sorted(reads):
        pos = bisect_left(stamps, reads[j])
        if j == 0 or pos == len(holders):
            continue
        f, last, k = best_from[pos]
        react.append(Sample(f - reads[j - 1], reads[j - 1], f, j - 1, k, last))
        react_r.append(Sample(f - reads[j], reads[j], f, j, k, last))
    return react, react_r
