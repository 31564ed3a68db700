"""What every activation kind tells the stages (specs/timing.md §3).

An activation kind is one class, in one module of this package, registered in ``KINDS`` by the name
the stages and reports show (``timer``, ``sporadic``, ``trigger``, ``hole``). The analysis, the
simulators, the proof search and the synthesis encoding ask an activation what they need instead of
testing its class:

- *Releases by time* (a source, in CPA terms: Richter 2005, §2): ``gaps`` is the least and greatest
  distance between two releases (the event model's δ⁻(2) and δ⁺(2)); ``strict_period`` the period of a
  strictly periodic one (only those have a hyperperiod; the others are ``irregular``); ``fixed_phase`` the
  first release when it is fixed, else the scenario chooses it in ``[0, offset_window)``.
- *Releases by data*: ``trigger_members`` are the in-ports whose arrivals count, ``release_every`` the
  prescaler (the task runs on every k-th activation event), ``all_members`` whether an event needs a
  fresh sample on every member, ``trigger_port`` the port or compound it names, ``single_port`` that port
  when it is one plain in-port, ``trigger_mode`` how the members make an event (single, and, or),
  ``listens_to(member)`` whether an arrival on ``member`` counts.
- *On an executor*: ``timer_callback`` whether the callback is a timer (else a subscription).
- *Open*: ``unknown`` is true for what ``synth`` has still to choose (no release is known).
- *Text*: ``describe()`` as the analysis report shows it, ``as_written()`` as a binding writes it.
"""
from __future__ import annotations

from fractions import Fraction
from typing import ClassVar, Literal


class Activation:
    """The behaviour of an activation; each kind overrides what applies to it."""

    #: the kind's name in reports and diagnostics
    kind: ClassVar[str]
    #: what the first release is called in a scenario's messages
    offset_name: ClassVar[str] = "first release"

    # ------------------------------------------------------------------ releases by time

    @property
    def gaps(self) -> tuple[Fraction, Fraction] | None:
        """(least, greatest) time between two releases of an activation that releases by time, else None."""
        return None

    @property
    def fixed_phase(self) -> Fraction | None:
        """The time of the first release when the model fixes it."""
        return None

    @property
    def strict_period(self) -> Fraction | None:
        """The period of an activation that releases strictly periodically (a hyperperiod exists)."""
        return None

    @property
    def irregular(self) -> bool:
        """Released by time, but not strictly periodically: its releases have no hyperperiod."""
        return self.gaps is not None and self.strict_period is None

    @property
    def offset_window(self) -> Fraction | None:
        """When the first release is free: it lies in ``[0, offset_window)``; None when fixed or not timed."""
        gaps = self.gaps
        return gaps[1] if gaps is not None and self.fixed_phase is None else None

    @property
    def first_release_latest(self) -> Fraction | None:
        """The latest first release of a timed activation: its fixed phase, else its greatest gap."""
        gaps = self.gaps
        if gaps is None:
            return None
        phase = self.fixed_phase
        return phase if phase is not None else gaps[1]

    # ------------------------------------------------------------------ releases by data

    @property
    def trigger_members(self) -> tuple[str, ...]:
        """The in-ports whose arrivals are activation events (none for a timed activation)."""
        return ()

    @property
    def release_every(self) -> int:
        """k: the task is released on every k-th activation event (1 unless a prescaler says otherwise)."""
        return 1

    @property
    def all_members(self) -> bool:
        """An activation event needs a fresh sample on every member (an AND compound)."""
        return False

    @property
    def trigger_port(self) -> str | None:
        """The in-port or compound a data trigger names."""
        return None

    @property
    def single_port(self) -> str | None:
        """The port of a data trigger on one plain in-port."""
        return None

    @property
    def trigger_mode(self) -> Literal["single", "and", "or"] | None:
        """How a data trigger's members make an activation event: one in-port (``single``), a fresh sample
        on every member (``and``), an arrival on any member (``or``); None when not released by data."""
        return None

    def listens_to(self, member: str) -> bool:
        """An arrival on in-port ``member`` is an activation event."""
        return member in self.trigger_members

    def describe(self) -> str:
        """The activation as the analysis report shows it, e.g. ``timer 10 ms``."""
        return self.kind

    def as_written(self) -> str:
        """The activation as a binding writes it, e.g. ``timer 10 ms phase 2 ms`` (``describe`` unless the
        kind writes more)."""
        return self.describe()

    # ------------------------------------------------------------------ executors (specs/timing.md §9)

    @property
    def timer_callback(self) -> bool:
        """On an executor, the callback is a timer (rcl skips a missed period), not a subscription."""
        return self.strict_period is not None

    # ------------------------------------------------------------------ synthesis

    @property
    def unknown(self) -> bool:
        """``synth`` still has to choose this activation (or a part of it)."""
        return False
