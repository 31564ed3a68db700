"""Hypothesis strategies for modules of the verify language.

``modules``: random *syntactically* valid trees. They say nothing sensible about timing (names need not
resolve, bounds need not be ordered); they are what the grammar accepts, for properties of the parser
and the formatter. ``valid_modules``: random *valid* models, which `verify check` accepts (see the
section at the end). Examples stay small.
"""
from __future__ import annotations

import re
from fractions import Fraction

from hypothesis import strategies as st

from verify.model import syntax as s
from verify.frontend.grammar import grammar_text

MODULE_PATH = "<text>"


def _grammar_keywords() -> frozenset[str]:
    """Every word the grammar spells as a string literal (comments in the grammar skipped)."""
    code = "\n".join(line.split("//", 1)[0] for line in grammar_text().splitlines())
    return frozenset(re.findall(r'"([A-Za-z_][A-Za-z0-9_]*)"', code))


KEYWORDS = _grammar_keywords()
UNITS = tuple(s.TIME_UNITS) + tuple(s.FREQUENCY_UNITS)
RESERVED = KEYWORDS | frozenset(UNITS)

#: plain names, and names that start like a keyword or a unit (the lexer must not split them)
NAME_POOL = tuple(sorted(
    ({"a", "b", "x", "_", "_x9", "A", "Cam", "lidar", "scan", "map_2", "cpu0", "plan", "msg", "sec"}
     | {word + suffix for word in KEYWORDS | set(UNITS) for suffix in ("_", "1", "s")})
    - RESERVED
))
names = st.sampled_from(NAME_POOL).map(s.Name)

#: exact values: integers, terminating decimals and non-terminating rationals such as 100/3
fractions = st.one_of(
    st.integers(0, 10**6).map(Fraction),
    st.builds(Fraction, st.integers(0, 10**5), st.sampled_from([2, 3, 4, 5, 6, 7, 8, 9, 10, 16, 25, 1000])),
)
numbers = fractions.map(s.Number)
quantities = st.builds(s.Quantity, fractions, st.sampled_from(UNITS))


def _optional(strategy):
    return st.none() | strategy


def _tuples(strategy, min_size: int = 0, max_size: int = 2):
    return st.lists(strategy, min_size=min_size, max_size=max_size).map(tuple)


# ------------------------------------------------------------------ components

tolerances = st.one_of(
    st.just(s.Tolerance("ok")),
    st.just(s.Tolerance("forbidden")),
    st.builds(s.Tolerance, st.just("max"), numbers),
)
reads = st.builds(s.Read, names, st.booleans(), _optional(tolerances), _optional(tolerances))
constraints = st.one_of(
    st.builds(s.ActivationConstraint, quantities, quantities, st.booleans()),
    st.builds(lambda q, ch: s.ActivationConstraint(q, q, ch), quantities, st.booleans()),
    st.builds(s.ActivationConstraint, quantities, st.none(), st.booleans()),
    st.builds(s.ActivationConstraint, st.none(), quantities, st.booleans()),
)
tasks = st.builds(
    s.Task,
    names,
    st.sampled_from(["preemptive", "cooperative"]),
    _tuples(reads),
    _tuples(names),
    _optional(quantities),
    _optional(quantities),
    _optional(constraints),
)
compound_constraints = _optional(constraints)
compounds = st.builds(
    s.CompoundPort, names, st.sampled_from(["and", "or"]), _tuples(names, 2, 3), compound_constraints
)
components = st.builds(
    s.Component,
    names,
    _tuples(st.builds(s.InPort, names, names), max_size=2),
    _tuples(st.builds(s.OutPort, names, names), max_size=2),
    _tuples(compounds, max_size=2),
    _tuples(tasks, max_size=3),
)

# ------------------------------------------------------------------ activations

period_holes = st.one_of(
    st.just(s.PeriodHole()),
    st.builds(s.PeriodHole, quantities, quantities, _optional(quantities)),
)
prescaler_holes = st.one_of(st.just(s.PrescalerHole()), st.builds(s.PrescalerHole, numbers, numbers))
activations = st.one_of(
    st.builds(s.Timer, quantities | period_holes, _optional(quantities)),
    st.builds(s.Trigger, names),
    st.builds(s.Trigger, names, numbers | prescaler_holes),
    st.builds(s.Sporadic, quantities, quantities),
    st.just(s.UnknownActivation()),
)

