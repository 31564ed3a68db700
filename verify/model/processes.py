"""The processes a system runs as on ROS 2 (rclpy): the partition of its tasks that `verify gen ros2`
generates (specs/codegen.md §9.2) and that the analysis of arrivals (``verify.model.arrivals``,
specs/timing.md §6.6) charges.

A process runs, on one thread, the jobs of an executor (its callbacks), of one preemptive task bound
with a priority, or of the cooperative tasks of one instance. It is pinned to the core of its task of
the highest priority, and it subscribes every connected in-port of the instances whose tasks it runs.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..core.ids import PortId
from .system import SystemModel, TaskModel


@dataclass(frozen=True)
class Process:
    """One process: an executor's (``kind`` "executor", ``name`` the executor's), one preemptive task's
    ("task", ``name`` the task id) or an instance's cooperative tasks' ("instance", the instance's)."""

    kind: Literal["executor", "task", "instance"]
    name: str

    @property
    def label(self) -> str:
        """The name the generated code derives the process's from: the executor's, the instance's, or
        ``instance_Task``."""
        return self.name.replace(".", "_", 1) if self.kind == "task" else self.name


def process_of(task: TaskModel) -> Process:
    """The process running ``task``: its executor's, its own (preemptive), its instance's (cooperative)."""
    if task.executor is not None:
        return Process("executor", task.executor)
    if task.kind == "cooperative":
        return Process("instance", task.instance)
    return Process("task", task.id)


def processes(model: SystemModel) -> dict[Process, list[TaskModel]]:
    """Every process and its tasks, in system order."""
    out: dict[Process, list[TaskModel]] = {}
    for task in model.tasks:
        out.setdefault(process_of(task), []).append(task)
    return out


def core_of(tasks: list[TaskModel]) -> str:
    """The core a process is pinned to: that of its task of the highest priority (the first of them)."""
    return max(tasks, key=lambda t: t.priority).core


def subscriptions(model: SystemModel, tasks: list[TaskModel]) -> tuple[PortId, ...]:
    """The in-ports a process with ``tasks`` takes arrivals on: every connected in-port of the instances
    whose tasks it runs, in instance and port order."""
    out: list[PortId] = []
    for instance in dict.fromkeys(t.instance for t in tasks):
        for port in model.instance(instance).ports:
            if model.link_into(port) is not None and port not in out:
                out.append(port)
    return tuple(out)
