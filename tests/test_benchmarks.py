"""Smoke tests of the benchmark suite: the generator's systems load cleanly, are deterministic and
follow the WATERS 2015 statistics; the infeasible option is infeasible; the chain generator for the
exact search gives what ``prove-exact`` needs; the quick mode's smoke tests (tests/test_benchmarks_quick*.py)
run every stage, per-stage defaults and overrides hold, and a failing stage becomes an error row with its
time."""
from __future__ import annotations

import json
import re
import time
from collections import Counter
from fractions import Fraction

import pytest

import verify
from benchmarks import run
from benchmarks.generate import (PERIOD_SHARES, draw_chain, draw_system, generate_chain_system, generate_system,
                                 main as generate_main, render)
from tests.benchmark_quick import GROUPS
from verify.model.system import DataTriggered, Periodic


def load_clean(text: str):
    result = verify.load_text(text)
    assert result.diagnostics == (), [f"{d.code} line {d.span.line}: {d.message}" for d in result.diagnostics[:5]]
    return result.system()


@pytest.mark.parametrize("n, seed, options", [
    (10, 1, {}),
    (10, 2, {"cores": 1}),
    (37, 3, {"hole_share": Fraction(1, 2)}),
    (60, 4, {"infeasible": True, "tightness": Fraction(1, 2)}),
    (150, 5, {"cores": 8, "chains": 40, "hole_share": Fraction(1, 5)}),
    (300, 6, {}),
    (2, 7, {}),
    (1, 8, {}),
])
def test_generated_systems_load_without_diagnostics(n, seed, options):
    model = load_clean(generate_system(n, seed, **options))
    assert len(model.tasks) == n
    assert len(model.cores) == options.get("cores", 4)


def test_no_floats_in_the_text():
    text = generate_system(200, 11, hole_share=Fraction(1, 4), tightness=Fraction(6, 5), infeasible=True)
    assert not re.search(r"\d[eE][+-]?\d", text)
    assert not re.search(r"\d\.\d*\.", text)
    numbers = re.findall(r"(?<![A-Za-z_\d.])\d[\d./]*", text)
    assert numbers and all(re.fullmatch(r"\d+(\.\d+)?(/\d+)?", n) for n in numbers)


def test_deterministic():
    assert generate_system(120, 5) == generate_system(120, 5)
    assert generate_system(120, 5, hole_share=Fraction(1, 3)) == generate_system(120, 5, hole_share=Fraction(1, 3))
    assert generate_system(120, 5) != generate_system(120, 6)


def _periods(model) -> dict[str, Fraction]:
    """Every task's period in the configured system: timers directly, triggers through their writers."""
    periods: dict[str, Fraction] = {}

    def period(task_id: str) -> Fraction:
        if task_id not in periods:
            task = model.task(task_id)
            act = task.activation
            if isinstance(act, Periodic):
                periods[task_id] = act.period
            else:
                assert isinstance(act, DataTriggered)
                writer = model.link_into(f"{task.instance}.{act.members[0]}").writer
                periods[task_id] = period(writer) * act.prescaler
        return periods[task_id]

    for t in model.tasks:
        period(t.id)
    return periods


@pytest.fixture(scope="module")
def large():
    text = generate_system(2000, 42)
    return draw_system(2000, 42), load_clean(text)


def test_waters_period_shares(large):
    _, model = large
    counts = Counter(_periods(model).values())
    n = len(model.tasks)
    for period_ms, percent in PERIOD_SHARES:
        share = Fraction(counts[Fraction(period_ms, 1000)], n)
        assert abs(share - Fraction(percent, 100)) <= Fraction(35, 1000), (period_ms, float(share))
    assert sum(counts.values()) == n
    assert set(counts) == {Fraction(p, 1000) for p, _ in PERIOD_SHARES}


