"""The benchmark runner's quick mode (``python -m benchmarks --quick``), run by the smoke tests in groups
of stages: pytest-xdist (``--dist loadfile``) gives each test file to one worker, so the groups are in
files of their own (``tests/test_benchmarks_quick_*.py``) rather than one file holding every stage. Each
group runs ``run.main(["--quick", "--stages", ...])``; every stage of it must give its rows, without an
error, at the stage's quick sizes, and its own check (``CHECKS``) must hold. ``tests/test_benchmarks.py``
checks that the groups together hold every registered stage, each once."""
from __future__ import annotations

import json
from collections.abc import Callable

import pytest

from benchmarks import run
from tests.conftest import in_ci

#: the stages of each smoke test (one file each)
GROUPS: dict[str, tuple[str, ...]] = {
    "in-process": ("parse+check", "parse-verify", "parse-lark-transformer", "parse-lark-standalone",
                   "parse-lark-tree", "analyze", "analyze-pipeline", "analyze-single-threaded",
                   "analyze-multi-threaded", "hostile-diagnostics", "hostile-recovery", "analyze-one-core",
                   "analyze-trigger-chain", "prove-bound", "prove-exact", "prove-search", "synth-feasibility",
                   "synth-optimum", "unsat-core", "baseline-brute-force", "baseline-random-search",
                   "baseline-z3-direct"),
    "processes": ("startup-python", "startup-help", "startup-check", "startup-analyze", "startup-analyze-waters",
                  "lsp-keystroke", "ros1-monitor"),
    "tightness": ("tightness",),
    "live": ("ros2-glue", "trace-read"),
}

#: the runner's options of a group beyond ``--quick``: the tightness stage's memory run (under
#: ``tracemalloc``, 2-3x slower) would double the smoke test's longest part; the other groups trace memory
OPTIONS: dict[str, tuple[str, ...]] = {"tightness": ("--no-memory",)}

#: stages whose files hold no chain (the hostile-input stages: a flood of errors, one crowded core)
NO_CHAIN = ("hostile-diagnostics", "hostile-recovery", "analyze-one-core")


def run_group(group: str, tmp_path, capsys) -> tuple[dict[str, list[dict]], str]:
    """Run the available stages of ``group`` in quick mode: (its rows by stage, the Markdown table).
    Asserts what every row must hold and each stage's own check."""
    missing = [f"{name} ({run.UNAVAILABLE.get(name, 'not registered')})" for name in GROUPS[group]
               if name not in run.STAGES]
    if missing and in_ci():  # (the project's set-up installs what every stage needs: scripts/install-tools)
        pytest.fail(f"stages unavailable: {', '.join(missing)}")
    stages = [name for name in GROUPS[group] if name in run.STAGES]
    out = tmp_path / "out" / "results.json"
    options = OPTIONS.get(group, ())
    assert run.main(["--quick", *options, "--stages", ",".join(stages), "--out", str(out)]) == 0  # 0: none failed
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["schema"] == run.SCHEMA
    results = doc["results"]
    assert not [r for r in results if "error" in r or "skipped" in r]
    assert {r["stage"] for r in results} == set(stages)
    by_stage = {name: [r for r in results if r["stage"] == name] for name in stages}
    for name, rows in by_stage.items():
        assert [r["tasks"] for r in rows] == list(run.QUICK[name]), name
        for r in rows:
            assert r["runs"] == 1 and len(r["seconds"]) == 1 and r["seconds"][0] > 0
            assert "--no-memory" in options or r["peak_bytes"][0] > 0
            assert r["chains"] >= (0 if name in NO_CHAIN else 1)
            CHECKS.get(name, _no_check)(r)
    table = capsys.readouterr().out
    assert table.splitlines()[0].endswith("| result |")
    return by_stage, table


def _no_check(row: dict) -> None:
    pass


def _prove_bound(r: dict) -> None:
    assert r["result"]["proved"] == r["result"]["verdicts"] > 0
    assert r["chains"] == max(1, r["tasks"] // 5)


def _prove_search(r: dict) -> None:
    assert r["result"]["by search"] > 0
    assert r["result"]["scenarios"] <= run.QUICK_PARAMS["prove-search"]["budget"]


def _analyze_pipeline(r: dict) -> None:
    assert r["chains"] == 1 and r["result"]["CPA rounds"] >= 1


def _prove_exact(r: dict) -> None:
    assert r["chains"] == 1 and r["result"]["jobs/hyperperiod"] > 0
    assert all(" by exact-" in r["result"][k] for k in ("reaction_time", "data_age"))


def _synth_feasibility(r: dict) -> None:
    assert r["result"]["status"] == "sat"


def _synth_optimum(r: dict) -> None:
    assert r["result"]["status"] == "sat" and r["result"]["optimal"] == "yes"


def _unsat_core(r: dict) -> None:
    assert r["result"]["status"] == "unsat" and "core" in r["result"]


def _baseline(name: str) -> Callable[[dict], None]:
    def check(r: dict) -> None:
        limit = run.QUICK_PARAMS[name]["limit"]
        res = r["result"]
        assert 1 <= res["evaluations"] <= limit and "combinations" in res["space"]
        gave_up = res["evaluations"] == limit and res["status"] != "found"
        assert res["status"] == (f"gave up after {limit} evaluations (limit)" if gave_up else res["status"])
        assert res["status"] in ("found", "unsat (space exhausted)") or gave_up

    return check


def _z3_direct(r: dict) -> None:
    assert r["result"]["status"] in ("sat", "unsat", "undecided")


#: each stage's own check of a row (beyond what every row must hold)
CHECKS: dict[str, Callable[[dict], None]] = {
    "prove-bound": _prove_bound, "prove-search": _prove_search, "analyze-pipeline": _analyze_pipeline,
    "prove-exact": _prove_exact, "synth-feasibility": _synth_feasibility, "synth-optimum": _synth_optimum,
    "unsat-core": _unsat_core, "baseline-brute-force": _baseline("baseline-brute-force"),
    "baseline-random-search": _baseline("baseline-random-search"), "baseline-z3-direct": _z3_direct,
}
