"""The counterexample chart reads at a glance: labels in a column of their own, rows grouped by core,
round axis ticks, the spec's end drawn, a legend (rendered and looked at when it was designed; these
tests hold its geometry)."""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from fractions import Fraction as F

from hypothesis import given
from hypothesis import strategies as st

import verify
from verify.prove import prove
from verify.prove.gantt import CHAR_W, axis_ticks, nice_step, to_svg

from .conftest import EXAMPLES

NS = "{http://www.w3.org/2000/svg}"


@given(st.fractions(min_value=0, max_value=100), st.fractions(min_value=F(1, 10**9), max_value=100))
def test_ticks_are_round_and_inside(t0, span):
    t1 = t0 + span
    step = nice_step(span)
    mantissa = step
    while mantissa >= 10:
        mantissa /= 10
    while mantissa < 1:
        mantissa *= 10
    assert mantissa in (1, 2, 5)
    ticks = axis_ticks(t0, t1)
    assert 1 <= len(ticks) <= 11 and all(t0 <= t <= t1 and t % step == 0 for t in ticks)
    assert span / step <= 10 and (step == F(1, 10**12) or span / _smaller(step) > 10)


def _smaller(step: F) -> F:
    """The round step below ``step``."""
    for a, b in ((5, 2), (2, 1)):
        digits = step
        power = F(1)
        while digits >= 10:
            digits, power = digits / 10, power * 10
        while digits < 1:
            digits, power = digits * 10, power / 10
        if digits == a:
            return b * power
    return step / 2  # (1 → 0.5)


def _chart():
    model = verify.load(str(EXAMPLES / "navigation" / "navigation-violated.vfy")).system()
    verdict = next(v for v in prove(model).verdicts if v.counterexample is not None)
    return model, verdict, ET.fromstring(to_svg(model, verdict))


def test_labels_never_reach_the_plot_and_rows_are_grouped_by_core():
    model, verdict, root = _chart()
    labels = [t for t in root.iter(f"{NS}text") if t.get("class") == "task"]
    bars = [float(r.get("x")) for r in root.iter(f"{NS}rect") if (r.get("class") or "").startswith("job")]
    violation = next(r for r in root.iter(f"{NS}rect") if r.get("class") == "violation")
    plot_left = min(bars + [float(violation.get("x"))])
    assert labels and all(t.get("font-family") == "monospace" for t in labels)
    assert all(float(t.get("x")) + CHAR_W * len(t.text) < plot_left for t in labels)
    cores = [("".join(t.itertext()), float(t.get("y"))) for t in root.iter(f"{NS}text") if t.get("class") == "core"]
    assert [c for c, _ in cores] == ["core cpu0", "core cpu1"]  # (the order the chain meets them)
    for label in labels:
        task = label.text.split()[0]
        core = model.task(task).core
        y = float(label.get("y"))
        mine = next(cy for c, cy in cores if c == f"core {core}")
        later = [cy for _, cy in cores if cy > mine]
        assert mine < y < min(later, default=float("inf"))
    by_core = {}
    for label in labels:
        name, _, prio = label.text.split()
        by_core.setdefault(model.task(name).core, []).append(int(prio))
    assert all(prios == sorted(prios, reverse=True) for prios in by_core.values())


def test_spec_line_legend_and_round_ticks():
    model, verdict, root = _chart()
    spec = [e for e in root.iter() if e.get("class") == "spec"]
    line = next(e for e in spec if e.tag == f"{NS}line")
    assert any("".join(e.itertext()) == "spec 150 ms" for e in spec)
    violation = next(r for r in root.iter(f"{NS}rect") if r.get("class") == "violation")
    x0, width = float(violation.get("x")), float(violation.get("width"))
    sample = verdict.counterexample.sample
    assert abs(float(line.get("x1")) - (x0 + width * float(verdict.spec / (sample.end - sample.begin)))) < 0.02
    ticks = ["".join(t.itertext()) for t in root.iter(f"{NS}text") if t.get("class") == "tick"]
    assert ticks and all(re.fullmatch(r"\d+ (ms|s|us)", t) for t in ticks)  # (no 44.1375 ms)
    legend = next(g for g in root.iter(f"{NS}g") if g.get("class") == "legend")
    words = ["".join(t.itertext()) for t in legend.iter(f"{NS}text")]
    assert words == ["job: start to completion", "job of the chain", "release", "data flow", "spec",
                     "violating interval"]
