"""Dominating rigid systems: the exact search beyond the exact class (specs/proof.md §4.7).

A cone outside the exact class (§4.1) is still decided exactly when a rigid system in the class has,
for its obligations, the same supremum and each of its runs is a run of the cone:

* **same runs** — a sporadic source whose least and greatest inter-arrival times are equal releases
  exactly like a timer of that period with a free phase (its first release lies in ``[0, a⁺)``);
  every obligation keeps its supremum and infimum;
* **sustainable deadlines** — when every obligation is a deadline and every task of the cone is
  preemptive and released by time (a timer or a sporadic source, no data trigger), the worst
  response of each task is that of the system with every job at its ``wcet`` and every sporadic
  source a timer of its least inter-arrival time with a free phase (Liu & Layland 1973; Lehoczky
  1990; Baruah & Burns 2006 on sustainability), fixed phases included; only the suprema are kept.

``dominant(model, targets)`` builds that rigid system (None when neither applies); each of its
scenarios replays, unchanged, as a run of ``model`` — the simulator's defaults (``wcet``,
``delay_min``, the least inter-arrival time) are the rigid system's constants.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

from ..model.activations.timer import Periodic
from ..model.system import LinkModel, SystemModel, TaskModel
from ..model.units import fmt_time
from .exact import exact_class
from .scenario import Target


@dataclass(frozen=True)
class Dominant:
    """A rigid system in the exact class standing for a cone (``model``), and what it changed
    (``what``, for the verdicts' notes)."""

    model: SystemModel
    what: str


def exact_system(model: SystemModel, targets: Iterable[Target]) -> Dominant | None:
    """The system the exact methods search for ``targets`` on ``model``: ``model`` itself in the
    exact class (``what`` empty), else its dominating rigid system in the class, else None."""
    if exact_class(model) is None:
        return Dominant(model, "")
    dom = dominant(model, targets)
    return dom if dom is not None and exact_class(dom.model) is None else None


def dominant(model: SystemModel, targets: Iterable[Target]) -> Dominant | None:
    """The rigid system whose exact search decides ``targets`` on ``model`` (proof spec §4.7), or None."""
    if sustainable_deadlines(model, targets):
        tasks = tuple(_worst_task(t) for t in model.tasks)
        links = tuple(_constant_delay(lk) for lk in model.links)
        what = ("on the dominating rigid system (proof spec §4.7): every job at its wcet"
                + "".join(f", `{t.id}` a timer of {_period_text(t)}" for t in model.tasks
                          if t.activation.irregular))
        return Dominant(replace(model, tasks=tasks, links=links), what)
    # (on an executor a sporadic source is a subscription, not a timer: §9)
    fixed = [t for t in model.tasks if _regular_in_fact(t) and t.executor is None]
    if not fixed:
        return None
    tasks = tuple(_as_timer(t) if t in fixed else t for t in model.tasks)
    what = ("on the same runs (proof spec §4.7): "
            + ", ".join(f"`{t.id}` a timer of {_period_text(t)}" for t in fixed))
    return Dominant(replace(model, tasks=tasks), what)


def sustainable_deadlines(model: SystemModel, targets: Iterable[Target]) -> bool:
    """Every target is a response time, and every task is preemptive and released by time."""
    return (all(t.kind == "response" for t in targets)
            and all(t.kind == "preemptive" and t.executor is None and t.activation.gaps is not None
                    for t in model.tasks))


def _regular_in_fact(t: TaskModel) -> bool:
    """Released by time, not strictly periodically, with its least and greatest gap equal."""
    gaps = t.activation.gaps
    return t.activation.irregular and gaps is not None and gaps[0] == gaps[1]


def _as_timer(t: TaskModel) -> TaskModel:
    """An irregular source as a timer of its least gap."""
    act = t.activation
    gaps = act.gaps
    assert gaps is not None and act.irregular
    return replace(t, activation=Periodic(gaps[0], None, act.span))


def _worst_task(t: TaskModel) -> TaskModel:
    worst = replace(t, bcet=t.wcet)
    return _as_timer(worst) if t.activation.irregular else worst


def _constant_delay(lk: LinkModel) -> LinkModel:
    """The connection at its least delay (the simulator's default); no task of the cone is triggered,
    so delays change no timing."""
    return replace(lk, delay_max=lk.delay_min)


def _period_text(t: TaskModel) -> str:
    gaps = t.activation.gaps
    assert gaps is not None  # (an irregular source)
    return fmt_time(gaps[0])
