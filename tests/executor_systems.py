"""Random systems with ROS 2 executors (specs/timing.md §9), as DSL text, for the property tests.

Callbacks on one or two executors per core (single-threaded, static, events; distinct thread
priorities), plain tasks of higher and lower priority beside them, timers (some with a fixed phase),
sporadic sources, single-port data triggers and AND/OR compounds across executors and cores,
connection delays, execution-time ranges, and chains along the connections.
"""
from __future__ import annotations

import random
from fractions import Fraction
from typing import TypeVar

T = TypeVar("T", int, tuple[int, int])

KINDS = ("single_threaded", "static_single_threaded", "events")
PERIODS_MS = (10, 20, 25, 40, 50, 100)


def _ms(value: Fraction) -> str:
    return f"{value.numerator}/{value.denominator} ms" if value.denominator != 1 else f"{value.numerator} ms"


def _timed_activation(rng: random.Random, rigid: bool) -> str:
    """A timer (with a fixed phase, sometimes) or, unless rigid, sometimes a sporadic source."""
    period = rng.choice(PERIODS_MS)
    if rng.random() < 0.2 and not rigid:
        return f"sporadic {period} ms .. {_ms(Fraction(period * rng.randint(4, 8), 4))}"
    phase = f" phase {_ms(Fraction(rng.randrange(2 * period), 2))}" if rng.random() < 0.3 else ""
    return f"timer {period} ms{phase}"


def _delay(rng: random.Random, rigid: bool, least: list[int], spread: list[int]) -> str:
    """A connection's delay clause: a least delay from ``least``, a range from ``spread`` unless rigid."""
    dmin = rng.choice(least)
    dmax = dmin + (0 if rigid else rng.choice(spread))
    return "" if dmax == 0 else f" delay {dmin} ms" if dmin == dmax else f" delay {dmin} ms .. {dmax} ms"


def _path(rng: random.Random, first: T, edges: dict[T, list[T]], longest: int) -> list[T]:
    """A random path along ``edges`` from ``first``, of at most ``longest`` elements and without a repeat."""
    path = [first]
    while len(path) < longest and path[-1] in edges and rng.randrange(longest) > 0:
        nxt = rng.choice(sorted(set(edges[path[-1]])))
        if nxt in path:
            break
        path.append(nxt)
    return path


def executor_system(rng: random.Random, kinds: tuple[str, ...] = KINDS, rigid: bool = False) -> str:
    """One random valid system with executors, as DSL text; ``rigid``: in the exact class of ``prove``
    (constant execution times and delays, no sporadic source)."""
    cores = rng.choice([1, 1, 2])
    threads: list[tuple[str, int, int]] = []  # (executor name, core, priority)
    lines = ["system S {"] + [f"  core c{c}" for c in range(cores)]
    for c in range(cores):
        for e in range(rng.choice([1, 1, 2])):
            name, prio = f"e{c}{e}", 10 + 10 * e
            threads.append((name, c, prio))
            lines.append(f"  executor {name} {rng.choice(kinds)} on c{c} priority {prio}")
    n = rng.randint(3, 7)
    components, bindings, connections, edges = [], [], [], {}
    for i in range(n):
        ins, reads, extra = [], [], []
        if i == 0 or rng.random() < 0.45:
            act = _timed_activation(rng, rigid)
        else:
            mode = rng.choice(["single", "single", "single", "and", "or"])
            members = ["a"] if mode == "single" else ["a", "b"]
            for m in members:
                w = rng.randrange(i)
                ins.append(m)
                reads.append(m)
                connections.append((w, i, m))
                edges.setdefault(w, []).append(i)
            port = "a" if mode == "single" else "ab"
            if mode != "single":
                extra.append(f"  in ab = a {'&' if mode == 'and' else '|'} b")
            act = f"trigger {port}"
        if i > 0 and rng.random() < 0.4:
            w = rng.randrange(i)
            ins.append("r")
            reads.append("r")
            connections.append((w, i, "r"))
            edges.setdefault(w, []).append(i)
        wcet = Fraction(rng.randint(1, 6), rng.choice([1, 2, 4]))
        bcet = wcet if rigid else wcet * Fraction(rng.randint(0, 4), 4)
        comp = [f"component C{i} {{"] + [f"  in {p} : T" for p in ins] + ["  out o : T"] + extra
        comp += ["  task T {"] + [f"    reads {r}" for r in reads]
        comp += ["    produces o", f"    bcet {_ms(bcet)}", f"    wcet {_ms(wcet)}", "  }", "}"]
        components.append("\n".join(comp))
        if rng.random() < 0.75:
            name, _c, _p = rng.choice(threads)
            bindings.append(f"  instance i{i} : C{i} {{ task T executor {name} {act} }}")
        else:  # a plain thread above or below the executors of its core
            core = rng.randrange(cores)
            prio = rng.choice([5, 15, 25, 35])
            bindings.append(f"  instance i{i} : C{i} on c{core} {{ task T priority {prio} {act} }}")
    lines += bindings
    for w, r, port in connections:
        lines.append(f"  connect i{w}.o -> i{r}.{port}{_delay(rng, rigid, [0, 0, 1, 2], [0, 0, 1, 3])}")
    for c in range(rng.randint(1, 3)):
        path = _path(rng, rng.randrange(n), edges, 5)
        lines.append(f"  chain ch{c}: " + " -> ".join(f"i{t}.o" for t in path))
    lines.append("}")
    return "\n\n".join(components) + "\n\n" + "\n".join(lines) + "\n"


