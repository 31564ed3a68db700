"""Job-level simulation of one concrete scenario in exact integer time (specs/proof.md §4.3, §6).

The searches of ``prove`` run the system many times: the exact enumeration once per representative,
the falsifying search once per scenario, on systems of up to thousands of tasks. This module runs the
same job-level semantics as the reference simulator ``verify.prove.sim`` — the same rounds (completions,
arrivals, releases, dispatch), the same dispatch ranks, cooperative tokens, FIFO back-pressure,
prescalers, AND freshness, registers and read-at-start, the same event count — but on integers:
every time is a multiple of one *unit* (the gcd of the model's times and the scenario's choices), so
no ``Fraction`` is built in the event loop, and each core's ready jobs are a heap by rank, so a
dispatch costs a few heap operations however many jobs are pending. Every choice of a
``scenario.ConcreteScenario`` is supported: phases, counter phases, and per-job patterns of
execution times, delays and sporadic inter-arrival times.

Chain samples and response samples are derived from the integer job records by the rules of
``verify.prove.sim.chain_latencies`` and converted back to exact ``Fraction`` seconds only for the extremes
returned. ``verify.prove.sim`` stays the independent oracle: ``tests/test_intsim.py`` compares the two on
random systems and scenarios (ranges, sporadic sources, compounds, prescalers, cooperative tasks),
``tests/test_prove.py`` the periodic evaluation of ``rigid.py`` built on this simulator.
"""
from __future__ import annotations

import heapq
from bisect import bisect_left
from collections.abc import Callable, Iterable, Mapping, Sequence
from fractions import Fraction
from typing import Protocol, TypeAlias, TypeVar

from ..model.system import ChainModel, LinkModel, SystemModel, TaskModel
from .sim import (
    DEFAULT_MAX_EVENTS, JobRecord, Message, Sample, ScenarioError, SimulationError, Trace, absorbs, exclusive_groups,
    executor_cores, snapshot_rank
)
from ..core.timebase import TimeBase
from .jobs import ARRIVAL, RELEASE, Job
from .scenario import ConcreteScenario, Extremes, Measured, ResponseSample, Target, TimingState

ZERO = Fraction(0)
_K = TypeVar("_K")

#: a message: (connection, index, writer task, writer job)
_Msg: TypeAlias = "tuple[int, int, int, int]"
#: a job's dispatch rank: (−priority, release, task, index)
_Key: TypeAlias = "tuple[int, int, int, int]"
#: a heap entry: (time, phase, sequence number, message of an arrival or task of a release)
_Event: TypeAlias = "tuple[int, int, int, int | _Msg]"
#: a chain sample in ticks: (value, begin, end, origin, stamp, last)
IntSample: TypeAlias = "tuple[int, int, int, int, int, int]"


#: a job of this simulator: its task by index, times in ticks, the messages (or None) of its task's
#: read ports in ``read_ports`` order once it has started, its core by index (−1 until a callback starts)
IntJob: TypeAlias = Job[int, int, "tuple[_Msg | None, ...] | None", int]


