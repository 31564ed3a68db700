"""A dedicated evaluator for rigid systems in exact integer time (specs/proof.md §4.3).

``measure_periodic`` evaluates each representative of the exact enumeration by running one system
for several hyperperiods. For systems in the exact class (constant execution times and delays, no
sporadic source) and scenarios that fix only phases and counter phases, this module does the same
job-level simulation as the reference simulator ``verify.sim`` — the same rounds (completions,
arrivals, releases, dispatch), the same dispatch ranks, FIFO back-pressure, prescalers, AND
freshness, registers and read-at-start, the same event count — but on integers: every time is a
multiple of one *unit* (the gcd of the model's times and the scenario's phases), so no ``Fraction``
is built in the event loop. Chain samples and response samples are derived from the integer job
records by the rules of ``verify.sim.chain_latencies``, once per chain and trace, and converted back
to exact ``Fraction`` seconds only for the extremes returned.

``verify.sim`` stays the independent oracle: ``tests/test_prove.py`` compares this evaluator with the
reference path (``scenario.measure_periodic_reference``) on random rigid systems and scenarios.
"""
from __future__ import annotations

import heapq
from bisect import bisect_left
from fractions import Fraction

from ..model import DataTriggered, Periodic, SporadicSource, SystemModel
from ..sim import Sample, ScenarioError, SimulationError

_ARRIVAL, _RELEASE = 1, 2  # heap phases, as in verify.sim


def rigid_scenario(model: SystemModel, scenario) -> bool:
    """Whether ``scenario`` on ``model`` is one this evaluator runs: constant execution times and
    delays, no sporadic source, no holes, and no per-job patterns in the scenario."""
    if model.holes or scenario.exec_times or scenario.delays or scenario.interarrivals:
        return False
    if any(t.bcet != t.wcet or isinstance(t.activation, SporadicSource) for t in model.tasks):
        return False
    return all(lk.delay_min == lk.delay_max for lk in model.links)


def _unit_of(values) -> Fraction:
    """The greatest d > 0 with every value an integer multiple of d (1 if all are 0)."""
    from .scenario import frac_gcd

    return frac_gcd(values) or Fraction(1)


class _Job:
    __slots__ = ("task", "index", "release", "remaining", "start", "finish", "reads", "key")

    def __init__(self, task: int, index: int, release: int, exec_time: int, key: tuple):
        self.task, self.index, self.release, self.remaining = task, index, release, exec_time
        self.start = self.finish = None
        self.reads: tuple | None = None
        self.key = key


