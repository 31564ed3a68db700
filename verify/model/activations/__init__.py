"""The activation kinds, one module each, and what they tell the stages (``base.Activation``).

A new kind is one module here — a frozen dataclass deriving from ``Activation`` with its ``kind`` name,
overriding the behaviour that applies to it — registered in ``KINDS`` and ``ActivationModel`` below, plus
its tests; the model builder makes it from its syntax (its grammar rule). The stages ask an activation
what they need (``base``); the analysis report's JSON Schema lists the names in ``KINDS``.
"""
from __future__ import annotations

from .base import Activation
from .hole import Hole, HoleWhat
from .sporadic import SporadicSource
from .timer import Periodic
from .trigger import DataTriggered

#: a task's activation: one of the kinds
ActivationModel = Periodic | SporadicSource | DataTriggered | Hole

#: every activation kind by its name
KINDS: dict[str, type[Activation]] = {cls.kind: cls for cls in (Periodic, SporadicSource, DataTriggered, Hole)}

__all__ = ["KINDS", "Activation", "ActivationModel", "DataTriggered", "Hole", "HoleWhat", "Periodic",
           "SporadicSource"]
