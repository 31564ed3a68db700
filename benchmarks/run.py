"""The benchmark runner: time each stage on generated systems of several sizes.

    python -m benchmarks                                  # every available stage, default sizes
    python -m benchmarks --sizes 10,100,1000,10000 --repeat 3 --stages parse+check
    python -m benchmarks --quick                          # tiny sizes, one repetition (smoke test)

For each (stage, size) the runner generates one system (``benchmarks.generate``, untimed), prepares
what the stage needs (untimed: e.g. the loaded model for ``analyze``), then runs the stage ``--repeat``
times for wall time (``time.perf_counter``, garbage collector on, as a user would run it) and as many
times again under ``tracemalloc`` for the peak memory the stage allocates (tracing slows a run down, so
the two are never mixed). It prints a Markdown table (median and min–max of both) and writes JSON to
``benchmarks/out/results.json`` (or ``--out``).

Stages live in the registry ``STAGES`` (name -> callable taking an :class:`Instance`); register one with
``@stage(...)``. Implemented:

- ``parse+check``: ``verify.load_text`` on the text (parse, resolve, validate, build the model, chain
  checks). The system must load without a single diagnostic.
- ``analyze``: ``verify.timing.analyze`` on the loaded model (registered only when it is importable).

Extension points — planned stages, not implemented yet (add each with ``@stage`` once the feature
exists; a stage must measure real work, never a stand-in):

- ``prove-bound``: proof of every spec by the analytic bound (target: 10,000 tasks / 2,000 chains
  < 2 s including parsing — measure it together with ``parse+check``);
- ``prove-exact``: the exact worst case of a chain by exploring its hyperperiod (target: a 10-task
  chain with a hyperperiod of up to 10,000 jobs < 2 s);
- ``synth-feasibility``: any assignment of the holes that meets every spec (target: 1,000 tasks and
  200 chains < 2 s; instances with ``hole_share`` > 0);
- ``synth-optimum``: a proven optimal assignment (target: 500 tasks / 100 chains < 10 s);
- ``unsat-core``: the minimal set of conflicting specs and constraints of an infeasible system
  (target: 500 tasks < 5 s; instances with ``infeasible=True``);
- baselines for the synthesis stages: ``baseline-brute-force`` and ``baseline-random-search`` over
  the hole candidates, and ``baseline-z3-direct`` (the whole problem handed to Z3 without the
  analytic pruning).

A stage that needs other instances than the configured default states generator options in
``@stage(options=...)`` (e.g. ``{"hole_share": Fraction(1, 5)}``); instances are cached per size and
options.
"""
from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import statistics
import sys
import time
import tracemalloc
from dataclasses import dataclass, field
from datetime import datetime, timezone
from fractions import Fraction
from functools import cached_property
from pathlib import Path
from typing import Callable

import verify

from .generate import generate_system

DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "results.json"
DEFAULT_SIZES = (10, 100, 1000)
QUICK_SIZES = (10, 30)
SCHEMA = "verify.benchmarks/1"


class BenchmarkError(Exception):
    """A stage did not do what it is measured for (e.g. the system did not load cleanly)."""


@dataclass
class Instance:
    """A generated system and what stages derive from it (derived values are computed once, untimed)."""

    n_tasks: int
    seed: int
    options: dict = field(default_factory=dict)  # keyword arguments of generate_system
    chains: int | None = None
    generate_seconds: float = 0.0  # set when the text is generated

    @cached_property
    def text(self) -> str:
        start = time.perf_counter()
        text = generate_system(self.n_tasks, self.seed, chains=self.chains, **self.options)
        self.generate_seconds = time.perf_counter() - start
        return text

    @property
    def name(self) -> str:
        return f"waters-{self.n_tasks}-s{self.seed}.vfy"

    @cached_property
    def loaded(self) -> verify.LoadResult:
        return _load_clean(self)

    @cached_property
    def model(self):
        """The semantic model of the system (``verify.model.SystemModel``)."""
        return self.loaded.system()

    @cached_property
    def chain_count(self) -> int:
        return sum(1 for line in self.text.splitlines() if line.lstrip().startswith("chain "))


def _load_clean(inst: Instance) -> verify.LoadResult:
    result = verify.load_text(inst.text, inst.name)
    if result.diagnostics:
        first = result.diagnostics[0]
        raise BenchmarkError(f"{inst.name} has {len(result.diagnostics)} diagnostic(s), first "
                             f"{first.code} at line {first.span.line}: {first.message}")
    return result


# ------------------------------------------------------------------------------ the registry

#: stage name -> the measured callable
STAGES: dict[str, Callable[[Instance], object]] = {}
#: stage name -> one line saying what it measures
DESCRIPTIONS: dict[str, str] = {}
#: stage name -> attributes of the Instance to compute before timing (untimed preparation)
NEEDS: dict[str, tuple[str, ...]] = {}
#: stage name -> generator options of its instances
OPTIONS: dict[str, dict] = {}
#: stage name -> why it is not available here (import failed)
UNAVAILABLE: dict[str, str] = {}


