"""The front end an editor needs: a partial tree after syntax errors, positions as offsets and UTF-16
(``SourceMap``), and the table from every use of a name to its declaration (``verify.frontend.symbols``)."""
from __future__ import annotations

import random

from hypothesis import given, settings
from hypothesis import strategies as st

import verify
from verify.frontend.parse import parse_source
from verify.core.source import SourceFile, SourceMap, Span

from .conftest import EXAMPLES

NAV = EXAMPLES / "navigation" / "navigation.vfy"
COMPONENTS = (EXAMPLES / "navigation" / "components.vfy").read_text(encoding="utf-8")


# ------------------------------------------------------------------ partial trees


def test_a_half_typed_file_has_a_partial_tree_with_what_was_typed():
    text = "component Laser {\n  in odom : Pose\n  out scan : LaserScan\n  task T {\n    reads odom\n    wcet 2"
    parsed = parse_source(text, "laser.vfy")
    assert parsed.module is None and [d.code for d in parsed.diagnostics] == ["E001"]
    (comp,) = parsed.partial.components
    assert comp.name.text == "Laser" and [p.name.text for p in comp.in_ports] == ["odom"]
    (task,) = comp.tasks
    assert task.reads[0].port.text == "odom" and task.reads[0].port.span == Span("laser.vfy", 5, 11, 5, 15)
    assert task.wcet is not None and task.wcet.value == 2  # (its unit a placeholder)


def test_recovery_inside_a_file_keeps_what_follows_the_error():
    text = ("component A { outx : T }\ncomponent B { in y : U }\n"
            "system S { core c instance b : B on c { task T priority } }\n")
    parsed = parse_source(text, "m.vfy")
    assert parsed.module is None
    assert [c.name.text for c in parsed.partial.components] == ["A", "B"]
    assert [i.name.text for i in parsed.partial.systems[0].instances] == ["b"]


def test_valid_text_and_text_that_is_no_model_have_no_partial_tree():
    assert parse_source(COMPONENTS, "c.vfy").partial is None
    assert parse_source("root:x:0:0:root:/root:/bin/bash\n", "passwd").partial is None


def test_every_prefix_of_a_model_parses_to_a_tree_or_a_partial_one():
    rng = random.Random(7)
    for cut in sorted(rng.sample(range(len(COMPONENTS)), 120)):
        parsed = parse_source(COMPONENTS[:cut], "c.vfy")
        assert parsed.module is not None or parsed.partial is not None, COMPONENTS[:cut][-60:]


def test_the_project_keeps_the_partial_tree_of_a_file_with_errors(tmp_path):
    path = tmp_path / "m.vfy"
    path.write_text("component A {\n  in x : T\n")
    result = verify.load(str(path))
    assert not result.project.modules and [c.name.text for c in result.project.partials[str(path)].components] == ["A"]


# ------------------------------------------------------------------ positions

_TEXT = st.text(alphabet=st.sampled_from(list("ab \n\t{}é€𝄞\r") + ["\u2028"]), max_size=60)


@settings(max_examples=200, deadline=None)
@given(text=_TEXT, bom=st.booleans())
def test_offsets_and_lsp_positions_round_trip(text, bom):
    text = ("\ufeff" if bom else "") + text
    m = SourceMap(text)
    for offset in range(m.bom, len(text) + 1):
        line, column = m.position(offset)
        assert m.offset(line, column) == offset
        lsp_line, character = m.to_lsp(line, column)
        line_text = text[m.line_start(line):offset]
        assert lsp_line == line - 1 and character == len(line_text.encode("utf-16-le")) // 2
        assert m.from_lsp(lsp_line, character) == (line, column)


def test_every_name_of_a_parsed_file_is_at_its_span_offsets():
    text = "// Télémètre 𝄞\n/* é𝄞 */ component Laser { in odom : Pose task T { reads odom wcet 1 ms } }\n"
    module = parse_source(text, "u.vfy").module
    m = SourceFile("u.vfy", "\ufeff" + text).map
    comp = module.components[0]
    for name in (comp.name, comp.in_ports[0].name, comp.tasks[0].reads[0].port):
        start, end = m.span_offsets(name.span)
        assert ("\ufeff" + text)[start:end] == name.text
    assert comp.name.span.column == 20  # (code points)
    assert m.lsp_range(comp.name.span) == {"start": {"line": 1, "character": 20},
                                           "end": {"line": 1, "character": 25}}  # (𝄞 is two UTF-16 units)


# ------------------------------------------------------------------ symbols


def test_every_reference_names_its_symbol_and_points_at_the_name():
    result = verify.load(str(NAV))
    idx = result.symbols
    assert idx.references
    for ref in idx.references:
        start, end = result.sources[ref.span.file].map.span_offsets(ref.span)
        assert result.sources[ref.span.file].text[start:end] == ref.symbol.name
        assert idx.at(ref.span.file, ref.span.line, ref.span.column) == ref.symbol
    for sym in idx.symbols:
        assert idx.at(sym.span.file, sym.span.line, sym.span.end_column) == sym  # (the cursor after the name)


def test_the_uses_of_a_port_across_files():
    result = verify.load(str(NAV))
    idx = result.symbols
    scan = idx.definition("out-port", "scan", "Laser")
    assert scan is not None and scan.span.file.endswith("components.vfy")
    uses = idx.references_to(scan)
    files = [sp.file.rsplit("/", 1)[-1] for sp in uses]
    # `produces scan` in the component; `connect laser.scan -> ...` twice and `laser.scan` in both chains
    assert files.count("components.vfy") == 1 and files.count("navigation.vfy") == 4, uses
    laser = idx.definition("instance", "laser", "Navigation")
    assert [sp.line for sp in idx.references_to(laser)] == [25, 28, 29, 35, 41]


def test_an_unknown_name_is_no_reference(tmp_path):
    path = tmp_path / "m.vfy"
    path.write_text("component A { out x : T task T { produces x produces y wcet 1 ms } }\n")
    idx = verify.load(str(path)).symbols
    assert idx.at(str(path), 1, 46) is None  # `y`: reported by resolve (E104), not a reference
    assert idx.at(str(path), 1, 44) == idx.definition("out-port", "x", "A")


def test_the_partial_tree_holds_only_what_the_text_says():
    """Fuzzing found a 3.5 kB text whose partial tree had 2.6 million names (17 s to build): the trial
    feeds of error recovery extended the child lists of trees on the parser's stack in place."""
    import re

    from .conftest import ROOT

    data = (ROOT / "tests" / "fuzz_regressions" / "validate" / "partial-tree-blowup").read_bytes()
    text = data.decode("utf-8", errors="replace")
    parsed = parse_source(text, "f.vfy")
    names = []

    def walk(node):
        import dataclasses

        if isinstance(node, tuple):
            for item in node:
                walk(item)
        elif dataclasses.is_dataclass(node):
            if type(node).__name__ == "Name":
                names.append(node)
            for f in dataclasses.fields(node):
                walk(getattr(node, f.name))

    walk(parsed.partial)
    words = len(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text))
    assert parsed.partial is not None and 0 < len(names) <= words


def test_load_takes_a_path_object_as_well_as_a_string():
    from pathlib import Path

    import verify

    from .conftest import EXAMPLES

    as_path = verify.load(Path(EXAMPLES / "navigation" / "navigation.vfy"), root=Path(EXAMPLES / "navigation"))
    as_text = verify.load(str(EXAMPLES / "navigation" / "navigation.vfy"), root=str(EXAMPLES / "navigation"))
    assert not as_path.diagnostics and as_path.system() is not None
    assert as_path.diagnostics == as_text.diagnostics
