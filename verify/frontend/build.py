"""Model building: the semantic model (``verify.model.system``) of a system that resolved and validated
without errors (``build_system``), the activation of a binding (``activation_model``) and the walk of a
chain through the connections (``chain_path``, which validation also uses to report broken chains)."""
from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction
from typing import Literal, TypedDict, cast

from ..core.construct import direct_constructor
from ..core.ids import PortId, TaskId
from ..core.source import NO_SPAN, Span
from ..model import syntax as s
from ..model.activations import DataTriggered, Hole, HoleWhat, Periodic, SporadicSource
from ..model.system import (
    ActivationModel, ChainModel, ComponentModel, CompoundDecl, CompoundModel, CoreModel, ExecutorKind, ExecutorModel,
    GroupKind, GroupModel, HopModel, InstanceModel, LinkModel, MessageModel, PortDecl, PortModel, ReadModel,
    SystemModel, TaskDecl, TaskModel,
)
from ..model.units import quantity_hertz, quantity_seconds
from .fmt import format_activation, format_number, format_quantity
from .resolve import SystemScope, ros_message

#: a 10,000-task system has as many of these (``verify.core.construct``)
_new_task = direct_constructor(TaskModel)
_new_read = direct_constructor(ReadModel)
_new_periodic = direct_constructor(Periodic)
_new_link = direct_constructor(LinkModel)
_new_hop = direct_constructor(HopModel)
_new_port = direct_constructor(PortModel)
_new_port_decl = direct_constructor(PortDecl)
_new_instance = direct_constructor(InstanceModel)
_new_component = direct_constructor(ComponentModel)
_new_task_decl = direct_constructor(TaskDecl)
_new_compound_decl = direct_constructor(CompoundDecl)


#: why a chain's element cannot be reached from the previous one (``chain_path``): its index, the kind
#: of problem and the reader(s) concerned
ChainProblem = tuple[int, Literal["unreachable", "ambiguous", "no-reader"], "TaskId | tuple[TaskId, ...] | None"]


def _seconds(q: s.Quantity | None) -> Fraction | None:
    return None if q is None else quantity_seconds(q)


def activation_model(act: s.Activation, component: s.Component) -> ActivationModel:
    """The semantic activation of a (validated) binding of a task of ``component``."""
    if isinstance(act, s.Timer):
        if isinstance(act.period, s.PeriodHole):
            return hole_of(act)
        return _new_periodic(quantity_seconds(act.period), _seconds(act.phase), act.span)
    if isinstance(act, s.Sporadic):
        a, b = quantity_seconds(act.low), quantity_seconds(act.high)
        return SporadicSource(min(a, b), max(a, b), act.span)
    if isinstance(act, s.Trigger):
        if isinstance(act.prescaler, s.PrescalerHole):
            return hole_of(act)
        mode, members = _trigger_members(component, act.port.text)
        return DataTriggered(act.port.text, members, mode, int(act.prescaler.value), act.span)
    return hole_of(act)


def _trigger_members(component: s.Component, port: str) -> tuple[Literal["single", "and", "or"], tuple[str, ...]]:
    """(mode, member in-ports) of the trigger port ``port``: a compound's, else ("single", (port,)) for
    an in-port (the last declaration of a name counts, as in a dict of them)."""
    for c in reversed(component.compounds):
        if c.name.text == port:
            return c.mode, tuple(m.text for m in c.members)
    if any(p.name.text == port for p in component.in_ports):
        return "single", (port,)
    raise KeyError(port)