class RigidSimulator:
    """``verify.sim._Simulator`` for rigid systems, in integer multiples of ``unit`` seconds.

    Messages are tuples ``(connection, index, writer task, writer job)``; a job's ``reads`` are the
    messages (or None) of its task's read ports in ``read_ports`` order, taken at its start."""

    def __init__(self, model: SystemModel, phases: dict, counters: dict, max_events: int,
                 extra_times=()):
        tasks = model.tasks
        phase_values = [v for v in phases.values()]
        times = [t.wcet for t in tasks] + [lk.delay_min for lk in model.links] + phase_values + list(extra_times)
        for t in tasks:
            if isinstance(t.activation, Periodic):
                times += [t.activation.period, t.activation.phase or Fraction(0)]
        self.unit = unit = _unit_of(times)
        self.model, self.max_events = model, max_events
        self.ids = [t.id for t in tasks]
        self.index_of = {t.id: i for i, t in enumerate(tasks)}
        cores = list(dict.fromkeys(t.core for t in tasks))
        self.core = [cores.index(t.core) for t in tasks]
        self.ncores = len(cores)
        self.coop = [t.kind == "cooperative" for t in tasks]
        self.instance = [t.instance for t in tasks]
        self.prio = [t.priority for t in tasks]
        self.exec = [_ticks(t.wcet, unit) for t in tasks]
        self.read_ports = [tuple(f"{t.instance}.{r.port}" for r in t.reads) for t in tasks]
        self.links = list(model.links)
        self.conn_of = {(lk.source, lk.target): c for c, lk in enumerate(self.links)}
        self.delay = [_ticks(lk.delay_min, unit) for lk in self.links]
        self.target = [lk.target for lk in self.links]
        links_from: dict[str, list[int]] = {}
        for c, lk in enumerate(self.links):
            links_from.setdefault(lk.source, []).append(c)
        self.sends = [tuple(c for port in t.produces for c in links_from.get(f"{t.instance}.{port}", ()))
                      for t in tasks]
        self.period: list[int | None] = [None] * len(tasks)
        self.triggered: dict[str, list[tuple[int, str]]] = {}
        self.counter: dict[int, int] = {}
        self.fresh: dict[int, set] = {}
        self.prescaler: dict[int, int] = {}
        self.and_members: dict[int, frozenset] = {}
        self.now = self.events = self.seq = 0
        self.heap: list = []
        self.jobs: list[list[_Job]] = [[] for _ in tasks]
        self.ready: list[list[_Job]] = [[] for _ in cores]
        self.running: list[_Job | None] = [None] * len(cores)
        self.holder: dict[str, _Job] = {}
        self.registers: dict[str, tuple] = {}
        self.sent = [0] * len(self.links)
        self.last_arrival: dict[int, int] = {}
        for i, t in enumerate(tasks):
            act = t.activation
            if isinstance(act, Periodic):
                phase = phases.get(t.id)
                if act.phase is not None:
                    if phase is not None and phase != act.phase:
                        raise ScenarioError(f"{t.id}: phase is fixed to {act.phase}")
                    phase = act.phase
                else:
                    phase = Fraction(0) if phase is None else phase
                    if not 0 <= phase < act.period:
                        raise ScenarioError(f"{t.id}: phase {phase} outside [0, {act.period})")
                self.period[i] = _ticks(act.period, unit)
                self._push(_ticks(phase, unit), _RELEASE, i)
            elif isinstance(act, DataTriggered):
                c = counters.get(t.id, 0)
                if not 0 <= c < act.prescaler:
                    raise ScenarioError(f"{t.id}: counter phase {c} outside 0..{act.prescaler - 1}")
                self.counter[i], self.fresh[i], self.prescaler[i] = c, set(), act.prescaler
                if act.mode == "and":
                    self.and_members[i] = frozenset(act.members)
                for member in act.members:
                    self.triggered.setdefault(f"{t.instance}.{member}", []).append((i, member))

    # -------------------------------------------------------------- the event loop

    def _push(self, time: int, phase: int, payload) -> None:
        self.seq += 1
        heapq.heappush(self.heap, (time, phase, self.seq, payload))

    def _count(self) -> None:
        self.events += 1
        if self.events > self.max_events:
            raise SimulationError(f"more than {self.max_events} events by t={self.now * self.unit} "
                                  "(a zero-time activation loop, or raise max_events)")

    def run_to(self, until: int) -> None:
        """Process every event strictly before ``until`` (verify.sim's rounds: completions, arrivals,
        releases, dispatch), then let time pass up to ``until``."""
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
            # advance, then complete every running job that is done (in task order)
            d = nxt - now
            due = None
            for job in running:
                if job is not None:
                    job.remaining -= d
                    if job.remaining == 0:
                        due = [job] if due is None else due + [job]
            self.now = nxt
            if due is not None:
                if len(due) > 1:
                    due.sort(key=lambda j: j.task)
                for job in due:
                    self._count()
                    self._complete(job)
            while heap and heap[0][0] == nxt and heap[0][1] == _ARRIVAL:
                self._count()
                self._arrive(pop(heap)[3])
            while heap and heap[0][0] == nxt and heap[0][1] == _RELEASE:
                self._count()
                self._timed_release(pop(heap)[3])
            self._dispatch()
        if self.now < until:
            self._advance(until)

    def _advance(self, t: int) -> None:
        d = t - self.now
        for job in self.running:
            if job is not None:
                job.remaining -= d
        self.now = t

    def _complete(self, job: _Job) -> None:
        t = job.task
        job.finish = self.now
        core = self.core[t]
        self.ready[core].remove(job)
        self.running[core] = None
        inst = self.instance[t]
        if self.holder.get(inst) is job:
            del self.holder[inst]
        for c in self.sends[t]:
            index = self.sent[c]
            self.sent[c] = index + 1
            arrival = self.now + self.delay[c]
            last = self.last_arrival.get(c)
            if last is not None and last > arrival:
                arrival = last
            self.last_arrival[c] = arrival
            self._push(arrival, _ARRIVAL, (c, index, t, job.index))

    def _arrive(self, msg: tuple) -> None:
        port = self.target[msg[0]]
        self.registers[port] = msg
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
        self._release(t)
        self._push(self.now + self.period[t], _RELEASE, t)

    def _release(self, t: int) -> None:
        jobs = self.jobs[t]
        index = len(jobs)
        job = _Job(t, index, self.now, self.exec[t], (-self.prio[t], self.now, t, index))
        jobs.append(job)
        self.ready[self.core[t]].append(job)

    def _dispatch(self) -> None:
        """Every core runs its best eligible job (rank ``key``); jobs about to start are started one
        at a time in rank order (verify.sim ``_dispatch``)."""
        holder, coop, instance, ready, running = self.holder, self.coop, self.instance, self.ready, self.running
        while True:
            starting = None
            for core, jobs in enumerate(ready):
                best = None
                for j in jobs:
                    if coop[j.task] and j.start is None and instance[j.task] in holder:
                        continue
                    if best is None or j.key < best.key:
                        best = j
                running[core] = best
                if best is not None and best.start is None and (starting is None or best.key < starting.key):
                    starting = best
            if starting is None:
                return
            self._start(starting)

    def _start(self, job: _Job) -> None:
        t = job.task
        job.start = self.now
        regs = self.registers
        job.reads = tuple(map(regs.get, self.read_ports[t]))
        if self.coop[t]:
            self.holder[self.instance[t]] = job

    # -------------------------------------------------------------- timing state (§4.3)

    def timing_state(self, at: int) -> tuple:
        """What ``scenario.timing_state`` records, relative to ``at``, with tasks and connections by
        index (a bijection with their names, so equality of states is the same)."""
        ready = tuple(sorted((core, tuple(sorted((j.task, j.release - at, j.remaining, j.start is not None)
                                                 for j in jobs))) for core, jobs in enumerate(self.ready)))
        holders = tuple(sorted((inst, j.task, j.release - at) for inst, j in self.holder.items()))
        heap = tuple(sorted((time - at, phase, payload if phase == _RELEASE else payload[0])
                            for time, phase, _seq, payload in self.heap))
        back = tuple(sorted((k, v - at) for k, v in self.last_arrival.items() if v > at))
        counters = tuple(sorted(self.counter.items()))
        fresh = tuple(sorted((k, tuple(sorted(v))) for k, v in self.fresh.items()))
        return ready, holders, heap, back, counters, fresh


