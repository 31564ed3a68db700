"""Typed ids of the semantic model: a task is ``instance.Task``, a port ``instance.port``.

They are strings at run time (dictionaries keyed by them stay as fast as before, and a model built by
hand with plain strings is the same model) and distinct types for the type checker, so that a port id
is never passed where a task id is expected.
"""
from __future__ import annotations

from typing import NewType

TaskId = NewType("TaskId", str)
PortId = NewType("PortId", str)


def task_id(instance: str, task: str) -> TaskId:
    return TaskId(f"{instance}.{task}")


def port_id(instance: str, port: str) -> PortId:
    return PortId(f"{instance}.{port}")