def build_system(scope: SystemScope) -> SystemModel:
    """The semantic model of a system that resolved and validated without errors."""
    system = scope.system
    executors = tuple(_executor_model(e) for e in system.executors)
    threads = {e.name: e for e in executors}
    tasks: list[TaskModel] = []
    for inst in system.instances:
        component = scope.component_of[inst.name.text].component
        for task in component.tasks:
            binding = scope.bindings[(inst.name.text, task.name.text)]
            tasks.append(_task_model(inst, task, binding, component, threads))
    groups = _groups(system, tasks)
    producers = {f"{t.instance}.{p}": t.id for t in tasks for p in t.produces}
    readers: dict[str, list[TaskId]] = {}
    for t in tasks:
        for r in t.reads:
            readers.setdefault(f"{t.instance}.{r.port}", []).append(t.id)
    instances, components, ports = _structure(scope)
    types = {p.id: p.message_type for p in ports}
    links = tuple(_link_model(conn, producers, readers, types) for conn in system.connections)
    cores = tuple(CoreModel(c.name.text, c.policy.text if c.policy else "fixed_priority", c.span)
                  for c in system.cores)
    compounds = tuple(cm for inst in system.instances
                      for cm in _compound_models(inst, scope.component_of[inst.name.text].component))
    used = {p.message_type for p in ports}
    messages = tuple(MessageModel(name, *ros, m.span) for name, m in sorted(scope.messages.items())
                     if name in used and (ros := ros_message(m.ros)) is not None)
    cost = system.arrival_costs[0] if system.arrival_costs else None
    model = SystemModel(system.name.text, cores, tuple(tasks), links, (), system.span, compounds, instances,
                        components, ports, executors, groups, messages,
                        quantity_seconds(cost.cost) if cost is not None else None,
                        cost.span if cost is not None else NO_SPAN)
    chains = tuple(_chain_model(ch, model, scope) for ch in system.chains)
    return model.with_chains(chains)


def _executor_model(e: s.Executor) -> ExecutorModel:
    assert e.core is not None and e.priority is not None  # (validation requires both)
    return ExecutorModel(e.name.text, cast(ExecutorKind, e.kind.text), e.core.text, int(e.priority.value), e.span,
                         tuple(c.text for c in e.cores) if e.more_cores else (),
                         int(e.threads.value) if e.threads is not None else len(e.cores))


def group_id(instance: str, group: str | None, executor: str) -> str:
    """A callback group's ``GroupModel.id``: ``instance.group``, or ``instance@executor`` for the
    instance's default group on ``executor``."""
    return f"{instance}.{group}" if group is not None else f"{instance}@{executor}"


def _groups(system: s.System, tasks: list[TaskModel]) -> tuple[GroupModel, ...]:
    """The callback groups of the callbacks, in order of their first callback (§9.4)."""
    declared = {f"{inst.name.text}.{g.name.text}": g for inst in system.instances for g in inst.groups}
    found: dict[str, GroupModel] = {}
    for t in tasks:
        if t.group is None or t.group in found:
            continue
        assert t.executor is not None  # (a callback has a group)
        decl = declared.get(t.group)
        found[t.group] = (GroupModel(t.group, t.instance, None, "mutually_exclusive", t.executor, t.span)
                          if decl is None else
                          GroupModel(t.group, t.instance, decl.name.text, cast(GroupKind, decl.kind.text), t.executor,
                                     decl.span))
    return tuple(found.values())


def _task_model(inst: s.Instance, task: s.Task, binding: s.TaskBinding, component: s.Component,
                executors: Mapping[str, ExecutorModel]) -> TaskModel:
    # validation guarantees a core (the binding's or the instance's) and a priority, or an executor, a WCET
    # and an activation
    activation = binding.activation
    assert activation is not None and task.wcet is not None
    executor = executors[binding.executor.text] if binding.executor is not None else None
    if executor is not None:
        core, priority = executor.core, executor.priority
    else:
        core_name = binding.core or inst.core
        assert core_name is not None and binding.priority is not None
        core, priority = core_name.text, int(binding.priority.value)
    c = task.constraint
    return _new_task(
        id=TaskId(f"{inst.name.text}.{task.name.text}"),
        instance=inst.name.text,
        name=task.name.text,
        component=inst.component.text,
        kind=task.kind,
        core=core,
        priority=priority,
        bcet=quantity_seconds(task.bcet) if task.bcet else Fraction(0),
        wcet=quantity_seconds(task.wcet),
        reads=tuple([_new_read(r.port.text, r.optional, r.oversampling, r.undersampling, r.span)
                     for r in task.reads]),
        produces=tuple(p.text for p in task.produces),
        activation=activation_model(activation, component),
        min_rate=quantity_hertz(c.min) if c and c.min else None,
        max_rate=quantity_hertz(c.max) if c and c.max else None,
        changeable=c.changeable if c else True,
        wcrt_bound=_seconds(binding.wcrt),
        deadline=_seconds(binding.deadline),
        span=binding.span,
        definition_span=task.span,
        executor=None if executor is None else executor.name,
        group=None if executor is None else group_id(inst.name.text, binding.group.text if binding.group else None,
                                                     executor.name),
    )


