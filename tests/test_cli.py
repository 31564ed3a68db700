"""The command line contract: exit codes, JSON output, files never overwritten unless asked."""
from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

from verify import cli
from verify.cli import main

from .conftest import EXAMPLES

NAV = str(EXAMPLES / "navigation" / "navigation.vfy")
BROKEN = "component Laser { task T { wcet 1 ms } }\nsystem S { instance a : Lazer }\n"


def _read(path: str) -> str:
    with open(path) as f:
        return f.read()


def test_check_json_schema(write, capsys):
    path = write({"m.vfy": BROKEN})
    assert main(["check", path, "--format", "json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "verify.diagnostics/1"
    (d,) = doc["diagnostics"]
    assert d["code"] == "E101" and d["severity"] == "error" and d["line"] == 2 and d["column"] == 25
    assert d["help"] == "did you mean `Laser`?" and d["spec"] == "specs/diagnostics.md#e101-unknown-name"
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
    assert _read(other) == "keep me\n"
    assert _read(path) == src
    assert main(["fmt", path, "--check"]) == 1
    assert main(["fmt", path, "-o", other, "--force"]) == 0
    assert main(["fmt", other, "--check"]) == 0
    assert main(["fmt", path, "--in-place"]) == 0
    assert _read(path) == _read(other)


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


def _github_anchors(markdown: str) -> set[str]:
    """The anchors GitHub generates for the headings of ``markdown``, written out independently of
    ``verify.core.codes``: lower case, every character but letters, digits, ``-``, ``_`` and spaces dropped,
    spaces turned into hyphens."""
    anchors = set()
    for line in markdown.splitlines():
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            anchors.add(re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-"))
    return anchors


def test_every_spec_link_points_at_a_heading():
    from verify.core.codes import CODES, spec_anchor

    from .conftest import ROOT

    text = (ROOT / "specs" / "diagnostics.md").read_text(encoding="utf-8")
    anchors = _github_anchors(re.sub(r"^```.*?^```", "", text, flags=re.MULTILINE | re.DOTALL))
    for code in CODES:
        link = spec_anchor(code)
        path, _, anchor = link.partition("#")
        assert path == "specs/diagnostics.md" and anchor in anchors, f"{code}: {link} names no heading"
    assert spec_anchor("E306") == "specs/diagnostics.md#e306-activation-contradicts-a-fixed-non-changeable-rate"
    assert spec_anchor("E308") == "specs/diagnostics.md#e308-phase-outside-0-period"


# ------------------------------------------------------------------ fmt --in-place: atomic, never lost

UNFORMATTED = "component A {  task T { wcet 1 ms } }\n"


def test_fmt_in_place_keeps_the_mode_and_leaves_no_temporary_file(write, tmp_path):
    import os
    import stat

    path = write({"a.vfy": UNFORMATTED})
    os.chmod(path, 0o640)
    assert main(["fmt", path, "--in-place"]) == 0
    assert _read(path) != UNFORMATTED and main(["fmt", path, "--check"]) == 0
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640
    assert sorted(os.listdir(tmp_path)) == ["a.vfy"]


def test_fmt_in_place_through_a_symbolic_link_rewrites_the_target(write, tmp_path):
    import os

    path = write({"a.vfy": UNFORMATTED})
    link = tmp_path / "link.vfy"
    os.symlink("a.vfy", link)
    assert main(["fmt", str(link), "--in-place"]) == 0
    assert os.path.islink(link) and main(["fmt", path, "--check"]) == 0


def test_fmt_in_place_failure_is_e004_and_loses_nothing(write, tmp_path, monkeypatch, capsys):
    import os

    path = write({"a.vfy": UNFORMATTED})

    def refuse(*_args, **_kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "replace", refuse)  # fails after the temporary file is written
    assert main(["fmt", path, "--in-place"]) == 2
    err = capsys.readouterr().err
    assert "error[E004]" in err and "cannot write" in err and "Permission denied" in err
    assert "Traceback" not in err and "internal error" not in err
    assert _read(path) == UNFORMATTED
    assert sorted(os.listdir(tmp_path)) == ["a.vfy"]  # the temporary file is removed


def test_fmt_in_place_where_no_temporary_file_can_be_made(write, tmp_path, monkeypatch, capsys):
    """A directory that refuses new files (as a read-only one does for non-root users): E004, exit 2,
    the original untouched."""
    import os
    import tempfile

    def refuse(*_args, **_kwargs):
        raise PermissionError(13, "Permission denied")

    path = write({"a.vfy": UNFORMATTED})
    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    assert main(["fmt", path, "--in-place"]) == 2
    err = capsys.readouterr().err
    assert "error[E004]" in err and "Permission denied" in err and "Traceback" not in err
    assert _read(path) == UNFORMATTED
    assert sorted(os.listdir(tmp_path)) == ["a.vfy"]


def test_fmt_output_failure_is_e004(tmp_path, write, capsys):
    path = write({"a.vfy": UNFORMATTED})
    assert main(["fmt", path, "-o", str(tmp_path / "no" / "such" / "dir.vfy")]) == 2
    err = capsys.readouterr().err
    assert "error[E004]" in err and "Traceback" not in err


# ------------------------------------------------------------------ check sees propagated rates (E305/E306)


def _navigation_with(tmp_path, old: str, new: str) -> str:
    from .conftest import EXAMPLES

    for name in ("components.vfy", "navigation.vfy"):
        text = (EXAMPLES / "navigation" / name).read_text(encoding="utf-8")
        (tmp_path / name).write_text(text.replace(old, new) if name == "navigation.vfy" else text, encoding="utf-8")
    return str(tmp_path / "navigation.vfy")


def test_check_reports_a_triggered_task_outside_its_constraint(tmp_path, capsys):
    path = _navigation_with(tmp_path, "trigger scan every 10", "trigger scan every 2")
    assert main(["check", path, "--format", "json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    found = [d for d in doc["diagnostics"] if d["code"] == "E305"]
    mapper = next(d for d in found if "mapper.CurMapTask" in d["message"])
    assert "20 Hz (40 Hz / 2)" in mapper["message"] and "10 Hz" in mapper["message"]


@pytest.mark.parametrize("command", ["analyze", "prove", "synth"])
def test_later_commands_report_it_once(tmp_path, capsys, command):
    path = _navigation_with(tmp_path, "trigger scan every 10", "trigger scan every 2")
    assert main([command, path]) == 2
    err = capsys.readouterr().err
    assert err.count("`mapper.CurMapTask` is activated at 20 Hz") == 1


_HOLE_UPSTREAM = """component W {{
  out o : T
  task Write {{
    produces o
    wcet 1 ms
  }}
}}
component R {{
  in i : T
  task Read {{
    reads i
    wcet 1 ms
    activation max 1 Hz
  }}
}}
system S {{
  core c
  instance w : W on c {{
    task Write priority 2 timer {writer}
  }}
  instance r : R on c {{
    task Read priority 1 trigger i every 2
  }}
  connect w.o -> r.i
}}
"""


def test_check_leaves_rates_behind_a_hole_to_synth(write):
    import verify

    assert verify.load_text(_HOLE_UPSTREAM.format(writer="?"), "m.vfy").ok
    (d,) = verify.load_text(_HOLE_UPSTREAM.format(writer="100 ms"), "m.vfy").diagnostics
    assert d.code == "E305" and "5 Hz (10 Hz / 2)" in d.message


# ------------------------------------------------------------------ analyze: which failures are exit 1


OVERLOADED = """component A {
  task T {
    wcet 60 ms
  }
}

system S {
  core c
  instance a : A on c {
    task T priority 2 timer 100 ms
  }
  instance b : A on c {
    task T priority 1 timer 100 ms
  }
}
"""


def test_analyze_exits_1_when_the_configured_system_misses_its_timing(write, capsys):
    """An overloaded core (E311) and a response time without a bound (E312) are timing failures of a
    valid configuration, exit 1 as `prove` exits on a missed deadline; `check` accepts the file."""
    path = write({"over.vfy": OVERLOADED})
    assert main(["check", path]) == 0
    capsys.readouterr()
    assert main(["analyze", path]) == 1
    err = capsys.readouterr().err
    assert "error[E311]" in err and "error[E312]" in err
    assert main(["prove", path]) == 1


def test_check_reports_a_compound_constraint_like_every_later_command(write, capsys):
    """E314 (a compound in-port's own constraint) is a property of the configuration: `check` reports
    it, and analyze, prove and synth stop at it with exit 2, each reporting it once."""
    import re

    from .conftest import ROOT

    text = (ROOT / "specs" / "diagnostics.md").read_text(encoding="utf-8")
    section = text[text.index("## E314"):]
    example = re.search(r"```vfy[^\n]*\n(.*?)```", section, re.S).group(1)
    path = write({"e314.vfy": example})
    for command in ("check", "analyze", "prove", "synth"):
        assert main([command, path]) == 2, command
        err = capsys.readouterr().err
        assert err.count("error[E314]") == 1, (command, err)


def test_a_system_selection_error_is_json_when_json_is_asked(write, capsys):
    """Two systems and no --system: E105, as a JSON document on stdout for analyze and synth too."""
    unit = "component A {\n  task T {\n    wcet 1 ms\n  }\n}\n"
    body = "  core c\n  instance a : A on c {\n    task T priority 1 timer 10 ms\n  }\n"
    path = write({"two.vfy": unit + "".join(f"system S{n} {{\n{body}}}\n" for n in (1, 2))})
    for command in ("analyze", "synth", "prove"):
        assert main([command, path, "--format", "json"]) == 2
        doc = json.loads(capsys.readouterr().out)
        assert [d["code"] for d in doc["diagnostics"]] == ["E105"], command


def test_an_empty_file_name_and_a_code_prefix(capsys):
    assert main(["check", ""]) == 2
    err = capsys.readouterr().err
    assert "error[E004]: no file name given" in err and "directory" not in err
    assert main(["explain", "E10"]) == 2
    assert "did you mean one of E101, E102" in capsys.readouterr().err


def _stdin(monkeypatch, data: bytes) -> None:
    import io

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data), encoding="utf-8"))


def test_file_dash_reads_standard_input(monkeypatch, capsys):
    """FILE `-` is standard input for every command that reads a model: named `<stdin>` in messages,
    its imports relative to the working directory; never rewritten in place."""
    nav = EXAMPLES / "navigation"
    monkeypatch.chdir(nav)
    text = (nav / "navigation.vfy").read_bytes()
    for argv, code in ((["check", "-"], 0), (["analyze", "-"], 0), (["prove", "-"], 0), (["fmt", "-"], 0)):
        _stdin(monkeypatch, text)
        assert main(argv) == code, argv
    assert capsys.readouterr().out.endswith(text.decode())  # (fmt: the example is formatted)
    _stdin(monkeypatch, (nav / "navigation-holes.vfy").read_bytes())
    assert main(["synth", "-", "--diff"]) == 0
    assert capsys.readouterr().out.startswith("--- <stdin>\n+++ <stdin> (synthesized)\n")
    for argv in (["synth", "-", "--in-place"], ["fmt", "-", "--in-place"]):
        _stdin(monkeypatch, text)
        assert main(argv) == 2
        assert "--in-place needs a file" in capsys.readouterr().err
    _stdin(monkeypatch, b"component X {\n  task T {\n    wcet 2 ms\n    wcet 3 ms\n  }\n}\n")
    assert main(["check", "-"]) == 2
    assert "--> <stdin>:4:5" in capsys.readouterr().err
    _stdin(monkeypatch, b"\xff\xfe")
    assert main(["check", "-"]) == 2
    assert "error[E003]: <stdin> is not UTF-8 text" in capsys.readouterr().err


def test_python_m_verify_is_the_verify_command():
    """``python -m verify`` runs the same command line (exit codes included) as the ``verify`` script."""
    nav = EXAMPLES / "navigation" / "navigation.vfy"
    done = subprocess.run([sys.executable, "-m", "verify", "check", str(nav)], capture_output=True, text=True)
    assert done.returncode == 0 and "ok (5 components, 1 system)" in done.stdout
    done = subprocess.run([sys.executable, "-m", "verify", "check", str(nav.parent / "missing.vfy")],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "E004" in done.stderr
    # importing the module (as the fuzzing harness does with every module of the package) runs nothing
    done = subprocess.run([sys.executable, "-c", "import verify.__main__"], capture_output=True, text=True)
    assert (done.returncode, done.stdout, done.stderr) == (0, "", "")


def test_check_loads_neither_the_response_time_analysis_nor_the_solvers():
    """`verify check` needs the activation rates of the timing analysis alone (E305/E306/E314): a run
    of it imports neither the response-time analysis, the chain bounds and the executors, nor Z3,
    networkx or Lark; `verify analyze` imports the analysis (start-up, issue 38)."""
    heavy = ("verify.timing.fastrta", "verify.timing.chains", "verify.timing.executors", "z3", "networkx", "lark")
    code = ("import sys, contextlib, io\nfrom verify.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n    code = main(sys.argv[1:])\n"
            f"print(code, [m for m in {heavy!r} if m in sys.modules])")
    nav = str(EXAMPLES / "navigation" / "navigation.vfy")
    for command, loaded in (("check", []), ("analyze", list(heavy[:3]))):
        done = subprocess.run([sys.executable, "-c", code, command, nav], capture_output=True, text=True, check=True)
        assert done.stdout.strip() == f"0 {loaded}", done.stderr


def test_the_command_line_loads_no_language_server_library_until_lsp_runs():
    """Building the parser (`verify --help`, every command) reads `verify lsp`'s options without pygls
    and lsprotocol (their types module alone costs more than half a second to compile)."""
    code = ("import sys, contextlib, io\nfrom verify.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        main(['--help'])\n    except SystemExit:\n        pass\n"
            "print([m for m in ('pygls', 'lsprotocol', 'verify.lsp.transport') if m in sys.modules])")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stderr
