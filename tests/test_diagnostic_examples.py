"""Every diagnostic code has a section in specs/diagnostics.md whose minimal failing example reports it.

For each ``## CODE title`` section the example's files are written into a temporary directory and run
(``verify check``, ``verify analyze`` for ``command=analyze``, ``verify prove`` for ``command=prove``,
``synth`` for ``command=synth``, with ``rlimit=N`` as its budget); the section's code must be among the
diagnostics, and the rendered text must equal ``tests/golden/diagnostics/CODE.txt``. Run with
``UPDATE_GOLDEN=1`` to (re)write the golden files, then read them as a user would.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

import verify
from verify import timing
from verify.api import SelectionError, require_configured
from verify.cli import main
from verify.core.codes import CODES
from verify.core.limits import Limits
from verify.outputs.rendering import render_all_text

from .conftest import ROOT

SPEC = ROOT / "specs" / "diagnostics.md"
GOLDEN = ROOT / "tests" / "golden" / "diagnostics"
UPDATE = os.environ.get("UPDATE_GOLDEN") == "1"

#: what a user must never see in a diagnostic
FORBIDDEN = ("__ANON", "$END", "Token(", "Tree(", "Traceback", "Fraction(", "<none>", "None`", "NoneType")


@dataclass(frozen=True)
class Block:
    name: str
    text: str
    encoding: str
    command: str
    rlimit: str | None = None
    limit: str | None = None
    target: str = "ros1"  # (``command=gen``: the target, ``target=ros2``)
    trace: str | None = None  # (``command=trace``: a trace of the repository, ``trace=tests/data/...``)


@dataclass(frozen=True)
class Section:
    code: str
    title: str
    body: str
    blocks: tuple[Block, ...]

    @property
    def command(self) -> str:
        for command in ("synth", "prove", "analyze", "gen", "import", "export", "trace"):
            if any(b.command == command for b in self.blocks):
                return command
        return "check"


_FENCE = re.compile(r"^```(?:vfy|toml|text|smartmdsd)([^\n]*)\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)


def _blocks(body: str) -> tuple[Block, ...]:
    blocks = []
    for match in _FENCE.finditer(body):
        attrs = dict(item.split("=", 1) for item in match.group(1).split())
        blocks.append(Block(attrs.get("file", "main.vfy"), match.group(2), attrs.get("encoding", "utf-8"),
                            attrs.get("command", "check"), attrs.get("rlimit"), attrs.get("limit"),
                            attrs.get("target", "ros1"), attrs.get("trace")))
    return tuple(blocks)


def parse_spec(text: str) -> dict[str, Section]:
    sections: dict[str, Section] = {}
    for part in re.split(r"^## ", text, flags=re.MULTILINE)[1:]:
        heading, _, body = part.partition("\n")
        code, _, title = heading.strip().partition(" ")
        assert code not in sections, f"two sections for {code}"
        sections[code] = Section(code, title, body, _blocks(body))
    return sections


SECTIONS = parse_spec(SPEC.read_text(encoding="utf-8"))
REQUIRED = sorted(c for c in CODES if not c.startswith(("E4", "E5")))


def _params() -> list:
    """One parameter per section (a list: pytest 10 refuses a generator)."""
    return [pytest.param(code, id=code) for code in sorted(SECTIONS)]


def run_example(section: Section, directory: Path):
    """Write the example into ``directory`` and run its command: (diagnostics, sources)."""
    for block in section.blocks:
        (directory / block.name).parent.mkdir(parents=True, exist_ok=True)
        (directory / block.name).write_bytes(block.text.encode(block.encoding))
    if section.command == "import":
        return import_diagnostics(directory)
    limits = Limits()
    for block in section.blocks:
        if block.limit:
            name, _, value = block.limit.partition(":")
            limits = replace(limits, **{name: int(value)})
    result = verify.load(str(directory / section.blocks[0].name), limits=limits)
    if section.command == "check" or not result.ok:
        return list(result.diagnostics), result.sources
    try:
        model = result.system(None)
    except SelectionError as err:
        return [err.diagnostic], result.sources
    if section.command == "synth":
        return synth_diagnostics(section, result, model), result.sources
    holes = require_configured(model, section.command)
    if holes:
        return holes, result.sources
    if section.command == "export":
        return export_diagnostics(model), result.sources
    if section.command == "gen":
        diagnostics, files = gen_diagnostics(model, directory, section.blocks[0].target)
        return diagnostics, {**result.sources, **files}
    if section.command == "trace":
        return trace_diagnostics(section, directory, result, model), result.sources
    if section.command == "prove":
        from verify.prove import prove

        return list(prove(model).diagnostics), result.sources
    return list(timing.diagnostics_of(timing.analyze(model))), result.sources


def gen_diagnostics(model, directory: Path, name: str):
    """What `verify gen TARGET main.vfy -o out` reports for the example (its other blocks may lie in out/):
    (diagnostics, the files they show)."""
    from verify.commands.gen import (clashing_names, differing_semantics, refusals, uncovered_parts,
                                     unsupported_parts)
    from verify.gen import target
    from verify.gen.tree import plan

    module = target(name)
    unsupported = (unsupported_parts(module, name, model) + differing_semantics(module, name, model)
                   + clashing_names(module, model))
    if unsupported:
        return unsupported, {}
    out = str(directory / "out")
    refused, files = refusals(plan(module.generate(model), out, force=False), out)
    return refused + uncovered_parts(module, name, model), files


def trace_diagnostics(section: Section, directory: Path, result, model) -> list:
    """What `verify trace main.vfy TRACE...` reports, its traces the example's other files, or the trace
    of the repository its model block names (``trace=``: an LTTng trace, which no text block holds)."""
    from verify.core.diagnostics import DiagnosticSink
    from verify.trace.run import read_traces, trace_system

    stored = [str(ROOT / b.trace) for b in section.blocks if b.trace]
    if stored:
        from .test_trace import require_bindings

        require_bindings()
    sink = DiagnosticSink()
    recording = read_traces([str(directory / b.name) for b in section.blocks[1:]] + stored, sink)
    if recording is None:
        return sink.items
    return list(trace_system(model, result.project, recording).diagnostics)


def import_diagnostics(directory: Path):
    """What `verify import smartmdsd DIR` reports for the example's SmartMDSD files: (diagnostics, sources)."""
    from verify.core.diagnostics import DiagnosticSink
    from verify.interop.smartmdsd import import_dirs

    sink = DiagnosticSink()
    _, sources = import_dirs([str(directory)], None, sink)
    return sink.items, sources


