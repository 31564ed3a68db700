"""The fuzzing driver: seeds a corpus per target, runs ``fuzz.harness`` under libFuzzer for each target
(several side by side), and sums up executions and findings.

Each target keeps its corpus in ``OUT/corpus/TARGET`` (seeded from ``fuzz.seeds``; libFuzzer adds the
inputs that reach new code, so a later run starts where the last one stopped) and its findings in
``OUT/findings/TARGET`` (``crash-*``: an exception or a broken invariant; ``timeout-*``: one input ran
longer than ``--timeout``; ``oom-*``). ``OUT/summary.json`` holds the numbers of the run, and
``OUT/history.jsonl`` those of every run (libFuzzer stops a target at its first finding). A finding,
once fixed, becomes a regression input in ``tests/fuzz_regressions/TARGET/`` (``tests/test_fuzz.py``
replays them all).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from .seeds import ROOT, dictionary, seeds
from .targets import TARGETS

#: how ``--total`` is shared among the targets (the later stages run fewer, slower executions)
SHARES = {"parse": 30, "validate": 25, "fmt": 20, "analyze": 15, "synth": 5, "prove": 5, "smartmdsd": 10, "caret": 10,
          "lsp": 5}
#: seconds one input may take before libFuzzer calls it a hang
TIMEOUTS = {"synth": 60, "prove": 60}
DEFAULT_TIMEOUT = 20
#: the smoke run of tests/test_fuzz.py: executions per target, and only the example (SmartMDSD, CARET and
#: LSP session) seeds
SMOKE_RUNS = {"parse": 300, "validate": 200, "fmt": 200, "analyze": 100, "synth": 30, "prove": 30, "smartmdsd": 200,
              "caret": 200, "lsp": 30}
FINDING = re.compile(r"^(crash|timeout|oom|leak)-")
#: inputs slower than libFuzzer's ``-report_slow_units`` (listed, not failed: a loaded machine makes them)
SLOW = re.compile(r"^slow-unit-")


def prepare(out: Path, target: str, smoke: bool) -> tuple[Path, Path, Path]:
    """The corpus, findings directory and dictionary of ``target`` under ``out`` (seeded)."""
    corpus = out / "corpus" / target
    findings = out / "findings" / target
    corpus.mkdir(parents=True, exist_ok=True)
    findings.mkdir(parents=True, exist_ok=True)
    for name, data in seeds().items():
        if smoke and not name.startswith(("example-", "smartmdsd-", "caret-", "lsp-")):
            continue
        path = corpus / f"seed-{name}"
        if not path.exists():
            path.write_bytes(data)
    words = out / "vfy.dict"
    words.write_text("\n".join(dictionary()) + "\n", encoding="utf-8")
    return corpus, findings, words


def fuzz_one(target: str, runs: int, out: Path, *, max_len: int, smoke: bool, seed: int) -> dict:
    """Run ``target`` for ``runs`` executions; what libFuzzer reported."""
    corpus, findings, words = prepare(out, target, smoke)
    before = {p.name for p in findings.iterdir()}
    timeout = TIMEOUTS.get(target, DEFAULT_TIMEOUT)
    command = [sys.executable, "-m", "fuzz.harness", target, f"-runs={runs}", f"-max_len={max_len}",
               f"-timeout={timeout}", f"-dict={words}", f"-seed={seed}", f"-artifact_prefix={findings}{os.sep}",
               "-print_final_stats=1", "-rss_limit_mb=4096", str(corpus)]
    started = time.monotonic()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    log_path = out / f"{target}.log"  # (written as libFuzzer goes: ``tail -f`` shows a long run's progress)
    with open(log_path, "w", encoding="utf-8") as log_file:
        proc = subprocess.run(command, cwd=ROOT, env=env, stdout=log_file, stderr=subprocess.STDOUT)
    seconds = time.monotonic() - started
    log = log_path.read_text(encoding="utf-8", errors="replace")
    executed = re.findall(r"stat::number_of_executed_units:\s*(\d+)", log) or re.findall(r"^#(\d+)\s", log, re.M)
    made = sorted(p.name for p in findings.iterdir() if p.name not in before)
    return {"target": target, "runs": runs, "executions": int(executed[-1]) if executed else 0,
            "seconds": round(seconds, 1), "exit_code": proc.returncode,
            "findings": [n for n in made if FINDING.match(n)], "slow": [n for n in made if SLOW.match(n)],
            "corpus": sum(1 for _ in corpus.iterdir())}


def split(total: int, targets: list[str]) -> dict[str, int]:
    """``total`` executions shared among ``targets`` by ``SHARES``."""
    weight = sum(SHARES[t] for t in targets)
    return {t: max(1, total * SHARES[t] // weight) for t in targets}


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True).stdout.strip() or "unknown"
    except OSError:
        return "unknown"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m fuzz", description=__doc__.split("\n\n")[0])
    p.add_argument("--targets", default=",".join(TARGETS), help="comma-separated (default: all): "
                   + ", ".join(TARGETS))
    group = p.add_mutually_exclusive_group()
    group.add_argument("--runs", type=int, help="executions of each target")
    group.add_argument("--total", type=int, help="executions of all targets together, shared by weight")
    group.add_argument("--smoke", action="store_true", help="a short run of every target (the test suite's)")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="targets run side by side")
    p.add_argument("--max-len", type=int, default=4096, help="the largest input libFuzzer makes (bytes)")
    p.add_argument("--seed", type=int, default=1, help="libFuzzer's random seed")
    p.add_argument("--out", default=str(ROOT / "fuzz" / "out"), help="corpus, findings and logs (default fuzz/out)")
    args = p.parse_args(argv)
    targets = [t.strip() for t in args.targets.split(",") if t.strip()]
    unknown = [t for t in targets if t not in TARGETS]
    if unknown:
        p.error(f"unknown target(s) {', '.join(unknown)}; known: {', '.join(TARGETS)}")
    if args.smoke:
        plan = {t: SMOKE_RUNS[t] for t in targets}
    elif args.total:
        plan = split(args.total, targets)
    else:
        plan = {t: args.runs or 1000 for t in targets}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = datetime.datetime.now(datetime.UTC)
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        results = list(pool.map(lambda t: fuzz_one(t, plan[t], out, max_len=args.max_len, smoke=args.smoke,
                                                   seed=args.seed), targets))
    summary = {"date": started.strftime("%Y-%m-%d %H:%M UTC"), "commit": _commit(),
               "executions": sum(r["executions"] for r in results),
               "findings": sum(len(r["findings"]) for r in results), "targets": results}
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    with open(out / "history.jsonl", "a", encoding="utf-8") as fh:  # every run, for the running total
        fh.write(json.dumps(summary) + "\n")
    for r in results:
        found = ", ".join(r["findings"]) or "none"
        slow = f"  slow: {', '.join(r['slow'])}" if r["slow"] else ""
        print(f"{r['target']:9} {r['executions']:>9,} executions in {r['seconds']:>8.1f} s  corpus {r['corpus']:>5}  "
              f"findings: {found}{slow}")
    print(f"total     {summary['executions']:>9,} executions, {summary['findings']} findings "
          f"(logs and findings in {out})")
    failed = [r for r in results if r["findings"] or r["exit_code"] != 0]
    return 1 if failed else 0
