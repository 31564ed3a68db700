"""``synth`` writes back only the holes: every byte outside the filled holes stays as the user wrote it
(comments, layout, line endings); ``--canonical`` formats the whole file as ``verify fmt``."""
from __future__ import annotations

import difflib
import random
import re
import shutil

import pytest

import verify
from verify.cli import main
from verify.synth import synthesize
from verify.synth.writeback import completed_text

from .conftest import EXAMPLES

NAV = EXAMPLES / "navigation"


@pytest.fixture(scope="module")
def choices():
    loaded = verify.load(str(NAV / "navigation-holes.vfy"))
    result = synthesize(loaded)
    assert result.status == "sat"
    return result.system, result.choices


def _hole_lines(loaded) -> set[int]:
    """The lines of the root file that a hole (with its range) covers."""
    lines: set[int] = set()
    for sy in loaded.project.root_module.systems:
        for inst in sy.instances:
            for b in inst.bindings:
                for act in b.activations:
                    part = getattr(act, "period", None) or getattr(act, "prescaler", None) or act
                    span = part.span if "Hole" in type(part).__name__ else act.span
                    if "Hole" in type(part).__name__ or type(act).__name__ == "UnknownActivation":
                        lines.update(range(span.line, span.end_line + 1))
    return lines


def _changed_lines(before: str, after: str) -> set[int]:
    a, b = before.split("\n"), after.split("\n")
    changed: set[int] = set()
    for tag, i1, i2, _, _ in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if tag != "equal":
            changed.update(range(i1 + 1, max(i2, i1 + 1) + 1))
    return changed


def test_the_diff_of_the_example_changes_only_the_lines_with_a_hole(capsys):
    assert main(["synth", str(NAV / "navigation-holes.vfy"), "--diff"]) == 0
    diff = capsys.readouterr().out
    removed = [ln[1:] for ln in diff.splitlines() if ln.startswith("-") and not ln.startswith("---")]
    added = [ln[1:] for ln in diff.splitlines() if ln.startswith("+") and not ln.startswith("+++")]
    assert len(removed) == len(added) == 3 and all("?" in ln for ln in removed)
    assert all("?" not in ln for ln in added)
    assert "    task PlannerTask priority 3 trigger map" in added


def _perturbed(text: str, rng: random.Random) -> str:
    """``text`` with extra blanks, line breaks and comments between its tokens (never inside one)."""
    tokens = re.findall(r'//[^\n]*|"[^"\n]*"|[A-Za-z_][A-Za-z0-9_]*|[0-9][0-9./]*|->|\.\.|<=|\S|\s+', text)
    out = []
    for tok in tokens:
        out.append(tok)
        if tok.isspace() or tok.startswith("//"):
            continue
        roll = rng.random()
        if roll < 0.08:
            out.append(" " * rng.randint(1, 3))
        elif roll < 0.12:
            out.append(f" /* c{rng.randint(0, 99)} */ ")
        elif roll < 0.14:
            out.append("\n" + " " * rng.randint(0, 6))
    return "".join(out)


@pytest.mark.parametrize("seed", range(8))
def test_every_byte_outside_the_holes_is_kept(seed, choices, tmp_path):
    system, chosen = choices
    shutil.copy(NAV / "components.vfy", tmp_path / "components.vfy")
    text = _perturbed((NAV / "navigation-holes.vfy").read_text(), random.Random(seed))
    if seed % 2:
        text = text.replace("\n", "\r\n")
    if seed % 3 == 0:
        text = "\ufeff" + text
    path = tmp_path / "holes.vfy"
    path.write_bytes(text.encode("utf-8"))
    loaded = verify.load(str(path))
    assert loaded.ok, loaded.diagnostics
    out = completed_text(loaded, system, chosen)
    assert "?" not in out
    assert _changed_lines(text, out) <= _hole_lines(loaded), (text, out)
    for comment in re.findall(r"/\* c\d+ \*/|//[^\n]*", text):
        assert out.count(comment) == text.count(comment)
    if seed % 2:
        assert out.count("\n") == out.count("\r\n")  # (no bare line feed in a file of CRLF lines)
    assert out.startswith("\ufeff") == text.startswith("\ufeff")
    reloaded = verify.load_text(out.lstrip("\ufeff"), str(path))
    assert reloaded.project.modules[0] == verify.load_text(completed_text(loaded, system, chosen, canonical=True),
                                                            str(path)).project.modules[0]