def _ticks(value: Fraction, unit: Fraction) -> int:
    q = Fraction(value) / unit
    assert q.denominator == 1, (value, unit)
    return q.numerator


# ------------------------------------------------------------------ samples (specs/timing.md §4)


class ChainSamples:
    """The samples of one chain in the run so far, as integer tuples ``(value, begin, end, origin,
    stamp, last)`` in the order ``verify.sim.chain_latencies`` lists them."""

    def __init__(self, sim: RigidSimulator, chain):
        first = sim.index_of[chain.tasks[0]]
        last = sim.index_of[chain.tasks[-1]]
        n = len(chain.tasks)
        # the read-port index, per chain position ≥ 1, of the hop's in-port in that position's task
        hop_port = {}
        for pos in range(1, n):
            port = chain.hops[pos - 1].link.target
            hop_port[pos] = port
        jobs = sim.jobs
        reads = {j.index: j.start for j in jobs[first] if j.start is not None}
        memo: dict = {}
        port_index: dict = {}

        def message(pos: int, job: _Job):
            """What ``job`` (at chain position ``pos`` ≥ 1) read on the hop's in-port, or None."""
            pk = (job.task, hop_port[pos])
            idx = port_index.get(pk)
            if idx is None:
                ports = sim.read_ports[job.task]
                idx = port_index[pk] = ports.index(hop_port[pos]) if hop_port[pos] in ports else -1
            return None if idx < 0 else job.reads[idx]

        def stamp(pos: int, job: _Job):
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

        holders = []
        for job in jobs[last]:
            if job.finish is None:
                continue
            # deep chains: resolve from the first position up so the recursion stays shallow
            st = _stamp_iterative(stamp, message, job, n - 1, jobs, memo)
            if st is not None:
                holders.append((st[1], st[0], job))
        self.holders = holders
        self.reads = reads

    def data_age(self) -> list[tuple]:
        return [(job.finish - s, s, job.finish, k, k, job.index) for s, k, job in self.holders]

    def data_age_nonreduced(self) -> list[tuple]:
        reads = self.reads
        return [(job.finish - reads[k - 1], reads[k - 1], job.finish, k - 1, k, job.index)
                for s, k, job in self.holders if k >= 1]

    def reactions(self) -> tuple[list[tuple], list[tuple]]:
        holders = sorted(self.holders, key=lambda h: h[0])
        stamps = [h[0] for h in holders]
        best_from: list = [None] * len(holders)
        running = None
        for i in range(len(holders) - 1, -1, -1):
            cand = (holders[i][2].finish, holders[i][2].index, holders[i][1])
            running = cand if running is None or cand < running else running
            best_from[i] = running
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

    def of_kind(self, kind: str) -> list[tuple]:
        if kind == "data_age":
            return self.data_age()
        if kind == "data_age_nonreduced":
            return self.data_age_nonreduced()
        react, react_r = self.reactions()
        return react if kind == "reaction_time" else react_r