def test_waters_chains_cores_and_variety(large):
    drawn, model = large
    assert 30 <= len(model.chains) <= 60
    assert all(2 <= len(c.tasks) <= 15 for c in model.chains)
    assert all(len(set(c.tasks)) == len(c.tasks) for c in model.chains)
    lengths = [len(c.tasks) for c in model.chains]
    assert 3 <= sum(lengths) / len(lengths) <= 6  # WATERS: about 4.3 on average
    periods = _periods(model)
    for core in model.cores:
        on = model.tasks_on(core.name)
        load = sum(t.wcet / periods[t.id] for t in on)
        assert Fraction(49, 100) <= load <= Fraction(71, 100), (core.name, float(load))
        # rate-monotonic: a shorter period never has a lower priority
        by_priority = sorted(on, key=lambda t: -t.priority)
        assert [periods[t.id] for t in by_priority] == sorted(periods[t.id] for t in on)
        assert all(0 <= t.bcet <= t.wcet for t in on)
    kinds = Counter(type(t.activation).__name__ for t in model.tasks)
    assert kinds["DataTriggered"] > 0
    assert any(lk.delay_max > 0 for lk in model.links)
    assert not any(t.hole for t in drawn.tasks)
    # specs: the default tightness 3/2 over each chain's reference bound
    for chain, drawn_chain in zip(model.chains, drawn.chains):
        assert chain.name == drawn_chain.name
        for spec in (chain.reaction_time, chain.data_age):
            assert spec is None or drawn_chain.reference * Fraction(3, 2) <= spec


def test_holes_share_and_kinds():
    drawn = draw_system(400, 9, hole_share=Fraction(1, 4))
    model = load_clean(render(drawn))
    assert len(model.holes) == sum(1 for t in drawn.tasks if t.hole) == 400 // 4
    text = render(drawn)
    assert "timer ? in" in text and "activation ?" in text and "every ? in 1 .. 10" in text
    assert all(t.constraint != "fixed" for t in drawn.tasks if t.hole)


def test_infeasible_option_puts_a_spec_below_the_reference_bound():
    drawn = draw_system(100, 3, infeasible=True)
    model = load_clean(render(drawn))
    conflicts = [c for c in drawn.chains if c.conflict]
    assert conflicts
    for c in conflicts:
        first = drawn.tasks[c.tasks[0]]
        assert first.constraint == "fixed" and not first.trigger and first.hole is None
        spec = next(m for m in model.chains if m.name == c.name).reaction_time
        assert spec is not None and spec < first.period < c.reference
    feasible = draw_system(100, 3)
    assert not any(c.conflict for c in feasible.chains)
    tight = draw_system(100, 3, tightness=Fraction(1, 2))
    assert all(s < c.reference for c in tight.chains for s in (c.reaction_time, c.data_age) if s is not None)


def test_feasible_and_infeasible_according_to_the_analysis():
    timing = pytest.importorskip("verify.timing")
    for seed in (1, 2, 3):
        model = load_clean(generate_system(30, seed, tightness=Fraction(1)))
        result = timing.analyze(model)
        assert not result.diagnostics
        assert all(check.ok for chain in result.chains for check in chain.specs)
    drawn = draw_system(30, 4, infeasible=True)
    result = timing.analyze(load_clean(render(drawn)))
    conflicts = {c.name for c in drawn.chains if c.conflict}
    failing = {chain.name for chain in result.chains for check in chain.specs if not check.ok}
    assert conflicts and conflicts <= failing