class IntSimulator:
    """``verify.prove.sim.Simulator`` in integer multiples of ``unit`` seconds, for one concrete scenario.

    The scenario's choices come as in ``scenario.ConcreteScenario``: ``phases`` (timers without a fixed
    phase, first releases of sporadic sources), prescaler ``counters``, and per-job patterns —
    ``exec_times[task]``, ``delays[(source, target)]``, ``interarrivals[task]`` (entry ``i mod len``
    for job, message or release ``i``); anything left out takes the simulator's default (``wcet``,
    ``d⁻``, the least inter-arrival time). A choice outside its range raises ``ScenarioError`` when
    the run first uses it, with the reference simulator's message.

    Messages are tuples ``(connection, index, writer task, writer job)``; a job's ``reads`` are the
    messages (or None) of its task's read ports in ``read_ports`` order, taken at its start. The ready
    jobs of a core are a heap by dispatch rank; a completed job leaves it when it reaches the top.
    With ``log`` the arrivals are recorded too, for ``trace``."""

    def __init__(self, model: SystemModel, phases: dict[str, Fraction], counters: dict[str, int], max_events: int,
                 extra_times: Iterable[Fraction] = (), *, exec_times: dict[str, tuple[Fraction, ...]] | None = None,
                 delays: dict[tuple[str, str], tuple[Fraction, ...]] | None = None,
                 interarrivals: dict[str, tuple[Fraction, ...]] | None = None, log: bool = False):
        if model.holes:
            raise ScenarioError(f"cannot simulate unresolved holes: {[t.id for t in model.holes]}")
        tasks = model.tasks
        exec_times, delays, interarrivals = exec_times or {}, delays or {}, interarrivals or {}
        times = [t.wcet for t in tasks] + [lk.delay_min for lk in model.links] + list(phases.values())
        times += list(extra_times)
        for t in tasks:
            act = t.activation
            if act.gaps is not None:  # released by time: the gaps a run takes, and a fixed phase
                times += [act.gaps[0], act.fixed_phase or ZERO]  # (0 counts for nothing)
        legal_exec: dict[str, tuple[Fraction, Fraction]] = {t.id: (t.bcet, t.wcet) for t in tasks}
        legal_delay: dict[tuple[str, str], tuple[Fraction, Fraction]] = {
            (lk.source, lk.target): (lk.delay_min, lk.delay_max) for lk in model.links}
        legal_gap: dict[str, tuple[Fraction, Fraction]] = {
            t.id: gaps for t in tasks if (gaps := t.activation.gaps) is not None and gaps[0] != gaps[1]}
        times += _legal(exec_times, legal_exec) + _legal(delays, legal_delay) + _legal(interarrivals, legal_gap)
        self.base = base = TimeBase.gcd_of(times)
        self.unit = base.unit
        self.model, self.max_events = model, max_events
        self.ids = [t.id for t in tasks]
        self.index_of: dict[str, int] = {t.id: i for i, t in enumerate(tasks)}
        cores = executor_cores(model)
        self.core = [cores.index(t.core) for t in tasks]
        self.ncores = len(cores)
        self.coop = [t.kind == "cooperative" for t in tasks]
        self.instance = [t.instance for t in tasks]
        self.prio = [t.priority for t in tasks]
        self.exec = [base.ticks(t.wcet) for t in tasks]
        self.exec_pattern = [_pattern(exec_times.get(t.id), legal_exec[t.id], base) for t in tasks]
        self.read_ports = [tuple(f"{t.instance}.{r.port}" for r in t.reads) for t in tasks]
        self.links = list(model.links)
        self.conn_of = {(lk.source, lk.target): c for c, lk in enumerate(self.links)}
        self.delay = [base.ticks(lk.delay_min) for lk in self.links]
        self.delay_pattern = [_pattern(delays.get((lk.source, lk.target)), (lk.delay_min, lk.delay_max), base)
                              for lk in self.links]
        self.target = [lk.target for lk in self.links]
        links_from: dict[str, list[int]] = {}
        for c, lk in enumerate(self.links):
            links_from.setdefault(lk.source, []).append(c)
        self.sends = [tuple(c for port in t.produces for c in links_from.get(f"{t.instance}.{port}", ()))
                      for t in tasks]
        self.period: list[int | None] = [None] * len(tasks)
        self.gap = [0] * len(tasks)  # a sporadic source's default gap (of the other tasks: never read)
        self.gap_pattern: list[_Pattern | None] = [None] * len(tasks)
        self.triggered: dict[str, list[tuple[int, str]]] = {}
        self.counter: dict[int, int] = {}
        self.fresh: dict[int, set[str]] = {}
        self.prescaler: dict[int, int] = {}
        self.and_members: dict[int, frozenset[str]] = {}
        self._init_executors(model, cores)
        self.now = self.events = self.seq = 0
        self.heap: list[_Event] = []
        self.jobs: list[list[IntJob]] = [[] for _ in tasks]
        self.ready: list[list[tuple[_Key, IntJob]]] = [[] for _ in cores]  # heaps of (rank, job)
        self.running: list[IntJob | None] = [None] * len(cores)
        self.holder: dict[str, IntJob] = {}
        self.registers: dict[str, _Msg] = {}
        self.sent = [0] * len(self.links)
        self.last_arrival: dict[int, int] = {}
        self.arrivals: list[tuple[_Msg, int]] | None = [] if log else None  # (message, arrival) for ``trace``
        for i, t in enumerate(tasks):
            self._init_activation(i, t, phases, counters, interarrivals, base)

    def _init_executors(self, model: SystemModel, cores: list[str]) -> None:
        """ROS 2 executors (specs/timing.md §9), as in ``verify.prove.sim._Executor``: per executor its
        released, unstarted jobs (``ex_pending``, in release order), the snapshot of its last polling
        point still to run, its worker cores and the job each started (``ex_running``), and its
        callbacks in mutually exclusive groups (``ex_exclusive``, task -> group); per task its executor
        (or −1), whether it absorbs activations while a job is pending and its kind's place in a snapshot."""
        executors = model.executors
        names = {e.name: n for n, e in enumerate(executors)}
        self.executor_of = [names[t.executor] if t.executor is not None else -1 for t in model.tasks]
        self.absorb = [t.executor is not None and absorbs(t, executors[names[t.executor]]) for t in model.tasks]
        self.snap_rank = [snapshot_rank(t, executors[names[t.executor]]) if t.executor is not None else 0
                          for t in model.tasks]
        self.polls = [e.polls for e in executors]
        self.ex_pending: list[list[IntJob]] = [[] for _ in executors]
        self.ex_snapshot: list[list[IntJob]] = [[] for _ in executors]
        self.ex_workers = [[cores.index(c) for c in e.workers] for e in executors]
        self.ex_running: list[dict[int, IntJob | None]] = [dict.fromkeys(w) for w in self.ex_workers]
        self.ex_exclusive = [{self.index_of[tid]: g for tid, g in exclusive_groups(model, e).items()}
                             for e in executors]
        self.threads: list[list[int]] = [[n for n, w in enumerate(self.ex_workers) if core in w]
                                         for core in range(len(cores))]
        self.released = [0] * len(model.tasks)

    def _head(self, e: int, core: int) -> IntJob | None:
        """The job executor ``e``'s worker on ``core`` runs when it gets its core
        (``verify.prove.sim._Executor.head``)."""
        current = self.ex_running[e][core]
        if current is not None:
            return current
        pending = self.ex_pending[e]
        if not pending:
            return None
        if not self.polls[e]:
            return min(pending, key=lambda j: (j.release, j.task, j.index))
        snapshot = self.ex_snapshot[e]
        if not self.ex_exclusive[e]:
            return snapshot[0] if snapshot else min(pending, key=self._snap_key)
        return next((j for j in snapshot if self._takeable(e, j)), None) or min(
            (j for j in pending if self._takeable(e, j)), key=self._snap_key, default=None)

    def _takeable(self, e: int, job: IntJob) -> bool:
        exclusive = self.ex_exclusive[e]
        group = exclusive.get(job.task)
        return group is None or not any(j is not None and exclusive.get(j.task) == group
                                        for j in self.ex_running[e].values())

    def _snap_key(self, job: IntJob) -> tuple[int, int, int]:
        return self.snap_rank[job.task], job.task, job.index

    def _take(self, e: int, job: IntJob, core: int) -> None:
        """Executor ``e``'s worker on ``core`` starts ``job``, polling first if no entry of its snapshot
        can be taken."""
        if self.polls[e]:
            snapshot = self.ex_snapshot[e]
            if not any(j is job for j in snapshot):
                snapshot[:] = sorted((j for j in self.ex_pending[e] if self._takeable(e, j)), key=self._snap_key)
            snapshot.remove(job)
        self.ex_pending[e].remove(job)
        self.ex_running[e][core] = job
        job.core = core

    def _settle(self) -> None:
        """``verify.prove.sim._Executor.settle`` for every executor with mutually exclusive groups."""
        for e, exclusive in enumerate(self.ex_exclusive):
            if exclusive and self.ex_snapshot[e] and any(
                    job is None and self._head(e, c) is None for c, job in self.ex_running[e].items()):
                self.ex_snapshot[e] = []

    @classmethod
    def of(cls, model: SystemModel, scenario: ConcreteScenario, max_events: int,
           extra_times: Iterable[Fraction] = (), log: bool = False) -> IntSimulator:
        """The simulator of a ``scenario.ConcreteScenario`` (its horizon is not used here); with
        ``log`` it records the arrivals that ``trace`` needs."""
        return cls(model, dict(scenario.phases), dict(scenario.counters), max_events, extra_times,
                   exec_times=dict(scenario.exec_times), delays=dict(scenario.delays),
                   interarrivals=dict(scenario.interarrivals), log=log)

    def _init_activation(self, i: int, t: TaskModel, phases: dict[str, Fraction], counters: dict[str, int],
                         interarrivals: dict[str, tuple[Fraction, ...]], base: TimeBase) -> None:
        act = t.activation
        if act.gaps is not None:  # released by time (specs/timing.md §3)
            phase = phases.get(t.id)
            if act.fixed_phase is not None:
                if phase is not None and phase != act.fixed_phase:
                    raise ScenarioError(f"{t.id}: phase is fixed to {act.fixed_phase}")
                phase = act.fixed_phase
            else:
                phase = Fraction(0) if phase is None else phase
                window = act.offset_window  # (a free phase has one)
                if window is None or not 0 <= phase < window:
                    raise ScenarioError(f"{t.id}: {act.offset_name} {phase} outside [0, {window})")
            low, high = act.gaps
            if low == high:
                self.period[i] = base.ticks(low)
            else:
                self.gap[i] = base.ticks(low)
                self.gap_pattern[i] = _pattern(interarrivals.get(t.id), act.gaps, base)
            self._push(base.ticks(phase), RELEASE, i)
        elif act.trigger_port is not None:
            c = counters.get(t.id, 0)
            if not 0 <= c < act.release_every:
                raise ScenarioError(f"{t.id}: counter phase {c} outside 0..{act.release_every - 1}")
            self.counter[i], self.fresh[i], self.prescaler[i] = c, set(), act.release_every
            if act.all_members:
                self.and_members[i] = frozenset(act.trigger_members)
            for member in act.trigger_members:
                self.triggered.setdefault(f"{t.instance}.{member}", []).append((i, member))

    # -------------------------------------------------------------- the event loop

    def _push(self, time: int, phase: int, payload: int | _Msg) -> None:
        self.seq += 1
        heapq.heappush(self.heap, (time, phase, self.seq, payload))

    def _count(self) -> None:
        self.events += 1
        if self.events > self.max_events:
            raise SimulationError(f"more than {self.max_events} events by t={self.now * self.unit} "
                                  "(a zero-time activation loop, or raise max_events)", self.now * self.unit)

    def run_to(self, until: int, event_budget: int | None = None) -> int:
        """Process every event strictly before ``until`` (verify.prove.sim's rounds: completions, arrivals,
        releases, dispatch), then let time pass up to ``until``; return ``until``. With
        ``event_budget``, stop instead at the first new instant reached with at least that many
        events processed, before any event of it (an instant already begun, e.g. by zero-time jobs,
        is finished first), and return that instant: the run is then the run over ``[0, instant)``."""
        heap, running, pop = self.heap, self.running, heapq.heappop
        while True:
            nxt = heap[0][0] if heap else None
            now = self.now
            for job in running:
                if job is not None:
                    t = now + job.remaining
                    if nxt is None or t < nxt:
                        nxt = t
            if nxt is None or nxt >= until:
                break
            if event_budget is not None and self.events >= event_budget and nxt > now:  # (not within an instant)
                until = nxt
                break
            # advance, then complete every running job that is done (in task order)
            d = nxt - now
            due: list[IntJob] | None = None
            for job in running:
                if job is not None:
                    job.remaining -= d
                    if job.remaining == 0:
                        due = [job] if due is None else due + [job]
            self.now = nxt
            if due is not None:
                if len(due) > 1:
                    due.sort(key=lambda j: (j.task, j.index))
                for job in due:
                    self._count()
                    self._complete(job)
            while heap and heap[0][0] == nxt and heap[0][1] == ARRIVAL:
                self._count()
                self._arrive(pop(heap)[3])  # type: ignore[arg-type]  # an arrival carries its message
            while heap and heap[0][0] == nxt and heap[0][1] == RELEASE:
                self._count()
                self._timed_release(pop(heap)[3])  # type: ignore[arg-type]  # a release its task
            self._dispatch()
        if self.now < until:
            self._advance(until)
        return until

    def _advance(self, t: int) -> None:
        d = t - self.now
        for job in self.running:
            if job is not None:
                job.remaining -= d
        self.now = t

    def _complete(self, job: IntJob) -> None:
        t = job.task
        job.finish = self.now  # (it leaves its core's heap once it reaches the top)
        if self.executor_of[t] >= 0:
            self.ex_running[self.executor_of[t]][job.core] = None
            self.running[job.core] = None
        else:
            self.running[self.core[t]] = None
        inst = self.instance[t]
        if self.holder.get(inst) is job:
            del self.holder[inst]
        for c in self.sends[t]:
            index = self.sent[c]
            self.sent[c] = index + 1
            pattern = self.delay_pattern[c]
            if pattern is None:
                delay = self.delay[c]
            else:
                lk = self.links[c]
                delay = pattern.at(index, _delay_outside(lk, index))
            arrival = self.now + delay
            last = self.last_arrival.get(c)
            if last is not None and last > arrival:
                arrival = last
            self.last_arrival[c] = arrival
            self._push(arrival, ARRIVAL, (c, index, t, job.index))

    def _arrive(self, msg: _Msg) -> None:
        port = self.target[msg[0]]
        self.registers[port] = msg
        if self.arrivals is not None:
            self.arrivals.append((msg, self.now))
        for task, member in self.triggered.get(port, ()):
            members = self.and_members.get(task)
            if members is not None:
                fresh = self.fresh[task]
                fresh.add(member)
                if not fresh.issuperset(members):
                    continue
                fresh.clear()
            self.counter[task] += 1
            if self.counter[task] >= self.prescaler[task]:
                self.counter[task] = 0
                self._release(task)

    def _timed_release(self, t: int) -> None:
        index = self.released[t]
        self._release(t)
        period = self.period[t]
        if period is not None:
            self._push(self.now + period, RELEASE, t)
            return
        pattern = self.gap_pattern[t]
        if pattern is None:
            gap = self.gap[t]
        else:
            low, high = pattern.legal
            gap = pattern.at(index, lambda v: f"{self.ids[t]}#{index}: inter-arrival {v} outside [{low}, {high}]")
        self._push(self.now + gap, RELEASE, t)

    def _release(self, t: int) -> None:
        self.released[t] += 1
        e = self.executor_of[t]
        if e >= 0 and self.absorb[t] and any(j.task == t for j in self.ex_pending[e]):
            return  # absorbed by the pending job (specs/timing.md §9)
        jobs = self.jobs[t]
        index = len(jobs)
        pattern = self.exec_pattern[t]
        if pattern is None:
            cost = self.exec[t]
        else:
            task = self.model.tasks[t]
            cost = pattern.at(index, lambda v: f"{task.id}#{index}: execution time {v} outside "
                                               f"[{task.bcet}, {task.wcet}]")
        key = (-self.prio[t], self.now, t, index)
        job: IntJob = Job(t, index, self.now, cost, key, None, -1)
        jobs.append(job)
        if e >= 0:
            self.ex_pending[e].append(job)
        else:
            heapq.heappush(self.ready[self.core[t]], (key, job))

    def _best(self, core: int) -> IntJob | None:
        """The best-ranked eligible job of ``core`` (a cooperative job that has not started is not
        eligible while another job of its instance holds the token)."""
        heap = self.ready[core]
        while heap and heap[0][1].finish is not None:
            heapq.heappop(heap)
        if not heap:
            return None
        job = heap[0][1]
        if not self.coop[job.task] or job.start is not None or self.instance[job.task] not in self.holder:
            return job
        skipped: list[tuple[_Key, IntJob]]
        best: IntJob | None
        skipped, best = [], None  # rare: ineligible jobs on top
        while heap:
            entry = heapq.heappop(heap)
            job = entry[1]
            if job.finish is not None:
                continue
            skipped.append(entry)
            if not self.coop[job.task] or job.start is not None or self.instance[job.task] not in self.holder:
                best = job
                break
        for entry in skipped:
            heapq.heappush(heap, entry)
        return best

    def _dispatch(self) -> None:
        """Every core runs its best eligible job (rank ``key``); jobs about to start are started one
        at a time in rank order (verify.prove.sim ``_dispatch``). Starting a job that neither takes its
        instance's token nor leaves its executor's queue changes no core's best job (its own core
        keeps it, now started), so the cores are ranked again only after such a start."""
        running, ready, coop, instance, holder = self.running, self.ready, self.coop, self.instance, self.holder
        pop = heapq.heappop
        best: IntJob | None
        rank = True
        while True:
            if rank:
                for core in range(self.ncores):
                    heap = ready[core]  # (``_best``, its common case inlined: the top is eligible)
                    while heap and heap[0][1].finish is not None:
                        pop(heap)
                    if not heap:
                        best = None
                    else:
                        best = heap[0][1]
                        if coop[best.task] and best.start is None and instance[best.task] in holder:
                            best = self._best(core)
                    for e in self.threads[core]:  # executor threads compete with their next job (§9)
                        head = self._head(e, core)
                        if head is not None and (best is None or head.key < best.key):
                            best = head
                    running[core] = best
            starting: IntJob | None = None
            for best in running:
                if best is not None and best.start is None and (starting is None or best.key < starting.key):
                    starting = best
            if starting is None:
                self._settle()
                return
            self._start(starting)
            rank = coop[starting.task] or self.executor_of[starting.task] >= 0

    def _start(self, job: IntJob) -> None:
        t = job.task
        job.start = self.now
        e = self.executor_of[t]
        if e >= 0:  # on the first free worker that chose it (``verify.prove.sim._Executor.worker_for``)
            running = self.ex_running[e]
            self._take(e, job, next(c for c in self.ex_workers[e] if running[c] is None and self.running[c] is job))
        regs = self.registers
        job.reads = tuple(map(regs.get, self.read_ports[t]))
        if self.coop[t]:
            self.holder[self.instance[t]] = job

    def pending(self, core: int) -> list[IntJob]:
        """The released, uncompleted jobs of ``core`` (its executors' included)."""
        jobs = [job for _key, job in self.ready[core] if job.finish is None]
        for e in self.threads[core]:
            current = self.ex_running[e][core]
            jobs += (self.ex_pending[e] if core == self.ex_workers[e][0] else []) + (
                [current] if current is not None else [])
        return jobs

    def trace(self, horizon: Fraction, tasks: Iterable[str] | None = None) -> Trace:
        """The run so far as the reference simulator's ``Trace`` of a run over ``[0, horizon)``
        (jobs with their reads, arrived messages in arrival order), in ``Fraction`` seconds. With
        ``tasks`` (task ids), only the jobs of those tasks and the messages they read. Needs a
        simulator built with ``log``."""
        assert self.arrivals is not None, "the simulator was built without log=True"
        unit, ids, links, jobs = self.unit, self.ids, self.links, self.jobs
        chosen = range(len(jobs)) if tasks is None else sorted(self.index_of[t] for t in set(tasks))
        wanted: set[tuple[int, int]] | None
        if tasks is None:
            wanted = None
        else:
            wanted = {(m[0], m[1]) for i in chosen for j in jobs[i] if j.reads for m in j.reads if m is not None}
        messages: dict[tuple[int, int], Message] = {}
        for (c, index, writer, job), at in self.arrivals:
            if wanted is None or (c, index) in wanted:
                lk = links[c]
                written = jobs[writer][job].finish
                assert written is not None, "a message is sent at its writer's completion"
                messages[(c, index)] = Message(lk.source, lk.target, index, ids[writer], job, written * unit, at * unit)
        records: dict[str, tuple[JobRecord, ...]] = {}
        for i in chosen:
            ports = self.read_ports[i]
            rows = []
            for j in jobs[i]:
                reads = () if j.reads is None else tuple(dict(zip(ports, (  # (a job reads at its start)
                    None if m is None else messages[(m[0], m[1])] for m in j.reads))).items())
                rows.append(JobRecord(ids[i], j.index, j.release * unit, j.cost * unit,
                                      None if j.start is None else j.start * unit,
                                      None if j.finish is None else j.finish * unit, reads))
            records[ids[i]] = tuple(rows)
        return Trace(Fraction(horizon), records, tuple(messages.values()))

    # -------------------------------------------------------------- timing state (§4.3)

    def timing_state(self, at: int) -> TimingState:
        """What ``scenario.timing_state`` records, relative to ``at``, with tasks and connections by
        index (a bijection with their names, so equality of states is the same)."""
        ready = tuple(sorted((core, tuple(sorted((j.task, j.release - at, j.remaining, j.start is not None)
                                                 for j in self.pending(core)))) for core in range(self.ncores)))
        holders = tuple(sorted((inst, j.task, j.release - at) for inst, j in self.holder.items()))
        # (a release carries its task, an arrival its message)
        heap = tuple(sorted((time - at, phase, payload if isinstance(payload, int) else payload[0])
                            for time, phase, _seq, payload in self.heap))
        back = tuple(sorted((k, v - at) for k, v in self.last_arrival.items() if v > at))
        counters = tuple(sorted(self.counter.items()))
        fresh = tuple(sorted((k, tuple(sorted(v))) for k, v in self.fresh.items()))
        snapshots = tuple(tuple((j.task, j.release - at) for j in snapshot) for snapshot in self.ex_snapshot)
        return ready, holders, heap, back, counters, fresh, snapshots