# ------------------------------------------------------------------ systems

bindings = st.builds(
    s.TaskBinding,
    names,
    _optional(numbers),
    _optional(names),
    _tuples(activations, max_size=2),
    _optional(quantities),
    _optional(quantities),
)
instances = st.builds(s.Instance, names, names, _optional(names), _tuples(bindings))
port_refs = st.builds(s.PortRef, names, names)
delays = st.one_of(
    st.just((None, None)),
    quantities.map(lambda q: (q, q)),
    st.tuples(quantities, quantities),
)
connections = st.builds(lambda src, dst, d: s.Connection(src, dst, *d), port_refs, port_refs, delays)
specs = st.builds(s.Spec, st.sampled_from(["reaction_time", "data_age", "jitter"]), quantities)
chains = st.builds(s.Chain, names, _tuples(port_refs, 1, 3), _tuples(specs))
systems = st.builds(
    s.System,
    names,
    _tuples(st.builds(s.Core, names, _optional(names)), max_size=2),
    _tuples(instances),
    _tuples(connections),
    _tuples(chains, max_size=2),
)

import_paths = st.sampled_from(["lib.vfy", "a//b.vfy", "dir/x.vfy", "/*.vfy", "_"])
modules = st.builds(
    s.Module,
    st.just(MODULE_PATH),
    _tuples(st.builds(s.Import, import_paths), max_size=2),
    _tuples(components, max_size=3),
    _tuples(systems, max_size=2),
)


# ================================================================== valid, resolvable models
#
# ``valid_modules`` draws whole projects that `verify check` accepts: components whose out-ports each
# have one producer, systems whose instances bind every task, connections between ports of one type
# (each in-port written at most once, flowing from earlier to later instances so no trigger cycle
# arises), data triggers only on connected ports the task reads, required reads only where every
# instance connects them, activation constraints that every binding of the task satisfies (timers and
# sporadic sources within them; triggered or open tasks only under a generous changeable bound, so the
# propagated rate lies within it), and chains that follow connections and read → produce
# dependencies, closed by an in-port with one reader or by a task.

COMPONENT_NAMES = ("Laser", "Mapper", "Planner", "Base", "Cam", "Fusion", "task", "timer")
SYSTEM_NAMES = ("Robot", "Navigation", "System2")
TYPE_NAMES = ("Pose", "Scan")
#: periods in milliseconds (1/3 ms steps included: exact, non-terminating rationals)
PERIODS_MS = tuple(map(Fraction, (1, 2, 5, 10, 20, 25, 50, 100, 200, 1000))) + (Fraction(100, 3), Fraction(5, 2))
WCETS_US = tuple(map(Fraction, (10, 50, 100, 250, 500, 1000)))
WIDE = s.ActivationConstraint(None, s.Quantity(Fraction(1000), "kHz"), True)  # above any rate drawn here


def _time(ms: Fraction, draw) -> s.Quantity:
    """``ms`` milliseconds, written in one of the units that expresses it."""
    unit = draw(st.sampled_from(["ms", "us", "s"]))
    return s.Quantity(ms * {"ms": 1, "us": 1000, "s": Fraction(1, 1000)}[unit], unit)


def _rate(hz: Fraction, draw) -> s.Quantity:
    unit = draw(st.sampled_from(["Hz", "kHz"]))
    return s.Quantity(hz / (1000 if unit == "kHz" else 1), unit)


#: sampling tolerances that validation accepts (a factor of at least 1)
tolerances_valid = st.one_of(
    st.just(s.Tolerance("ok")),
    st.just(s.Tolerance("forbidden")),
    st.builds(s.Tolerance, st.just("max"), st.sampled_from([1, 2, Fraction(5, 2), 10]).map(Fraction).map(s.Number)),
)


def _unique(draw, pool, n: int) -> list[str]:
    return draw(st.lists(st.sampled_from(pool), min_size=n, max_size=n, unique=True))


