"""The parser: positions, recovery from several errors, messages in the language's words."""
from __future__ import annotations

import re
from fractions import Fraction

import pytest

import verify
from verify.model import syntax as s
from verify.core.diagnostics import DiagnosticSink
from verify.frontend.parse import parse_text


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


# ---------------------------------------------------------------- keywords are whole words

#: every keyword of the language, each where the grammar accepts it (the text parses)
EVERY_KEYWORD = """\
import "lib.vfy"
message T = ros "std_msgs/Header"
component A {
  in a : T
  in b : T
  in c = a & b activation 1 Hz .. 2 Hz changeable
  in d = a | b activation min 1 Hz max 2 Hz fixed
  out o : T
  task T1 preemptive {
    reads a optional oversampling ok undersampling forbidden
    reads b required oversampling <= 2
    produces o
    bcet 1 ms
    wcet 2 ms
    activation 5 Hz
  }
  task T2 cooperative { wcet 1 ms activation max 5 Hz }
  task T3 { wcet 1 ms activation min 1 Hz }
}
system S {
  core c policy fp
  arrival_cost 500 us
  executor e events on c priority 2
  executor m multi_threaded 2 threads on d, f priority 2
  executor n multi_threaded 1 thread on g priority 2
  instance x : A on c {
    task T1 priority 1 on c wcrt 5 ms deadline 10 ms timer 10 ms phase 1 ms
    task T2 trigger c every 2
    task T3 sporadic 1 ms .. 2 ms
  }
  instance y : A {
    group g reentrant
    task T1 executor e group g activation ?
    task T2 timer ? in 10 ms .. 20 ms step 5 ms
    task T3 trigger a every ? in 1 .. 3
  }
  connect x.o -> y.a delay 1 ms .. 2 ms
  chain ch : x.o -> y.o { reaction_time <= 5 ms data_age <= 5 ms jitter <= 1 ms }
}
"""


def _keywords():
    from verify.frontend.grammar import keyword_terminals

    return sorted(keyword_terminals())


def test_the_keyword_sample_parses_and_has_every_keyword():
    module, diags = _parse(EVERY_KEYWORD)
    assert module is not None and not diags
    words = set(re.findall(r"[A-Za-z_]\w*", EVERY_KEYWORD))
    assert set(_keywords()) <= words


def _both_paths(text):
    """(whether the fast path accepted ``text``, Lark's diagnostics)."""
    from verify.frontend.fastparse import Unparsable
    from verify.frontend.parse import fast_parser
    from verify.frontend.recovery import recover
    from verify.frontend.treebuild import TreeBuilder

    sink = DiagnosticSink()
    recover(text, "m.vfy", sink)
    builder = TreeBuilder("m.vfy", DiagnosticSink())
    try:
        fast_parser().parse(text, builder.callbacks(fast_parser().callback_names()), builder.tokens())
        fast = True
    except Unparsable:
        fast = False
    return fast, sink.items


@pytest.mark.parametrize("keyword", _keywords())
def test_every_keyword_glued_to_a_name_is_an_located_error_naming_the_word(keyword):
    match = re.search(rf"(?<![\w\"])({keyword})(?=\s)", EVERY_KEYWORD)
    assert match, keyword
    text = EVERY_KEYWORD[:match.end()] + "x" + EVERY_KEYWORD[match.end():]
    line = EVERY_KEYWORD.count("\n", 0, match.start()) + 1
    column = match.start() - (EVERY_KEYWORD.rfind("\n", 0, match.start()) + 1) + 1
    fast, diags = _both_paths(text)
    assert not fast  # the fast path and Lark agree: both reject it
    assert diags and diags[0].code == "E001", diags
    d = diags[0]
    assert f"found '{keyword}x'" in d.message
    assert (d.span.line, d.span.column, d.span.end_column) == (line, column, column + len(keyword) + 1)
    assert d.help


@pytest.mark.parametrize("text, word, fix", [
    ("component A { outx : T }", "outx", "out x"),
    ("component A { taskT1 { wcet 1 ms } }", "taskT1", "task T1"),
    ("component A { out x : T task T { producesx wcet 1 ms } }", "producesx", "produces x"),
    ("system S { corec }", "corec", "core c"),
    ("system S { instancea : A on c }", "instancea", "instance a"),
    ("system S { instance a : A onc }", "onc", "on c"),
    ("system S { instance a : A { task T triggernavvel } }", "triggernavvel", "trigger navvel"),
    ("system S { connectbase.odom -> a.b }", "connectbase", "connect base"),
    ("system S { chainreactive: a.b }", "chainreactive", "chain reactive"),
    ("system S { instance a : A { task T priority1 } }", "priority1", "priority 1"),
])
def test_glued_keywords_are_reported_once_with_the_split_as_help(text, word, fix):
    fast, diags = _both_paths(text)
    assert not fast
    assert [d.code for d in diags] == ["E001"], [(d.message, d.span) for d in diags]
    assert f"found '{word}'" in diags[0].message
    assert diags[0].help.startswith(f"did you mean `{fix}`?")