def _stamp_iterative(stamp, message, job, pos, jobs, memo):
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


def to_sample(t: tuple, unit: Fraction) -> Sample:
    value, begin, end, origin, stamp, last = t
    return Sample(value * unit, begin * unit, end * unit, origin, stamp, last)


# ------------------------------------------------------------------ one scenario, completely


def repetition(run_to, timing_state, hyper, max_periods: int):
    """(t₀, P) of specs/proof.md §4.3: drive a run to the multiples of ``hyper`` until its timing
    state at one equals that at an earlier one; (None, None) if none repeats within ``max_periods``."""
    seen: dict[tuple, int] = {}
    for k in range(max_periods + 1):
        run_to(k * hyper)
        state = timing_state(k * hyper)
        if state in seen:
            return seen[state] * hyper, (k - seen[state]) * hyper
        seen[state] = k
    return None, None


_new_job = object.__new__


class _Snapshot:
    """What ``PeriodicShift`` needs of a run at one multiple of the hyperperiod: jobs per task, the
    index of each task's oldest pending job, messages sent and already arrived per connection, and
    the event count."""

    __slots__ = ("released", "first_pending", "arrived", "events")

    def __init__(self, sim: RigidSimulator):
        self.released = [len(jobs) for jobs in sim.jobs]
        self.first_pending = list(self.released)
        for jobs in sim.ready:
            for j in jobs:
                if j.index < self.first_pending[j.task]:
                    self.first_pending[j.task] = j.index
        in_flight = [0] * len(sim.links)
        for _time, phase, _seq, payload in sim.heap:
            if phase == _ARRIVAL:
                in_flight[payload[0]] += 1
        self.arrived = [sent - flying for sent, flying in zip(sim.sent, in_flight)]
        self.events = sim.events


