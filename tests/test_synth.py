"""`synth` (verify/synth, specs/synthesis.md): the navigation examples, the command line, the unsat core,
objectives, the budget and byte-identical output across processes."""
from __future__ import annotations

import json
import random
import subprocess
import sys
from fractions import Fraction as F
from pathlib import Path

import pytest

import verify
from verify.cli import main
from verify.prove.sim import random_scenario, simulate
from verify.synth import brute_force, synthesize
from verify.synth.statements import configured_model
from verify.synth.writeback import completed_text, recheck
from verify.timing import analyze

from .conftest import EXAMPLES
from .test_timing import bound_violations

NAV = EXAMPLES / "navigation"
HOLES = str(NAV / "navigation-holes.vfy")
CONFLICT = str(NAV / "navigation-conflict.vfy")
MS = F(1, 1000)


def accepted(model) -> bool:
    result = analyze(model)
    return (not [d for d in result.diagnostics if d.severity.value == "error"]
            and all(s.ok for c in result.chains for s in c.specs))


def simulated_within_bounds(model, runs: int = 2, horizon=F(2)) -> None:
    for run in range(runs):
        trace = simulate(model, random_scenario(model, random.Random(f"synth/{run}"), horizon))
        assert bound_violations(model, trace) == []


# ------------------------------------------------------------------ the navigation examples


@pytest.fixture(scope="module")
def holes():
    loaded = verify.load(HOLES)
    return loaded, synthesize(loaded)


@pytest.fixture(scope="module")
def conflict():
    loaded = verify.load(CONFLICT)
    return loaded, synthesize(loaded)


def test_navigation_holes_are_filled_optimally(holes):
    loaded, result = holes
    assert result.status == "sat" and result.optimal
    assert {t: c.text() for t, c in result.choices.items()} == {
        "oa.OATask": "timer 100 ms",
        "mapper.CurMapTask": "trigger scan every 20",
        "planner.PlannerTask": "trigger map",
    }
    assert result.values == (F(893, 2000),)  # 44.65 % total utilisation
    assert accepted(result.model)
    simulated_within_bounds(result.model)


def test_navigation_answer_is_rechecked_as_written(holes):
    loaded, result = holes
    text = completed_text(loaded, result.system, result.choices)
    assert "?" not in text and "timer 100 ms" in text and "every 20" in text
    assert "// The navigation system with the integrator's open choices" in text  # comments kept
    _, model, analysis, problems = recheck(loaded, result.system, text)
    assert problems == [] and model.is_configured


@pytest.mark.slow
def test_navigation_optimum_agrees_with_brute_force_over_the_pruned_space(holes):
    loaded, result = holes
    naive = brute_force(loaded, prune=True)
    assert naive.status == "sat" and naive.values == result.values
    assert naive.complete


def test_brute_force_stopped_at_its_limit_says_so():
    """Stopping at the evaluation limit with nothing accepted is "limit", never "unsat"; only an
    exhausted space is unsatisfiable."""
    conflict = brute_force(verify.load(str(NAV / "navigation-conflict.vfy")), limit=3)
    assert (conflict.status, conflict.complete, conflict.evaluated) == ("limit", False, 3)
    assert conflict.choices is None


def test_navigation_conflict_core_names_laser_constraint_and_spec(conflict):
    loaded, result = conflict
    assert result.status == "unsat"
    assert [st.key for st in result.core] == [
        "fixed:Laser.LaserTask", "max:ObstacleAvoidance.OATask", "spec:emergency_stop:reaction_time"]
    assert result.explanation.minimal
    diag = result.diagnostics[0]
    assert diag.code == "E401"
    assert "reaction_time <= 45 ms" in diag.message and diag.primary.span.file.endswith("navigation-conflict.vfy")
    assert [lb.message for lb in diag.secondary] == ["fixed at 40 Hz (laser.LaserTask)",
                                                      "at most 40 Hz (oa.OATask)"]
    assert "64.3 ms" in diag.help  # the smallest reaction time any configuration allows


def test_removing_any_core_member_makes_the_conflict_satisfiable(conflict):
    loaded, result = conflict
    expl = result.explanation
    keys = {st.key for st in result.core}
    for member in keys:
        witness = expl.witnesses[member]
        assert not (witness.off & (keys - {member})), "the rest of the core stays in force"
        model = configured_model(expl.problem.model, expl.problem.activations(witness), expl.problem.statements,
                                 witness.off)
        assert accepted(model), member


