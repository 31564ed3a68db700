"""`synth` decides small problems, and decides them right (issue 38; specs/synthesis.md §2, §6, §7).

Hypothesis draws small systems with holes (3–7 tasks on one or two cores; timer holes with a grid,
prescaler holes, AND joins — most of them of one cascade, timing.md (7.3e) —, delays) and sets the
chain's specs to the bounds ``analyze`` gives one configuration inside the holes' domains, so that a
solution exists and the specs are met with margin 0. For each, ``synth`` must answer ``sat``, proven
optimal, with the optimum brute force finds over every candidate combination (each one analysed): never
"no configuration", never undecided. The AND cascade of the issue is a fixed example. A small problem
the solver leaves open or calls unsatisfiable is enumerated (every configuration analysed), and an
unsat answer that no statement is blamed for stands on the holes, never on the system alone.
"""
from __future__ import annotations

from fractions import Fraction as F

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.synth import brute_force, synthesize
from verify.timing import analyze

from .test_synth import accepted

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


class Draws:
    """The few ``random.Random`` methods a system is drawn with, as Hypothesis draws (so that failures
    shrink)."""

    def __init__(self, draw):
        self.draw = draw

    def randint(self, low: int, high: int) -> int:
        return self.draw(st.integers(low, high))

    def choice(self, items):
        return self.draw(st.sampled_from(items))

    def chance(self, percent: int) -> bool:
        return self.draw(st.integers(0, 99)) < percent


def _task(rng: Draws, i: int, cores: int, tasks: list[dict]) -> dict:
    wcet = rng.randint(2, 20)  # tenths of ms
    task = {"i": i, "wcet": wcet, "bcet": rng.randint(0, wcet), "core": rng.randint(0, cores - 1),
            "prio": rng.randint(1, 8), "inputs": [], "hole": None}
    kind = rng.choice(["timer", "grid"] if i == 0 else ["timer", "grid", "trigger", "every", "and", "and"])
    if kind == "and" and i < 2:
        kind = "trigger"
    if kind in ("timer", "grid"):
        task["inputs"] = [rng.randint(0, i - 1)] if i else []
        if kind == "timer":
            task["act"] = f"timer {rng.choice([5, 10, 20])} ms"
        else:
            low, step, count = rng.choice([5, 10]), rng.choice([5, 10]), rng.randint(2, 3)
            task["act"] = f"timer ? in {low} ms .. {low + step * (count - 1)} ms step {step} ms"
            task["hole"] = [f"timer {low + step * n} ms" for n in range(count)]
    elif kind in ("trigger", "every"):
        task["inputs"] = [rng.randint(0, i - 1)]
        if kind == "trigger":
            k = rng.choice([1, 1, 2])
            task["act"] = "trigger a" + (f" every {k}" if k > 1 else "")
        else:
            high = rng.randint(2, 4)
            task["act"] = f"trigger a every ? in 1 .. {high}"
            task["hole"] = ["trigger a"] + [f"trigger a every {k}" for k in range(2, high + 1)]
    else:  # an AND join, mostly of one cascade: a triggered task and the task that triggers it
        fed = [j for j in range(i) if tasks[j]["act"].startswith("trigger a") and tasks[j]["inputs"]]
        if fed and rng.chance(70):
            a = rng.choice(fed)
            b = tasks[a]["inputs"][0]
        else:
            a = rng.randint(0, i - 1)
            b = rng.choice([j for j in range(i) if j != a])
        task["inputs"] = [a, b]
        if rng.chance(30):
            high = rng.randint(2, 3)
            task["act"] = f"trigger both every ? in 1 .. {high}"
            task["hole"] = ["trigger both"] + [f"trigger both every {k}" for k in range(2, high + 1)]
        else:
            task["act"] = "trigger both"
    return task


