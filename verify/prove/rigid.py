"""The periodic evaluation of rigid scenarios in exact integer time (specs/proof.md §4.3).

``measure_periodic`` evaluates each representative of the exact enumeration by running one system
for several hyperperiods. For systems in the exact class (constant execution times and delays, no
sporadic source) and scenarios that fix only phases and counter phases, this module runs the integer
simulator of ``intsim.py`` to the multiples of the hyperperiod until the timing state repeats, then
builds the rest of the run by shifting (``PeriodicShift``) instead of simulating it, and takes the
extremes of every target from the integer job records.

``verify.prove.sim`` stays the independent oracle: ``tests/test_prove.py`` compares this evaluator with the
reference path (``scenario.measure_periodic_reference``) on random rigid systems and scenarios.
"""
from __future__ import annotations

from collections.abc import Hashable, Iterable
from fractions import Fraction

from ..model.system import SystemModel
from .intsim import ChainSamples, IntJob, IntSimulator, extremes_of
from .jobs import Job
from .scenario import ConcreteScenario, Measured, Target, repetition


def rigid_scenario(model: SystemModel, scenario: ConcreteScenario) -> bool:
    """Whether ``scenario`` on ``model`` is one this evaluator runs: constant execution times and
    delays, no sporadic source, no holes, and no per-job patterns in the scenario."""
    if model.holes or scenario.exec_times or scenario.delays or scenario.interarrivals:
        return False
    if any(t.bcet != t.wcet or t.activation.irregular for t in model.tasks):
        return False
    return all(lk.delay_min == lk.delay_max for lk in model.links)


# ------------------------------------------------------------------ one scenario, completely


_new_job = object.__new__


class _Snapshot:
    """What ``PeriodicShift`` needs of a run at one multiple of the hyperperiod: jobs per task, the
    index of each task's oldest pending job, messages sent and already arrived per connection, and
    the event count."""

    __slots__ = ("released", "first_pending", "arrived", "events")

    def __init__(self, sim: IntSimulator):
        self.released = [len(jobs) for jobs in sim.jobs]
        self.first_pending = list(self.released)
        for core in range(sim.ncores):
            for j in sim.pending(core):
                if j.index < self.first_pending[j.task]:
                    self.first_pending[j.task] = j.index
        in_flight = [0] * len(sim.links)
        for _time, _phase, _seq, payload in sim.heap:
            if not isinstance(payload, int):  # an arrival (it carries its message; a release its task)
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

    def __init__(self, sim: IntSimulator, before: _Snapshot, after: _Snapshot, period: int):
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
    def of(cls, sim: IntSimulator, before: _Snapshot, after: _Snapshot, period: int) -> PeriodicShift | None:
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

    def _moved(self, task: int, src: IntJob) -> IntJob | None:
        """Job ``src.index + n`` of ``task``: the record of ``src`` moved by one period."""
        start, finish = src.start, src.finish
        if start is None or finish is None:  # (a finished job has started)
            return None
        p, shift = self.period, self.shift
        job: IntJob = _new_job(Job)
        job.task, job.index, job.release = task, src.index + shift[task], src.release + p
        # (a record is never ranked again: its ``key`` is left unset)
        job.start, job.finish, job.remaining = start + p, finish + p, 0
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

    def view(self, horizon: int) -> PeriodicShift:
        """The job records as a run stopped at ``horizon`` (a multiple of the period past ``t₁``) has
        them: released before it, started and finished only if before it."""
        moved, last_release = self._moved, horizon - self.period
        for i, jobs in enumerate(self.full):
            n = self.shift[i]
            if n > 0:
                append = jobs.append
                while jobs[-n].release < last_release:
                    job = moved(i, jobs[-n])
                    if job is None:  # (never: the source has finished, see ``of``)
                        break
                    append(job)
        self.jobs = [self._cut(jobs, horizon) for jobs in self.full]
        self.events = self.events_at(horizon)
        return self

    @staticmethod
    def _cut(jobs: list[IntJob], horizon: int) -> list[IntJob]:
        k = len(jobs)
        while k and jobs[k - 1].release >= horizon:
            k -= 1
        out = jobs[:k]
        for j in range(k - 1, -1, -1):
            job = out[j]
            finish, start = job.finish, job.start  # (every job before the horizon finishes)
            if finish is not None and finish < horizon:
                break
            cut: IntJob = _new_job(Job)
            cut.task, cut.index, cut.release, cut.remaining = job.task, job.index, job.release, 0
            started = start is not None and start < horizon
            cut.start, cut.reads = (job.start, job.reads) if started else (None, None)
            cut.finish = None
            out[j] = cut
        return out


def measure_rigid(model: SystemModel, scenario: ConcreteScenario, targets: Iterable[Target], hyper: Fraction,
                  max_periods: int, max_events: int) -> Measured:
    """``measure.measure_periodic`` for a rigid scenario (``rigid_scenario``): the same detection
    of the periodic timing state at multiples of ``hyper``, the same coverage steps and the same
    extremes, computed on integers. Past the first repetition the run is not simulated again but
    shifted (``PeriodicShift``), which gives the same job records."""
    targets = tuple(targets)
    sim = IntSimulator(model, dict(scenario.phases), dict(scenario.counters), max_events, (hyper,))
    unit = sim.unit
    big_h = sim.base.ticks(hyper)
    snapshots: dict[int, _Snapshot] = {}

    def timing_state(at: int) -> Hashable:
        snapshots[at] = _Snapshot(sim)
        return sim.timing_state(at)

    found = repetition(sim.run_to, timing_state, big_h, max_periods)  # (t₀, P)
    horizon = sim.now
    complete = False
    chains = {c.name: c for c in model.chains}
    samples: dict[str, ChainSamples] = {}
    run: IntSimulator | PeriodicShift = sim
    shift = None if found is None else PeriodicShift.of(sim, snapshots[found[0]], snapshots[found[0] + found[1]],
                                                        found[1])

    def chain_samples(name: str) -> ChainSamples:
        if name not in samples:
            samples[name] = ChainSamples(run, chains[name])
        return samples[name]

    def covered(target: Target, mark: int, end: int) -> bool:
        if target.kind == "response":
            return all(j.finish is not None for j in run.jobs[sim.index_of[target.name]] if j.release < end)
        return any(h[0] >= mark for h in chain_samples(target.name).holders)

    if found is not None:
        t0, period = found
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
    values = extremes_of(targets, unit, lambda tid: run.jobs[sim.index_of[tid]], chain_samples)
    h = horizon * unit
    return Measured(scenario.with_horizon(h), values, complete, h, None if found is None else found[0] * unit,
                    None if found is None else found[1] * unit, run.events)