def export_diagnostics(model):
    """What `verify export smartmdsd main.vfy -o out` reports."""
    from verify.core.diagnostics import DiagnosticSink
    from verify.interop.smartmdsd.export import export_system

    sink = DiagnosticSink()
    export_system(model, None, {}, sink)
    return sink.items


def synth_diagnostics(section: Section, result, model) -> list:
    """What `synth` reports for the example (its budget from the block's ``rlimit=N``)."""
    from verify.synth import TooManyCandidates, synthesize
    from verify.synth.driver import DEFAULT_RLIMIT

    rlimit = next((int(b.rlimit) for b in section.blocks if b.rlimit), DEFAULT_RLIMIT)
    try:
        return list(synthesize(result, model.name, rlimit=rlimit).diagnostics)
    except TooManyCandidates as err:
        return [err.diagnostic()]


# ------------------------------------------------------------------ the registry and the spec agree


def test_every_code_has_a_section():
    missing = [c for c in REQUIRED if c not in SECTIONS]
    assert not missing, f"codes without a section in specs/diagnostics.md: {missing}"


def test_every_section_is_a_registered_code_with_its_title():
    for code, section in SECTIONS.items():
        assert code in CODES, f"section for unknown code {code}"
        assert section.title == CODES[code].title, f"{code}: heading must be `## {code} {CODES[code].title}`"


def test_every_section_has_one_example():
    for code, section in SECTIONS.items():
        assert section.blocks, f"{code}: no ```vfy example"
        names = [b.name for b in section.blocks]
        assert len(set(names)) == len(names), f"{code}: two blocks for one file"
        assert section.body.strip().split("```")[0].strip(), f"{code}: no explanation before the example"


# ------------------------------------------------------------------ each example


def matches_golden(golden, text: str) -> None:
    """``text`` equals the golden file (rewritten instead with ``UPDATE_GOLDEN=1``)."""
    if UPDATE:
        golden.parent.mkdir(parents=True, exist_ok=True)
        golden.write_text(text, encoding="utf-8")
    else:
        assert golden.exists(), f"no golden file {golden}: run with UPDATE_GOLDEN=1 and read it"
        assert text == golden.read_text(encoding="utf-8")


@pytest.mark.parametrize("code", _params())
def test_example_reports_its_code(code, tmp_path):
    section = SECTIONS[code]
    diagnostics, sources = run_example(section, tmp_path)
    codes = [d.code for d in diagnostics]
    assert code in codes, f"{code}: the example reports {codes}"

    prefix = str(tmp_path) + os.sep
    text = render_all_text(diagnostics, sources).replace(prefix, "") + "\n"
    for word in FORBIDDEN:
        assert word not in text, f"{code}: the message shows `{word}`:\n{text}"
    assert str(tmp_path) not in text
    matches_golden(GOLDEN / f"{code}.txt", text)


