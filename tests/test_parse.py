"""The parser: positions, recovery from several errors, messages in the language's words."""
from __future__ import annotations

from fractions import Fraction

import verify
from verify import syntax as s
from verify.diagnostics import DiagnosticSink
from verify.parse import parse_text


def _parse(text):
    sink = DiagnosticSink()
    return parse_text(text, "m.vfy", sink), sink.items


def test_quantities_are_exact():
    module, diags = _parse("component A { task T { bcet 0.1 ms wcet 100/3 ms activation 37.5 Hz } }")
    assert not diags
    task = module.components[0].tasks[0]
    assert task.bcet.base == Fraction(1, 10000)
    assert task.wcet.base == Fraction(1, 30)
    assert task.constraint.min.base == Fraction(75, 2)
    assert s.Quantity(Fraction(100), "ms") == s.Quantity(Fraction(1, 10), "s")


def test_spans_point_at_the_word():
    module, _ = _parse("component A {\n  in scan : LaserScan\n}")
    port = module.components[0].in_ports[0]
    assert (port.name.span.line, port.name.span.column) == (2, 6)
    assert (port.type.span.line, port.type.span.column) == (2, 13)


def test_several_syntax_errors_are_reported():
    text = "component A {\n  task T { wcet 5 }\n  out b c\n}\nsystem { }\n"
    module, diags = _parse(text)
    assert module is None
    assert [(d.code, d.span.line) for d in diags] == [("E001", 2), ("E001", 3), ("E001", 5)]
    assert "a unit" in diags[0].message and "10 ms" in diags[0].help
    assert "expected ':'" in diags[1].message
    assert all("__ANON" not in d.message and "$END" not in d.message for d in diags)


def test_unexpected_end_of_file():
    _, diags = _parse("component A {\n  in a : T\n")
    assert [d.code for d in diags] == ["E001"]
    assert "the end of the file" in diags[0].message and "}" in diags[0].help


def test_keywords_are_names_where_only_a_name_can_stand():
    module, diags = _parse("component task { in timer : in task in { wcet 1 ms } }")
    assert not diags
    comp = module.components[0]
    assert comp.name.text == "task" and comp.in_ports[0].name.text == "timer"
    assert comp.tasks[0].name.text == "in"


def test_names_resolution_collects_every_error_with_hints():
    text = """
    component Laser { out scan : Scan task T { produces scan wcet 1 ms } }
    system S {
      core cpu0
      instance a : Lazer on cpu0
      instance b : Laser on cpu9 { task Tt priority 1 timer 10 ms }
      connect b.scn -> c.x
    }
    """
    result = verify.load_text(text)
    got = [(d.code, d.help) for d in result.diagnostics]
    assert ("E101", "did you mean `Laser`?") in got
    assert ("E101", "did you mean `cpu0`?") in got
    assert ("E101", "did you mean `T`?") in got
    assert ("E101", "did you mean `scan`?") in got
    assert any(code == "E101" and "instance" in (h or "") or code == "E101" for code, h in got)
    assert len([c for c, _ in got if c == "E101"]) >= 5
