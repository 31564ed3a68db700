"""Whole-process stages: what a user waits for when they type a command (issue 19's start-up goals).

Each run starts a fresh interpreter as a user's shell does — the installed ``verify`` script when it
is beside this interpreter or on ``PATH``, else ``python -m verify`` — and waits for it to exit:
interpreter start-up, imports, reading the file and the work itself. ``startup-python`` is the
anchor every Python tool pays (``python -c pass``). Generated inputs are written once, at the first
run, to ``benchmarks/out/``; the parser's table cache (``~/.cache/verify-timing``) is warm after the
first run, as it is on a user's machine.

Parameter ``bytecode``: ``cached`` (default) runs each interpreter as an installed tool runs, with the
compiled bytecode of every module it imports kept between runs (``pip install`` compiles it; Python writes
it at the first import otherwise), in a cache of its own under ``benchmarks/out/pycache``
(``PYTHONPYCACHEPREFIX``: the source tree stays clean; an untimed run of each command fills it before the
stage is measured), whatever ``PYTHONDONTWRITEBYTECODE`` says; ``off`` runs them with the caller's
environment as it is, where ``PYTHONDONTWRITEBYTECODE=1`` makes every run compile the sources it imports
again (the first measurement of issue 38 was made so).
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


BYTECODE = ("cached", "off")
PYCACHE = OUT / "pycache"


def environment(bytecode: str = "cached") -> dict[str, str]:
    """The environment of a run (see ``bytecode`` in the module docstring)."""
    if bytecode not in BYTECODE:
        raise ValueError(f"bytecode must be one of {BYTECODE}, not {bytecode!r}")
    env = {**os.environ, "PYTHONHASHSEED": "0"}
    if bytecode == "cached":
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(PYCACHE)
    return env


def run_process(argv: list[str], expect: tuple[int, ...] = (0,), bytecode: str = "cached") -> dict:
    done = subprocess.run(argv, capture_output=True, text=True, env=environment(bytecode), check=False, timeout=120)
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

    def run(argv: list[str], bytecode: str, expect: tuple[int, ...] = (0,)) -> dict:
        try:
            return run_process(argv, expect, bytecode)
        except (RuntimeError, subprocess.TimeoutExpired, ValueError) as err:
            raise error(str(err), {}) from None

    def warm(*args: str) -> Callable[[], object]:
        """An untimed run of ``verify ARGS`` (or of ``python -c pass`` without) that fills the bytecode cache."""
        argv = verify_command() + [str(a) for a in args] if args else [sys.executable, "-c", "pass"]
        return lambda: subprocess.run(argv, capture_output=True, env=environment(), check=False, timeout=120)

    options = {"params": {"bytecode": "cached"}, "sizes": (1,), "quick_sizes": (1,), "generator": navigation_text}

    @stage("startup-python", "whole process: `python -c pass`, the interpreter start-up any Python tool pays "
           "(the anchor of the start-up stages)", setup=warm(), **options)
    def startup_python(inst, bytecode: str) -> dict:
        return run([sys.executable, "-c", "pass"], bytecode)

    @stage("startup-help", "whole process: `verify --help`", setup=warm("--help"), **options)
    def startup_help(inst, bytecode: str) -> dict:
        return run(verify_command() + ["--help"], bytecode)

    @stage("startup-check", "whole process: `verify check` on the navigation example (the size is ignored)",
           setup=warm("check", NAVIGATION), **options)
    def startup_check(inst, bytecode: str) -> dict:
        return run(verify_command() + ["check", str(file_of(inst))], bytecode)

    @stage("startup-analyze", "whole process: `verify analyze` on the navigation example (the size is ignored)",
           setup=warm("analyze", NAVIGATION), **options)
    def startup_analyze(inst, bytecode: str) -> dict:
        return run(verify_command() + ["analyze", str(file_of(inst))], bytecode)

    @stage("startup-analyze-waters", "whole process: `verify analyze` on a generated WATERS system (exit 0, or 3 "
           "when a spec is not proved by its bound)", params={"bytecode": "cached"}, sizes=(100,), quick_sizes=(10,),
           setup=warm("analyze", NAVIGATION))
    def startup_analyze_waters(inst, bytecode: str) -> dict:
        return run(verify_command() + ["analyze", str(file_of(inst))], bytecode, expect=(0, 3))