class _Pattern(tuple[int | None, ...]):
    """A per-job pattern in ticks; an entry outside the legal range is None (``values``: as given,
    ``legal``: the range)."""

    values: tuple[Fraction, ...]
    legal: tuple[Fraction, Fraction]

    def at(self, index: int, refusal: Callable[[Fraction], str]) -> int:
        """Entry ``index mod len``, or ``ScenarioError(refusal(value as given))`` if it is out of range."""
        value = self[index % len(self)]
        if value is None:
            raise ScenarioError(refusal(self.values[index % len(self)]))
        return value


def _delay_outside(lk: LinkModel, index: int) -> Callable[[Fraction], str]:
    """The refusal of an out-of-range delay of message ``index`` on ``lk``."""
    return lambda v: f"{lk.source}->{lk.target}#{index}: delay {v} outside [{lk.delay_min}, {lk.delay_max}]"


def _pattern(values: Sequence[Fraction] | None, legal: tuple[Fraction, Fraction], base: TimeBase) -> _Pattern | None:
    if not values:
        return None
    lo, hi = legal
    pattern = _Pattern(base.ticks(v) if lo <= v <= hi else None for v in values)
    pattern.values = tuple(values)
    pattern.legal = legal
    return pattern


def _legal(patterns: Mapping[_K, Sequence[Fraction]], legal: Mapping[_K, tuple[Fraction, Fraction]]) -> list[Fraction]:
    """The entries of ``patterns`` in the range ``legal`` gives their key (those of keys without one left out)."""
    return [v for key, pattern in patterns.items() if key in legal
            for v in pattern if legal[key][0] <= v <= legal[key][1]]