def stage(name: str, description: str, *, needs: tuple[str, ...] = (), options: dict | None = None):
    """Register the decorated callable as stage ``name``."""

    def register(fn: Callable[[Instance], object]) -> Callable[[Instance], object]:
        STAGES[name] = fn
        DESCRIPTIONS[name] = description
        NEEDS[name] = needs
        OPTIONS[name] = dict(options or {})
        return fn

    return register


@stage("parse+check", "verify.load_text: parse, resolve, validate, build the model, check the chains")
def parse_and_check(inst: Instance) -> verify.LoadResult:
    return _load_clean(inst)


def _register_analyze() -> None:
    try:
        from verify.timing import analyze
    except Exception as err:  # not implemented yet, or broken: say so, measure the rest
        UNAVAILABLE["analyze"] = f"verify.timing.analyze is not importable ({type(err).__name__}: {err})"
        return

    @stage("analyze", "verify.timing.analyze on the loaded model: rates, response times, chain latencies",
           needs=("model",))
    def analyze_stage(inst: Instance) -> object:
        return analyze(inst.model)


_register_analyze()


# ------------------------------------------------------------------------------ measuring


def _summary(values: list) -> dict:
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def measure(name: str, inst: Instance, repeat: int, memory: bool = True, budget: float | None = None) -> dict:
    """Run stage ``name`` on ``inst``: ``repeat`` timed runs, then ``repeat`` traced runs. A run that takes
    longer than ``budget`` seconds ends the repetitions of its kind (the row says how many ran)."""
    fn = STAGES[name]
    for attr in ("text",) + NEEDS[name]:
        getattr(inst, attr)
    seconds, peaks = [], []
    for _ in range(repeat):
        gc.collect()
        start = time.perf_counter()
        result = fn(inst)
        seconds.append(time.perf_counter() - start)
        del result
        if budget is not None and seconds[-1] > budget:
            break
    if memory:
        for _ in range(repeat):
            gc.collect()
            start = time.perf_counter()
            tracemalloc.start()
            try:
                result = fn(inst)
                peaks.append(tracemalloc.get_traced_memory()[1])
            finally:
                tracemalloc.stop()
            del result
            if budget is not None and time.perf_counter() - start > budget:
                break
    row = {"stage": name, "tasks": inst.n_tasks, "seed": inst.seed, "chains": inst.chain_count,
           "lines": inst.text.count("\n"), "options": {k: str(v) for k, v in inst.options.items()},
           "runs": len(seconds), "generate_seconds": inst.generate_seconds,
           "seconds": seconds, "seconds_summary": _summary(seconds)}
    if peaks:
        row.update(memory_runs=len(peaks), peak_bytes=peaks, peak_bytes_summary=_summary(peaks))
    return row


def profile(name: str, inst: Instance, path: Path, top: int = 30) -> str:
    """One run of stage ``name`` under cProfile; the top functions by cumulative time, also written to
    ``path``."""
    import cProfile
    import io
    import pstats

    for attr in ("text",) + NEEDS[name]:
        getattr(inst, attr)
    profiler = cProfile.Profile()
    profiler.runcall(STAGES[name], inst)
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats("cumulative").print_stats(top)
    text = f"cProfile of stage {name} on {inst.n_tasks} tasks (seed {inst.seed}), top {top} by cumulative time\n"
    text += out.getvalue()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return text


def machine() -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"), "nproc": os.cpu_count(),
            "cpu": cpu, "python": platform.python_version(), "platform": platform.platform()}


# ------------------------------------------------------------------------------ reporting


def _seconds(x: float) -> str:
    return f"{x * 1000:.1f} ms" if x < 1 else f"{x:.2f} s"


def _bytes(x: int) -> str:
    return f"{x / 2**20:.1f} MiB" if x >= 2**20 else f"{x / 2**10:.0f} KiB"


