"""Recorded callbacks paired with the model's tasks (specs/trace.md §2).

A callback is identified as CARET identifies it — node, type, period or topic, symbol, construction
order — and a task by what the model says of it: its instance (the node: the instance's name is the
node's name as ``verify import caret`` writes it), its activation (a timer is a timer callback, a data
trigger on an in-port is the subscription callback of the topic the port is named after) and its place
among the instance's tasks alike. Tasks and callbacks alike are paired in order — tasks in the order the
model declares them, callbacks in the order they were registered (their construction order) — when
their numbers agree (timers alike are paired by period first); when they do not, none of them is paired,
and each is listed with the reason. Nothing is guessed.

A job record names its node (``/SYSTEM/INSTANCE``) and its task, or (the ROS 2 nodes') its process and
``INSTANCE.TASK``: it is paired with that task.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction

from ..gen.ros2 import unit_of
from ..interop.caret.read import IGNORED_TOPICS
from ..interop.caret.to_vfy import language_name
from ..model.activations import DataTriggered, Periodic
from ..model.system import SystemModel, TaskModel
from .recording import Callback, Recording


@dataclass(frozen=True)
class Matching:
    """``pairs``: task id → callback key; what is left unpaired, each with why."""

    pairs: dict[str, str]
    tasks_unmatched: tuple[tuple[str, str], ...]  # (task id, reason)
    callbacks_unmatched: tuple[tuple[str, str], ...]  # (callback key, reason)
    callbacks_left_out: int  # callbacks of topics CARET leaves out (/parameter_events, /rosout, /clock)


def _task_class(task: TaskModel) -> tuple[str, str | None] | None:
    """(kind, port) a task is recorded as: ("timer", None), ("subscription", in-port); None for an
    activation no callback has."""
    if isinstance(task.activation, Periodic):
        return ("timer", None)
    if isinstance(task.activation, DataTriggered):
        return ("subscription", task.activation.port)
    return None


def _callback_class(c: Callback) -> tuple[str, str | None]:
    return (c.kind, None if c.kind == "timer" else language_name(c.topic or ""))


def _instance_of(node: str | None) -> str | None:
    return None if node is None else language_name(node)


def match(model: SystemModel, recording: Recording) -> Matching:
    """The pairing of ``model``'s tasks with ``recording``'s callbacks."""
    if recording.source == "job records":
        return _match_records(model, recording)
    if recording.source == "bag":
        return _match_topics(model, recording)
    left_out = [c for c in recording.callbacks.values() if c.kind == "subscription" and c.topic in IGNORED_TOPICS]
    callbacks = [c for c in recording.callbacks.values() if c not in left_out]
    groups: dict[tuple[str | None, str, str | None], tuple[list[TaskModel], list[Callback]]] = {}
    tasks_unmatched: list[tuple[str, str]] = []
    for task in model.tasks:
        cls = _task_class(task)
        if cls is None:
            tasks_unmatched.append((task.id, f"a {task.activation.kind} activation is no ROS 2 callback's"))
            continue
        groups.setdefault((task.instance, *cls), ([], []))[0].append(task)
    callbacks_unmatched: list[tuple[str, str]] = []
    instances = {i.name for i in model.instances} | {t.instance for t in model.tasks}
    for c in sorted(callbacks, key=lambda c: c.registered):
        instance = _instance_of(c.node)
        if instance is None:
            callbacks_unmatched.append((c.key, "its node is not in the trace (no `rclcpp_timer_link_node` or "
                                               "`rcl_subscription_init` for it)"))
            continue
        if instance not in instances:
            callbacks_unmatched.append((c.key, f"the model has no instance `{instance}`"))
            continue
        groups.setdefault((instance, *_callback_class(c)), ([], []))[1].append(c)
    pairs: dict[str, str] = {}
    for (instance, kind, port), (tasks, found) in groups.items():
        paired = _pair(tasks, found)
        if paired is not None:
            pairs.update(paired)
            continue
        what = "timer" if kind == "timer" else f"subscription on `{port}`"
        if not found:
            reason = f"no {what} callback of node `{instance}` in the trace"
        elif not tasks:
            reason = f"the model has no task of instance `{instance}` activated as this {what} callback"
        else:
            reason = (f"{len(tasks)} task(s) of instance `{instance}` and {len(found)} {what} callback(s) of its "
                      "node in the trace: not told apart")
        tasks_unmatched += [(t.id, reason) for t in tasks]
        callbacks_unmatched += [(c.key, reason) for c in found]
    return Matching(pairs, tuple(tasks_unmatched), tuple(callbacks_unmatched), len(left_out))


def _pair(tasks: list[TaskModel], found: list[Callback]) -> dict[str, str] | None:
    """Tasks and callbacks alike, paired in order (timers by period first); None when their numbers differ."""
    if not tasks or len(tasks) != len(found):
        return None
    if len(tasks) > 1 and all(isinstance(t.activation, Periodic) for t in tasks):
        by_period = _pair_by_period(tasks, found)
        if by_period is not None:
            return by_period
    return {t.id: c.key for t, c in zip(tasks, found, strict=True)}


def _pair_by_period(tasks: list[TaskModel], found: list[Callback]) -> dict[str, str] | None:
    """Timers paired by period, in order among those of one period (None when the periods do not agree)."""
    def period(t: TaskModel) -> Fraction:
        assert isinstance(t.activation, Periodic)
        return t.activation.period

    model_periods = sorted(period(t) for t in tasks)
    trace_periods = sorted(Fraction(c.period_ns or 0, 10**9) for c in found)
    if model_periods != trace_periods:
        return None
    out: dict[str, str] = {}
    for p in dict.fromkeys(model_periods):
        alike = [c for c in found if Fraction(c.period_ns or 0, 10**9) == p]
        out.update({t.id: c.key for t, c in zip((t for t in tasks if period(t) == p), alike, strict=False)})
    return out


def _match_records(model: SystemModel, recording: Recording) -> Matching:
    """Job records by the names their generator gives: the ROS 1 nodes' (``/SYSTEM/INSTANCE``, task name),
    the ROS 2 nodes' (process as ``verify gen ros2`` names it, ``INSTANCE.TASK``)."""
    by_name = {(f"/{model.name}/{t.instance}", t.name): t.id for t in model.tasks}
    by_name.update({(unit_of(model, t), t.id): t.id for t in model.tasks})
    pairs: dict[str, str] = {}
    unmatched = []
    for c in recording.callbacks.values():
        task = by_name.get((c.node or "", c.task or ""))
        if task is None:
            unmatched.append((c.key, f"the model has no task `{c.task}` in a node `{c.node}`"))
        else:
            pairs[task] = c.key
    missing = tuple((t.id, "no job of it in the records") for t in model.tasks if t.id not in pairs)
    return Matching(pairs, missing, tuple(unmatched), 0)