@st.composite
def _component_shape(draw, name: str) -> dict:
    """Ports, compounds and tasks of one component, before reads are marked required and constraints
    chosen (both depend on the systems that use it)."""
    n_in, n_out = draw(st.sampled_from([0, 1, 2, 2, 3])), draw(st.sampled_from([0, 1, 1, 2, 2]))
    n_tasks = draw(st.integers(1, 3))
    n_compounds = draw(st.integers(0, 1)) if n_in >= 2 else 0
    names = _unique(draw, NAME_POOL, n_in + n_out + n_tasks + n_compounds)
    ins = [(n, draw(st.sampled_from(TYPE_NAMES))) for n in names[:n_in]]
    outs = [(n, draw(st.sampled_from(TYPE_NAMES))) for n in names[n_in:n_in + n_out]]
    task_names = names[n_in + n_out:n_in + n_out + n_tasks]
    compounds = []
    for cname in names[n_in + n_out + n_tasks:]:
        members = draw(st.lists(st.sampled_from([p for p, _ in ins]), min_size=2, max_size=n_in, unique=True))
        compounds.append((cname, draw(st.sampled_from(["and", "or"])), members,
                          draw(st.sampled_from([None, WIDE]))))
    tasks = []
    for t in task_names:
        wcet = draw(st.sampled_from(WCETS_US))
        tasks.append({
            "name": t,
            "kind": draw(st.sampled_from(["preemptive", "cooperative"])),
            "reads": [p for p, _ in ins if draw(st.booleans())],
            "tolerances": {p: (draw(_optional(tolerances_valid)), draw(_optional(tolerances_valid))) for p, _ in ins},
            "produces": [],
            "wcet": wcet,
            "bcet": draw(st.sampled_from([None, Fraction(0), wcet / 2, wcet])),
        })
    for o, _ in outs:
        tasks[draw(st.integers(0, n_tasks - 1))]["produces"].append(o)
    return {"name": name, "ins": ins, "outs": outs, "compounds": compounds, "tasks": tasks}


def _trigger_options(shape: dict, task: dict, connected: set[str]) -> list[str]:
    """The ports ``task`` may be triggered by in an instance whose connected in-ports are ``connected``."""
    options = [p for p in task["reads"] if p in connected]
    for cname, mode, members, _ in shape["compounds"]:
        if not set(members) <= set(task["reads"]):
            continue
        live = [m for m in members if m in connected]
        if (mode == "and" and len(live) == len(members)) or (mode == "or" and live):
            options.append(cname)
    return options


@st.composite
def _activation(draw, options: list[str]) -> tuple[s.Activation, tuple[Fraction, Fraction] | None, bool]:
    """(activation, its rate interval in Hz if it fixes one here, whether it is a trigger or a hole)."""
    kinds = ["timer", "timer", "sporadic", "hole"] + ["trigger"] * (6 if options else 0)
    kind = draw(st.sampled_from(kinds))
    if kind == "trigger":
        port = s.Name(draw(st.sampled_from(options)))
        prescaler = draw(st.one_of(st.just(s.Number(Fraction(1))), st.integers(1, 5).map(Fraction).map(s.Number),
                                   st.just(s.PrescalerHole()),
                                   st.integers(1, 4).map(lambda k: s.PrescalerHole(s.Number(Fraction(1)),
                                                                                   s.Number(Fraction(k))))))
        return s.Trigger(port, prescaler), None, True
    if kind == "hole":
        return draw(st.sampled_from([s.Timer(s.PeriodHole()), s.UnknownActivation()])), None, True
    if kind == "timer":
        period = draw(st.sampled_from(PERIODS_MS))
        written = _rate(1000 / period, draw) if draw(st.booleans()) else _time(period, draw)
        phase = None
        if draw(st.booleans()):
            phase = _time(period * draw(st.sampled_from([Fraction(0), Fraction(1, 2), Fraction(1, 3)])), draw)
        return s.Timer(written, phase), (1000 / period, 1000 / period), False
    low, high = sorted(draw(st.lists(st.sampled_from(PERIODS_MS), min_size=2, max_size=2)))
    if draw(st.booleans()):
        act = s.Sporadic(_time(low, draw), _time(high, draw))
    else:
        act = s.Sporadic(_rate(1000 / high, draw), _rate(1000 / low, draw))
    return act, (1000 / high, 1000 / low), False