def test_a_wrong_keyword_is_flagged_itself():
    _, diags = _parse("component A { output x : T }")
    assert [d.code for d in diags] == ["E001"]
    d = diags[0]
    assert d.message == "expected one of 'in', 'out', 'task', '}', found 'output'"
    assert (d.span.column, d.span.end_column) == (15, 21)
    assert "not a keyword" in d.help


def test_fmt_no_longer_splits_glued_keywords():
    from verify.frontend.fmt import format_text

    out, diags = format_text("component A { outx : T }")
    assert out is None and [d.code for d in diags] == ["E001"]


# ---------------------------------------------------------------- syntax error messages

def test_expected_tokens_are_those_the_parser_accepts_here():
    # after a quantity the table's row merges what may follow one anywhere ('..', 'chain', ...)
    _, diags = _parse("component A { task T { wcet 5 ms activaton 5 Hz } }")
    assert [d.code for d in diags] == ["E001"]
    assert diags[0].message == (
        "expected one of 'activation', 'bcet', 'produces', 'reads', 'wcet', '}', found 'activaton'")
    assert diags[0].help == "did you mean `activation`?"


@pytest.mark.parametrize("text, word, keyword", [
    ("compnent A {}", "compnent", "component"),
    ("component A { task T { activaton 5 Hz } }", "activaton", "activation"),
    ("component A { ot x : T }", "ot", "out"),
    ("system S { instance a : A { task T priorty 1 } }", "priorty", "priority"),
    ("system S { instance a : A { task T timer 1 ms } } sytem T { }", "sytem", "system"),
    ("component A { task T { reads a optinal } }", "optinal", "optional"),
    ("system S { cahin c : a.b }", "cahin", "chain"),
])
def test_a_misspelt_keyword_gets_did_you_mean(text, word, keyword):
    _, diags = _parse(text)
    assert diags and diags[0].code == "E001"
    assert f"found '{word}'" in diags[0].message
    assert diags[0].help == f"did you mean `{keyword}`?"


@pytest.mark.parametrize("text", [
    "component A { in x : }",
    "component A {\n  in y T\n}",
    "system S { task T }",
    "component A { task T { wcet 5 } }",
    "component A { task T { wcet 2 ms }",
    "component A { task T { wcet 2 ms } } }",
    "import component",
    "system S { connect a.b -> c }",
    "system S { instance a : A { task T timer ? in 5 .. } }",
    "component { }",
    "system S { chain c : a.b { jitter 5 ms } }",
])
def test_every_syntax_error_has_a_help(text):
    _, diags = _parse(text)
    assert diags and all(d.help for d in diags if d.code == "E001"), [(d.message, d.help) for d in diags]


def test_a_missing_symbol_recovery_supplies_is_named_in_the_help():
    _, diags = _parse("component A {\n  in y T\n}")
    assert [d.code for d in diags] == ["E001"]
    assert diags[0].message == "expected one of ':', '=', found 'T'"
    assert diags[0].help == "insert ':' before 'T'"


def test_unterminated_block_comment_points_at_its_opening():
    _, diags = _parse("component A {\n  /* the laser\n  task T { }\n}\n")
    assert [d.code for d in diags] == ["E002"]
    d = diags[0]
    assert d.message == "unterminated block comment"
    assert (d.span.line, d.span.column, d.span.end_column) == (2, 3, 5)
    assert "*/" in d.help and "//" not in d.help


def test_nested_block_comment_is_explained():
    _, diags = _parse("component A {\n  /* outer /* inner */ still comment */\n  out o : T\n}\n")
    assert [d.code for d in diags][:1] == ["E001"]
    d = diags[0]
    assert (d.span.line, d.span.column) == (2, 24)  # `still`
    assert "comment opened at 2:3 ended at 2:21" in d.primary.message
    (inner,) = d.secondary
    assert (inner.span.line, inner.span.column, inner.span.end_column) == (2, 12, 14)
    assert "do not nest" in d.help
    # two comments side by side are no nesting: the usual help
    _, diags = _parse("component A {\n  /* one */ /* two */ foo\n}\n")
    assert "nest" not in diags[0].help and not diags[0].secondary


def test_unterminated_string():
    _, diags = _parse('import "lib.vfy\ncomponent A { }\n')
    assert [d.code for d in diags] == ["E002"]
    assert diags[0].message == "unterminated string" and (diags[0].span.line, diags[0].span.column) == (1, 8)
    assert '"' in diags[0].help and "comment" not in diags[0].help


def test_negative_numbers_say_times_are_non_negative():
    _, diags = _parse("component A { task T { wcet -1 ms } }")
    assert [d.code for d in diags] == ["E002"]
    assert "negative" in diags[0].message and "non-negative" in diags[0].help
    assert "comment" not in diags[0].help


