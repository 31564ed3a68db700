"""Release offsets in a pipeline on one core (specs/timing.md §6.2, "pipeline release offsets").

A task ``i`` released by the completions of a task ``p`` of its core (a single-port data trigger
without delay), ``p`` of higher priority, is released only after ``p``'s job has run; and
``p`` may be released the same way by its own predecessor, and so on. The busy window of §6.2 lets
``i``'s first job be released at the window's start ``t₀`` *and* charges every job of ``p`` released
in the window — both together cannot happen: the job of ``p`` that releases ``i``'s first job either
runs in the window (then that job is released no earlier than ``t₀ + C⁻ₚ``) or completed at ``t₀``
itself (then it was released before ``t₀``, and ``p``'s jobs in the window are one fewer than its
event model allows from that release on). Offset-based analysis (Tindell 1994, *Adding time-offsets
to schedulability analysis*; Palencia & González Harbour, RTSS 1998) exploits the same precedence;
this is its case split over where the cascade that releases ``i``'s first job crosses ``t₀``.

Every job of a task of the path, and of ``i``, is level-``i`` work, so one released before ``t₀``
has completed by ``t₀`` (no such job is pending there). Walking up from ``i``: the highest level
whose job of the cascade is released in the window is ``h`` (``h = -1``: none, the predecessor's job
completed at ``t₀``). The cascade's jobs at levels ``0..h`` then run one after another in the window
before ``i``'s first job is released, and the cascade's job at each level ``m > h`` was released
before ``t₀``, no earlier than ``t₀ − Σ_{h < l ≤ m} Rₗ`` (each completed at or before the release it
caused, within its response time), so the level's jobs released in the window are at most
``η⁺ₘ(w + Xₘ) − 1`` with ``Xₘ`` that sum. Job q of ``i`` is released at the completion of the
``k·(q − 1)``-th job of ``p`` after the one that released the first (``k`` the prescaler).

The response ``f_q − a_q`` of job q is the window's work less the work done before ``a_q``:
* by time: ``a_q − t₀ ≥ Σ_{l ≤ h} C⁻ₗ + max(δ⁻ᵢ(q), (q − 1)·k·C⁻ₚ)``;
* by work, where every task of the path has ``C⁻ > 0``: the jobs of the cascade and those ``k·(q−1)``
  jobs of ``p`` all run before ``a_q`` and are among the jobs the window counts at ``C⁺``, so
  ``f_q − a_q ≤ w_c(q) − Σ_{l ≤ h} C⁺ₗ − (q − 1)·k·C⁺ₚ``. (A job that runs for no time could be
  released before ``t₀`` and complete at it, outside the window's count: hence ``C⁻ > 0``.)
``Case`` holds one level's terms; the busy window takes the worst case, and the larger offset.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction

from ..model.system import SystemModel, TaskModel

ZERO = Fraction(0)
#: the longest path followed: each level is one more busy window per analysed task
MAX_DEPTH = 4


@dataclass(frozen=True)
class Case:
    """Where the cascade that releases the first job of the window crosses its start ``t₀`` (module
    docstring): the lower bounds on ``a₁ − t₀`` by time (``offset``) and by work (``work``, None where
    a task of the path may run for no time), the same per further job (``per_job``, ``per_job_work``),
    and per task of the path whose cascade job was released before ``t₀``, how long before at most
    (``before``: task id → ``Xₘ``)."""

    offset: Fraction
    per_job: Fraction
    work: Fraction | None
    per_job_work: Fraction
    before: Mapping[str, Fraction]

    def gone(self, q: int, delta_min: Fraction) -> Fraction:
        """What job q's response is shorter than its busy window ``w_c(q)``: the larger of the two bounds
        on the time or work before its release (``delta_min``: ``δ⁻ᵢ(q)``)."""
        by_time = self.offset + max(delta_min, (q - 1) * self.per_job)
        return by_time if self.work is None else max(by_time, self.work + (q - 1) * self.per_job_work)


def upstream(system: SystemModel, task: TaskModel, cooperative: Mapping[str, int]) -> tuple[tuple[TaskModel, int], ...]:
    """The local trigger path into ``task``, nearest first: (writer, prescaler) while the reader is
    released by that writer's output alone (a single-port data trigger, any prescaler), the
    connection has no delay, and the writer runs on ``task``'s core at a higher priority than
    ``task``; no task on it (``task`` included) ever waits for a token (preemptive, or the only
    cooperative task of its instance: ``cooperative`` counts them). Each task once, at most
    ``MAX_DEPTH`` of them (a shorter path is a valid one: its top's cascade job is one more case)."""
    def free(t: TaskModel) -> bool:
        return t.kind != "cooperative" or cooperative.get(t.instance, 0) <= 1

    if not free(task):
        return ()
    path: list[tuple[TaskModel, int]] = []
    seen = {task.id}
    reader = task
    while len(path) < MAX_DEPTH:
        act = reader.activation
        port = act.single_port
        if port is None:
            break
        link = system.link_into(f"{reader.instance}.{port}")
        if link is None or link.delay_max != 0 or link.writer in seen:
            break
        writer = system.task(link.writer)
        if writer.core != task.core or writer.priority <= task.priority or not free(writer):
            break
        path.append((writer, act.release_every))
        seen.add(writer.id)
        reader = writer
    return tuple(path)


def cases(path: tuple[tuple[TaskModel, int], ...], estimates: Mapping[str, Fraction | None]) -> tuple[Case, ...]:
    """One ``Case`` per level ``h = -1 .. len(path) − 1`` of the crossing (module docstring); empty
    without a path. An ancestor whose WCRT is not bounded, and every one above it, keeps its full
    count."""
    if not path:
        return ()
    writer, k = path[0]
    by_work = all(t.bcet > 0 for t, _ in path)
    out = []
    for h in range(-1, len(path)):
        ran = [path[m][0] for m in range(h + 1)]
        before: dict[str, Fraction] = {}
        span = ZERO
        for m in range(h + 1, len(path)):
            r = estimates.get(path[m][0].id)
            if r is None:
                break
            span += r
            before[path[m][0].id] = span
        out.append(Case(sum((t.bcet for t in ran), ZERO), k * writer.bcet,
                        sum((t.wcet for t in ran), ZERO) if by_work else None, k * writer.wcet, before))
    return tuple(out)