@pytest.mark.parametrize("code", REQUIRED)
def test_explain_prints_the_example(code, capsys):
    section = SECTIONS.get(code)
    if section is None:
        pytest.fail(f"{code} has no section in specs/diagnostics.md")
    assert main(["explain", code]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"## {code} {CODES[code].title}\n")
    for block in section.blocks:
        assert block.text in out


# ------------------------------------------------------------------ E313 beyond its example

_HOLE = """component C {{
  task T {{
    wcet 1 ms
    activation {constraint}
  }}
}}
system S {{
  core cpu
  instance c : C on cpu {{
    task T priority 1 timer {hole}
  }}
}}
"""


@pytest.mark.parametrize("constraint, hole, reported", [
    ("1 Hz .. 10 Hz", "? in 10 ms .. 100 ms", False),  # 100 ms is allowed
    ("1 Hz .. 10 Hz", "? in 20 Hz .. 50 Hz", True),  # a frequency range, all too fast
    ("max 10 Hz", "? in 10 ms .. 50 ms", True),
    ("min 30 Hz", "? in 40 ms .. 50 ms", True),
    ("min 30 Hz", "? in 20 ms .. 50 ms", False),
    ("1 Hz .. 10 Hz", "? in 50 ms .. 105 ms step 60 ms", True),  # the grid 50, 110 misses 100 .. 105
    ("1 Hz .. 10 Hz", "? in 40 ms .. 100 ms step 30 ms", False),  # 40, 70, 100: 100 ms is allowed
    ("1 Hz .. 10 Hz", "?", False),
])
def test_a_period_hole_needs_a_candidate(constraint, hole, reported):
    result = verify.load_text(_HOLE.format(constraint=constraint, hole=hole), "m.vfy")
    assert [d.code for d in result.diagnostics] == (["E313"] if reported else [])


# ------------------------------------------------------------------ E210 beyond its example

_RING = """component Filter {{
  in input : Pose
  out output : Pose
  task FilterTask {{
    reads input
    produces output
    wcet 1 ms
  }}
}}
system Robot {{
  core cpu
{instances}
{connections}
}}
"""


def _ring(declared: list[str], edges: list[tuple[str, str]]) -> str:
    instances = "\n".join(f"  instance {n} : Filter on cpu {{\n    task FilterTask priority 1 trigger input\n  }}"
                          for n in declared)
    connections = "\n".join(f"  connect {a}.output -> {b}.input" for a, b in edges)
    return _RING.format(instances=instances, connections=connections)


def test_a_trigger_cycle_is_printed_in_the_direction_of_its_triggers():
    """A ring f0 → f1 → f2 → f3 → f0 whose instances are declared in another order: the message shows
    the ring as it is, from the first task in source order (not the tasks sorted by declaration)."""
    ring = [("f0", "f1"), ("f1", "f2"), ("f2", "f3"), ("f3", "f0")]
    result = verify.load_text(_ring(["f0", "f3", "f1", "f2"], ring), "m.vfy")
    (d,) = result.diagnostics
    assert d.code == "E210"
    assert d.message.endswith("`f0.FilterTask` -> `f1.FilterTask` -> `f2.FilterTask` -> `f3.FilterTask` "
                              "-> `f0.FilterTask`")
    assert d.span.line == 13  # the trigger of f0, the first declared
    assert sorted(lb.message for lb in d.secondary) == ["`f1.FilterTask`", "`f2.FilterTask`", "`f3.FilterTask`"]
    # started elsewhere in source order, the same ring is printed from that task
    result = verify.load_text(_ring(["f2", "f0", "f3", "f1"], ring), "m.vfy")
    (d,) = result.diagnostics
    assert d.message.endswith("`f2.FilterTask` -> `f3.FilterTask` -> `f0.FilterTask` -> `f1.FilterTask` "
                              "-> `f2.FilterTask`")


_TWO_RINGS = """component Node {
  in a : Pose
  in b : Pose
  in both = a & b
  out x : Pose
  out y : Pose
  task T {
    reads a optional
    reads b optional
    produces x, y
    wcet 1 ms
  }
}
system Robot {
  core cpu
  instance f0 : Node on cpu { task T priority 1 trigger a }
  instance f1 : Node on cpu { task T priority 1 trigger both }
  instance f2 : Node on cpu { task T priority 1 trigger a }
  instance f3 : Node on cpu { task T priority 1 trigger a }
  connect f0.x -> f1.a
  connect f1.x -> f2.a
  connect f2.x -> f0.a
  connect f1.y -> f3.a
  connect f3.x -> f1.b
}
"""