class PeriodicShift:
    """The run past ``t₁ = t₀ + P`` as the shift of the run from ``t₀`` (specs/proof.md §4.3).

    The timing state at ``t₁`` equals that at ``t₀``, so everything the run does from ``t₀`` on it
    does again ``P`` later: job ``j`` of task ``i`` that is pending at ``t₀`` or released after it
    has the record of job ``j − nᵢ`` moved by ``P``, with ``nᵢ`` the releases of ``i`` in
    ``[t₀, t₁)``. A message on connection ``c`` is sent by every completion of its writer, so its
    index is the writer's job index and moves by the writer's ``n``. A read that saw a message which
    had arrived before ``t₀`` (or none) saw no arrival on its port since ``t₀``; ``P`` later it sees
    the port's register at ``t₁``. Events come in the same number every period.

    ``of`` returns None when a record cannot be derived (which the state equality rules out; the
    caller then simulates)."""

    def __init__(self, sim: RigidSimulator, before: _Snapshot, after: _Snapshot, period: int):
        self.index_of, self.read_ports, self.period = sim.index_of, sim.read_ports, period
        self.start, self.events_start = sim.now, sim.events
        self.events_per_period = after.events - before.events
        self.shift = [a - b for a, b in zip(after.released, before.released)]
        self.arrived = before.arrived
        self.registers = [tuple(sim.registers.get(port) for port in ports) for ports in sim.read_ports]
        self.full = [list(jobs) for jobs in sim.jobs]
        self.jobs = self.full
        self.events = sim.events

    @classmethod
    def of(cls, sim: RigidSimulator, before: _Snapshot, after: _Snapshot, period: int) -> "PeriodicShift | None":
        shift = cls(sim, before, after, period)
        for i, jobs in enumerate(shift.full):
            n = shift.shift[i]
            for j in range(after.first_pending[i], len(jobs)):
                done = shift._moved(i, jobs[j - n]) if j - n >= before.first_pending[i] and n > 0 else None
                if done is None or (jobs[j].start is not None and done.start != jobs[j].start):
                    return None
                if jobs[j].start is not None:
                    done.reads = jobs[j].reads
                jobs[j] = done
        return shift

    def _moved(self, task: int, src: _Job) -> _Job | None:
        """Job ``src.index + n`` of ``task``: the record of ``src`` moved by one period."""
        if src.finish is None:
            return None
        p, shift = self.period, self.shift
        job = _new_job(_Job)
        job.task, job.index, job.release = task, src.index + shift[task], src.release + p
        job.start, job.finish, job.remaining, job.key = src.start + p, src.finish + p, 0, None
        reads = src.reads
        if reads:
            arrived, regs = self.arrived, self.registers[task]
            reads = tuple([regs[k] if msg is None or msg[1] < arrived[msg[0]]
                           else (msg[0], msg[1] + shift[msg[2]], msg[2], msg[3] + shift[msg[2]])
                           for k, msg in enumerate(reads)])
        job.reads = reads
        return job

    def events_at(self, horizon: int) -> int:
        return self.events_start + (horizon - self.start) // self.period * self.events_per_period

    def view(self, horizon: int) -> "PeriodicShift":
        """The job records as a run stopped at ``horizon`` (a multiple of the period past ``t₁``) has
        them: released before it, started and finished only if before it."""
        moved, last_release = self._moved, horizon - self.period
        for i, jobs in enumerate(self.full):
            n = self.shift[i]
            if n > 0:
                append = jobs.append
                while jobs[-n].release < last_release:
                    append(moved(i, jobs[-n]))
        self.jobs = [self._cut(jobs, horizon) for jobs in self.full]
        self.events = self.events_at(horizon)
        return self

    @staticmethod
    def _cut(jobs: list, horizon: int) -> list:
        k = len(jobs)
        while k and jobs[k - 1].release >= horizon:
            k -= 1
        out = jobs[:k]
        for j in range(k - 1, -1, -1):
            job = out[j]
            if job.finish < horizon:
                break
            cut = _new_job(_Job)
            cut.task, cut.index, cut.release, cut.remaining, cut.key = job.task, job.index, job.release, 0, None
            started = job.start < horizon
            cut.start, cut.reads = (job.start, job.reads) if started else (None, None)
            cut.finish = None
            out[j] = cut
        return out