def test_a_configured_system_is_checked_as_written():
    loaded = verify.load(str(NAV / "navigation.vfy"))
    result = synthesize(loaded)
    assert result.status == "sat" and result.choices == {} and result.optimal


# ------------------------------------------------------------------ generated systems


def _generated(n: int, seed: int, **options):
    from benchmarks.generate import generate_system

    return verify.load_text(generate_system(n, seed, **options), f"gen-{n}-{seed}.vfy")


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_repair_turns_a_rejected_seed_into_an_accepted_configuration(seed):
    from verify.synth.problem import build_problem
    from verify.synth.repair import repair

    loaded = _generated(40, seed, hole_share=F(1, 3))
    model = loaded.system()
    problem = build_problem(model, loaded.resolution.systems[model.name])
    config, ev = problem.seed()
    assert not ev.accepted  # the slowest candidates miss a spec or a minimum rate
    config, ev = repair(problem, config, ev)
    assert ev.accepted and accepted(problem.configured(config))
    result = synthesize(loaded, objective="none")
    assert result.status == "sat" and result.stats["solver_calls"] == 0 and accepted(result.model)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 4])
def test_core_seeded_from_the_blamed_chain_is_unsat_and_minimal(seed):
    """Pruning blames a chain; minimisation starts from the statements about it. The core is checked
    unsat by the solver over the whole tracked encoding (every other statement off), and each member's
    witness is accepted by the analysis."""
    import z3

    from verify.synth.core import explain_unsat
    from verify.synth.problem import build_problem
    from verify.synth.solve import Budget, Engine

    loaded = _generated(60, seed, hole_share=F(1, 5), infeasible=True)
    model = loaded.system()
    scope = loaded.resolution.systems[model.name]
    untracked = build_problem(model, scope)
    assert untracked.culprit is not None and untracked.culprit[0]
    expl = explain_unsat(model, scope, Budget(50_000_000), culprit=untracked.culprit, hints=False)
    assert expl.status == "unsat" and expl.minimal
    keys = {st.key for st in expl.core}
    assert any(k.startswith("spec:") for k in keys)
    problem = expl.problem
    enc = problem.encoding(z3.Context())
    lits = [enc.lit(st.key) if st.key in keys else z3.Not(enc.lit(st.key)) for st in problem.statements]
    assert Engine(problem, enc, Budget(50_000_000)).run([], lits).status == "unsat"
    for member in keys:
        witness = expl.witnesses[member]
        assert not (witness.off & (keys - {member}))
        assert accepted(configured_model(problem.model, problem.activations(witness), problem.statements, witness.off))


def test_spec_hint_with_other_conflicts_names_a_reached_latency_and_a_lower_bound():
    result = synthesize(_generated(120, 1, hole_share=F(1, 5), infeasible=True))
    assert result.status == "unsat"
    hint = next(h for h in result.explanation.hints if h.startswith("relax `"))
    assert "once the other conflicting specs are relaxed too" in hint
    assert "a configuration reaches it; none gets below" in hint or "to at least" in hint


# ------------------------------------------------------------------ the command line