def mt_system(rng: random.Random, rigid: bool = False) -> str:
    """One random valid system with a multi-threaded executor (specs/timing.md §9.4), as DSL text:
    nodes of one to three callbacks in declared mutually exclusive or reentrant groups or in their
    default group, on a multi-threaded executor with two or three cores of its own, beside a core with
    a single-threaded executor and plain tasks; timers, sporadic sources, data triggers across nodes,
    delays, execution-time ranges and chains. ``rigid`` as for ``executor_system``."""
    workers = rng.choice([2, 2, 3])
    threads = workers + rng.choice([0, 0, 1])
    lines = ["system S {"] + [f"  core c{c}" for c in range(workers + 1)]
    cores = ", ".join(f"c{c}" for c in range(workers))
    lines.append(f"  executor mt multi_threaded {threads} threads on {cores} priority 10")
    lines.append(f"  executor st single_threaded on c{workers} priority 10")
    nodes = rng.randint(2, 4)
    outputs: list[tuple[int, int]] = []  # (node, task) of every callback so far
    components, bindings, connections, edges = [], [], [], {}
    for i in range(nodes):
        ntasks = rng.choice([1, 2, 2, 3])
        groups = [g for g in ("g", "h") if rng.random() < 0.5]
        kinds = {g: rng.choice(["reentrant", "mutually_exclusive"]) for g in groups}
        comp, body = [f"component N{i} {{"], [f"    group {g} {k}" for g, k in kinds.items()]
        tasks = []
        for k in range(ntasks):
            reads = []
            if not outputs or rng.random() < 0.4:
                act = _timed_activation(rng, rigid)
            else:
                w = rng.choice(outputs)
                comp.append(f"  in a{k} : T")
                reads.append(f"a{k}")
                connections.append((w, (i, k), f"a{k}"))
                edges.setdefault(w, []).append((i, k))
                act = f"trigger a{k}"
            comp.append(f"  out o{k} : T")
            wcet = Fraction(rng.randint(1, 8), rng.choice([1, 2]))
            bcet = wcet if rigid else wcet * Fraction(rng.randint(0, 4), 4)
            tasks += [f"  task T{k} {{"] + [f"    reads {r}" for r in reads]
            tasks += [f"    produces o{k}", f"    bcet {_ms(bcet)}", f"    wcet {_ms(wcet)}", "  }"]
            where = "mt" if rng.random() < 0.85 else "st"
            group = f" group {rng.choice(groups)}" if groups and where == "mt" and rng.random() < 0.7 else ""
            body.append(f"    task T{k} executor {where}{group} {act}")
        outputs += [(i, k) for k in range(ntasks)]
        components.append("\n".join(comp + tasks + ["}"]))
        bindings.append(f"  instance n{i} : N{i} {{\n" + "\n".join(body) + "\n  }")
    if rng.random() < 0.5:  # a plain task beside the single-threaded executor
        components.append("component P {\n  out o : T\n  task T {\n    produces o\n    wcet 1 ms\n  }\n}")
        bindings.append(f"  instance p : P on c{workers} {{ task T priority {rng.choice([5, 15])} timer 20 ms }}")
    lines += bindings
    for (wi, wk), (ri, _rk), port in connections:
        lines.append(f"  connect n{wi}.o{wk} -> n{ri}.{port}{_delay(rng, rigid, [0, 0, 1], [0, 0, 2])}")
    for c in range(rng.randint(1, 3)):
        path = _path(rng, rng.choice(outputs), edges, 4)
        lines.append(f"  chain ch{c}: " + " -> ".join(f"n{a}.o{b}" for a, b in path))
    lines.append("}")
    return "\n\n".join(components) + "\n\n" + "\n".join(lines) + "\n"
