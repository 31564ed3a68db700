"""The command line contract: exit codes, JSON output, files never overwritten unless asked."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

from verify import cli
from verify.cli import main

from .conftest import EXAMPLES

NAV = str(EXAMPLES / "navigation" / "navigation.vfy")
BROKEN = "component Laser { task T { wcet 1 ms } }\nsystem S { instance a : Lazer }\n"


def test_check_json_schema(write, capsys):
    path = write({"m.vfy": BROKEN})
    assert main(["check", path, "--format", "json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "verify.diagnostics/1"
    (d,) = doc["diagnostics"]
    assert d["code"] == "E101" and d["severity"] == "error" and d["line"] == 2 and d["column"] == 25
    assert d["help"] == "did you mean `Laser`?" and d["spec"] == "specs/diagnostics.md#e101"
    assert doc["summary"] == {"errors": 1, "warnings": 0}


def test_check_ok_and_usage_errors(capsys):
    assert main(["check", NAV]) == 0
    assert "ok" in capsys.readouterr().out
    assert main([]) == 2
    assert main(["check"]) == 2
    assert main(["frobnicate", NAV]) == 2
    assert main(["explain", "E999"]) == 2
    assert main(["explain", "e101"]) == 0


def test_fmt_never_overwrites_unless_asked(write, capsys):
    src = "component A {  task T { wcet 1 ms } }\n"
    path = write({"a.vfy": src, "b.vfy": "keep me\n"})
    other = path.replace("a.vfy", "b.vfy")
    assert main(["fmt", path, "-o", other]) == 2
    assert open(other).read() == "keep me\n"
    assert open(path).read() == src
    assert main(["fmt", path, "--check"]) == 1
    assert main(["fmt", path, "-o", other, "--force"]) == 0
    assert main(["fmt", other, "--check"]) == 0
    assert main(["fmt", path, "--in-place"]) == 0
    assert open(path).read() == open(other).read()


def test_internal_errors_exit_70_without_traceback(monkeypatch, capsys):
    def boom(_args):
        raise RuntimeError("simulated bug")

    monkeypatch.setattr(cli, "cmd_check", boom)
    assert main(["check", NAV]) == 70
    err = capsys.readouterr().err
    assert "internal error" in err and "Traceback" not in err


@pytest.mark.parametrize("script", ["verify", "synth", "prove"])
def test_console_scripts_exist(script):
    proc = subprocess.run([sys.executable, "-c", f"import shutil,sys; sys.exit(0 if shutil.which('{script}') else 1)"])
    assert proc.returncode == 0, f"console script {script} is not installed"