def test_cli_prints_the_completed_file_and_the_summary(capsys):
    assert main(["synth", HOLES]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("// The navigation system") and "task OATask priority 5 timer 100 ms" in out
    assert "synth NavigationHoles: satisfiable" in err and "proven optimal" in err
    for needle in ("oa.OATask", "timer ? in 25 ms .. 200 ms step 25 ms", "reactive", "cpu1", "44.65 %"):
        assert needle in err


def test_cli_never_overwrites_unless_asked(tmp_path, capsys):
    src = tmp_path / "holes.vfy"
    src.write_text(Path(HOLES).read_text())
    (tmp_path / "components.vfy").write_text((NAV / "components.vfy").read_text())
    before = src.read_text()
    out = tmp_path / "done.vfy"
    out.write_text("keep me\n")
    assert main(["synth", str(src), "-o", str(out)]) == 2
    assert out.read_text() == "keep me\n" and src.read_text() == before
    assert main(["synth", str(src), "-o", str(out), "--force"]) == 0
    assert "timer 100 ms" in out.read_text() and src.read_text() == before
    assert main(["analyze", str(out)]) == 0
    capsys.readouterr()
    assert main(["synth", str(src), "--diff"]) == 0
    diff = capsys.readouterr().out
    assert "-    task OATask priority 5 timer ? in 25 ms .. 200 ms step 25 ms" in diff
    assert "+    task OATask priority 5 timer 100 ms" in diff and src.read_text() == before
    assert main(["synth", str(src), "--in-place"]) == 0
    assert src.read_text() == out.read_text()


def test_cli_json(capsys):
    assert main(["synth", HOLES, "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "verify.synth/1" and doc["status"] == "sat" and doc["optimal"]
    assert [c["task"] for c in doc["choices"]] == ["oa.OATask", "mapper.CurMapTask", "planner.PlannerTask"]
    assert doc["objective"] == [{"name": "utilisation", "sense": "min",
                                 "value": {"exact": "893/2000", "decimal": "0.4465"}, "unit": "fraction"}]
    assert {(s["chain"], s["kind"]) for s in doc["specs"]} == {("reactive", "reaction_time"), ("reactive", "data_age"),
                                                                ("planning", "reaction_time")}
    assert doc["output"]["dsl"].startswith("// The navigation system")


def test_cli_unsat_exit_1_with_the_core(capsys):
    assert main(["synth", CONFLICT]) == 1
    out, err = capsys.readouterr()
    assert out == "" and "error[E401]" in err and "fixed at 40 Hz" in err and "at most 40 Hz" in err
    assert main(["synth", CONFLICT, "--format", "json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "unsat" and [c["kind"] for c in doc["core"]] == ["rate", "max_rate", "spec"]
    assert doc["diagnostics"][0]["code"] == "E401"


def test_cli_undecided_exit_3(write, capsys):
    """A problem of more candidate configurations than synth enumerates (``EXHAUSTIVE_LIMIT``) is left
    undecided when the solver's budget runs out (a smaller one is decided by enumeration, below)."""
    from benchmarks.generate import generate_system

    path = write({"gen.vfy": generate_system(40, 1, hole_share=F(1, 5), chains=8)})
    assert main(["synth", path, "--rlimit", "1"]) == 3
    out, err = capsys.readouterr()
    assert "error[E402]" in err and "rlimit 1" in err
    assert "no better one has been ruled out" in err and verify.load_text(out, path).ok  # (the best found)


def test_a_small_problem_the_solver_leaves_open_is_decided_by_enumeration(holes):
    """The navigation example has 1,156 candidate configurations after pruning: with a budget too small
    for the solver, every one is analysed and the optimum is the solver's (specs/synthesis.md §7)."""
    from verify.synth.exhaust import space

    loaded, full = holes
    result = synthesize(loaded, rlimit=1)
    assert space(result.problem) == result.stats["enumerated"] == 1156
    assert (result.status, result.optimal) == ("sat", True)
    assert result.values == full.values and accepted(result.model)


def test_cli_usage_errors_exit_2(capsys):
    assert main(["synth", HOLES, "--objective", "latency:reactiv"]) == 2
    assert "did you mean `reactive`" in capsys.readouterr().err
    assert main(["synth", HOLES, "--objective", "speed"]) == 2
    assert main(["synth", HOLES, "--rlimit", "-5"]) == 2


# ------------------------------------------------------------------ objectives and budget


def test_objectives_on_navigation():
    loaded = verify.load(HOLES)
    slack = synthesize(loaded, objective="slack")
    fast = synthesize(loaded, objective="latency:reactive,utilisation")
    assert slack.status == fast.status == "sat" and slack.optimal and fast.optimal
    assert slack.values[0] == min(s.margin for c in slack.analysis.chains for s in c.specs)
    assert fast.values[0] == fast.analysis.chain("reactive").reaction_time.worst
    assert fast.values[0] <= synthesize(loaded).analysis.chain("reactive").reaction_time.worst
    assert synthesize(loaded, objective="none").status == "sat"


def test_budget_exhaustion_returns_the_best_so_far_unproven():
    loaded = _generated(40, 1, hole_share=F(1, 5), chains=8)  # (69,120 configurations: not enumerated)
    full = synthesize(loaded)
    used = full.stats["rlimit_used"]
    outcomes = set()
    for rlimit in (1, used // 4, used // 2, used - 1):
        result = synthesize(loaded, rlimit=max(1, rlimit))
        outcomes.add(result.status)
        if result.status == "undecided":
            assert not result.optimal and result.diagnostics[0].code == "E402"
            if result.model is not None:
                assert accepted(result.model) and result.values >= full.values
    assert "undecided" in outcomes


# ------------------------------------------------------------------ determinism across processes


def _run(args: list[str]) -> tuple[int, bytes, bytes]:
    proc = subprocess.run([sys.executable, "-c", "from verify.cli import synth_main; synth_main()", *args],
                          capture_output=True, timeout=120)
    return proc.returncode, proc.stdout, proc.stderr


@pytest.mark.parametrize("args", [[HOLES], [CONFLICT], [HOLES, "--format", "json", "--objective", "slack"]],
                         ids=["holes", "conflict", "json-slack"])
def test_same_input_same_bytes_in_separate_processes(args):
    first, second = _run(args), _run(args)
    assert first == second
    assert first[0] in (0, 1)


def test_a_rate_hint_whose_budget_runs_out_is_left_out(write, capsys):
    """A core of one activation constraint (the robot task triggered at 10 Hz, capped at 0.5 Hz): with a
    solver budget too small for the repair hint's own search, E401 comes without that hint (it was an
    internal error, exit 70); with the default budget the hint names the rate the task needs. A core of
    one statement is worded as one."""
    components = (EXAMPLES / "navigation" / "components.vfy").read_text()
    holes = (EXAMPLES / "navigation" / "navigation-holes.vfy").read_text()
    path = write({"components.vfy": components.replace("activation max 50 Hz", "activation max 0.5 Hz", 1),
                  "holes.vfy": holes})
    path = str(Path(path).parent / "holes.vfy")
    assert main(["synth", path, "--rlimit", "100000"]) == 1
    small = capsys.readouterr().err
    assert "error[E401]: no configuration of `NavigationHoles` satisfies this statement" in small
    assert "this statement cannot hold" in small and "would need to run" not in small
    assert main(["synth", path]) == 1
    assert "`base.RobotTask` would need to run at up to 10 Hz (at most 0.5 Hz now)" in capsys.readouterr().err


def test_terms_built_through_the_c_api_equal_z3py_operators():
    """``terms.Terms`` builds through Z3's C API the very terms z3py's operators build (same
    argument order, also where Python dispatches to the numeral's reflected operator), so the
    solver — and every answer — is unchanged by it."""
    import z3

    from verify.synth.terms import Terms

    ctx = z3.Context()
    t = Terms(ctx)
    x, y, b = z3.Int("x", ctx), z3.Int("y", ctx), z3.Bool("b", ctx)
    iv = lambda k: z3.IntVal(k, ctx)  # noqa: E731
    cases = [
        (t.add(x, y, 3), x + y + 3), (t.add(x, 0), x), (t.add(2, 3), 5), (t.mul(4, x), 4 * x), (t.mul(1, x), x),
        (t.le(x, 5), x <= iv(5)), (t.le(5, x), iv(5) <= x), (t.le(x, y), x <= y),
        (t.ge(x, 5), x >= iv(5)), (t.ge(x, y), x >= y), (t.eq(x, 7), x == iv(7)), (t.eq(7, x), iv(7) == x),
        (t.eq(x, y), x == y), (t.at_least(x, 9), x >= 9),
        (t.max(x, 2), z3.If(x >= iv(2), x, iv(2))), (t.min(1, y), z3.If(iv(1) <= y, iv(1), y)),
        (t.ite(b, x, 3), z3.If(b, x, iv(3))), (t.implies([b], x <= y), z3.Implies(b, x <= y)),
        (t.implies([b, z3.Not(b)], x <= y), z3.Implies(z3.And(b, z3.Not(b)), x <= y)),
    ]
    for ours, theirs in cases:
        if isinstance(theirs, int):
            assert ours == theirs
        else:
            assert ours.sexpr() == theirs.sexpr() and ours.eq(theirs), (ours, theirs)
