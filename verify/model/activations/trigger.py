"""``trigger PORT [every K]``: released by arrivals on an in-port or compound (specs/timing.md §3)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

from ...core.source import NO_SPAN, Span
from .base import Activation


@dataclass(frozen=True)
class DataTriggered(Activation):
    """Activated by arrivals on ``port`` (an in-port or compound of the task's component).

    ``members`` are the in-ports whose arrivals count: one for a plain in-port; for a compound,
    its members with ``mode`` "and" (every member holds a fresh sample) or "or" (any arrival).
    The task fires on every ``prescaler``-th activation event.
    """

    kind: ClassVar[str] = "trigger"

    port: str
    members: tuple[str, ...]
    mode: Literal["single", "and", "or"] = "single"
    prescaler: int = 1
    span: Span = field(default=NO_SPAN, compare=False, repr=False)

    @property
    def trigger_members(self) -> tuple[str, ...]:
        return self.members

    @property
    def release_every(self) -> int:
        return self.prescaler

    @property
    def all_members(self) -> bool:
        return self.mode == "and"

    @property
    def trigger_port(self) -> str:
        return self.port

    @property
    def single_port(self) -> str | None:
        return self.port if self.mode == "single" else None

    @property
    def trigger_mode(self) -> Literal["single", "and", "or"]:
        return self.mode

    def describe(self) -> str:
        return f"trigger {self.port}" + (f" every {self.prescaler}" if self.prescaler != 1 else "")