def measure_rigid(model: SystemModel, scenario, targets, hyper: Fraction, max_periods: int, max_events: int):
    """``scenario.measure_periodic`` for a rigid scenario (``rigid_scenario``): the same detection
    of the periodic timing state at multiples of ``hyper``, the same coverage steps and the same
    extremes, computed on integers. Past the first repetition the run is not simulated again but
    shifted (``PeriodicShift``), which gives the same job records."""
    from .scenario import Extremes, Measured, ResponseSample

    targets = tuple(targets)
    sim = RigidSimulator(model, dict(scenario.phases), dict(scenario.counters), max_events, (hyper,))
    unit = sim.unit
    big_h = _ticks(hyper, unit)
    snapshots: dict[int, _Snapshot] = {}

    def timing_state(at: int) -> tuple:
        snapshots[at] = _Snapshot(sim)
        return sim.timing_state(at)

    t0, period = repetition(sim.run_to, timing_state, big_h, max_periods)
    horizon = sim.now
    complete = False
    chains = {c.name: c for c in model.chains}
    samples: dict[str, ChainSamples] = {}
    run = sim
    shift = None if t0 is None else PeriodicShift.of(sim, snapshots[t0], snapshots[t0 + period], period)

    def chain_samples(name: str) -> ChainSamples:
        if name not in samples:
            samples[name] = ChainSamples(run, chains[name])
        return samples[name]

    def covered(target, mark: int, end: int) -> bool:
        if target.kind == "response":
            return all(j.finish is not None for j in run.jobs[sim.index_of[target.name]] if j.release < end)
        return any(s >= mark for s, _k, _job in chain_samples(target.name).holders)

    if t0 is not None:
        mark, end = t0 + 2 * period, t0 + period
        horizon = max(horizon, t0 + 3 * period)
        limit = big_h * (max_periods + 1) + 2 * period
        while True:
            if shift is not None and shift.events_at(horizon) <= max_events:
                run = shift.view(horizon)
            else:  # past the event budget: simulate, so the error is the simulator's own
                shift, run = None, sim
                sim.run_to(horizon)
            samples.clear()
            if all(covered(t, mark, end) for t in targets):
                complete = True
                break
            if horizon >= limit:
                break
            horizon += period
    values = {}
    for t in targets:
        if t.kind == "response":
            found = [(j.finish - j.release, j.index, j.release, j.finish)
                     for j in run.jobs[sim.index_of[t.name]] if j.finish is not None]
            if not found:
                values[t] = Extremes(None, None)
                continue
            worst = max(found, key=lambda s: (s[0], -s[2]))
            best = min(found, key=lambda s: (s[0], s[2]))
            values[t] = Extremes(*(ResponseSample(v * unit, t.name, i, r * unit, f * unit)
                                   for v, i, r, f in (worst, best)))
        else:
            found = chain_samples(t.name).of_kind(t.kind)
            if not found:
                values[t] = Extremes(None, None)
                continue
            worst = max(found, key=lambda s: (s[0], -s[1]))
            best = min(found, key=lambda s: (s[0], s[1]))
            values[t] = Extremes(to_sample(worst, unit), to_sample(best, unit))
    h = horizon * unit
    return Measured(scenario.with_horizon(h), values, complete, h, None if t0 is None else t0 * unit,
                    None if period is None else period * unit, run.events)
