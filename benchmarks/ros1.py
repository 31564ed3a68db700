"""ROS 1 stage: what the generated nodes' runtime monitors cost (issue 14, item 5).

``ros1-monitor`` measures two things and sets them side by side:
- the monitors' own work, in a C++ micro-benchmark of the runtime library (``ros1_monitor_cost.cpp``):
  per chain hop (taking the stamp from the input, passing it on, its bytes in the message's out-of-band
  record, encoded and decoded) and per chain end (``ChainMonitor::on_end``), each against the same work without a chain;
- the middleware's own per-message latency, from a live run of a generated pipeline (a 100 Hz source,
  two relays and a sink on two cores, one chain through all): the time from a writer job's completion to
  the release of the reader job it triggers, from the job records, once with monitors (``monitor:=true``)
  and once without (``monitor:=false``: no records beside the messages, no stamps, no monitors).
The goal: the monitors' work per hop under 5 % of the middleware's median per-message latency.
The project is generated and built once (untimed) in ``benchmarks/out/ros1-pipeline``.
"""
from __future__ import annotations

import contextlib
import io
import json
import statistics
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
RUNTIME = Path(__file__).resolve().parent.parent / "verify" / "gen" / "ros1_runtime"
MICRO = Path(__file__).resolve().parent / "ros1_monitor_cost.cpp"

PIPELINE = """
component Source {
  out o : Msg
  task Emit {
    produces o
    wcet 100 us
  }
}
component Relay {
  in i : Msg
  out o : Msg
  task Pass {
    reads i
    produces o
    wcet 100 us
  }
}
component Sink {
  in i : Msg
  task Take {
    reads i
    wcet 100 us
  }
}
system Pipeline {
  core cpu0
  core cpu1
  instance src : Source on cpu0 {
    task Emit priority 4 timer 100 Hz
  }
  instance r1 : Relay on cpu1 {
    task Pass priority 3 trigger i
  }
  instance r2 : Relay on cpu0 {
    task Pass priority 2 trigger i
  }
  instance sink : Sink on cpu1 {
    task Take priority 1 trigger i
  }
  connect src.o -> r1.i
  connect r1.o -> r2.i
  connect r2.o -> sink.i
  chain through: src.o -> r1.o -> r2.o -> sink.Take {
    reaction_time <= 100 ms
  }
}
"""


def pipeline_text(n_tasks: int, seed: int, **_: object) -> str:
    return PIPELINE


def _hop_latencies(jobs: list[dict]) -> list[int]:
    """Writer completion to reader release, per triggered job, in ns."""
    finish = {(j["node"], j["seq"]): j["finish"] for j in jobs}
    writer = {"/Pipeline/r1": "/Pipeline/src", "/Pipeline/r2": "/Pipeline/r1", "/Pipeline/sink": "/Pipeline/r2"}
    return [j["release"] - finish[(writer[j["node"]], j["trigger_seq"])] for j in jobs
            if j["node"] in writer and (writer[j["node"]], j["trigger_seq"]) in finish]


def register(stage: Callable[..., Callable], error: type[Exception], unavailable: dict[str, str]) -> None:
    from . import roslive

    missing = roslive.missing_tools()
    if missing:
        unavailable["ros1-monitor"] = f"ROS 1 tools missing: {', '.join(missing)} (scripts/install-tools)"
        return
    built: dict[str, Path] = {}

    def setup() -> None:
        if built:
            return
        from verify import load_text
        from verify.cli import main

        project = OUT / "ros1-pipeline"
        OUT.mkdir(parents=True, exist_ok=True)
        model_file = OUT / "ros1-pipeline.vfy"
        model_file.write_text(PIPELINE, encoding="utf-8")
        with contextlib.redirect_stdout(io.StringIO()):
            generated = main(["gen", "ros1", str(model_file), "-o", str(project), "--force"])
        if generated != 0:
            raise error("verify gen failed on the pipeline", {})
        load_text(PIPELINE).system()
        roslive.build(project)
        micro = OUT / "ros1_monitor_cost"
        flags = subprocess.run(["pkg-config", "--cflags", "--libs", "roscpp"], capture_output=True, text=True,
                               check=True).stdout.split()
        subprocess.run(["g++", "-O2", "-std=c++17", f"-I{RUNTIME}", str(MICRO), "-o", str(micro), *flags],
                       check=True, capture_output=True, timeout=300)
        built.update(project=project, micro=micro)

    def live(seconds: float, monitor: bool) -> list[int]:
        with tempfile.TemporaryDirectory() as tmp:
            home = Path(tmp)
            with roslive.master(built["project"], home / "ros") as env:
                roslive.run_system(env, "pipeline_nodes", "Pipeline.launch", seconds, home / "run.jsonl", [],
                                   home / "summary", launch_args=[f"monitor:={'true' if monitor else 'false'}"])
            return _hop_latencies(roslive.jobs(roslive.recorded(home / "run.jsonl")))

    @stage("ros1-monitor", "the generated ROS 1 nodes' monitors: their work per chain hop and end (C++), against "
           "the middleware's median per-message latency in a live pipeline with and without monitors (the size "
           "is ignored)", sizes=(1,), quick_sizes=(1,), generator=pipeline_text, setup=setup,
           params={"seconds": 8.0}, quick_params={"seconds": 4.0})
    def ros1_monitor(inst, seconds: float) -> dict:
        try:
            micro = json.loads(subprocess.run([str(built["micro"])], capture_output=True, text=True, check=True,
                                              timeout=120).stdout)
            with_monitors = live(seconds, True)
            without = live(seconds, False)
        except (OSError, RuntimeError, AssertionError, subprocess.SubprocessError) as err:
            raise error(f"{type(err).__name__}: {str(err)[:200]}", {}) from None
        if not with_monitors or not without:
            raise error("no triggered job was recorded", {})
        plain_us = statistics.median(without) / 1000
        hop_ns = micro["hop_monitored_ns"] - micro["hop_plain_ns"]
        return {"monitor work per hop": f"{hop_ns:.0f} ns", "per chain end": f"{micro['end_ns']:.0f} ns",
                "middleware latency (median) without monitors": f"{plain_us:.0f} us",
                "with monitors": f"{statistics.median(with_monitors) / 1000:.0f} us",
                "hop work / latency": f"{hop_ns / (plain_us * 1000):.2%}",
                "messages": f"{len(without)} + {len(with_monitors)}"}