# ------------------------------------------------------------------ samples (specs/timing.md §4)


class JobRecords(Protocol):
    """The job records of a run (``IntSimulator``, or ``rigid.PeriodicShift``'s view of one)."""

    index_of: dict[str, int]
    read_ports: list[tuple[str, ...]]
    jobs: list[list[IntJob]]


class ChainSamples:
    """The samples of one chain in the run so far, as integer tuples ``(value, begin, end, origin,
    stamp, last)`` in the order ``verify.prove.sim.chain_latencies`` lists them."""

    def __init__(self, sim: JobRecords, chain: ChainModel):
        first = sim.index_of[chain.tasks[0]]
        last = sim.index_of[chain.tasks[-1]]
        n = len(chain.tasks)
        # the read-port index, per chain position ≥ 1, of the hop's in-port in that position's task
        hop_port: dict[int, str] = {}
        for pos in range(1, n):
            port = chain.hops[pos - 1].link.target
            hop_port[pos] = port
        jobs = sim.jobs
        reads = {j.index: j.start for j in jobs[first] if j.start is not None}
        memo: dict[tuple[int, int, int], tuple[int, int] | None] = {}
        port_index: dict[tuple[int, str], int] = {}

        def message(pos: int, job: IntJob) -> _Msg | None:
            """What ``job`` (at chain position ``pos`` ≥ 1) read on the hop's in-port, or None."""
            pk = (job.task, hop_port[pos])
            idx = port_index.get(pk)
            if idx is None:
                ports = sim.read_ports[job.task]
                idx = port_index[pk] = ports.index(hop_port[pos]) if hop_port[pos] in ports else -1
            reads = job.reads  # (it has started)
            return None if idx < 0 or reads is None else reads[idx]

        def stamp(pos: int, job: IntJob) -> tuple[int, int] | None:
            if pos == 0:
                assert job.start is not None
                return job.index, job.start
            key = (pos, job.task, job.index)
            if key in memo:
                return memo[key]
            msg = message(pos, job)
            value = None if msg is None else stamp(pos - 1, jobs[msg[2]][msg[3]])
            memo[key] = value
            return value

        #: (stamp time, stamp index, finish, index) of each finished job of τₙ with a stamp
        holders: list[tuple[int, int, int, int]] = []
        for job in jobs[last]:
            finish = job.finish
            if finish is None:
                continue
            # deep chains: resolve from the first position up so the recursion stays shallow
            st = _stamp_iterative(stamp, message, job, n - 1, jobs, memo)
            if st is not None:
                holders.append((st[1], st[0], finish, job.index))
        self.holders = holders
        self.reads = reads

    def data_age(self) -> list[IntSample]:
        return [(f - s, s, f, k, k, index) for s, k, f, index in self.holders]

    def data_age_nonreduced(self) -> list[IntSample]:
        reads = self.reads
        return [(f - reads[k - 1], reads[k - 1], f, k - 1, k, index) for _s, k, f, index in self.holders if k >= 1]

    def reactions(self) -> tuple[list[IntSample], list[IntSample]]:
        holders = sorted(self.holders, key=lambda h: h[0])
        stamps = [h[0] for h in holders]
        best_from: list[tuple[int, int, int]] = []  # suffix minima of (finish, τₙ index, stamp index)
        running = None
        for _s, k, f, index in reversed(holders):
            cand = (f, index, k)
            running = cand if running is None or cand < running else running
            best_from.append(running)
        best_from.reverse()
        react, react_r = [], []
        reads = self.reads
        for j in sorted(reads):
            pos = bisect_left(stamps, reads[j])
            if j == 0 or pos == len(holders):
                continue
            f, last, k = best_from[pos]
            react.append((f - reads[j - 1], reads[j - 1], f, j - 1, k, last))
            react_r.append((f - reads[j], reads[j], f, j, k, last))
        return react, react_r

    def of_kind(self, kind: str) -> list[IntSample]:
        if kind == "data_age":
            return self.data_age()
        if kind == "data_age_nonreduced":
            return self.data_age_nonreduced()
        react, react_r = self.reactions()
        return react if kind == "reaction_time" else react_r