def markdown(rows: list[dict]) -> str:
    head = ("| stage | tasks | chains | lines | runs | time (median) | time (min–max) | peak memory (median) "
            "| peak memory (min–max) |")
    out = [head, "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if "error" in r or "skipped" in r:
            what = f"error: {r['error']}" if "error" in r else f"skipped: {r['skipped']}"
            out.append(f"| {r['stage']} | {r['tasks']} | | | 0 | {what} | | | |")
            continue
        t = r["seconds_summary"]
        m = r.get("peak_bytes_summary")
        mem = (_bytes(m["median"]), f"{_bytes(m['min'])} – {_bytes(m['max'])}") if m else ("–", "–")
        runs = f"{r['runs']}" + (f" (+{r['memory_runs']} traced)" if m else "")
        out.append(f"| {r['stage']} | {r['tasks']} | {r['chains']} | {r['lines']} | {runs} | "
                   f"{_seconds(t['median'])} | {_seconds(t['min'])} – {_seconds(t['max'])} | {mem[0]} | {mem[1]} |")
    return "\n".join(out)


# ------------------------------------------------------------------------------ command line


def _sizes(text: str) -> list[int]:
    try:
        sizes = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of task counts: {text!r}") from None
    if not sizes or min(sizes) < 1:
        raise argparse.ArgumentTypeError("sizes must be positive task counts")
    return sizes


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks", description="Time verify's stages on generated "
                                "WATERS-2015-like systems of several sizes.")
    p.add_argument("--sizes", type=_sizes, help=f"task counts (default {','.join(map(str, DEFAULT_SIZES))})")
    p.add_argument("--repeat", type=int, help="repetitions per stage and size (default 3)")
    p.add_argument("--stages", help="comma-separated stage names (default: every available stage)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--chains", type=int, default=None, help="chains per system (default: WATERS, 30-60)")
    p.add_argument("--quick", action="store_true", help=f"sizes {','.join(map(str, QUICK_SIZES))}, one repetition")
    p.add_argument("--no-memory", action="store_true", help="skip the tracemalloc runs")
    p.add_argument("--budget", type=float, default=60.0,
                   help="seconds: a run longer than this ends its repetitions, and a size that would take "
                        "longer even with linear growth from the last one is skipped (default 60; 0: no limit)")
    p.add_argument("--profile", action="store_true",
                   help="also profile each stage once at its largest measured size (cProfile, written next "
                        "to --out as profile-STAGE-TASKS.txt)")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"JSON results (default {DEFAULT_OUT})")
    p.add_argument("--list", action="store_true", help="list the stages and exit")
    args = p.parse_args(argv)

    if args.list:
        for name in STAGES:
            print(f"{name}: {DESCRIPTIONS[name]}")
        for name, why in UNAVAILABLE.items():
            print(f"{name}: unavailable: {why}")
        return 0
    sizes = args.sizes or (list(QUICK_SIZES) if args.quick else list(DEFAULT_SIZES))
    repeat = args.repeat if args.repeat is not None else 1 if args.quick else 3
    if repeat < 1:
        p.error("--repeat must be at least 1")
    names = [s.strip() for s in args.stages.split(",")] if args.stages else list(STAGES)
    for name in names:
        if name not in STAGES:
            why = UNAVAILABLE.get(name, "known stages: " + ", ".join(list(STAGES) + list(UNAVAILABLE)))
            p.error(f"stage {name!r} is not available: {why}")

    verify.load_text(generate_system(4, 0))  # warm-up, untimed: builds the parser once
    info = machine()
    print(f"verify benchmarks — {info['date']}; {info['nproc']} CPUs ({info['cpu']}); Python {info['python']}",
          file=sys.stderr)
    budget = args.budget or None
    instances: dict[tuple, Instance] = {}
    rows: list[dict] = []
    largest: dict[str, Instance] = {}
    failed = False
    for name in names:
        last = None  # (size, median seconds) of the last measured size
        for size in sizes:
            if budget is not None and last is not None and last[1] * size / last[0] > budget:
                rows.append({"stage": name, "tasks": size, "seed": args.seed,
                             "skipped": f"{last[0]} tasks took {last[1]:.1f} s; even linear growth exceeds "
                                        f"the budget of {args.budget:g} s"})
                last = (size, last[1] * size / last[0])
                continue
            key = (size, tuple(sorted((k, str(v)) for k, v in OPTIONS[name].items())))
            inst = instances.setdefault(key, Instance(size, args.seed, OPTIONS[name], args.chains))
            print(f"  {name} on {size} tasks ...", file=sys.stderr, flush=True)
            try:
                row = measure(name, inst, repeat, memory=not args.no_memory, budget=budget)
            except Exception as err:  # recorded, and the run goes on with the other stages and sizes
                failed = True
                what = str(err) if isinstance(err, BenchmarkError) else f"{type(err).__name__}: {err}"
                rows.append({"stage": name, "tasks": size, "seed": args.seed, "error": what})
                continue
            rows.append(row)
            largest[name] = inst
            last = (size, row["seconds_summary"]["median"])
    profiles = {}
    if args.profile:
        for name, inst in largest.items():
            path = args.out.parent / f"profile-{name.replace('+', '-')}-{inst.n_tasks}.txt"
            print(f"  profiling {name} on {inst.n_tasks} tasks -> {path}", file=sys.stderr, flush=True)
            profile(name, inst, path)
            profiles[name] = str(path)
    table = markdown(rows)
    print(table)
    doc = {"schema": SCHEMA, "machine": info,
           "config": {"sizes": sizes, "repeat": repeat, "seed": args.seed, "chains": args.chains,
                      "memory": not args.no_memory, "stages": names},
           "unavailable": UNAVAILABLE, "results": rows, "profiles": profiles, "markdown": table}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(doc, indent=2, default=_json_default) + "\n", encoding="utf-8")
    print(f"results written to {args.out}", file=sys.stderr)
    return 1 if failed else 0


def _json_default(value):
    if isinstance(value, Fraction):
        return str(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