def test_canonical_is_the_formatted_file(tmp_path, capsys):
    shutil.copy(NAV / "components.vfy", tmp_path / "components.vfy")
    path = tmp_path / "holes.vfy"
    path.write_text(_perturbed((NAV / "navigation-holes.vfy").read_text(), random.Random(3)))
    out = tmp_path / "done.vfy"
    assert main(["synth", str(path), "-o", str(out), "--canonical"]) == 0
    capsys.readouterr()
    assert main(["fmt", str(out), "--check"]) == 0
    minimal = tmp_path / "minimal.vfy"
    assert main(["synth", str(path), "-o", str(minimal)]) == 0
    assert main(["fmt", str(minimal), "--check"]) == 1  # (the user's layout is kept)


def _project(tmp_path):
    """A copy of the navigation example in ``tmp_path/models`` (the holes file imports its components)."""
    models = tmp_path / "models"
    models.mkdir()
    shutil.copy(NAV / "components.vfy", models / "components.vfy")
    shutil.copy(NAV / "navigation-holes.vfy", models / "holes.vfy")
    return models


def test_output_elsewhere_names_the_same_imported_files(tmp_path, capsys, monkeypatch):
    """``synth examples/navigation/navigation-holes.vfy -o configured.vfy`` from the repository root
    (docs/guide/ros.md writes to ``out/`` the same way): the written file imports the components from
    where it is, and nothing else moves."""
    models = _project(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main(["synth", "models/holes.vfy", "-o", "configured.vfy"]) == 0
    capsys.readouterr()
    written = (tmp_path / "configured.vfy").read_text()
    assert 'import "models/components.vfy"' in written
    changed = _changed_lines((models / "holes.vfy").read_text(), written)
    loaded = verify.load(str(models / "holes.vfy"))
    import_line = loaded.project.root_module.imports[0].span.line
    assert changed <= _hole_lines(loaded) | {import_line} and import_line in changed
    assert main(["check", "configured.vfy"]) == 0
    assert main(["prove", "configured.vfy"]) == 0
    # written into a subdirectory, the import climbs back out: inside a root given for both
    (tmp_path / "models" / "out").mkdir()
    assert main(["synth", "models/holes.vfy", "-o", "models/out/done.vfy", "--root", "models"]) == 0
    assert 'import "../components.vfy"' in (tmp_path / "models" / "out" / "done.vfy").read_text()
    assert main(["check", "models/out/done.vfy", "--root", "models"]) == 0
    # next to the input, the import is kept byte for byte
    assert main(["synth", "models/holes.vfy", "-o", "models/next.vfy"]) == 0
    assert 'import "components.vfy"' in (models / "next.vfy").read_text()


def test_output_whose_imports_would_leave_its_root_is_refused(tmp_path, capsys):
    """Written where its imports would lead outside the output's own root, nothing is written: one
    located error at the import (not its follow-on unknown names), exit 2."""
    models = _project(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = elsewhere / "configured.vfy"
    assert main(["synth", str(models / "holes.vfy"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert not out.exists()
    assert "error[E006]" in err and "../models/components.vfy" in err and "nothing was written" in err
    assert "E101" not in err and err.count("error[") == 1
    # a root that holds both makes it loadable: then it is written, and loads with that root
    assert main(["synth", str(models / "holes.vfy"), "-o", str(out), "--root", str(tmp_path)]) == 0
    assert main(["check", str(out), "--root", str(tmp_path)]) == 0
