"""The canonical formatter: round trip, idempotence, and no comment lost or reordered."""
from __future__ import annotations

import re
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .strategies import MODULE_PATH, modules, valid_modules
from verify.model import syntax as s
from verify.core.diagnostics import DiagnosticSink
from verify.frontend.fmt import collect_comments, format_module, format_number, format_text
from verify.frontend.parse import parse_text


def parse(text: str, path: str = MODULE_PATH) -> s.Module:
    sink = DiagnosticSink()
    module = parse_text(text, path, sink)
    assert module is not None, [d.message for d in sink.items]
    return module


def fmt(text: str) -> str:
    out, diagnostics = format_text(text, MODULE_PATH)
    assert out is not None, [d.message for d in diagnostics]
    return out


# ------------------------------------------------------------------ properties


@pytest.mark.slow
@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(modules)
def test_roundtrip_and_idempotence(module):
    text = format_module(module)
    reparsed = parse(text)
    assert reparsed == module
    assert format_module(reparsed) == text
    assert text == "" or (text.endswith("\n") and not text.endswith("\n\n"))


_COMMENT_FORMS = {
    "line": " // note !{}!\n",
    "block": " /* note !{}! */ ",
    "multiline": " /* note !{}!\n     second line */ ",
    "own_line": "\n// note !{}!\n",
}


def _insert_comments(text: str, picks: list[tuple[int, str]]) -> tuple[str, list[str]]:
    """Insert comments at whitespace positions of ``text``, numbered in the order they appear."""
    gaps = [i for i, ch in enumerate(text) if ch in " \n"]
    chosen = sorted({gaps[k % len(gaps)]: form for k, form in picks}.items()) if gaps else []
    pieces, inserted, last = [], [], 0
    for n, (at, form) in enumerate(chosen):
        comment = _COMMENT_FORMS[form].format(n)
        pieces += [text[last:at], comment]
        inserted.append(comment.strip())
        last = at
    pieces.append(text[last:])
    return "".join(pieces), inserted


@pytest.mark.slow
@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(modules, st.lists(st.tuples(st.integers(0, 10**6), st.sampled_from(sorted(_COMMENT_FORMS))), max_size=8))
def test_comments_survive_in_order(module, picks):
    text, inserted = _insert_comments(format_module(module), picks)
    out = fmt(text)
    assert [int(n) for n in re.findall(r"!(\d+)!", out)] == list(range(len(inserted)))
    for comment in inserted:
        assert comment in out
    assert parse(out) == module
    assert fmt(out) == out


# ------------------------------------------------------------------ a realistic file

REALISTIC = """\
// Navigation stack of a small mobile robot.
import "sensors.vfy"   // lidar and camera components

/* The planner: replans on every new map,
   at most every 100 ms. */
component Planner {
  in map : Map
  out path : Path // the planned path
  in odom : Odometry
  task plan preemptive {
    reads map required oversampling ok
    reads odom optional undersampling <= 2.5
    bcet 2 ms wcet 37.5 ms // measured on the target
    produces path
    activation min 1 Hz max 10 Hz changeable
    // nothing else
  }
  // end of Planner
}

system Robot {
  instance planner : Planner on cpu0 {
    task plan priority 3 /* high */ on cpu0 trigger map every 1
  }
  core cpu0 policy fixed_priority
  connect lidar.scan -> planner.map delay 1 ms .. 1 ms
  chain nav: lidar.scan -> planner.path -> planner.plan {
    // the end-to-end requirement
    reaction_time <= 100/3 ms
    data_age <= 0.25 s
  }
  instance idle : Planner { }
}
// trailing notes
/* last words */
"""

REALISTIC_CANONICAL = """\
// Navigation stack of a small mobile robot.
import "sensors.vfy"  // lidar and camera components

/* The planner: replans on every new map,
   at most every 100 ms. */
component Planner {
  in map : Map
  in odom : Odometry
  out path : Path  // the planned path
  task plan {
    reads map oversampling ok
    reads odom optional undersampling <= 2.5
    produces path
    bcet 2 ms
    wcet 37.5 ms  // measured on the target
    activation 1 Hz .. 10 Hz
    // nothing else
  }
  // end of Planner
}

system Robot {
  core cpu0 policy fixed_priority
  instance planner : Planner on cpu0 {
    task plan priority 3 on cpu0 trigger map  /* high */
  }
  instance idle : Planner
  connect lidar.scan -> planner.map delay 1 ms
  chain nav: lidar.scan -> planner.path -> planner.plan {
    // the end-to-end requirement
    reaction_time <= 100/3 ms
    data_age <= 0.25 s
  }
}

// trailing notes
/* last words */
"""