def test_generate_cli_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "s.vfy"
    assert generate_main(["--tasks", "12", "--seed", "3", "-o", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == generate_system(12, 3)
    out.write_text("mine", encoding="utf-8")
    assert generate_main(["--tasks", "12", "--seed", "3", "-o", str(out)]) == 2
    assert out.read_text(encoding="utf-8") == "mine"
    assert generate_main(["--tasks", "12", "--seed", "3", "-o", str(out), "--force", "--hole-share", "1/2"]) == 0
    assert out.read_text(encoding="utf-8") == generate_system(12, 3, hole_share=Fraction(1, 2))


def test_quick_groups_hold_every_stage_once():
    """The smoke tests of quick mode (tests/test_benchmarks_quick*.py) run every registered stage, each
    in one group."""
    named = [name for stages in GROUPS.values() for name in stages]
    assert len(named) == len(set(named))
    assert set(named) == set(run.STAGES)


def test_stage_defaults_and_overrides(tmp_path):
    assert run.SIZES["prove-bound"] == (100, 1000, 10000)
    assert run.SIZES["prove-exact"] == (10,)
    assert run.SIZES["synth-feasibility"] == (100, 500, 1000)
    # the targets' instances: one chain per five tasks unless --chains says otherwise
    assert run.chains_for("prove-bound", 10000, None) == 2000
    assert run.chains_for("synth-feasibility", 1000, None) == 200
    assert run.chains_for("parse+check", 1000, None) is None  # WATERS: 30-60
    assert run.chains_for("prove-bound", 10000, 7) == 7
    assert run.chains_for("prove-exact", 10, 7) is None  # one chain, whatever --chains says
    assert run.OPTIONS["unsat-core"] == {"hole_share": Fraction(1, 5), "infeasible": True}
    out = tmp_path / "r.json"
    assert run.main(["--stages", "prove-bound,parse+check", "--sizes", "15", "--repeat", "2", "--no-memory",
                     "--out", str(out)]) == 0
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["config"]["sizes"] == {"prove-bound": [15], "parse+check": [15]}
    rows = doc["results"]
    assert [(r["stage"], r["tasks"], r["runs"]) for r in rows] == [("prove-bound", 15, 2), ("parse+check", 15, 2)]
    assert rows[0]["chains"] == 3 and "peak_bytes" not in rows[0]


def test_a_failing_stage_is_an_error_row_with_its_time(tmp_path, monkeypatch, capsys):
    for registry in ("STAGES", "DESCRIPTIONS", "NEEDS", "OPTIONS", "PARAMS", "QUICK_PARAMS", "SIZES", "QUICK",
                     "GENERATORS", "CHAINS_PER_TASK"):
        monkeypatch.setattr(run, registry, dict(getattr(run, registry)))

    @run.stage("failing", "stands for a synthesis that is not proven optimal", sizes=(5, 6, 7), params={"pause": 0.01})
    def failing(inst, pause):
        time.sleep(pause)
        raise run.BenchmarkError("not proven optimal: status undecided", {"status": "undecided"})

    out = tmp_path / "r.json"
    assert run.main(["--stages", "failing,parse+check", "--repeat", "1", "--budget", "0.05", "--out", str(out)]) == 1
    doc = json.loads(out.read_text(encoding="utf-8"))
    first, second, third = [r for r in doc["results"] if r["stage"] == "failing"]
    assert first["error"] == "not proven optimal: status undecided" and first["result"] == {"status": "undecided"}
    assert first["seconds"][0] >= 0.01 and first["lines"] > 0
    assert "error" in second  # 6 tasks: 0.01 s * 6/5 is within the budget
    assert "skipped" in third or "error" in third
    assert any(r["stage"] == "parse+check" and "error" not in r for r in doc["results"])  # the run went on
    assert "| failing | 5 |" in capsys.readouterr().out


def test_chain_system_for_the_exact_search():
    from verify.prove.exact import count_representatives, exact_class, grid_of
    from verify.prove.scenario import hyperperiod
    from verify.timing import analyze

    text = generate_chain_system(6, 3)
    assert text == generate_chain_system(6, 3) != generate_chain_system(6, 4)
    model = load_clean(text)
    drawn = draw_chain(6, 3)
    assert len(model.tasks) == 6 and [len(c.tasks) for c in model.chains] == [6]
    assert exact_class(model) is None  # constant execution times and delays: the exact search applies
    assert count_representatives(grid_of(model)) <= 1000  # within prove's default budget
    hyper = hyperperiod(model)
    assert hyper == Fraction(drawn.hyperperiod_ms, 1000)
    assert sum(hyper / p for p in _periods(model).values()) == drawn.jobs <= 6000
    chain, bounds = model.chains[0], analyze(model).chain("c0")
    assert chain.reaction_time < bounds.reaction_time.worst  # the bound cannot prove the specs
    assert chain.data_age < bounds.data_age_reduced.worst
    ten = draw_chain(10, 1)
    assert 9000 <= ten.jobs <= 10_000 and len(ten.tasks) == 10  # the target: up to 10,000 jobs
    assert draw_chain(10, 1, jobs=500).jobs <= 500


def test_runner_rejects_unknown_stage(tmp_path):
    assert "parse+check" in run.STAGES
    with pytest.raises(SystemExit) as exc:
        run.main(["--quick", "--stages", "no-such-stage", "--out", str(tmp_path / "r.json")])
    assert exc.value.code == 2
    assert not (tmp_path / "r.json").exists()