@st.composite
def _constraint(draw, rates: list[tuple[Fraction, Fraction] | None]) -> s.ActivationConstraint | None:
    """An activation constraint that every binding (its rate interval; None: a trigger or a hole) meets."""
    if not rates or any(r is None for r in rates):
        return draw(st.sampled_from([None, WIDE]))  # (unused, or rates only known after propagation)
    low, high = min(r[0] for r in rates), max(r[1] for r in rates)
    choice = draw(st.sampled_from(["none", "range", "min", "max", "fixed"]))
    if choice == "fixed" and low == high:
        return s.ActivationConstraint(_rate(low, draw), _rate(low, draw), False)
    if choice == "none":
        return None
    lo = _rate(low / draw(st.sampled_from([1, 2, 4])), draw)
    hi = _rate(high * draw(st.sampled_from([1, 2, 4])), draw)
    changeable = draw(st.booleans())
    if choice == "min":
        return s.ActivationConstraint(lo, None, changeable)
    if choice == "max":
        return s.ActivationConstraint(None, hi, changeable)
    return s.ActivationConstraint(lo, hi, changeable)


@st.composite
def _chain(draw, name: str, instances: list[tuple[str, dict]], links: list[tuple[tuple[str, str], tuple[str, str]]],
           ) -> s.Chain | None:
    """A chain that follows the connections: out-port → (connection, reader's read → produce) → out-port …,
    optionally closed by the reading task or by an in-port with exactly one reader."""
    shape_of = dict(instances)
    starts = [(inst, o) for inst, shape in instances for o, _ in shape["outs"]]
    if not starts:
        return None
    refs = [draw(st.sampled_from(starts))]
    for _ in range(draw(st.sampled_from([0, 1, 2, 3, 3]))):
        inst, port = refs[-1]
        steps = []
        for (src, dst) in links:
            if src != (inst, port):
                continue
            reader_inst, in_port = dst
            readers = [t for t in shape_of[reader_inst]["tasks"] if in_port in t["reads"]]
            for t in readers:
                steps += [("out", reader_inst, o) for o in t["produces"]]
                steps.append(("task", reader_inst, t["name"]))
            if len(readers) == 1:
                steps.append(("in", reader_inst, in_port))
        if not steps:
            break
        kind, inst, member = draw(st.sampled_from(steps))
        refs.append((inst, member))
        if kind != "out":
            break  # closed by a task or an in-port
    kinds = draw(st.lists(st.sampled_from(["reaction_time", "data_age", "jitter"]), unique=True, max_size=3))
    specs = tuple(s.Spec(k, _time(draw(st.sampled_from(PERIODS_MS)) * 10, draw)) for k in kinds)
    return s.Chain(s.Name(name), tuple(s.PortRef(s.Name(i), s.Name(m)) for i, m in refs), specs)


