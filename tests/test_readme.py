"""Every command of the README, and of the manual's pages in docs/, runs as written, from a temporary copy
of the clone.

The convention, for README.md and docs/**/*.md:

- A fenced block marked ```` ```sh ```` is runnable: each of its lines (a line ending in ``\\`` goes on
  with the next) runs on its own, with ``sh -c``, in the root of the copy, with the installed ``verify``,
  ``synth`` and ``prove`` first on ``PATH``. It must exit 0, or N when the line says ``# exit N``.
- Blocks in any other language (``` ``` ```` for the modelling language, ```` ```yaml ````, …) are not run.
- A ```` ```sh ```` block right after a line ``<!-- readme-test: skip (REASON) -->`` is not run: for
  commands that need a ROS install, take minutes, or are the test suite itself.
- Install steps (``python3 -m pip install …``, ``scripts/install-tools``) in a ``&&`` list are left out and
  the rest of the list runs: CI's own run (``.ci/run``) installs, the way set-up 2 says.

Without Graphviz the test skips (``verify graph`` lays out the SVG), but not under ``CI=true``.

The commands of one document run in order, as a reader would type them; each document starts without
``out/``. They must leave the copy's root as it was but for ``out/`` (git-ignored), and change no file
of the copy: what a documented command writes goes to ``out/`` or a temporary directory.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from .conftest import ROOT, in_ci

README = ROOT / "README.md"
#: the documents whose commands run: the README first, then the manual's pages
DOCUMENTS = [README, *sorted((ROOT / "docs").rglob("*.md"))]
SKIP = re.compile(r"^<!--\s*readme-test:\s*skip\s*\((.+)\)\s*-->$")
EXPECTED_EXIT = re.compile(r"#\s*exit (\d+)\b")
INSTALL_STEPS = ("python3 -m pip install ", "scripts/install-tools")
#: what the commands may add to the root of the copy
OUTPUT_DIR = "out"


@dataclass(frozen=True)
class Block:
    language: str
    line: int  # 1-based line of the opening fence
    lines: tuple[str, ...]
    skip_reason: str | None


@dataclass(frozen=True)
class Command:
    text: str  # as the document writes it
    line: int
    expected_exit: int

    def runnable(self) -> str:
        """The command without its install steps ("" when it is nothing but installs)."""
        steps = [s for s in self.text.split(" && ") if not s.strip().startswith(INSTALL_STEPS)]
        return " && ".join(steps)


def fenced_blocks(text: str) -> list[Block]:
    blocks: list[Block] = []
    lines = text.splitlines()
    i = 0
    previous = ""
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            language = line[3:].strip().split(" ")[0]
            end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
            marker = SKIP.match(previous.strip())
            blocks.append(Block(language, i + 1, tuple(lines[i + 1:end]), marker.group(1) if marker else None))
            i = end + 1
            previous = ""
            continue
        if line.strip():
            previous = line
        i += 1
    return blocks


def commands(block: Block) -> list[Command]:
    found: list[Command] = []
    pending = ""
    start = 0
    for offset, line in enumerate(block.lines, start=block.line + 1):
        if not pending:
            start = offset
        pending += line
        if line.endswith("\\"):
            pending = pending[:-1] + " "
            continue
        text = pending.strip()
        pending = ""
        if text and not text.startswith("#"):
            expected = EXPECTED_EXIT.search(text)
            found.append(Command(text, start, int(expected.group(1)) if expected else 0))
    return found


def runnable_commands(text: str) -> list[Command]:
    return [c for b in fenced_blocks(text) if b.language == "sh" and b.skip_reason is None
            for c in commands(b) if c.runnable()]


def test_the_conventions_are_read_as_stated():
    text = "\n".join([
        "```sh", "verify check a.vfy", "prove b.vfy   # exit 1", "verify graph a.vfy \\", "    -o out/a.svg", "```",
        "<!-- readme-test: skip (needs ROS 1) -->", "```sh", "roscore &", "```",
        "```", "component C {}", "```",
        "```sh", "python3 -m pip install -q . && verify analyze a.vfy", "scripts/install-tools", "```",
    ])
    found = runnable_commands(text)
    assert [(c.runnable(), c.expected_exit, c.line) for c in found] == [
        ("verify check a.vfy", 0, 2), ("prove b.vfy   # exit 1", 1, 3), ("verify graph a.vfy      -o out/a.svg", 0, 4),
        ("verify analyze a.vfy", 0, 15)]
    assert [b.skip_reason for b in fenced_blocks(text)] == [None, "needs ROS 1", None, None]


def test_set_up_2_is_what_ci_runs():
    """Set-up 2 is skipped here (it is the suite itself); `.ci/run` runs exactly that line."""
    blocks = fenced_blocks(README.read_text(encoding="utf-8"))
    set_up_2 = [b for b in blocks if b.skip_reason is not None and any("python3 -m pytest" in x for x in b.lines)]
    assert len(set_up_2) == 1 and len(set_up_2[0].lines) == 1
    line = set_up_2[0].lines[0]
    assert line == "scripts/install-tools && python3 -m pip install -q -e '.[test]' && python3 -m pytest"
    assert line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()


def writes(command: str) -> bool:
    """Whether a command writes a file (``-o``, ``mkdir``, a redirection): such a one is run every time."""
    words = command.split()
    return bool({"-o", "--output", "--in-place", "--trace-svg", ">", ">>"} & set(words)) or words[:1] == ["mkdir"]


def copy_of_the_clone(destination: Path) -> Path:
    """The files git tracks (and new ones it would), as they are in the working tree."""
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                            capture_output=True, check=True).stdout.decode().split("\0")
    for name in filter(None, listed):
        source = ROOT / name
        if source.is_file():
            target = destination / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
    return destination


def digests(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in root.rglob("*") if p.is_file() and OUTPUT_DIR not in p.relative_to(root).parts[:1]}


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(), reason="needs a git clone")
def test_every_documented_command_runs_in_a_copy_of_the_clone(tmp_path):
    if shutil.which("dot") is None and not in_ci():  # `verify graph -o FILE.svg` lays out with Graphviz
        pytest.skip("Graphviz is not installed (scripts/install-tools)")
    found = [(path, c) for path in DOCUMENTS for c in runnable_commands(path.read_text(encoding="utf-8"))]
    assert any(path == README and c.runnable() == "verify analyze examples/navigation/navigation.vfy"
               for path, c in found)  # set-up 1
    copy = copy_of_the_clone(tmp_path / "clone")
    before_root, before = sorted(os.listdir(copy)), digests(copy)
    env = dict(os.environ, PATH=os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")]),
               NO_COLOR="1", XDG_CACHE_HOME=str(tmp_path / "cache"))
    failures = []
    session = None
    passed: set[tuple[str, int]] = set()
    for path, command in found:
        if path != session:  # each document starts afresh: what one wrote to out/ does not stay for the next
            shutil.rmtree(copy / OUTPUT_DIR, ignore_errors=True)
            session = path
        key = (command.runnable().split("#")[0].strip(), command.expected_exit)
        if key in passed:  # the same command, writing nothing, passed for an earlier document
            continue
        done = subprocess.run(["sh", "-c", command.runnable()], cwd=copy, env=env, capture_output=True, text=True,
                              timeout=300, stdin=subprocess.DEVNULL)
        if done.returncode == command.expected_exit and not writes(key[0]):
            passed.add(key)
        if done.returncode != command.expected_exit:
            failures.append(f"{path.relative_to(ROOT)}:{command.line}: `{command.text}` exited {done.returncode}, "
                            f"not {command.expected_exit}\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    assert not failures, "\n\n".join(failures)
    added = sorted(set(os.listdir(copy)) - set(before_root))
    assert added in ([], [OUTPUT_DIR]), f"documented commands left files in the root: {added}"
    assert f"/{OUTPUT_DIR}/" in (ROOT / ".gitignore").read_text(encoding="utf-8").splitlines()
    assert digests(copy) == before, "a documented command changed a file of the clone"