def _stamp_iterative(stamp: Callable[[int, IntJob], tuple[int, int] | None],
                     message: Callable[[int, IntJob], _Msg | None], job: IntJob, pos: int, jobs: list[list[IntJob]],
                     memo: dict[tuple[int, int, int], tuple[int, int] | None]) -> tuple[int, int] | None:
    """``stamp(pos, job)``, first filling the memo along the chain of writers from the back so
    that the recursion in ``stamp`` is at most one level deep per call."""
    path = []
    cur, p = job, pos
    while p > 0:
        if (p, cur.task, cur.index) in memo:
            break
        path.append((p, cur))
        msg = message(p, cur)
        if msg is None:
            break
        cur, p = jobs[msg[2]][msg[3]], p - 1
    for p, j in reversed(path):
        stamp(p, j)
    return stamp(pos, job)


def to_sample(t: IntSample, unit: Fraction) -> Sample:
    value, begin, end, origin, stamp, last = t
    return Sample(value * unit, begin * unit, end * unit, origin, stamp, last)


# ------------------------------------------------------------------ one scenario up to its horizon


def run_trace(model: SystemModel, scenario: ConcreteScenario, max_events: int = DEFAULT_MAX_EVENTS,
              tasks: Iterable[str] | None = None) -> Trace:
    """The ``Trace`` of ``scenario`` (a ``scenario.ConcreteScenario``) over ``[0, horizon)``: what
    ``scenario.replay`` gives by the reference simulator (tests/test_intsim.py compares the two); with
    ``tasks``, only their jobs and the messages they read (``IntSimulator.trace``)."""
    sim = IntSimulator.of(model, scenario, max_events, (scenario.horizon,), log=True)
    sim.run_to(sim.base.ticks(scenario.horizon))
    return sim.trace(scenario.horizon, tasks)