def test_realistic_file_formats_canonically():
    assert fmt(REALISTIC) == REALISTIC_CANONICAL


def test_realistic_file_keeps_its_meaning_and_is_stable():
    assert parse(REALISTIC_CANONICAL) == parse(REALISTIC)
    assert fmt(REALISTIC_CANONICAL) == REALISTIC_CANONICAL


def test_realistic_file_keeps_every_comment():
    before = [c.text for c in collect_comments(REALISTIC)]
    after = [c.text for c in collect_comments(REALISTIC_CANONICAL)]
    # the system's members are reordered (cores first), but none of its lines carries a comment
    assert after == before


def test_comment_positions():
    text = 'import "a//b" // x\n  /* y\n z */ // w\n'
    comments = collect_comments(text)
    assert [(c.text, c.line, c.column, c.own_line) for c in comments] == [
        ("// x", 1, 15, False),
        ("/* y\n z */", 2, 3, True),
        ("// w", 3, 7, True),
    ]


def test_comments_stay_with_their_node_when_members_move():
    text = "system S {\n  // the link\n  connect a.b -> c.d\n  // the core\n  core k\n}\n"
    assert fmt(text) == "system S {\n  // the core\n  core k\n  // the link\n  connect a.b -> c.d\n}\n"


def test_comments_in_an_empty_body_keep_the_body():
    text = "system S {\n  chain c: a.b {\n    // to do\n  }\n  instance i : C {} // spare\n}\n"
    assert fmt(text) == (
        "system S {\n  instance i : C {\n  }  // spare\n  chain c: a.b {\n    // to do\n  }\n}\n"
    )


def test_a_comment_after_a_line_comment_moves_to_the_next_line():
    text = "component C { in a : T // one\n /* two */ in b : T }\n"
    assert fmt(text) == "component C {\n  in a : T  // one\n  /* two */\n  in b : T\n}\n"


def test_only_comments():
    assert fmt("// just this\n\n/* and this */") == "// just this\n/* and this */\n"
    assert fmt("") == ""


# ------------------------------------------------------------------ canonical forms


@pytest.mark.parametrize(
    "value, text",
    [
        (Fraction(10), "10"),
        (Fraction(0), "0"),
        (Fraction(75, 2), "37.5"),
        (Fraction(1, 8), "0.125"),
        (Fraction(1, 1000), "0.001"),
        (Fraction(100, 3), "100/3"),
        (Fraction(7, 6), "7/6"),
    ],
)
def test_numbers_are_exact(value, text):
    assert format_number(value) == text
    assert parse(f"system S {{ chain c: a.b {{ jitter <= {text} ms }} }}").systems[0].chains[0].specs[0].bound \
        == s.Quantity(value, "ms")


def test_floats_and_negatives_are_refused():
    with pytest.raises(ValueError):
        format_number(0.5)
    with pytest.raises(ValueError):
        format_number(Fraction(-1))


@pytest.mark.parametrize(
    "clause, canonical",
    [
        ("activation 10 ms .. 20 ms", "activation 10 ms .. 20 ms"),
        ("activation min 10 ms max 20 ms changeable", "activation 10 ms .. 20 ms"),
        ("activation 1 s .. 1000 ms", "activation 1 s"),
        ("activation min 5 Hz fixed", "activation min 5 Hz fixed"),
        ("activation max 2.50 kHz", "activation max 2.5 kHz"),
    ],
)
def test_activation_constraints(clause, canonical):
    out = fmt(f"component C {{ task t {{ {clause} }} }}")
    assert out == f"component C {{\n  task t {{\n    {canonical}\n  }}\n}}\n"


@pytest.mark.parametrize(
    "binding, canonical",
    [
        ("task t timer 10 ms phase 0 ms", "task t timer 10 ms phase 0 ms"),
        ("task t timer ?", "task t timer ?"),
        ("task t timer ? in 1 ms .. 2 ms step 0.5 ms", "task t timer ? in 1 ms .. 2 ms step 0.5 ms"),
        ("task t trigger p every 1", "task t trigger p"),
        ("task t trigger p every 02", "task t trigger p every 2"),
        ("task t trigger p every ?", "task t trigger p every ?"),
        ("task t trigger p every ? in 1 .. 4", "task t trigger p every ? in 1 .. 4"),
        ("task t sporadic 1 ms .. 2 ms", "task t sporadic 1 ms .. 2 ms"),
        ("task t activation ?", "task t activation ?"),
        ("task t timer 1 s deadline 1 s wcrt 2 ms on k priority 1",
         "task t priority 1 on k wcrt 2 ms deadline 1 s timer 1 s"),
    ],
)
def test_bindings(binding, canonical):
    out = fmt(f"system S {{ instance i : C {{ {binding} }} }}")
    assert out == f"system S {{\n  instance i : C {{\n    {canonical}\n  }}\n}}\n"


