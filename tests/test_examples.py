"""Every example in examples/ loads, resolves and validates."""
from __future__ import annotations

import pytest

import verify
from verify.cli import main

from .conftest import EXAMPLES

#: examples that show an import's output as written, before it is completed (what `verify check` lists)
INCOMPLETE = {EXAMPLES / "smartmdsd-gazebo" / "imported.vfy": ["E207"] + ["E217"] * 10,
              EXAMPLES / "caret-talker-listener" / "imported.vfy": ["E213", "E213", "E214", "E214", "E217", "E217"]}
EXAMPLE_FILES = sorted(p for p in EXAMPLES.rglob("*.vfy") if p not in INCOMPLETE)


def test_examples_exist():
    assert len(EXAMPLE_FILES) >= 4


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=lambda p: p.name)
def test_example_checks_clean(path, capsys):
    result = verify.load(str(path))
    assert result.ok, [d.message for d in result.diagnostics]
    assert main(["check", str(path)]) == 0


@pytest.mark.parametrize("path", sorted(INCOMPLETE), ids=lambda p: p.name)
def test_an_incomplete_example_lists_what_is_left_to_complete(path):
    result = verify.load(str(path))
    assert sorted(d.code for d in result.diagnostics if d.severity == "error") == INCOMPLETE[path]


def test_navigation_model_shape():
    model = verify.load(str(EXAMPLES / "navigation" / "navigation.vfy")).system()
    assert [t.id for t in model.tasks] == [
        "base.PoseUpdateTask", "base.RobotTask", "laser.LaserTask", "oa.OATask",
        "mapper.CurMapTask", "planner.PlannerTask",
    ]
    mapper = model.task("mapper.CurMapTask")
    assert mapper.activation.prescaler == 10 and mapper.activation.port == "scan"
    reactive = next(c for c in model.chains if c.name == "reactive")
    assert reactive.tasks == ("base.PoseUpdateTask", "laser.LaserTask", "oa.OATask", "base.RobotTask")
    assert [h.link.target for h in reactive.hops] == ["laser.odom", "oa.scan", "base.navvel"]
    from fractions import Fraction
    assert reactive.reaction_time == Fraction(1, 4)
    assert model.task("laser.LaserTask").activation.period == Fraction(1, 40)


@pytest.mark.parametrize("name", ["navigation.vfy", "navigation-holes.vfy"])
def test_every_model_node_points_at_the_source(name):
    """Every node of the semantic model carries the span of the text it comes from (issue: a source
    span on every node), and spans name the line the node's text is on."""
    import dataclasses

    from verify.model.system import Hole
    from verify.core.source import NO_SPAN

    loaded = verify.load(str(EXAMPLES / "navigation" / name))
    model = loaded.system()
    seen = set()

    def walk(node, path):
        if isinstance(node, (tuple, list)):
            for n, item in enumerate(node):
                walk(item, f"{path}[{n}]")
            return
        if not dataclasses.is_dataclass(node) or id(node) in seen or type(node).__module__ != "verify.model.system":
            return
        seen.add(id(node))
        span = node.span  # (a Hole's is that of the syntax node it keeps)
        assert span != NO_SPAN, f"{path} ({type(node).__name__}) has no span"
        line = loaded.sources[span.file].text.splitlines()[span.line - 1]
        assert line.strip(), (path, span)
        for f in dataclasses.fields(node):
            if f.name not in ("span", "activation") or not isinstance(node, Hole):
                walk(getattr(node, f.name), f"{path}.{f.name}")

    walk(model, "model")
    assert len(seen) > 30
    for chain in model.chains:
        for kind in ("reaction_time", "data_age", "jitter"):
            if getattr(chain, kind) is not None:
                span = chain.spec_span(kind)
                assert kind in loaded.sources[span.file].text.splitlines()[span.line - 1]


def test_holes_variant_has_holes():
    model = verify.load(str(EXAMPLES / "navigation" / "navigation-holes.vfy")).system()
    assert sorted(t.id for t in model.holes) == ["mapper.CurMapTask", "oa.OATask", "planner.PlannerTask"]
    assert not model.is_configured


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=lambda p: p.name)
def test_example_is_canonically_formatted(path):
    assert main(["fmt", "--check", str(path)]) == 0


def test_analyze_navigation_outline_and_chain_table(capsys):
    """The short view has every task's rate and response time and the chain table; `--explain` (`-v`)
    adds the derivation: how each rate comes about, sampling, each chain hop by hop."""
    path = str(EXAMPLES / "navigation" / "navigation.vfy")
    assert main(["analyze", path]) == 0
    brief = capsys.readouterr().out
    assert "mapper.CurMapTask" in brief and "4 Hz" in brief and "§" not in brief
    assert len(brief.splitlines()) < 40
    for flag in ("--explain", "-v"):
        assert main(["analyze", path, flag]) == 0
        out = capsys.readouterr().out
        assert "mapper.CurMapTask" in out and "4 Hz = 40 Hz / 10" in out
        assert "undersampled ×10" in out
        for chain in ("reactive", "planning"):
            assert chain in out and f"chain {chain}: " in out


def test_analyze_ends_with_a_verdict_per_spec_in_the_words_of_prove(capsys):
    """A bound above a spec proves nothing either way: `analyze` says "not proved by the bound" and exits
    3, as `prove` says undecided before its search decides (here: violated, exit 1)."""
    import json

    path = str(EXAMPLES / "navigation" / "navigation-violated.vfy")
    assert main(["analyze", path]) == 3
    out = capsys.readouterr().out
    assert "VIOLATED" not in out and "violated" not in out
    last = out.split("\n")[2:6]  # (after the system's line: the verdicts lead)
    assert last[0].startswith("3 specs: 2 proved by the bound, 1 not proved by the bound")
    assert "chain reactive: reaction time" in last[1] and "not proved by the bound: 189.3 ms exceeds it by 39.3 ms" \
        in last[1]
    assert all("proved by the bound: " in line and "not proved" not in line for line in last[2:])
    assert main(["analyze", path, "--format", "json"]) == 3
    specs = [s for c in json.loads(capsys.readouterr().out)["chains"] for s in c["specs"]]
    assert [s["status"] for s in specs] == ["undecided", "proved", "proved"]
    assert main(["prove", path]) == 1  # (the search finds a run above the spec)
    capsys.readouterr()
    assert main(["analyze", str(EXAMPLES / "navigation" / "navigation.vfy")]) == 0
    assert capsys.readouterr().out.split("\n")[2].startswith("3 specs: 3 proved by the bound, 0 not")
    assert main(["analyze", path, "--explain"]) == 3  # (the derivation ends with the same verdicts)
    assert capsys.readouterr().out.rstrip("\n").split("\n")[-4:] == last


def test_analyze_refuses_holes_with_a_located_error(capsys):
    assert main(["analyze", str(EXAMPLES / "navigation" / "navigation-holes.vfy")]) == 2
    err = capsys.readouterr().err
    assert err.count("error[E218]") == 3 and "navigation-holes.vfy:17:28" in err
