"""Whole-process stages: what a user waits for when they type a command (issue 19's start-up goals).

Each run starts a fresh interpreter as a user's shell does — the installed ``verify`` script when it
is beside this interpreter or on ``PATH``, else ``python -m verify`` — and waits for it to exit:
interpreter start-up, imports, reading the file and the work itself. ``startup-python`` is the
anchor every Python tool pays (``python -c pass``). Generated inputs are written once, at the first
run, to ``benchmarks/out/``; the parser's table cache (``~/.cache/verify-timing``) is warm after the
first run, as it is on a user's machine.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = Path(__file__).resolve().parent / "out"
NAVIGATION = ROOT / "examples" / "navigation" / "navigation.vfy"


def verify_command() -> list[str]:
    """The command a user types: the ``verify`` script installed with this interpreter, if any."""
    script = Path(sys.executable).parent / "verify"
    if script.exists():
        return [str(script)]
    found = shutil.which("verify")
    return [found] if found else [sys.executable, "-m", "verify"]


def run_process(argv: list[str], expect: tuple[int, ...] = (0,)) -> dict:
    done = subprocess.run(argv, capture_output=True, text=True, env={**os.environ, "PYTHONHASHSEED": "0"},
                          check=False, timeout=120)
    if done.returncode not in expect:
        raise RuntimeError(f"{' '.join(argv[-3:])} exited {done.returncode}: {done.stderr.strip()[:200]}")
    return {"exit": done.returncode}


def navigation_text(n_tasks: int, seed: int, **_: object) -> str:
    """The navigation example, whatever the size (its own task count is the stage's size)."""
    return NAVIGATION.read_text(encoding="utf-8")


def register(stage: Callable[..., Callable], error: type[Exception]) -> None:
    """Register the start-up stages with the runner's ``stage`` decorator; ``error`` is its
    ``BenchmarkError`` (a failed command becomes an error row)."""
    written: dict[str, Path] = {}

    def file_of(inst) -> Path:  # (written at the first run; a few milliseconds at most)
        if inst.n_tasks == 1:
            return NAVIGATION  # (in place: it imports its components)
        if inst.name not in written:
            OUT.mkdir(parents=True, exist_ok=True)
            path = OUT / f"startup-{inst.name}"
            path.write_text(inst.text, encoding="utf-8")
            written[inst.name] = path
        return written[inst.name]

    def run(argv: list[str], expect: tuple[int, ...] = (0,)) -> dict:
        try:
            return run_process(argv, expect)
        except (RuntimeError, subprocess.TimeoutExpired) as err:
            raise error(str(err), {}) from None

    @stage("startup-python", "whole process: `python -c pass`, the interpreter start-up any Python tool pays "
           "(the anchor of the start-up stages)", sizes=(1,), quick_sizes=(1,), generator=navigation_text)
    def startup_python(inst) -> dict:
        return run([sys.executable, "-c", "pass"])

    @stage("startup-help", "whole process: `verify --help`", sizes=(1,), quick_sizes=(1,), generator=navigation_text)
    def startup_help(inst) -> dict:
        return run(verify_command() + ["--help"])

    @stage("startup-check", "whole process: `verify check` on the navigation example (the size is ignored)",
           sizes=(1,), quick_sizes=(1,), generator=navigation_text)
    def startup_check(inst) -> dict:
        return run(verify_command() + ["check", str(file_of(inst))])

    @stage("startup-analyze", "whole process: `verify analyze` on the navigation example (the size is ignored)",
           sizes=(1,), quick_sizes=(1,), generator=navigation_text)
    def startup_analyze(inst) -> dict:
        return run(verify_command() + ["analyze", str(file_of(inst))])

    @stage("startup-analyze-waters", "whole process: `verify analyze` on a generated WATERS system (exit 0, or 3 "
           "when a spec is not proved by its bound)", sizes=(100,), quick_sizes=(10,))
    def startup_analyze_waters(inst) -> dict:
        return run(verify_command() + ["analyze", str(file_of(inst))], expect=(0, 3))