def test_task_clauses_in_canonical_order():
    text = "component C { task t cooperative { wcet 2 ms produces a reads x required produces b bcet 1 ms } }"
    assert fmt(text) == (
        "component C {\n  task t cooperative {\n    reads x\n    produces a, b\n"
        "    bcet 1 ms\n    wcet 2 ms\n  }\n}\n"
    )


def test_top_level_items_keep_source_order_with_imports_first():
    text = 'system A { }\ncomponent B { }\nimport "x"\nimport "y"\nsystem C { }'
    assert fmt(text) == 'import "x"\nimport "y"\n\nsystem A {\n}\n\ncomponent B {\n}\n\nsystem C {\n}\n'


def test_without_spans_components_come_first():
    module = s.Module("m", systems=(s.System(s.Name("S")),), components=(s.Component(s.Name("C")),))
    assert format_module(module) == "component C {\n}\n\nsystem S {\n}\n"


def test_compound_ports():
    text = "component C { in x = a & b in y = a | b | c }"
    assert fmt(text) == "component C {\n  in x = a & b\n  in y = a | b | c\n}\n"


def test_compound_constraint_is_printed():
    constraint = s.ActivationConstraint(s.Quantity(Fraction(10), "ms"), s.Quantity(Fraction(10), "ms"), False)
    compound = s.CompoundPort(s.Name("x"), "and", (s.Name("a"), s.Name("b")), constraint)
    text = format_module(s.Module(MODULE_PATH, components=(s.Component(s.Name("C"), compounds=(compound,)),)))
    assert text == "component C {\n  in x = a & b activation 10 ms fixed\n}\n"


def test_compound_constraint_survives_parsing():
    text = "component C {\n  in x = a & b activation 10 Hz fixed\n}\n"
    constraint = parse(text).components[0].compounds[0].constraint
    assert constraint is not None and constraint.min.base == 10 and not constraint.changeable


def test_inexpressible_trees_are_refused():
    one_member = s.CompoundPort(s.Name("x"), "and", (s.Name("a"),))
    with pytest.raises(ValueError):
        format_module(s.Module("m", components=(s.Component(s.Name("C"), compounds=(one_member,)),)))


# ------------------------------------------------------------------ errors


def test_syntax_errors_give_no_text():
    out, diagnostics = format_text("component C { task }")
    assert out is None
    assert diagnostics and diagnostics[0].code == "E001"


def test_a_repeated_clause_is_not_dropped_silently():
    out, diagnostics = format_text("component C { task t { bcet 1 ms bcet 2 ms } }")
    assert out is None
    assert [d.code for d in diagnostics] == ["E212"]


def test_blank_lines_between_members_are_kept_once():
    text = "system S {\n  core a\n\n\n  core b\n  core c\n}\n"
    formatted, _ = format_text(text)
    assert formatted == "system S {\n  core a\n\n  core b\n  core c\n}\n"
    assert format_text(formatted)[0] == formatted


# ------------------------------------------------------------------ random valid models (issue 2, item 10)


def _models_of_tree(module: s.Module):
    """The semantic models of a syntax tree itself, built without any text (resolve, validate, build)."""
    from verify.api import finish_load
    from verify.frontend.loader import Project
    from verify.core.source import SourceFile

    sink = DiagnosticSink()
    return finish_load(Project(MODULE_PATH, (module,), {MODULE_PATH: SourceFile(MODULE_PATH, "")}), sink)


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(valid_modules())
def test_random_valid_models_check_format_and_parse_back(module):
    import verify

    text = format_module(module)
    loaded = verify.load_text(text, MODULE_PATH)
    assert loaded.ok, "\n".join(f"{d.code} {d.message}" for d in loaded.diagnostics) + "\n\n" + text
    assert not loaded.diagnostics
    assert sorted(loaded.models) == sorted(sy.name.text for sy in module.systems)
    assert fmt(text) == text  # canonical already: formatting is idempotent
    assert parse(text) == module
    original = _models_of_tree(module)
    assert original.ok and original.models == loaded.models  # parse(format(m)) means what m means
    for name, model in loaded.models.items():
        system = next(sy for sy in module.systems if sy.name.text == name)
        assert len(model.tasks) == sum(len(i.bindings) for i in system.instances)
        assert len(model.links) == len(system.connections) and len(model.chains) == len(system.chains)
