"""Start every process of a generated system here, without the ROS 2 launch package (which the package
index does not offer): the same processes, parameters and start protocol as launch/*.launch.py.

    python -m PACKAGE.run [--duration S] [--summary-dir DIR] [--trace-dir DIR] [--no-monitor] [--no-realtime]

With ``--duration S`` every process stops S seconds after the agreed start (however long the start-up
took); on SIGINT/SIGTERM the runner stops them all (SIGINT, as launch does).
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from types import ModuleType

#: the middleware and discovery the runner uses unless the environment says otherwise
#: with ``--duration``: how long the other processes may run on once one has stopped (every process stops
#: ``duration`` s after the same agreed start; one that does not is stopped, specs/codegen.md §9.4)
STRAGGLE_S = 30.0
ENVIRONMENT = {"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


def parameters_file(package: ModuleType) -> str:
    """config/parameters.yaml beside the package's sources, or in its installed share directory."""
    here = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(package.__file__ or ""))), "config",
                        "parameters.yaml")
    if os.path.isfile(here):
        return here
    from ament_index_python.packages import get_package_share_directory

    return os.path.join(get_package_share_directory(package.__name__), "config", "parameters.yaml")


def command(package: str, system: ModuleType, unit: str, params: str, args: argparse.Namespace, run: str) -> list[str]:
    """The command line of process ``unit``."""
    extra = {"verify.run": run, "verify.duration": str(float(args.duration)),
             "verify.monitor": "false" if args.no_monitor else "true",
             "verify.realtime": "false" if args.no_realtime else "true"}
    if args.summary_dir:
        extra["verify.summary_dir"] = os.path.abspath(args.summary_dir)
    if args.trace_dir:
        extra["verify.trace_dir"] = os.path.abspath(args.trace_dir)
    line = [sys.executable, "-m", f"{package}.main", unit, "--ros-args", "--params-file", params,
            "-r", f"__ns:=/{system.NAMESPACE}"]
    for key, value in extra.items():
        line += ["-p", f"{key}:={value}"]
    return line


def main(package: ModuleType, system: ModuleType, argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog=f"python -m {package.__name__}.run", description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=0.0,
                   help="seconds to run after the agreed start (0: until SIGINT)")
    p.add_argument("--summary-dir", default="", help="where each process ending a chain writes its monitors' summary")
    p.add_argument("--trace-dir", default="", help="where each process writes its job records (JSON lines)")
    p.add_argument("--params-file", default="", help="the parameter file (default: config/parameters.yaml)")
    p.add_argument("--no-monitor", action="store_true", help="no chain stamps and no monitors")
    p.add_argument("--no-realtime", action="store_true", help="no SCHED_FIFO and no CPU affinity")
    args = p.parse_args(argv)
    params = args.params_file or parameters_file(package)
    env = {**ENVIRONMENT, **os.environ}
    run = "r" + uuid.uuid4().hex[:12]
    children = [subprocess.Popen(command(package.__name__, system, unit, params, args, run), env=env)
                for unit in system.UNITS]
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda _s, _f: stop.set())
    first_exit = None
    while not stop.wait(0.1) and any(child.poll() is None for child in children):
        if args.duration and first_exit is None and any(child.poll() is not None for child in children):
            first_exit = time.monotonic()
        if first_exit is not None and time.monotonic() - first_exit > STRAGGLE_S:
            late = [unit for unit, child in zip(system.UNITS, children) if child.poll() is None]
            print(f"{package.__name__}.run: {', '.join(late)} still running {STRAGGLE_S:.0f} s after the first "
                  "process stopped; stopping them", file=sys.stderr)
            break
    for child in children:
        if child.poll() is None:
            child.send_signal(signal.SIGINT)
    codes = []
    for child in children:
        try:
            codes.append(child.wait(timeout=30))
        except subprocess.TimeoutExpired:
            child.kill()
            codes.append(child.wait())
    return next((1 for code in codes if code != 0), 0)  # (a process killed by a signal: negative)