@st.composite
def shapes(draw) -> dict:
    rng = Draws(draw)
    cores = rng.randint(1, 2)
    tasks: list[dict] = []
    for i in range(rng.randint(3, 7)):
        tasks.append(_task(rng, i, cores, tasks))
    path = [len(tasks) - 1]
    while tasks[path[-1]]["inputs"]:
        path.append(rng.choice(tasks[path[-1]]["inputs"]))
    delays = {}
    for task in tasks:
        for j in task["inputs"]:
            if rng.chance(30):
                d = rng.randint(0, 1)
                delays[(j, task["i"])] = (d, d + rng.randint(0, 1))
    fill = {t["i"]: rng.choice(t["hole"]) for t in tasks if t["hole"]}
    kinds = rng.choice([("reaction_time", "data_age"), ("reaction_time",), ("data_age",)])
    return {"tasks": tasks, "cores": cores, "path": path[::-1], "delays": delays, "fill": fill, "kinds": kinds}


def _ms(value: F) -> str:
    return f"{value.numerator}/{value.denominator} ms" if value.denominator != 1 else f"{value.numerator} ms"


def render(shape: dict, specs: dict[str, F] | None = None, fill: dict[int, str] | None = None) -> str:
    """The DSL text: one component per task (in-ports ``a``, ``b`` and their AND ``both``)."""
    comps, insts, conns = [], [], []
    for t in shape["tasks"]:
        ports = ["a", "b"][:len(t["inputs"])]
        lines = [f"component C{t['i']} {{"] + [f"  in {p} : M" for p in ports]
        lines += ["  in both = a & b"] if len(ports) == 2 else []
        lines += ["  out o : M", "  task T {"] + [f"    reads {p}" for p in ports]
        lines += ["    produces o", f"    bcet {_ms(F(t['bcet'], 10))}", f"    wcet {_ms(F(t['wcet'], 10))}",
                  "  }", "}"]
        comps.append("\n".join(lines))
        act = (fill or {}).get(t["i"], t["act"])
        insts.append(f"  instance t{t['i']} : C{t['i']} on c{t['core']} {{ task T priority {t['prio']} {act} }}")
        for port, j in zip(ports, t["inputs"]):
            d = shape["delays"].get((j, t["i"]))
            delay = f" delay {d[0]} ms .. {d[1]} ms" if d and d[1] else ""
            conns.append(f"  connect t{j}.o -> t{t['i']}.{port}{delay}")
    chain = "  chain c: " + " -> ".join(f"t{i}.o" for i in shape["path"]) + " {\n"
    chain += "".join(f"    {kind} <= {_ms(value)}\n" for kind, value in (specs or {}).items()) + "  }"
    cores = [f"  core c{c}" for c in range(shape["cores"])]
    return "\n".join(comps) + "\n\nsystem S {\n" + "\n".join(cores + insts + conns + [chain]) + "\n}\n"


def at_the_bound(shape: dict) -> str | None:
    """The text with the specs at the bounds of the drawn configuration (None when the analysis rejects
    that configuration, or the text does not load)."""
    configured = verify.load_text(render(shape, fill=shape["fill"]), "configured.vfy")
    if not configured.ok:
        return None
    result = analyze(configured.system())
    if any(d.severity.value == "error" or d.code == "E316" for d in result.diagnostics):
        return None
    chain = result.chain("c")
    specs = {kind: chain.bound(kind).worst for kind in shape["kinds"]}
    if any(v is None for v in specs.values()):
        return None
    text = render(shape, {kind: value * 1000 for kind, value in specs.items()})  # (bounds are in seconds)
    return text if verify.load_text(text, "holes.vfy").ok else None


def assert_decided_as_brute_force(text: str) -> None:
    loaded = verify.load_text(text, "holes.vfy")
    result = synthesize(loaded)
    naive = brute_force(loaded)
    assert naive.status == "sat", text  # (the drawn configuration is accepted)
    assert (result.status, result.optimal) == ("sat", True), (result.status, result.reason,
                                                              [d.message for d in result.diagnostics], text)
    assert result.values == naive.values, text
    assert accepted(result.model)