def test_a_trigger_cycle_with_a_chord_names_every_member():
    """Two rings f0 → f1 → f2 → f0 and f1 → f3 → f1 form one strongly connected component: a real,
    shortest cycle through f0 is printed, the task outside it named in a note, every member labelled."""
    (d,) = verify.load_text(_TWO_RINGS, "m.vfy").diagnostics
    assert d.code == "E210"
    assert d.message.endswith("`f0.T` -> `f1.T` -> `f2.T` -> `f0.T`")
    assert d.notes == ("in the same cycle of triggers: `f3.T`",)
    assert sorted(lb.message for lb in d.secondary) == ["`f1.T`", "`f2.T`", "`f3.T`"]
    self_loop = verify.load_text(_ring(["f0"], [("f0", "f0")]), "m.vfy")
    (d,) = self_loop.diagnostics
    assert d.code == "E210" and d.message.endswith("`f0.FilterTask` -> `f0.FilterTask`")


# ------------------------------------------------------------------ E212 on chain specs

_CHAIN_SPECS = """component A {{
  out o : T
  task W {{
    produces o
    wcet 1 ms
  }}
}}
system S {{
  core c
  instance a : A on c {{
    task W priority 1 timer 10 ms
  }}
  chain k: a.o {{
{specs}
  }}
}}
"""


@pytest.mark.parametrize("kind", ["reaction_time", "data_age", "jitter"])
def test_a_repeated_chain_spec_is_e212_not_last_wins(kind):
    specs = f"    {kind} <= 1 ms\n    data_age <= 9 ms\n    {kind} <= 2 ms" if kind != "data_age" else \
        "    data_age <= 1 ms\n    jitter <= 9 ms\n    data_age <= 2 ms"
    result = verify.load_text(_CHAIN_SPECS.format(specs=specs), "m.vfy")
    (d,) = result.diagnostics
    assert d.code == "E212" and f"`{kind}`" in d.message and "chain `k`" in d.message
    assert (d.span.line, d.span.column) == (16, 5)  # the second one
    (first,) = d.secondary
    assert (first.span.line, first.message) == (14, "first given here")
    assert not result.ok and result.models == {}
    once = verify.load_text(_CHAIN_SPECS.format(specs="    jitter <= 1 ms\n    data_age <= 2 ms"), "m.vfy")
    assert once.ok


# ------------------------------------------------------------------ rule variants beyond the section examples

_PIPELINE = """component Laser {{
  out scan : LaserScan
  task LaserTask {{
    produces scan
    wcet 2 ms
  }}
}}

component Fusion {{
  in scan : LaserScan
  in odom : LaserScan
  task FuseTask {{
    reads scan
    reads odom optional
    wcet 5 ms{constraint}
  }}
}}

system Robot {{
  core cpu
  instance laser : Laser on cpu {{
    task LaserTask priority 2 timer 25 ms
  }}
  instance fusion : Fusion on cpu {{
    task FuseTask priority 1 {binding}
  }}
  connect laser.scan -> fusion.scan
  connect laser.scan -> fusion.odom
}}
"""

#: (name, code, source, words the message must contain): the variants of issue 2 item 5 that the
#: one example per section does not show; each has a golden file tests/golden/diagnostics/variants/NAME.txt
VARIANTS = [
    ("E304-every-0", "E304", _PIPELINE.format(constraint="", binding="trigger scan every 0"),
     ("at least 1", "found 0")),
    ("E304-fraction", "E304", _PIPELINE.format(constraint="", binding="trigger scan every 1/2"),
     ("found 0.5",)),
    ("E204-two-data-triggers", "E204", _PIPELINE.format(constraint="", binding="trigger scan trigger odom"),
     ("more than one data trigger",)),
    ("E302-time-for-a-frequency", "E302",
     _PIPELINE.format(constraint="\n    activation max 100 ms", binding="trigger scan"),
     ("must be a frequency", "the time 100 ms")),
    ("E305-propagated-rate", "E305",
     _PIPELINE.format(constraint="\n    activation 1 Hz .. 10 Hz", binding="trigger scan every 2"),
     ("20 Hz (40 Hz / 2)", "above its maximum activation rate 10 Hz")),
    ("E306-propagated-rate", "E306",
     _PIPELINE.format(constraint="\n    activation 10 Hz fixed", binding="trigger scan every 2"),
     ("20 Hz (40 Hz / 2)",)),
]


@pytest.mark.parametrize("name, code, source, words", VARIANTS, ids=[v[0] for v in VARIANTS])
def test_rule_variant(name, code, source, words, tmp_path):
    path = tmp_path / "main.vfy"
    path.write_text(source, encoding="utf-8")
    result = verify.load(str(path))
    assert [d.code for d in result.diagnostics] == [code], [d.message for d in result.diagnostics]
    (d,) = result.diagnostics
    for word in words:
        assert word in d.message, d.message
    text = render_all_text(list(result.diagnostics), result.sources).replace(str(tmp_path) + os.sep, "") + "\n"
    matches_golden(GOLDEN / "variants" / f"{name}.txt", text)
