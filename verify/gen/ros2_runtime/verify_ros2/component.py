"""What the functional code sees (specs/codegen.md §2): a component's base class, the values a job read
(``Input``) and the values it writes (``Output``), and a burn loop for stand-in functional code."""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Input:
    """The value an in-port's register held when the job started: ``has_value()`` whether one arrived."""

    value: Any
    present: bool

    def has_value(self) -> bool:
        return self.present


class Output:
    """An out-port's value, published when the job completes: a fresh message of the port's type (or
    None for a type bound to no ROS message) that the job fills or replaces."""

    def __init__(self, value: Any) -> None:
        self.value = value


class Component:
    """The base of every generated component class. ``release_task(name)`` releases a sporadic task of
    this instance from the node's own code; ``node`` is the rclpy node of the process running it."""

    def __init__(self, instance: str, node: Any, release: Callable[[str], None]) -> None:
        self.instance = instance
        self.node = node
        self._release = release

    def release_task(self, task: str) -> None:
        self._release(task)


def burn(nanoseconds: int) -> None:
    """Run on the CPU for ``nanoseconds`` of this thread's CPU time (stand-in functional code)."""
    end = time.thread_time_ns() + nanoseconds
    while time.thread_time_ns() < end:
        pass