def _compound_models(inst: s.Instance, component: s.Component) -> list[CompoundModel]:
    """The compound in-ports of ``inst`` with their constraints (the last declaration of a name counts,
    as in ``_trigger_members``)."""
    last = {c.name.text: c for c in component.compounds}
    out = []
    for c in component.compounds:
        if last[c.name.text] is not c:
            continue
        k = c.constraint
        out.append(CompoundModel(
            id=PortId(f"{inst.name.text}.{c.name.text}"), instance=inst.name.text, name=c.name.text, mode=c.mode,
            members=tuple(m.text for m in c.members),
            min_rate=quantity_hertz(k.min) if k and k.min else None,
            max_rate=quantity_hertz(k.max) if k and k.max else None,
            changeable=k.changeable if k else True,
            span=inst.name.span, constraint_span=k.span if k else c.span))
    return out


def _link_model(conn: s.Connection, producers: Mapping[str, TaskId], readers: Mapping[str, list[TaskId]],
                types: Mapping[PortId, str]) -> LinkModel:
    low = _seconds(conn.delay_min) or Fraction(0)
    high = _seconds(conn.delay_max) or Fraction(0)
    source = PortId(str(conn.source))
    return _new_link(source, PortId(str(conn.target)), producers[source], tuple(readers.get(str(conn.target), ())),
                     low, high, conn.span, types.get(source, ""))


def _component_model(component: s.Component) -> ComponentModel:
    """The component as the model keeps it (the last declaration of a name counts, as in a dict of
    them; validation reports duplicates)."""
    ports = {p.name.text: _new_port_decl(p.name.text, "in", p.type.text, p.span) for p in component.in_ports}
    ports.update({p.name.text: _new_port_decl(p.name.text, "out", p.type.text, p.span) for p in component.out_ports})
    compounds = {c.name.text: _new_compound_decl(c.name.text, c.mode, tuple(m.text for m in c.members), c.span)
                 for c in component.compounds}
    tasks = tuple(_task_decl(t) for t in component.tasks)
    return _new_component(component.name.text, tuple(ports.values()), tuple(compounds.values()), tasks,
                          component.span)


def _task_decl(task: s.Task) -> TaskDecl:
    c = task.constraint
    return _new_task_decl(task.name.text, task.kind,
                    tuple([_new_read(r.port.text, r.optional, r.oversampling, r.undersampling, r.span)
                           for r in task.reads]),
                    tuple(p.text for p in task.produces),
                    quantity_seconds(task.bcet) if task.bcet else Fraction(0),
                    quantity_seconds(task.wcet) if task.wcet else None,
                    quantity_hertz(c.min) if c and c.min else None, quantity_hertz(c.max) if c and c.max else None,
                    c.changeable if c else True, task.span)


def _structure(scope: SystemScope) -> tuple[tuple[InstanceModel, ...], tuple[ComponentModel, ...],
                                             tuple[PortModel, ...]]:
    """The instances, the components they instantiate (in order of first use) and their ports."""
    components: dict[str, ComponentModel] = {}
    instances, ports = [], []
    for inst in scope.system.instances:
        name = inst.name.text
        component = scope.component_of[name].component
        comp = components.get(component.name.text)
        if comp is None:
            comp = components[component.name.text] = _component_model(component)
        own = [_new_port(PortId(f"{name}.{p.name}"), name, p.name, p.direction, p.message_type, p.span)
               for p in comp.ports]
        ports.extend(own)
        instances.append(_new_instance(name, comp.name, inst.core.text if inst.core else None,
                                       tuple(TaskId(f"{name}.{t.name}") for t in comp.tasks),
                                       tuple(p.id for p in own), inst.span))
    return tuple(instances), tuple(components.values()), tuple(ports)


