"""The typed syntax tree: what the user wrote, as frozen dataclasses with a source span on every node.

The parser (``verify.frontend.parse``) builds these; nothing here resolves names or checks meaning. Spans never
take part in equality, so two trees that say the same thing compare equal wherever they were written
(``parse(format(m)) == m``). Names and references carry their own span so that diagnostics can point at
exactly the word that is wrong.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Literal

from ..core.source import NO_SPAN, Span

TIME_UNITS: dict[str, Fraction] = {
    "s": Fraction(1),
    "ms": Fraction(1, 1000),
    "us": Fraction(1, 1_000_000),
    "ns": Fraction(1, 1_000_000_000),
}
FREQUENCY_UNITS: dict[str, Fraction] = {"Hz": Fraction(1), "kHz": Fraction(1000)}

Dimension = Literal["time", "frequency"]


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False)


@dataclass(frozen=True)
class Name:
    """An identifier as written, with its span."""

    text: str
    span: Span = _span()

    def __str__(self) -> str:
        return self.text


@dataclass(frozen=True)
class Number:
    """A unitless exact number (priority, prescaler, sampling factor)."""

    value: Fraction
    span: Span = _span()

    @property
    def is_integer(self) -> bool:
        return self.value.denominator == 1


@dataclass(frozen=True, eq=False)
class Quantity:
    """A time or a frequency, exact. ``value`` is in ``unit``; equality compares the physical amount."""

    value: Fraction
    unit: str
    span: Span = _span()

    @property
    def dimension(self) -> Dimension:
        return "time" if self.unit in TIME_UNITS else "frequency"

    @property
    def base(self) -> Fraction:
        """The amount in seconds (time) or hertz (frequency)."""
        scale = TIME_UNITS.get(self.unit) or FREQUENCY_UNITS[self.unit]
        return self.value * scale

    def seconds(self) -> Fraction:
        """This quantity read as a time: a period for a frequency (1/f)."""
        return self.base if self.dimension == "time" else 1 / self.base

    def hertz(self) -> Fraction:
        """This quantity read as a frequency: a rate for a time (1/T)."""
        return self.base if self.dimension == "frequency" else 1 / self.base

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Quantity):
            return NotImplemented
        return (self.dimension, self.base) == (other.dimension, other.base)

    def __hash__(self) -> int:
        return hash((self.dimension, self.base))


# ------------------------------------------------------------------ components


@dataclass(frozen=True)
class InPort:
    name: Name
    type: Name
    span: Span = _span()


@dataclass(frozen=True)
class OutPort:
    name: Name
    type: Name
    span: Span = _span()


@dataclass(frozen=True)
class ActivationConstraint:
    """Lotz et al.: min/max activation frequency and whether the integrator may change the rate."""

    min: Quantity | None
    max: Quantity | None
    changeable: bool = True
    span: Span = _span()


@dataclass(frozen=True)
class CompoundPort:
    """A group of in-ports of one component with AND (all fresh) or OR (any) activation."""

    name: Name
    mode: Literal["and", "or"]
    members: tuple[Name, ...]
    constraint: ActivationConstraint | None = None
    span: Span = _span()


@dataclass(frozen=True)
class Tolerance:
    """How much over- or undersampling an input accepts: ok, forbidden, or at most ``factor``."""

    kind: Literal["ok", "forbidden", "max"]
    factor: Number | None = None
    span: Span = _span()


@dataclass(frozen=True)
class Read:
    port: Name
    optional: bool = False
    oversampling: Tolerance | None = None
    undersampling: Tolerance | None = None
    span: Span = _span()


@dataclass(frozen=True)
class Task:
    name: Name
    kind: Literal["preemptive", "cooperative"] = "preemptive"
    reads: tuple[Read, ...] = ()
    produces: tuple[Name, ...] = ()
    bcet: Quantity | None = None
    wcet: Quantity | None = None
    constraint: ActivationConstraint | None = None
    span: Span = _span()
    #: clauses that may appear once but were given again (validation reports them)
    repeated: tuple[Span, ...] = field(default=(), compare=False, repr=False)
    end: Span = _span()


@dataclass(frozen=True)
class Component:
    name: Name
    in_ports: tuple[InPort, ...] = ()
    out_ports: tuple[OutPort, ...] = ()
    compounds: tuple[CompoundPort, ...] = ()
    tasks: tuple[Task, ...] = ()
    span: Span = _span()
    end: Span = _span()


# ------------------------------------------------------------------ activation sources


@dataclass(frozen=True)
class PeriodHole:
    """An unknown period for ``synth``: optionally a range (times or frequencies) and a grid step."""

    low: Quantity | None = None
    high: Quantity | None = None
    step: Quantity | None = None
    span: Span = _span()


@dataclass(frozen=True)
class PrescalerHole:
    low: Number | None = None
    high: Number | None = None
    span: Span = _span()


@dataclass(frozen=True)
class Timer:
    period: Quantity | PeriodHole
    phase: Quantity | None = None
    span: Span = _span()


@dataclass(frozen=True)
class Trigger:
    port: Name
    prescaler: Number | PrescalerHole = Number(Fraction(1))
    span: Span = _span()


@dataclass(frozen=True)
class Sporadic:
    """Min and max inter-arrival time, or a frequency range."""

    low: Quantity
    high: Quantity
    span: Span = _span()


@dataclass(frozen=True)
class UnknownActivation:
    """``activation ?``: synthesis chooses the kind."""

    span: Span = _span()


Activation = Timer | Trigger | Sporadic | UnknownActivation


def is_hole(act: Activation | None) -> bool:
    """``act`` leaves something for ``synth`` to choose: ``activation ?``, ``timer ?`` or ``every ?``."""
    return (isinstance(act, UnknownActivation)
            or (isinstance(act, Timer) and isinstance(act.period, PeriodHole))
            or (isinstance(act, Trigger) and isinstance(act.prescaler, PrescalerHole)))


# ------------------------------------------------------------------ systems


@dataclass(frozen=True)
class Core:
    name: Name
    policy: Name | None = None
    span: Span = _span()


@dataclass(frozen=True)
class Executor:
    """``executor NAME KIND [N threads] on CORE, … priority N``: a ROS 2 executor (specs/timing.md §9)."""

    name: Name
    kind: Name
    core: Name | None = None  # the first core it lists
    priority: Number | None = None
    span: Span = _span()
    repeated: tuple[Span, ...] = field(default=(), compare=False, repr=False)
    more_cores: tuple[Name, ...] = ()  # the cores after the first (a multi-threaded executor's)
    threads: Number | None = None  # ``N threads`` (multi-threaded)

    @property
    def cores(self) -> tuple[Name, ...]:
        return () if self.core is None else (self.core, *self.more_cores)


@dataclass(frozen=True)
class CallbackGroup:
    """``group NAME KIND`` in an instance body: a ROS 2 callback group of the instance's node (§9)."""

    name: Name
    kind: Name
    span: Span = _span()