@st.composite
def valid_modules(draw) -> s.Module:
    """A module with one to three components and one or two systems that `verify check` accepts."""
    comp_names = _unique(draw, COMPONENT_NAMES, draw(st.integers(1, 3)))
    shapes = {n: draw(_component_shape(n)) for n in comp_names}
    n_systems = draw(st.integers(1, 2))
    sys_names = _unique(draw, SYSTEM_NAMES, n_systems)
    rates_of: dict[tuple[str, str], list] = {}  # (component, task) -> rate intervals of its bindings
    required_ok: dict[tuple[str, str], bool] = {}  # (component, in-port) -> connected in every instance
    systems = []
    for sys_name in sys_names:
        n_inst = draw(st.sampled_from([1, 2, 3, 3, 4, 4]))  # (sampled: Hypothesis favours small integers)
        n_cores, n_chains = draw(st.integers(1, 2)), draw(st.sampled_from([0, 1, 2, 2]))
        names = _unique(draw, NAME_POOL, n_inst + n_cores + n_chains)
        inst_names, core_names, chain_names = names[:n_inst], names[n_inst:n_inst + n_cores], names[n_inst + n_cores:]
        cores = tuple(s.Core(s.Name(c), draw(st.sampled_from([None, s.Name("fixed_priority")]))) for c in core_names)
        placed = [(i, shapes[draw(st.sampled_from(comp_names))]) for i in inst_names]
        links, connections = [], []
        for j, (inst, shape) in enumerate(placed):  # connections only from earlier instances: no cycles
            for port, typ in shape["ins"]:
                sources = [(i, o) for i, sh in placed[:j] for o, t in sh["outs"] if t == typ]
                if sources and draw(st.sampled_from([True, True, True, False])):  # (mostly: longer chains)
                    src = draw(st.sampled_from(sources))
                    links.append((src, (inst, port)))
                    delay = draw(st.sampled_from([(None, None), (Fraction(1, 2),) * 2, (Fraction(0), Fraction(1))]))
                    d = tuple(None if v is None else _time(v, draw) for v in delay)
                    connections.append(s.Connection(s.PortRef(s.Name(src[0]), s.Name(src[1])),
                                                    s.PortRef(s.Name(inst), s.Name(port)), *d))
        instances = []
        for inst, shape in placed:
            connected = {p for (_, _), (i, p) in links if i == inst}
            for port, _ in shape["ins"]:
                key = (shape["name"], port)
                required_ok[key] = required_ok.get(key, True) and port in connected
            inst_core = s.Name(draw(st.sampled_from(core_names))) if draw(st.booleans()) else None
            bindings = []
            for task in shape["tasks"]:
                act, rate, _open = draw(_activation(_trigger_options(shape, task, connected)))
                rates_of.setdefault((shape["name"], task["name"]), []).append(rate)
                wcet_ms = task["wcet"] / 1000
                bindings.append(s.TaskBinding(
                    s.Name(task["name"]),
                    s.Number(Fraction(draw(st.integers(0, 10)))),
                    s.Name(draw(st.sampled_from(core_names))) if inst_core is None or draw(st.booleans()) else None,
                    (act,),
                    draw(st.sampled_from([None, _time(wcet_ms * 3, draw)])),
                    draw(st.sampled_from([None, _time(draw(st.sampled_from(PERIODS_MS)), draw)])),
                ))
            order = draw(st.permutations(bindings))  # bindings may come in any order
            instances.append(s.Instance(s.Name(inst), s.Name(shape["name"]), inst_core, tuple(order)))
        chains = tuple(c for c in (draw(_chain(n, placed, links)) for n in chain_names) if c is not None)
        costs = tuple(s.ArrivalCost(_time(Fraction(draw(st.integers(1, 40)), 10), draw))
                      for _ in range(draw(st.integers(0, 1))))
        systems.append(s.System(s.Name(sys_name), cores, tuple(instances), tuple(connections), chains,
                                arrival_costs=costs))
    components = []
    for shape in shapes.values():
        tasks = []
        for t in shape["tasks"]:
            reads = []
            for p in t["reads"]:
                over, under = t["tolerances"][p]
                may_require = required_ok.get((shape["name"], p), True)
                reads.append(s.Read(s.Name(p), not (may_require and draw(st.booleans())), over, under))
            bcet = None if t["bcet"] is None else _time(t["bcet"] / 1000, draw)
            constraint = draw(_constraint(rates_of.get((shape["name"], t["name"]), [])))
            tasks.append(s.Task(s.Name(t["name"]), t["kind"], tuple(reads), tuple(map(s.Name, t["produces"])),
                                bcet, _time(t["wcet"] / 1000, draw), constraint))
        components.append(s.Component(
            s.Name(shape["name"]),
            tuple(s.InPort(s.Name(n), s.Name(ty)) for n, ty in shape["ins"]),
            tuple(s.OutPort(s.Name(n), s.Name(ty)) for n, ty in shape["outs"]),
            tuple(s.CompoundPort(s.Name(n), mode, tuple(map(s.Name, members)), c)
                  for n, mode, members, c in shape["compounds"]),
            tuple(tasks),
        ))
    return s.Module(MODULE_PATH, (), tuple(components), tuple(systems))