def chain_path(chain: s.Chain, model: SystemModel,
               scope: SystemScope) -> tuple[list[TaskId], list[HopModel], ChainProblem | None]:
    """Walk a chain. Returns (tasks, hops, problem) where problem is None or
    (index of the element that cannot be reached, kind 'unreachable'|'ambiguous'|'no-reader', detail)."""
    refs = chain.refs
    first = model.producer(str(refs[0]))
    assert first is not None  # a chain starts at an out-port, and a task produces every out-port (E202)
    tasks = [first]
    hops: list[HopModel] = []
    for i in range(1, len(refs)):
        prev_port = str(refs[i - 1])
        ref = refs[i]
        kind = scope.component_of[ref.instance.text].kind_of(ref.member.text)
        outgoing = [lk for lk in model.links_from(prev_port) if lk.target.split(".")[0] == ref.instance.text]
        if kind == "out-port":
            reader = model.producer(str(ref))
            candidates = [lk for lk in outgoing if reader in lk.readers]
        elif kind == "task":
            reader = TaskId(str(ref))
            candidates = [lk for lk in outgoing if reader in lk.readers]
        else:  # in-port closing the chain
            candidates = [lk for lk in outgoing if lk.target == str(ref)]
            if not candidates:
                return tasks, hops, (i, "unreachable", None)
            readers = candidates[0].readers
            if len(readers) != 1:
                return tasks, hops, (i, "ambiguous" if readers else "no-reader", readers)
            reader = readers[0]
        if not candidates:
            return tasks, hops, (i, "unreachable", reader)
        assert reader is not None  # it reads a candidate
        hops.append(_new_hop(tasks[-1], reader, candidates[0], ref.span))
        tasks.append(reader)
    return tasks, hops, None


def _chain_model(chain: s.Chain, model: SystemModel, scope: SystemScope) -> ChainModel:
    tasks, hops, _ = chain_path(chain, model, scope)
    bounds = {sp.kind: quantity_seconds(sp.bound) for sp in chain.specs}
    return ChainModel(chain.name.text, tuple(tasks), tuple(hops), bounds.get("reaction_time"),
                      bounds.get("data_age"), bounds.get("jitter"), chain.span,
                      tuple((sp.kind, sp.span) for sp in chain.specs))


def hole_of(node: s.Activation) -> Hole:
    """The hole that the activation ``node`` (with a ``?``) leaves open."""
    return Hole(**_hole_fields(node))


class _HoleFields(TypedDict, total=False):
    """The fields of a ``Hole`` read from its syntax node."""

    what: HoleWhat
    low: Fraction
    high: Fraction
    step: Fraction | None
    phase: Fraction | None
    port: str
    text: str
    range_text: str
    span: Span
    range_span: Span


def _hole_fields(node: s.Activation) -> _HoleFields:
    text = format_activation(node)
    if isinstance(node, s.Timer) and isinstance(node.period, s.PeriodHole):
        h = node.period
        bounds: _HoleFields = {}
        range_text = ""
        if h.low is not None and h.high is not None:
            bounds = {"low": h.low.seconds(), "high": h.high.seconds(),
                      "step": h.step.seconds() if h.step is not None else None}
            range_text = f"{format_quantity(h.low)} .. {format_quantity(h.high)}" + (
                f" step {format_quantity(h.step)}" if h.step is not None else "")
        phase = node.phase.seconds() if node.phase is not None else None
        fields: _HoleFields = {"what": "period", "phase": phase, "text": text,
                               "range_text": range_text, "span": node.span, "range_span": h.span}
        fields.update(bounds)
        return fields
    if isinstance(node, s.Trigger) and isinstance(node.prescaler, s.PrescalerHole):
        ph = node.prescaler
        bounds = {}
        range_text = ""
        if ph.low is not None and ph.high is not None:
            bounds = {"low": Fraction(ph.low.value), "high": Fraction(ph.high.value)}
            range_text = f"{format_number(ph.low.value)} .. {format_number(ph.high.value)}"
        fields = {"what": "prescaler", "port": node.port.text, "text": text, "range_text": range_text,
                  "span": node.span, "range_span": ph.span}
        fields.update(bounds)
        return fields
    return {"what": "kind", "text": text, "span": node.span, "range_span": node.span}