@dataclass(frozen=True)
class TaskBinding:
    task: Name
    priority: Number | None = None
    core: Name | None = None
    activations: tuple[Activation, ...] = ()
    wcrt: Quantity | None = None
    deadline: Quantity | None = None
    executor: Name | None = None  # the executor running it as a callback (then no priority, no core)
    group: Name | None = None  # its callback group (of its instance), with an executor
    span: Span = _span()
    repeated: tuple[Span, ...] = field(default=(), compare=False, repr=False)

    @property
    def activation(self) -> Activation | None:
        return self.activations[0] if self.activations else None


@dataclass(frozen=True)
class Instance:
    name: Name
    component: Name
    core: Name | None = None
    bindings: tuple[TaskBinding, ...] = ()
    span: Span = _span()
    end: Span | None = field(default=None, compare=False, repr=False)
    groups: tuple[CallbackGroup, ...] = ()


@dataclass(frozen=True)
class PortRef:
    """``instance.member`` where member is a port or (closing a chain) a task."""

    instance: Name
    member: Name
    span: Span = _span()

    def __str__(self) -> str:
        return f"{self.instance.text}.{self.member.text}"


@dataclass(frozen=True)
class Connection:
    source: PortRef
    target: PortRef
    delay_min: Quantity | None = None
    delay_max: Quantity | None = None
    span: Span = _span()


SpecKind = Literal["reaction_time", "data_age", "jitter"]


@dataclass(frozen=True)
class Spec:
    kind: SpecKind
    bound: Quantity
    span: Span = _span()


@dataclass(frozen=True)
class Chain:
    name: Name
    refs: tuple[PortRef, ...]
    specs: tuple[Spec, ...] = ()
    span: Span = _span()
    end: Span | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class System:
    name: Name
    cores: tuple[Core, ...] = ()
    instances: tuple[Instance, ...] = ()
    connections: tuple[Connection, ...] = ()
    chains: tuple[Chain, ...] = ()
    span: Span = _span()
    end: Span = _span()
    executors: tuple[Executor, ...] = ()
    arrival_costs: tuple[ArrivalCost, ...] = ()  # (more than one: E212)


@dataclass(frozen=True)
class ArrivalCost:
    """``arrival_cost QUANTITY``: what a ROS 2 (rclpy) process spends taking one written value off the
    wire (specs/timing.md §6.6)."""

    cost: Quantity
    span: Span = _span()


@dataclass(frozen=True)
class Import:
    path: str
    span: Span = _span()
    path_span: Span = _span()  #: the quoted file name


@dataclass(frozen=True)
class Message:
    """``message NAME = ros "PACKAGE/TYPE"``: message type NAME is a ROS message (``ros``: the string's
    text, unchecked; ``verify.frontend.resolve`` checks it)."""

    name: Name
    ros: str
    span: Span = _span()
    ros_span: Span = _span()  #: the quoted ROS name


@dataclass(frozen=True)
class Module:
    """One source file: its imports, components and systems, in source order; its message declarations."""

    path: str
    imports: tuple[Import, ...] = ()
    components: tuple[Component, ...] = ()
    systems: tuple[System, ...] = ()
    span: Span = _span()
    messages: tuple[Message, ...] = ()
