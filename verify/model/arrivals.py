"""The work a ROS 2 (rclpy) process does to take arrivals, as tasks of the model (specs/timing.md §6.6).

rclpy's executor takes every value (and its out-of-band record) a process receives on a thread of its
own, at a real-time priority above the jobs' threads (specs/codegen.md §9.2 and §9.5); that Python work
takes the CPU, and within the process the interpreter lock, from the jobs of its core. With
``arrival_cost C`` declared, ``with_arrivals`` adds, per process (``verify.model.processes``) and per
in-port it subscribes, one **arrival task**: preemptive, on the process's core, at a priority above
every task of the system, released by every write of the port's writer as a data trigger on that port
is (the writer's completions, the connection's delay), running up to ``C`` (at least 0) and writing
nothing; and per sporadic task it runs, one released as that task is (its releases may come as
messages on its release topic). Every analysis of the model — the response times of tasks, executors' callbacks and
multi-threaded executors, the CPA fixed point, the chain bounds, the simulators of ``prove`` and
``synth``'s evaluations — then charges that work as it charges any task's. An arrival task has no
deadline; it is marked (``TaskModel.arrival``) and named ``instance.arrival[PROCESS]:port`` (or
``instance.arrival[PROCESS]:release(Task)``), a name no declared task can have.

A model without ``arrival_cost``, or one that has its arrival tasks already, is returned as it is.
"""
from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

from ..core.ids import task_id
from ..core.source import Span
from .activations import DataTriggered, SporadicSource
from .processes import core_of, processes, subscriptions
from .system import ActivationModel, SystemModel, TaskModel

ZERO = Fraction(0)


def arrival_task_name(process: str, port: str) -> str:
    """The name of the arrival task of ``process`` (its label) for its in-port ``port`` (the local name)."""
    return f"arrival[{process}]:{port}"


def arrival_tasks(model: SystemModel) -> tuple[TaskModel, ...]:
    """The arrival tasks of ``model`` (none without ``arrival_cost``), in process and port order."""
    cost = model.arrival_cost
    if cost is None or not model.tasks or any(t.arrival for t in model.tasks):
        return ()
    top = max(t.priority for t in model.tasks) + 1
    out: list[TaskModel] = []
    for process, tasks in processes(model).items():
        core = core_of(tasks)
        for port in subscriptions(model, tasks):
            link = model.link_into(port)
            assert link is not None  # (``subscriptions`` takes connected ports only)
            instance, local = port.split(".", 1)
            name = arrival_task_name(process.label, local)
            trigger = DataTriggered(local, (local,), "single", 1, link.span)
            out.append(_arrival(model, instance, name, core, top, trigger, link.span))
        for task in tasks:  # (a sporadic task's releases by message: `/SYSTEM/INSTANCE/release/TASK`)
            if isinstance(task.activation, SporadicSource):
                name = arrival_task_name(process.label, f"release({task.name})")
                out.append(_arrival(model, task.instance, name, core, top, task.activation, task.span))
    return tuple(out)


def _arrival(model: SystemModel, instance: str, name: str, core: str, priority: int, activation: ActivationModel,
             span: Span) -> TaskModel:
    assert model.arrival_cost is not None
    return TaskModel(task_id(instance, name), instance, name, model.instance(instance).component, "preemptive", core,
                     priority, ZERO, model.arrival_cost, (), (), activation, changeable=False, span=span,
                     definition_span=model.arrival_cost_span, arrival=True)


def with_arrivals(model: SystemModel) -> SystemModel:
    """``model`` with its arrival tasks after its own tasks (the model itself when it has none to add)."""
    added = arrival_tasks(model)
    if not added:
        return model
    return replace(model, tasks=model.tasks + added)
