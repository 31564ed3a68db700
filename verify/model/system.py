"""The semantic model of one validated system: what analysis, synthesis, proof and generators walk.

Built from a resolved, validated system (``verify.frontend.build.build_system``). Every time is an exact ``Fraction`` of
seconds; every rate a ``Fraction`` of hertz. Tasks are identified as ``instance.Task`` (``ids.TaskId``),
ports as ``instance.port`` (``ids.PortId``); ``SystemModel.task``, ``port``, ``instance`` and
``component`` look them up. Besides what the analysis walks (tasks with their activations, links,
chains, compounds), the model holds the typed structure a generator or an importer walks: the
instances, the components they instantiate with their ports' message types, compound ports and task
declarations, and every port of every instance. A synthesis hole is a semantic ``Hole`` (what is
open and within which range), not syntax. Nodes keep the span of the statement they come from so
results can point back at the user's text. Computed results never live here: analyses return their
own result objects.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Literal, TypedDict

from . import syntax as s
from .activations import KINDS as KINDS
from .activations import Activation as Activation
from .activations import ActivationModel as ActivationModel
from .activations import DataTriggered as DataTriggered
from .activations import Hole as Hole
from .activations import Periodic as Periodic
from .activations import SporadicSource as SporadicSource
from .activations import HoleWhat as HoleWhat
from ..core.ids import PortId, TaskId
from ..core.source import NO_SPAN, Span


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False)


# ------------------------------------------------------------------ system


@dataclass(frozen=True)
class ReadModel:
    port: str  # local in-port name
    optional: bool
    oversampling: s.Tolerance | None
    undersampling: s.Tolerance | None
    span: Span = _span()  # the read in the component


@dataclass(frozen=True)
class TaskModel:
    id: TaskId  # "instance.Task"
    instance: str
    name: str
    component: str
    kind: Literal["preemptive", "cooperative"]
    core: str
    priority: int
    bcet: Fraction
    wcet: Fraction
    reads: tuple[ReadModel, ...]
    produces: tuple[str, ...]  # local out-port names
    activation: ActivationModel
    min_rate: Fraction | None = None  # activation constraint, Hz
    max_rate: Fraction | None = None
    changeable: bool = True
    wcrt_bound: Fraction | None = None  # a response-time bound given by the user
    deadline: Fraction | None = None
    span: Span = _span()  # the binding in the system
    definition_span: Span = _span()  # the task in its component
    executor: str | None = None  # the ROS 2 executor running it as a callback (core, priority: the executor's)
    group: str | None = None  # a callback's group (``GroupModel.id``)
    #: the work of a process taking arrivals on an in-port (``verify.model.arrivals``), not a declared task
    arrival: bool = False

    def reads_port(self, port: str) -> bool:
        return any(r.port == port for r in self.reads)


@dataclass(frozen=True)
class LinkModel:
    """A connection ``source`` (out-port) → ``target`` (in-port), with its writer and its readers."""

    source: PortId  # "inst.port"
    target: PortId
    writer: TaskId  # the task producing source
    readers: tuple[TaskId, ...]  # the tasks reading the target in-port
    delay_min: Fraction = Fraction(0)
    delay_max: Fraction = Fraction(0)
    span: Span = _span()
    message_type: str = ""  # what the connection carries (the ports' type)


@dataclass(frozen=True)
class HopModel:
    """One step of a chain: ``writer`` produces on ``link.source``; ``reader`` reads ``link.target``."""

    writer: TaskId
    reader: TaskId
    link: LinkModel
    span: Span = _span()  # the chain element the hop reaches


@dataclass(frozen=True)
class ChainModel:
    name: str
    tasks: tuple[TaskId, ...]  # first samples the stimulus, last produces the response
    hops: tuple[HopModel, ...]
    reaction_time: Fraction | None = None  # spec bounds, seconds
    data_age: Fraction | None = None
    jitter: Fraction | None = None
    span: Span = _span()
    spec_spans: tuple[tuple[str, Span], ...] = field(default=(), compare=False, repr=False)  # (kind, span)

    def spec_span(self, kind: str, default: Span = NO_SPAN) -> Span:
        """Where the ``kind`` spec (reaction_time, data_age, jitter) is written."""
        return next((span for k, span in self.spec_spans if k == kind), default)


@dataclass(frozen=True)
class CompoundModel:
    """A compound in-port of one instance (``in any = a | b``) and its own activation constraint.

    Its events (specs/timing.md §3) are the arrivals on its members (``mode`` "or") or the arrivals
    completing a fresh set ("and"), before the prescaler of any task it triggers. ``min_rate`` /
    ``max_rate`` (Hz, None: no bound) are a requirement on their rate, checked by the analysis
    (E314, §5.1); they never change the rate it propagates."""

    id: PortId  # "instance.port"
    instance: str
    name: str
    mode: Literal["and", "or"]
    members: tuple[str, ...]  # local in-port names
    min_rate: Fraction | None = None
    max_rate: Fraction | None = None
    changeable: bool = True
    span: Span = _span()  # the instance in the system
    constraint_span: Span = _span()  # the constraint in its component

    @property
    def constrained(self) -> bool:
        return self.min_rate is not None or self.max_rate is not None


@dataclass(frozen=True)
class PortDecl:
    """A port a component declares: its local name, direction and message type (``in scan : LaserScan``)."""

    name: str
    direction: Literal["in", "out"]
    message_type: str
    span: Span = _span()  # the declaration in the component


@dataclass(frozen=True)
class CompoundDecl:
    """A compound in-port a component declares (``in both = a & b``)."""

    name: str
    mode: Literal["and", "or"]
    members: tuple[str, ...]
    span: Span = _span()


@dataclass(frozen=True)
class TaskDecl:
    """A task as its component declares it (the same for every instance): what it reads and produces,
    its execution times and its activation constraint."""

    name: str
    kind: Literal["preemptive", "cooperative"]
    reads: tuple[ReadModel, ...]
    produces: tuple[str, ...]
    bcet: Fraction
    wcet: Fraction | None
    min_rate: Fraction | None = None
    max_rate: Fraction | None = None
    changeable: bool = True
    span: Span = _span()


@dataclass(frozen=True)
class ComponentModel:
    """A component used by the system (Lotz et al.: the component developer's part): its ports with
    their message types, its compound in-ports and its tasks."""

    name: str
    ports: tuple[PortDecl, ...]
    compounds: tuple[CompoundDecl, ...]
    tasks: tuple[TaskDecl, ...]
    span: Span = _span()

    def port(self, name: str) -> PortDecl | None:
        return next((p for p in self.ports if p.name == name), None)

    @property
    def in_ports(self) -> tuple[PortDecl, ...]:
        return tuple(p for p in self.ports if p.direction == "in")

    @property
    def out_ports(self) -> tuple[PortDecl, ...]:
        return tuple(p for p in self.ports if p.direction == "out")


@dataclass(frozen=True)
class MessageModel:
    """Message type ``name`` bound to the ROS message ``package/type`` (specs/language.md)."""

    name: str
    package: str
    type: str
    span: Span = _span()

    @property
    def ros1(self) -> str:
        """The ROS 1 name: ``sensor_msgs/LaserScan``; in C++ ``sensor_msgs::LaserScan``."""
        return f"{self.package}/{self.type}"

    @property
    def ros2(self) -> str:
        """The ROS 2 name: ``sensor_msgs/msg/LaserScan``."""
        return f"{self.package}/msg/{self.type}"


@dataclass(frozen=True)
class PortModel:
    """A port of an instance: ``id`` is ``instance.port``; ``message_type`` what it carries."""

    id: PortId
    instance: str
    name: str
    direction: Literal["in", "out"]
    message_type: str
    span: Span = _span()  # the declaration in the component


@dataclass(frozen=True)
class InstanceModel:
    """An instance of a component in the system: its core (where its tasks run unless a binding says
    otherwise), its tasks and its ports."""

    name: str
    component: str
    core: str | None
    tasks: tuple[TaskId, ...]
    ports: tuple[PortId, ...]
    span: Span = _span()  # the instance in the system


@dataclass(frozen=True)
class CoreModel:
    name: str
    policy: str = "fixed_priority"
    span: Span = _span()


ExecutorKind = Literal["single_threaded", "static_single_threaded", "events", "multi_threaded"]
GroupKind = Literal["mutually_exclusive", "reentrant"]


@dataclass(frozen=True)
class ExecutorModel:
    """A ROS 2 executor (specs/timing.md §9): one thread of ``priority`` on ``core`` that runs the
    callbacks bound to it one at a time, in the order its ``kind`` defines; a multi-threaded one has
    ``threads`` threads over its ``cores`` (§9.4: one worker per core, the cores its own)."""

    name: str
    kind: ExecutorKind
    core: str  # its first core
    priority: int
    span: Span = _span()
    cores: tuple[str, ...] = ()  # every core (empty: ``core`` alone)
    threads: int = 1

    @property
    def workers(self) -> tuple[str, ...]:
        """The cores on which it runs callbacks at once: one callback per core (§9.4)."""
        return self.cores or (self.core,)

    @property
    def multi_threaded(self) -> bool:
        return self.kind == "multi_threaded"

    def kind_rank(self, task: TaskModel) -> int:
        """The position of a callback's kind in a wait-set executor's processing order (§9.2): timers
        before subscriptions, except on the static executor, which processes subscriptions first."""
        timer = task.activation.timer_callback
        return int(timer) if self.kind == "static_single_threaded" else int(not timer)

    @property
    def polls(self) -> bool:
        """A wait-set executor: it takes a snapshot of the ready callbacks at polling points (the events
        executor runs its events in FIFO order instead)."""
        return self.kind != "events"


@dataclass(frozen=True)
class GroupModel:
    """A ROS 2 callback group (specs/timing.md §9.4): a declared ``group NAME KIND`` of an instance, or
    the default group (``name`` None, mutually exclusive) of the instance's callbacks on one executor
    that name no group."""

    id: str
    instance: str
    name: str | None
    kind: GroupKind
    executor: str
    span: Span = _span()

    @property
    def exclusive(self) -> bool:
        return self.kind == "mutually_exclusive"

    def describe(self) -> str:
        what = f"group `{self.name}`" if self.name is not None else "the default group"
        return f"{what} of `{self.instance}` ({self.kind.replace('_', ' ')})"


class _Index(TypedDict):
    """``SystemModel``'s lookup tables."""

    tasks: dict[str, TaskModel]
    producers: dict[str, TaskId]  # out-port "inst.port" -> the task producing it
    into: dict[str, LinkModel]  # in-port -> its connection
    out_of: dict[str, list[LinkModel]]  # out-port -> its connections, in source order
    ports: dict[str, PortModel]
    instances: dict[str, InstanceModel]
    components: dict[str, ComponentModel]
    executors: dict[str, ExecutorModel]
    groups: dict[str, GroupModel]
    callbacks: dict[str, tuple[TaskModel, ...]]  # executor -> its callbacks, in system order
    order: dict[str, int]  # task -> its position in ``tasks``



@dataclass(frozen=True)
class SystemModel:
    name: str
    cores: tuple[CoreModel, ...]
    tasks: tuple[TaskModel, ...]
    links: tuple[LinkModel, ...]
    chains: tuple[ChainModel, ...]
    span: Span = _span()
    compounds: tuple[CompoundModel, ...] = ()  # every compound in-port of every instance
    #: the typed structure generators and importers walk: the instances, the components they
    #: instantiate (in order of first use) and every port of every instance
    instances: tuple[InstanceModel, ...] = ()
    components: tuple[ComponentModel, ...] = ()
    ports: tuple[PortModel, ...] = ()
    executors: tuple[ExecutorModel, ...] = ()
    groups: tuple[GroupModel, ...] = ()  # the callback groups with callbacks, in system order
    #: the ROS messages the message types of its ports are bound to (``message T = ros pkg/Name``)
    messages: tuple[MessageModel, ...] = ()
    #: ``arrival_cost``: the CPU time a process takes per written value it receives (specs/timing.md §6.6),
    #: None: not declared (arrivals cost nothing in the analysis)
    arrival_cost: Fraction | None = None
    arrival_cost_span: Span = _span()

    def message(self, message_type: str) -> MessageModel | None:
        """The ROS message ``message_type`` is bound to; None: unbound (bytes on ROS, specs/codegen.md)."""
        return next((m for m in self.messages if m.name == message_type), None)

    def task(self, task_id: str) -> TaskModel:
        return self._index()["tasks"][task_id]

    def port(self, port_id: str) -> PortModel:
        """The port ``instance.port`` (with its message type)."""
        return self._index()["ports"][port_id]

    def instance(self, name: str) -> InstanceModel:
        return self._index()["instances"][name]

    def component(self, name: str) -> ComponentModel:
        return self._index()["components"][name]

    def _index(self) -> _Index:
        """Lookup tables, built once per model (the model is immutable, so they never go stale)."""
        index: _Index | None = self.__dict__.get("_lookup")
        if index is None:
            producers: dict[str, TaskId] = {f"{t.instance}.{p}": t.id for t in self.tasks for p in t.produces}
            into: dict[str, LinkModel] = {lk.target: lk for lk in self.links}
            out_of: dict[str, list[LinkModel]] = {}
            for lk in self.links:
                out_of.setdefault(lk.source, []).append(lk)
            index = {"tasks": {t.id: t for t in self.tasks}, "producers": producers, "into": into,
                     "out_of": out_of, "ports": {p.id: p for p in self.ports},
                     "instances": {i.name: i for i in self.instances},
                     "components": {c.name: c for c in self.components},
                     "executors": {e.name: e for e in self.executors}, "groups": {g.id: g for g in self.groups},
                     "callbacks": {e.name: tuple(t for t in self.tasks if t.executor == e.name)
                                   for e in self.executors},
                     "order": {t.id: n for n, t in enumerate(self.tasks)}}
            object.__setattr__(self, "_lookup", index)
        return index

    def with_chains(self, chains: tuple[ChainModel, ...]) -> SystemModel:
        """This system with ``chains``; it shares the lookup tables, which do not depend on the chains."""
        other = SystemModel(self.name, self.cores, self.tasks, self.links, chains, self.span, self.compounds,
                            self.instances, self.components, self.ports, self.executors, self.groups, self.messages,
                            self.arrival_cost, self.arrival_cost_span)
        if "_lookup" in self.__dict__:
            object.__setattr__(other, "_lookup", self.__dict__["_lookup"])
        return other

    def link_into(self, port: str) -> LinkModel | None:
        """The connection into in-port ``inst.port`` (at most one: rule E211)."""
        return self._index()["into"].get(port)

    def links_from(self, port: str) -> tuple[LinkModel, ...]:
        """The connections out of out-port ``inst.port``, in source order."""
        return tuple(self._index()["out_of"].get(port, ()))

    def producer(self, port: str) -> TaskId | None:
        """The task id producing out-port ``inst.port``."""
        return self._index()["producers"].get(port)

    @property
    def holes(self) -> tuple[TaskModel, ...]:
        return tuple(t for t in self.tasks if t.activation.unknown)

    @property
    def is_configured(self) -> bool:
        return not self.holes

    def tasks_on(self, core: str) -> tuple[TaskModel, ...]:
        return tuple(t for t in self.tasks if t.core == core)

    def executor(self, name: str) -> ExecutorModel:
        return self._index()["executors"][name]

    def capacity(self, core: str) -> int:
        """How many jobs the tasks of ``core`` (``TaskModel.core``) run at once: the workers of the
        multi-threaded executor whose first core it is (its callbacks' core, §9.4), else 1."""
        return next((len(e.workers) for e in self.executors if e.multi_threaded and e.core == core), 1)

    def group(self, group_id: str) -> GroupModel:
        return self._index()["groups"][group_id]

    def order(self, task_id: str) -> int:
        """The position of a task in the system's order (``tasks``)."""
        return self._index()["order"][task_id]

    def callbacks(self, executor: str) -> tuple[TaskModel, ...]:
        """The tasks bound to ``executor``, in system order (its registration order, §9)."""
        return self._index()["callbacks"].get(executor, ())
