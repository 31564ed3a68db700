"""Shared test fixtures."""
from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import settings

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@pytest.fixture
def write(tmp_path):
    """Write files into a temporary project directory; returns the path of the first one."""

    def _write(files: dict[str, str | bytes]) -> str:
        first = None
        for name, content in files.items():
            path = tmp_path / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                path.write_bytes(content)
            else:
                path.write_text(content, encoding="utf-8")
            first = first or str(path)
        return first

    return _write


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() in ("1", "true", "yes")


#: under CI the property-based tests draw the same examples every run (a red run is reproduced by running
#: it again, and a green one stays green); elsewhere they draw new ones and remember what failed
settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
if in_ci():
    settings.load_profile("ci")


#: held by a test module that runs real ROS 1, ROS 2 or LTTng processes and measures their timing, for the
#: whole module: pytest-xdist's workers are separate processes, and the generated ROS 2 nodes' real-time
#: threads (SCHED_FIFO 97-99) or a ROS 1 system running beside another live run would change what it measures
LIVE_LOCK = Path(tempfile.gettempdir()) / "verify-live-tests.lock"


@pytest.fixture(scope="module")
def live_processes_alone():
    """Runs the module's live processes with no other test module's beside them (a file lock)."""
    with open(LIVE_LOCK, "a+b") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


#: where the tightness log is written (git-ignored); the terminal summary shows it too
TIGHTNESS_LOG = ROOT / "tests" / "out" / "tightness.txt"
#: the property tests that collect tightness ratios (``tightness_summary()``), with a heading each
TIGHTNESS_SOURCES = (("tests.test_bounds_vs_simulation", "random systems (tests/test_bounds_vs_simulation.py)"),
                     ("tests.test_priority_refinement",
                      "systems around a same-core hop, §7.6 (tests/test_priority_refinement.py)"))


def pytest_sessionfinish(session):
    """Under pytest-xdist, a worker hands the tightness ratios its property tests collected to the
    controller (``workeroutput``), which reports them (``pytest_testnodedown``)."""
    import sys

    output = getattr(session.config, "workeroutput", None)
    if output is None:
        return
    output["tightness"] = {name: {kind: [str(r) for r in ratios] for kind, ratios in module.TIGHTNESS.items()}
                           for name, _ in TIGHTNESS_SOURCES if (module := sys.modules.get(name)) is not None}


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    """(pytest-xdist, in the controller) The tightness ratios of a worker, added to those of its modules
    here, from which the summary is made."""
    import importlib
    from fractions import Fraction

    for name, kinds in getattr(node, "workeroutput", {}).get("tightness", {}).items():
        module = importlib.import_module(name)
        for kind, ratios in kinds.items():
            module.TIGHTNESS[kind].extend(Fraction(r) for r in ratios)


def pytest_terminal_summary(terminalreporter):
    """Report the tightness of the analytic bounds against the simulator — simulated worst / bound
    per latency kind, from the property tests that ran — in the summary and in ``TIGHTNESS_LOG``."""
    import sys

    sections = []
    for name, heading in TIGHTNESS_SOURCES:
        module = sys.modules.get(name)
        lines = module.tightness_summary() if module else []
        if lines:
            sections.append((heading, lines))
    if not sections:
        return
    title = "tightness of the analytic bounds (simulated worst / bound)"
    terminalreporter.section(title)
    text = [title]
    for heading, lines in sections:
        terminalreporter.write_line(heading)
        text.append(heading)
        for line in lines:
            terminalreporter.write_line("  " + line)
            text.append("  " + line)
    TIGHTNESS_LOG.parent.mkdir(parents=True, exist_ok=True)
    TIGHTNESS_LOG.write_text("\n".join(text) + "\n", encoding="utf-8")
    terminalreporter.write_line(f"(also written to {TIGHTNESS_LOG.relative_to(ROOT)})")


@pytest.fixture
def navigation_models(tmp_path):
    """A copy of examples/navigation (its systems and component library) in the test's own directory."""
    import shutil

    directory = tmp_path / "model"
    shutil.copytree(EXAMPLES / "navigation", directory)
    return directory
