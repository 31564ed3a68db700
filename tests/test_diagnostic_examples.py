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
from dataclasses import dataclass
from pathlib import Path

import pytest

import verify
from verify import timing
from verify.api import SelectionError, require_configured
from verify.cli import main
from verify.codes import CODES
from verify.render import render_all_text

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


@dataclass(frozen=True)
class Section:
    code: str
    title: str
    body: str
    blocks: tuple[Block, ...]

    @property
    def command(self) -> str:
        for command in ("synth", "prove", "analyze"):
            if any(b.command == command for b in self.blocks):
                return command
        return "check"


_FENCE = re.compile(r"^```vfy([^\n]*)\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)


def _blocks(body: str) -> tuple[Block, ...]:
    blocks = []
    for match in _FENCE.finditer(body):
        attrs = dict(item.split("=", 1) for item in match.group(1).split())
        blocks.append(Block(attrs.get("file", "main.vfy"), match.group(2), attrs.get("encoding", "utf-8"),
                            attrs.get("command", "check"), attrs.get("rlimit")))
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


def _params():
    for code in sorted(SECTIONS):
        yield pytest.param(code, id=code)


def run_example(section: Section, directory: Path):
    """Write the example into ``directory`` and run its command: (diagnostics, sources)."""
    for block in section.blocks:
        (directory / block.name).write_bytes(block.text.encode(block.encoding))
    result = verify.load(str(directory / section.blocks[0].name))
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
    if section.command == "prove":
        from verify.prove import prove

        return list(prove(model).diagnostics), result.sources
    return list(timing.diagnostics_of(timing.analyze(model))), result.sources


def synth_diagnostics(section: Section, result, model) -> list:
    """What `synth` reports for the example (its budget from the block's ``rlimit=N``)."""
    from verify.synth import TooManyCandidates, synthesize
    from verify.synth.command import too_many
    from verify.synth.driver import DEFAULT_RLIMIT

    rlimit = next((int(b.rlimit) for b in section.blocks if b.rlimit), DEFAULT_RLIMIT)
    try:
        return list(synthesize(result, model.name, rlimit=rlimit).diagnostics)
    except TooManyCandidates as err:
        return [too_many(err)]


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
    golden = GOLDEN / f"{code}.txt"
    if UPDATE:
        golden.parent.mkdir(parents=True, exist_ok=True)
        golden.write_text(text, encoding="utf-8")
    else:
        assert golden.exists(), f"no golden file {golden}: run with UPDATE_GOLDEN=1 and read it"
        assert text == golden.read_text(encoding="utf-8")


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