def target_samples(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target],
                   max_events: int = DEFAULT_MAX_EVENTS) -> dict[Target, list[ResponseSample] | list[Sample]]:
    """Every sample of each target in the run of ``scenario`` over ``[0, horizon)``, as the reference
    path lists them (``scenario._chain_samples`` of the trace; for a task ``_response_samples`` with
    the jobs still open at the horizon, their value ``horizon − release``)."""
    sim = IntSimulator.of(model, scenario, max_events, (scenario.horizon,))
    horizon = sim.base.ticks(scenario.horizon)
    sim.run_to(horizon)
    return samples_at(sim, model, targets, horizon)


def samples_at(sim: IntSimulator, model: SystemModel, targets: Iterable[Target],
               horizon: int) -> dict[Target, list[ResponseSample] | list[Sample]]:
    """``target_samples`` of the run of ``sim`` (of ``model``) so far, up to ``horizon`` ticks (where
    it has run to): a job still open there has the value ``horizon − release``."""
    from .scenario import ResponseSample

    unit = sim.unit
    chain_samples = _chain_samples_of(sim, model)
    out: dict[Target, list[ResponseSample] | list[Sample]] = {}
    for t in targets:
        if t.kind == "response":
            out[t] = [ResponseSample((horizon if j.finish is None else j.finish) * unit - j.release * unit, t.name,
                                     j.index, j.release * unit, None if j.finish is None else j.finish * unit)
                      for j in sim.jobs[sim.index_of[t.name]]]
        else:
            out[t] = [to_sample(s, unit) for s in chain_samples(t.name).of_kind(t.kind)]
    return out


