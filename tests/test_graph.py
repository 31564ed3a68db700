"""`verify graph`: the system as a picture (verify/outputs/diagram.py), as DOT text and laid out by Graphviz."""
from __future__ import annotations

import os
import shutil

import pytest

from verify.cli import main

from .conftest import EXAMPLES, ROOT, in_ci

NAVIGATION = str(EXAMPLES / "navigation" / "navigation.vfy")
GOLDEN = ROOT / "tests" / "golden" / "graph"


def _dot(capsysbinary, *args: str) -> str:
    assert main(["graph", *args]) == 0
    return capsysbinary.readouterr().out.decode("utf-8")


def require_graphviz() -> None:
    if shutil.which("dot") is None:
        if in_ci():
            pytest.fail("Graphviz missing (scripts/install-tools installs it)")
        pytest.skip("Graphviz missing")


def test_the_navigation_diagram_is_its_golden_dot(capsysbinary):
    text = _dot(capsysbinary, NAVIGATION)
    golden = GOLDEN / "navigation.dot"
    if os.environ.get("UPDATE_GOLDEN") == "1":
        golden.write_text(text, encoding="utf-8")
    assert text == golden.read_text(encoding="utf-8")


def test_the_diagram_shows_what_the_analysis_found(capsysbinary):
    text = _dot(capsysbinary, NAVIGATION)
    for shown in ("<B>laser</B> : Laser", "timer 25 ms · 40 Hz", "trigger scan every 10 · 4 Hz", "R ≤ 172 ms",
                  "triggers CurMapTask every 10", "OATask: oversampled ×2", "PlannerTask: undersampled ×2.5",
                  "reaction time ≤ 189.3 ms against spec 250 ms ✓, margin 60.7 ms", "cpu1 U = 0.72"):
        assert shown in text, shown
    # the reactive chain's hops in its colour; a connection both chains take in both
    assert '"laser":"out_scan":e -> "oa":"in_scan":w [color="#1b9e77"' in text
    assert '"laser":"out_scan":e -> "mapper":"in_scan":w [color="#d95f02"' in text
    assert 'style=dashed' in text  # a sampled connection on no chain


def test_a_system_with_holes_is_drawn_without_analysis(capsysbinary):
    text = _dot(capsysbinary, str(EXAMPLES / "navigation" / "navigation-holes.vfy"))
    assert "synthesis hole" in text and "R ≤" not in text and "reaction time ≤" not in text


def test_svg_and_png_are_laid_out_by_graphviz(tmp_path):
    require_graphviz()
    svg, png = tmp_path / "nav.svg", tmp_path / "nav.png"
    assert main(["graph", NAVIGATION, "-o", str(svg)]) == 0
    assert main(["graph", NAVIGATION, "-o", str(png)]) == 0
    text = svg.read_text(encoding="utf-8")
    assert text.lstrip().startswith("<?xml") and "<svg" in text and "ObstacleAvoidance" in text
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name", ["autoware.vfy", "autoware-executors.vfy"])
def test_every_autoware_diagram_is_laid_out(tmp_path, name):
    """Fusions (compound in-ports beside the in-ports: one table per label cell) and executor callbacks
    (named with their executor) are drawn by Graphviz."""
    require_graphviz()
    svg = tmp_path / "autoware.svg"
    assert main(["graph", str(EXAMPLES / "autoware-reference" / name), "-o", str(svg)]) == 0
    text = svg.read_text(encoding="utf-8")
    assert "point_cloud_fusion" in text and "both = input0 &amp; input1" in text
    assert ("executor inner · priority 10" in text) == (name == "autoware-executors.vfy")


def test_an_existing_file_is_not_overwritten(tmp_path, capsys):
    out = tmp_path / "nav.dot"
    out.write_text("mine", encoding="utf-8")
    assert main(["graph", NAVIGATION, "-o", str(out)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err and out.read_text(encoding="utf-8") == "mine"
    assert main(["graph", NAVIGATION, "-o", str(out), "--force"]) == 0
    assert out.read_text(encoding="utf-8").startswith('digraph "Navigation"')


def test_without_graphviz_svg_is_a_usage_error_and_dot_still_works(monkeypatch, capsysbinary):
    import verify.outputs.diagram

    monkeypatch.setattr(verify.outputs.diagram.shutil, "which", lambda name: None)
    assert main(["graph", NAVIGATION, "--format", "svg"]) == 2
    assert "needs Graphviz's `dot`" in capsysbinary.readouterr().err.decode("utf-8")
    assert _dot(capsysbinary, NAVIGATION).startswith("digraph")


def test_a_graphviz_failure_is_reported_not_a_traceback(monkeypatch, capsys):
    import subprocess

    import verify.outputs.diagram

    def crash(*args, **kwargs):
        return subprocess.CompletedProcess(args, -11, b"", b"")

    monkeypatch.setattr(verify.outputs.diagram.subprocess, "run", crash)
    monkeypatch.setattr(verify.outputs.diagram.shutil, "which", lambda name: "/usr/bin/dot")
    assert main(["graph", NAVIGATION, "--format", "png", "-o", os.devnull, "--force"]) == 2
    err = capsys.readouterr().err
    assert "Graphviz's `dot` failed: exit status -11" in err and "Traceback" not in err


def test_an_invalid_model_gets_its_diagnostics_as_text(write, capsys):
    path = write({"main.vfy": "system S { instance x : Nope }"})
    assert main(["graph", path, "--format", "svg"]) == 2
    assert "error[E101]" in capsys.readouterr().err