def test_exponent_notation_is_not_supported():
    _, diags = _parse("component A { task T { wcet 1e999999 } }")
    assert [d.code for d in diags] == ["E001"]
    d = diags[0]
    assert "exponent notation is not supported" in d.message and "`1e999999`" in d.message
    assert (d.span.column, d.span.end_column) == (29, 37)
    assert "unit" in d.help
    _, diags = _parse("component A { task T { wcet 2.5e-3 s } }")
    assert "exponent" in diags[0].message


def test_a_leading_byte_order_mark_is_skipped():
    module, diags = _parse("\ufeffcomponent A {\n  in scan : LaserScan\n}")
    assert not diags
    assert (module.components[0].name.span.line, module.components[0].name.span.column) == (1, 11)
    result = verify.load_text("\ufeffcomponent A { in x : T }")
    assert result.ok, [(d.code, d.message) for d in result.diagnostics]
    _, diags = _parse("component A {}\n\ufeff")  # elsewhere it is a stray character
    assert [d.code for d in diags] == ["E002"]


def test_a_byte_order_mark_does_not_shift_the_snippet():
    from verify.outputs.rendering import render_all_text
    from verify.core.source import SourceFile

    text = "\ufeffcomponent A { outx : T }"
    _, diags = _parse(text)
    rendered = render_all_text(diags, {"m.vfy": SourceFile("m.vfy", text)})
    assert "1 | component A { outx : T }\n  |               ^^^^" in rendered


@pytest.mark.parametrize("written, unit", [("hz", "Hz"), ("KHZ", "kHz"), ("MS", "ms"), ("Us", "us")])
def test_a_unit_in_the_wrong_case_is_one_error_naming_the_unit(written, unit, tmp_path):
    """`50 hz` is one E001 at the unit with the right spelling as help, and parsing goes on as if the
    unit were right (no second error at the next `}`)."""
    text = ("component A {\n  task T {\n    wcet 1 ms\n  }\n}\nsystem S {\n  core c\n"
            f"  instance a : A on c {{\n    task T priority 1 timer 50 {written}\n  }}\n}}\n")
    sink = DiagnosticSink()
    assert parse_text(text, "u.vfy", sink) is None
    (d,) = sink.items
    assert d.code == "E001" and f"`{written}`" in d.message and "case-sensitive" in d.message
    assert (d.span.line, d.span.column) == (9, 32) and d.help == f"write `{unit}`"


@pytest.mark.parametrize("written, unit, fix", [
    ("2 mss", "mss", "; did you mean `ms`?"), ("50 sec", "sec", "; did you mean `s`?"),
    ("3 msec", "msec", "; did you mean `ms`?"), ("40 hertz", "hertz", "; did you mean `Hz`?"),
    ("2 foo", "foo", ""),
])
def test_an_unknown_unit_is_one_error_at_the_word(written, unit, fix):
    """`wcet 2 mss`: one error, under the word, naming the unit meant when it is close; the parser
    goes on as if the unit were written (no second error at the next `}`)."""
    text = f"component Laser {{\n  task LaserTask {{\n    wcet {written}\n  }}\n}}\n"
    sink = DiagnosticSink()
    assert parse_text(text, "u.vfy", sink) is None
    [d] = sink.items
    column = text.split("\n")[2].index(unit) + 1
    assert (d.code, d.message) == ("E001", f"unknown unit `{unit}`{fix}")
    assert (d.span.line, d.span.column, d.span.end_column) == (3, column, column + len(unit))


def test_a_missing_unit_still_points_at_the_number():
    sink = DiagnosticSink()
    parse_text("component Laser {\n  task LaserTask {\n    wcet 2\n  }\n}\n", "u.vfy", sink)
    [d] = sink.items
    assert d.message == "expected a unit after the number `2`, found '}'" and d.span.column == 10


@pytest.mark.parametrize("constraint, message", [
    ("activation 100 ms fixed", "an activation-constraint bound must be a frequency, found the time 100 ms"),
    ("activation 100 ms .. 1 s", "an activation constraint is a range of frequencies, found the times 100 ms .. 1 s"),
])
def test_a_constraint_written_in_times_is_one_error(constraint, message):
    """One slip, one error: an exact rate is one quantity, a range of times one E302 (not one per bound)."""
    text = f"component Laser {{\n  task LaserTask {{\n    wcet 2 ms\n    {constraint}\n  }}\n}}\n"
    result = verify.load_text(text, "c.vfy")
    assert [(d.code, d.message) for d in result.diagnostics] == [("E302", message)]


def test_an_invalid_constraint_is_not_reported_again_at_its_bindings():
    """`activation 0 Hz fixed`: E307 at the constraint, not an E306 at every binding as well."""
    text = ("component Laser {\n  out scan : LaserScan\n  task LaserTask {\n    produces scan\n    wcet 2 ms\n"
            "    activation 0 Hz fixed\n  }\n}\nsystem S {\n  core cpu0\n  instance laser : Laser on cpu0 {\n"
            "    task LaserTask priority 1 timer 100 ms\n  }\n}\n")
    result = verify.load_text(text, "c.vfy")
    assert [d.code for d in result.diagnostics] == ["E307"]