def _chain_samples_of(sim: IntSimulator, model: SystemModel) -> Callable[[str], ChainSamples]:
    """``ChainSamples`` of a chain of ``model`` (by name) in the run of ``sim``, each made once."""
    chains = {c.name: c for c in model.chains}
    made: dict[str, ChainSamples] = {}

    def chain_samples(name: str) -> ChainSamples:
        if name not in made:
            made[name] = ChainSamples(sim, chains[name])
        return made[name]

    return chain_samples


def extremes_of(targets: Iterable[Target], unit: Fraction, jobs_of: Callable[[str], list[IntJob]],
                chain_samples: Callable[[str], ChainSamples],
                open_until: int | None = None) -> dict[Target, Extremes]:
    """The ``scenario.Extremes`` of each target from integer job records, in seconds: ``jobs_of(task
    id)`` gives a task's jobs, ``chain_samples(chain name)`` a chain's ``ChainSamples``. A job not
    finished is left out, or, with ``open_until`` (ticks), counted with ``open_until − release`` (as
    ``scenario.extremes`` with ``with_open``). Ties go to the earliest sample, as there."""
    values: dict[Target, Extremes] = {}
    for t in targets:
        if t.kind == "response":
            found: list[tuple[int, int, int, int | None]] = []
            for j in jobs_of(t.name):
                if j.finish is not None:
                    found.append((j.finish - j.release, j.index, j.release, j.finish))
                elif open_until is not None:
                    found.append((open_until - j.release, j.index, j.release, None))
            if not found:
                values[t] = Extremes(None, None)
                continue
            worst = max(found, key=lambda s: (s[0], -s[2]))
            best = min(found, key=lambda s: (s[0], s[2]))
            values[t] = Extremes(*(ResponseSample(v * unit, t.name, i, r * unit, None if f is None else f * unit)
                                   for v, i, r, f in (worst, best)))
            continue
        samples = chain_samples(t.name).of_kind(t.kind)
        if not samples:
            values[t] = Extremes(None, None)
            continue
        worst_s = max(samples, key=lambda s: (s[0], -s[1]))
        best_s = min(samples, key=lambda s: (s[0], s[1]))
        values[t] = Extremes(to_sample(worst_s, unit), to_sample(best_s, unit))
    return values


def measure_prefix(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target], max_events: int,
                   event_budget: int | None = None) -> Measured:
    """``measure.measure`` on integers: the run of ``scenario`` over ``[0, horizon)`` and the
    extremes of every target in it, jobs still open at the horizon counted with ``horizon − release``
    (a lower bound on their response). The same run, samples and extremes as the reference path
    ``scenario.measure_reference`` (tests/test_intsim.py compares the two). With ``event_budget``
    the run may end earlier (``IntSimulator.run_to``); the result then holds the scenario with that
    shorter horizon."""
    sim = IntSimulator.of(model, scenario, max_events, (scenario.horizon,))
    unit = sim.unit
    horizon = sim.run_to(sim.base.ticks(scenario.horizon), event_budget)
    if horizon * unit != scenario.horizon:
        scenario = scenario.with_horizon(horizon * unit)
    values = extremes_of(targets, unit, lambda tid: sim.jobs[sim.index_of[tid]], _chain_samples_of(sim, model),
                         horizon)
    return Measured(scenario, values, False, scenario.horizon)