def _topic_port(model: SystemModel, topic: str) -> str | None:
    """The out-port a topic is: ``/SYSTEM/INSTANCE/PORT`` (the generated nodes' topics), or ``/PORT`` (the
    topic an imported model's port is named after) of the one instance with an out-port so named."""
    parts = [language_name(p) for p in topic.strip("/").split("/") if p]
    if not parts:
        return None
    outs = [p for p in model.ports if p.direction == "out" and p.name == parts[-1]]
    if len(parts) >= 2:
        exact = [p for p in outs if p.instance == parts[-2]]
        if exact:
            return exact[0].id
    return outs[0].id if len(outs) == 1 else None


def _match_topics(model: SystemModel, recording: Recording) -> Matching:
    pairs: dict[str, str] = {}
    unmatched = []
    for c in recording.callbacks.values():
        if c.topic in IGNORED_TOPICS:
            continue
        port = _topic_port(model, c.topic or "")
        task = model.producer(port) if port is not None else None
        if task is None:
            unmatched.append((c.key, "no out-port of the model is this topic" if port is None
                              else f"no task produces `{port}`"))
        elif task in pairs:
            unmatched.append((c.key, f"task `{task}` is measured by topic `{pairs[task]}` already"))
        else:
            pairs[task] = c.key
    missing = tuple((t.id, "it produces no topic of the bag") for t in model.tasks if t.id not in pairs)
    return Matching(pairs, missing, tuple(unmatched), 0)


def describe(recording: Recording, keys: Iterable[str]) -> list[str]:
    """The recorded callbacks ``keys`` in words."""
    return [recording.callbacks[k].describe() for k in keys]