#: the AND cascade of the issue: t0 (10 ms) → t1 (every ?) → t2 = AND(t1, t0) → t3 (every ?), specs at
#: the bounds of `every 1`, `every 1` (18 ms and 8 ms): the only configuration that meets them
CASCADE = """
component C0 { out o : M
  task T { produces o  bcet 1 ms  wcet 1 ms } }
component C1 { in a : M  out o : M
  task T { reads a  produces o  bcet 1 ms  wcet 1 ms } }
component C2 { in x : M  in y : M  in both = x & y  out o : M
  task T { reads x  reads y  produces o  bcet 1 ms  wcet 1 ms } }
component C3 { in a : M  out o : M
  task T { reads a  produces o  bcet 1 ms  wcet 1 ms } }

system S {
  core c0
  instance t0 : C0 on c0 { task T priority 4 timer 10 ms }
  instance t1 : C1 on c0 { task T priority 3 trigger a every ? in 1 .. 4 }
  instance t2 : C2 on c0 { task T priority 2 trigger both }
  instance t3 : C3 on c0 { task T priority 1 trigger a every ? in 1 .. 4 }
  connect t0.o -> t1.a
  connect t1.o -> t2.x
  connect t0.o -> t2.y
  connect t2.o -> t3.a
  chain c: t0.o -> t1.o -> t2.o -> t3.o {
    reaction_time <= 18 ms
    data_age <= 8 ms
  }
}
"""


def test_an_and_cascade_with_specs_at_its_bound_is_satisfiable():
    """Pruning's data-age lower bound of an AND join hop waited for the other members' period, which the
    join of one cascade does not (timing.md (7.3e)): it declared the problem infeasible (E401)."""
    result = synthesize(verify.load_text(CASCADE, "cascade.vfy"))
    assert (result.status, result.optimal) == ("sat", True)
    assert {t: c.activation.release_every for t, c in result.choices.items()} == {"t1.T": 1, "t3.T": 1}
    chain = result.analysis.chain("c")
    assert (chain.bound("reaction_time").worst, chain.bound("data_age").worst) == (F(18, 1000), F(8, 1000))


@pytest.mark.slow
@settings(max_examples=60, **SETTINGS)
@given(shapes())
def test_synth_decides_systems_with_specs_at_a_bound_as_brute_force_does(shape):
    text = at_the_bound(shape)
    if text is not None:
        assert_decided_as_brute_force(text)


def test_an_unsat_answer_without_a_blamed_statement_stands_on_the_holes():
    """A deadline below the execution time is not a statement synth relaxes, so the core is empty: E401
    stands on the hole, not on the system, with why the analysis rejects the slowest configuration."""
    text = """
component Worker {
  task Work {
    bcet 3 ms
    wcet 3 ms
  }
}

system Robot {
  core cpu
  instance worker : Worker on cpu { task Work priority 1 deadline 2 ms timer ? in 10 ms .. 20 ms step 10 ms }
}
"""
    result = synthesize(verify.load_text(text, "deadline.vfy"))
    assert result.status == "unsat" and result.core == ()
    (diag,) = result.diagnostics
    assert diag.code == "E401" and (diag.span.line, diag.span.column) == (11, 72)
    assert diag.primary.message == "no value accepted (`worker.Work`)"
    assert any("E316" in note and "deadline 2 ms" in note for note in diag.notes)


def test_the_solver_s_unsat_answer_on_a_small_problem_is_checked_by_enumeration(monkeypatch):
    """When the solver answers that no configuration exists, a small problem's configurations are all
    analysed: an accepted one is the answer (here the solver is made to answer unsat wrongly)."""
    from verify.synth import solve

    monkeypatch.setattr(solve.Engine, "run", lambda self, *a, **k: solve.Outcome("unsat"))
    loaded = verify.load_text(CASCADE.replace("reaction_time <= 18 ms", "reaction_time <= 30 ms"), "cascade.vfy")
    result = synthesize(loaded)
    naive = brute_force(loaded)
    assert (result.status, result.optimal, result.values) == ("sat", True, naive.values)
    assert result.stats["enumerated"] == 16 and accepted(result.model)
