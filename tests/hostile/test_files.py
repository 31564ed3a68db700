"""Hostile input, files (issue 37): every file verify reads or writes obeys one rule (``verify.core.fileaccess``).

An attacker with a pull request controls the files of the checkout, not the command line. Each case
commits a file that leads somewhere else — a symbolic link to a secret outside the project, a FIFO, a
number of thousands of digits, a corrupt cache table — and checks that the run ends in a located
diagnostic (or a correct result), never exit 70 or a wait without end, and that the secret is not in
standard output or standard error in any format (text, JSON, SARIF).
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from verify.frontend import grammar, parse, parsecache
from verify.cli import main

from ..conftest import EXAMPLES
from ..test_smartmdsd import ACTIVITIES, ACTOR, CHAINS, COMPONENT, FILTER, SYSTEM

SECRET = "hostile-files-secret-7f3a9c"
FORMATS = ("text", "json", "sarif")
NAVIGATION = EXAMPLES / "navigation"
needs_fifo = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")


@pytest.fixture
def secret(tmp_path) -> Path:
    """A credentials file outside the project (``tmp_path / "project"``)."""
    path = tmp_path / "outside" / "credentials"
    path.parent.mkdir()
    path.write_text(f"token = \"{SECRET}\"\n{SECRET}\n")
    return path


@pytest.fixture
def project(tmp_path) -> Path:
    """A copy of the navigation example (a configured, valid system) in ``tmp_path / "project"``."""
    directory = tmp_path / "project"
    directory.mkdir()
    for name in ("components.vfy", "navigation.vfy", "navigation-violated.vfy"):
        shutil.copy(NAVIGATION / name, directory / name)
    (directory / ".git").mkdir()  # (the search for pyproject.toml stops here)
    return directory


def run(capsys, *args: str) -> tuple[int, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out + err


def codes(output: str, fmt: str) -> list[str]:
    """The diagnostic codes in an output of format ``fmt``."""
    if fmt == "json":
        return [d["code"] for d in json.loads(output[:output.rindex("}") + 1])["diagnostics"]]
    if fmt == "sarif":
        return [r["ruleId"] for r in json.loads(output[:output.rindex("}") + 1])["runs"][0]["results"]]
    return [line.split("[")[1].split("]")[0] for line in output.splitlines() if line.startswith("error[")]


def run_apart(args: list[str], env: dict[str, str] | None = None,
              timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """``verify ARGS`` in a process of its own: a case that would wait forever fails at the timeout."""
    return subprocess.run([sys.executable, "-m", "verify", *args], capture_output=True, text=True,
                          env={**os.environ, **(env or {})}, timeout=timeout, check=False)


# ------------------------------------------------------------------ pyproject.toml


@pytest.mark.parametrize("command", ["check", "prove"])
@pytest.mark.parametrize("fmt", FORMATS)
def test_a_pyproject_that_links_to_a_secret_is_named_never_quoted(project, secret, capsys, command, fmt):
    (project / "pyproject.toml").symlink_to(secret)
    code, output = run(capsys, command, str(project / "navigation.vfy"), "--format", fmt)
    assert code == 2 and SECRET not in output
    assert "E009" in output and "pyproject.toml is a symbolic link to a file outside its own directory" in output


def test_a_pyproject_that_links_to_the_environment_is_not_read(project, capsys, monkeypatch):
    if not os.path.exists("/proc/self/environ"):
        pytest.skip("needs /proc")
    monkeypatch.setenv("VERIFY_HOSTILE_SECRET", SECRET)
    (project / "pyproject.toml").symlink_to("/proc/self/environ")
    for fmt in FORMATS:
        code, output = run(capsys, "check", str(project / "navigation.vfy"), "--format", fmt)
        assert code == 2 and SECRET not in output and "E009" in output and "PATH=" not in output
        assert "pyproject.toml is a symbolic link to a file outside its own directory" in output


def test_a_pyproject_that_links_inside_its_directory_is_read(project, capsys):
    (project / "lib").mkdir()
    (project / "components.vfy").rename(project / "lib" / "components.vfy")  # (found in `include` only)
    (project / "settings.toml").write_text('[tool.verify]\ninclude = ["lib"]\n')
    (project / "pyproject.toml").symlink_to("settings.toml")
    code, output = run(capsys, "check", str(project / "navigation.vfy"))
    assert code == 0 and output.endswith("navigation.vfy: ok (5 components, 1 system)\n")


@needs_fifo
def test_a_pyproject_that_is_a_fifo_is_refused_without_blocking(project):
    os.mkfifo(project / "pyproject.toml")
    done = run_apart(["check", str(project / "navigation.vfy")])
    assert done.returncode == 2 and "E009" in done.stderr and "is not a regular file" in done.stderr


# ------------------------------------------------------------------ the model named on the command line


@pytest.mark.parametrize("command", ["check", "analyze", "prove"])
@pytest.mark.parametrize("fmt", FORMATS)
def test_a_model_that_links_out_of_its_directory_is_named_never_quoted(project, secret, capsys, command, fmt):
    model = project / "model.vfy"
    model.symlink_to(secret)
    code, output = run(capsys, command, str(model), "--format", fmt)
    assert code == 2 and SECRET not in output
    assert codes(output, fmt) == ["E006"] and "model.vfy is a symbolic link to a file outside" in output


def test_a_model_that_links_to_the_environment_is_not_read(project, capsys, monkeypatch):
    if not os.path.exists("/proc/self/environ"):
        pytest.skip("needs /proc")
    monkeypatch.setenv("VERIFY_HOSTILE_SECRET", SECRET)
    (project / "model.vfy").symlink_to("/proc/self/environ")
    for fmt in FORMATS:
        code, output = run(capsys, "check", str(project / "model.vfy"), "--format", fmt)
        assert code == 2 and SECRET not in output and codes(output, fmt) == ["E006"]


def test_the_rule_holds_for_a_root_given_on_the_command_line(project, secret, capsys):
    (project / "model.vfy").symlink_to(secret)
    code, output = run(capsys, "check", str(project / "model.vfy"), "--root", str(project))
    assert code == 2 and SECRET not in output and "E006" in output
    # a root that holds the target lets the link be followed: then it is read as a model (one token shown)
    code, output = run(capsys, "check", str(project / "model.vfy"), "--root", str(secret.parent.parent))
    assert code == 2 and "E001" in output and output.count(SECRET) <= 1


@pytest.mark.parametrize("mode", ["--check", "--in-place"])
def test_fmt_neither_reads_nor_rewrites_a_model_that_links_out(project, secret, capsys, mode):
    before = secret.read_text()
    (project / "model.vfy").symlink_to(secret)
    code, output = run(capsys, "fmt", mode, str(project / "model.vfy"))
    assert code == 2 and SECRET not in output and codes(output, "text") == ["E006"]
    assert secret.read_text() == before


def test_a_model_that_links_inside_its_directory_is_read(project, capsys):
    (project / "model.vfy").symlink_to("navigation.vfy")
    code, output = run(capsys, "check", str(project / "model.vfy"))
    assert code == 0 and output.endswith("model.vfy: ok (5 components, 1 system)\n")


# ------------------------------------------------------------------ importers' inputs


def smartmdsd_model(directory: Path) -> Path:
    files = {"Sensor.component": COMPONENT, "Filter.component": FILTER, "Actor.component": ACTOR,
             "Small.componentArch": SYSTEM, "Small.activityArch": ACTIVITIES, "Small.causeEffectChain": CHAINS}
    directory.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (directory / name).write_text(text)
    return directory


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_smartmdsd_file_that_links_out_is_named_never_quoted(tmp_path, secret, capsys, fmt):
    model = smartmdsd_model(tmp_path / "model")
    (model / "Stolen.component").symlink_to(secret)
    code, output = run(capsys, "import", "smartmdsd", str(model), "--format", fmt)
    assert code == 2 and SECRET not in output
    assert codes(output, fmt) == ["E006"] and "Stolen.component is a symbolic link to a file outside" in output


def test_a_smartmdsd_file_that_links_to_the_environment_is_not_read(tmp_path, capsys, monkeypatch):
    if not os.path.exists("/proc/self/environ"):
        pytest.skip("needs /proc")
    monkeypatch.setenv("VERIFY_HOSTILE_SECRET", SECRET)
    model = smartmdsd_model(tmp_path / "model")
    (model / "Env.component").symlink_to("/proc/self/environ")
    code, output = run(capsys, "import", "smartmdsd", str(model))
    assert code == 2 and SECRET not in output and codes(output, "text") == ["E006"]


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_caret_file_that_links_out_is_named_never_quoted(tmp_path, secret, capsys, fmt):
    directory = tmp_path / "caret"
    directory.mkdir()
    (directory / "architecture.yaml").symlink_to(secret)
    for named in (directory, directory / "architecture.yaml"):
        code, output = run(capsys, "import", "caret", str(named), "--format", fmt)
        assert code == 2 and SECRET not in output and codes(output, fmt)[0] == "E006"


def test_an_importer_input_that_links_inside_is_read(tmp_path, capsys):
    model = smartmdsd_model(tmp_path / "model")
    (model / "Actor.component").rename(model / "actor.txt")
    (model / "Actor.component").symlink_to("actor.txt")
    code, output = run(capsys, "import", "smartmdsd", str(model))
    # (imported: what the small model leaves to complete is E207, as without the link)
    assert "component Actor" in output and codes(output, "text") == ["E207"]


@needs_fifo
def test_an_importer_input_that_is_a_fifo_is_refused_without_blocking(tmp_path):
    model = smartmdsd_model(tmp_path / "model")
    os.mkfifo(model / "Pipe.component")
    done = run_apart(["import", "smartmdsd", str(model)])
    assert done.returncode == 2 and "E004" in done.stderr and "not a regular file" in done.stderr


# ------------------------------------------------------------------ generators' outputs


@pytest.mark.parametrize("fmt", ["text", "json"])
def test_a_generated_file_that_is_a_link_is_named_never_quoted_nor_written(project, secret, capsys, fmt):
    out = project / "out"
    out.mkdir()
    (out / "CMakeLists.txt").symlink_to(secret)
    for force in ([], ["--force"]):
        code, output = run(capsys, "gen", "ros1", str(project / "navigation.vfy"), "-o", str(out), "--format", fmt,
                           *force)
        assert code == 2 and SECRET not in output and "E601" in output and "CMakeLists.txt is a symbolic link" in output
        assert secret.read_text().count(SECRET) == 2 and sorted(os.listdir(out)) == ["CMakeLists.txt"]


def test_a_directory_link_in_the_output_is_never_written_through(project, tmp_path, capsys):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = project / "out"
    out.mkdir()
    (out / "glue").symlink_to(elsewhere)
    for force in ([], ["--force"]):
        code, output = run(capsys, "gen", "ros1", str(project / "navigation.vfy"), "-o", str(out), *force)
        assert code == 2 and output.count("error[E601]") == 1 and "out/glue is a symbolic link" in output
        assert os.listdir(elsewhere) == [] and os.listdir(out) == ["glue"]


def test_a_user_file_that_is_a_link_is_kept_and_the_rest_generated(project, capsys):
    out = project / "out"
    assert run(capsys, "gen", "ros1", str(project / "navigation.vfy"), "-o", str(out))[0] == 0
    (out / "user" / "Laser.hpp").rename(project / "laser.hpp")
    (out / "user" / "Laser.hpp").symlink_to(project / "laser.hpp")
    (out / "config" / "parameters.yaml").unlink()
    code, output = run(capsys, "gen", "ros1", str(project / "navigation.vfy"), "-o", str(out))
    assert code == 0 and (out / "config" / "parameters.yaml").is_file() and (out / "user" / "Laser.hpp").is_symlink()


# ------------------------------------------------------------------ numbers of any length


def caret_with_period(tmp_path: Path, period: str) -> Path:
    text = (Path(__file__).parent.parent / "caret" / "architecture.yaml").read_text()
    path = tmp_path / "architecture.yaml"
    path.write_text(text.replace("period_ns: 50000000", f"period_ns: {period}", 1))
    return path


@pytest.mark.parametrize("period", ["1" * 5000, "9" * 41, "²"])
def test_a_caret_period_of_any_length_is_a_located_error(tmp_path, capsys, period):
    path = caret_with_period(tmp_path, period)
    code, output = run(capsys, "import", "caret", str(path), "--format", "json")
    (d,) = json.loads(output[:output.rindex("}") + 1])["diagnostics"]
    assert code == 2 and d["code"] == ("E701" if period == "²" else "E005")
    assert (d["file"], d["line"]) == (str(path), 45) and d["column"] == 16


def test_a_caret_period_of_forty_digits_is_read(tmp_path, capsys):
    code, output = run(capsys, "import", "caret", str(caret_with_period(tmp_path, "1" + "0" * 39)))
    # (imported; what the file lacks for timing, the execution times and the executor's thread, is left to do)
    assert "timer 1000000000000000000000000000000 s" in output and "E005" not in output
    assert sorted(set(codes(output, "text"))) == ["E217", "E219"]


@pytest.mark.parametrize(("old", "new", "line", "column", "why"), [
    ("coreNumber 0", "coreNumber " + "7" * 5000, 2, 28, "5,000 characters"),
    ("periodicActFreq 40.0", "periodicActFreq 4" + "0" * 5000, 5, 52, "5,001 characters"),
    ("periodicActFreq 40.0", "periodicActFreq 4e-999999999", 5, 52, "exponent is larger than 40"),
    ("periodicActFreq 40.0", "periodicActFreq 4e99999999999999999999999999999999999", 5, 52, "exponent"),
])
def test_a_smartmdsd_number_of_any_size_is_a_located_error(tmp_path, capsys, old, new, line, column, why):
    model = smartmdsd_model(tmp_path / "model")
    (model / "Small.activityArch").write_text(ACTIVITIES.replace(old, new))
    code, output = run(capsys, "import", "smartmdsd", str(model), "--format", "json")
    (d,) = json.loads(output[:output.rindex("}") + 1])["diagnostics"]
    assert code == 2 and d["code"] == "E005" and why in d["message"]
    assert (d["file"], d["line"], d["column"]) == (str(model / "Small.activityArch"), line, column)


def test_a_dsl_number_of_any_length_is_a_located_error(tmp_path, capsys):
    path = tmp_path / "big.vfy"
    path.write_text("component A {\n  task T {\n    wcet " + "9" * 5000 + " ms\n  }\n}\n")
    code, output = run(capsys, "check", str(path), "--format", "json")
    (d,) = json.loads(output)["diagnostics"]
    assert code == 2 and (d["code"], d["line"], d["column"]) == ("E005", 3, 10)


# ------------------------------------------------------------------ the parser's cache


@pytest.fixture
def cache(monkeypatch, tmp_path):
    """An empty cache home, no parser built yet in this process; returns the fast table's path."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()
    directory = parsecache.private_cache_dir()
    assert directory is not None
    yield Path(parsecache.table_file(directory))
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()


def fresh_parse() -> bool:
    """A parse of the example by a parser loaded anew (from the cache when it holds a valid table)."""
    parse.fast_parser.cache_clear()
    text = (NAVIGATION / "navigation.vfy").read_text()
    return parse.parse_source(text, "navigation.vfy").module is not None


def valid_table(table: Path) -> dict:
    assert fresh_parse()
    return json.loads(table.read_text().partition("\n")[2])


@pytest.mark.parametrize("damage", [
    lambda d: {**d, "rows": [{"NAME": 10**6}] + d["rows"][1:]},  # a state that does not exist
    lambda d: {**d, "rows": [{"NAME": -10**6}] + d["rows"][1:]},  # a rule that does not exist
    lambda d: {**d, "shapes": [[9, "x", 1, [], False]] + d["shapes"][1:]},  # a mode that does not exist
    lambda d: {**d, "shapes": [[0, "x", 1, [[5, False]], False]] + d["shapes"][1:]},  # a child beyond its rule
    lambda d: {**d, "names": [None] * len(d["names"])},  # no callbacks
    lambda d: {**d, "start": len(d["rows"])},
    lambda d: [d],
])
def test_a_corrupt_table_in_valid_json_is_rebuilt(cache, damage):
    damaged = json.dumps(damage(valid_table(cache)))
    for text in (damaged, parsecache.stamped_table(damaged)):  # (changed after it was written, or written so)
        cache.write_text(text)
        assert parsecache.read_table(str(cache)) is None
        assert fresh_parse() and parsecache.read_table(str(cache)) is not None


def test_a_table_changed_after_it_was_written_is_rebuilt(cache):
    valid_table(cache)
    digest, _, body = cache.read_text().partition("\n")
    cache.write_text(digest + "\n" + body.replace('"NAME"', '"NAMES"', 1))
    assert parsecache.read_table(str(cache)) is None and fresh_parse()
    assert parsecache.read_table(str(cache)) is not None


def test_a_link_in_the_cache_is_not_followed(cache, secret):
    cache.symlink_to(secret)
    assert parsecache.read_table(str(cache)) is None
    assert fresh_parse() and not cache.is_symlink() and parsecache.read_table(str(cache)) is not None
    assert secret.read_text().count(SECRET) == 2


@needs_fifo
def test_a_fifo_in_the_cache_blocks_no_run(tmp_path):
    home = tmp_path / "cache"
    env = {"XDG_CACHE_HOME": str(home)}
    assert run_apart(["check", str(NAVIGATION / "navigation.vfy")], env).returncode == 0
    directory = home / parsecache.CACHE_DIR
    names = sorted(os.listdir(directory))
    for name in names:
        os.unlink(directory / name)
        os.mkfifo(directory / name)
    done = run_apart(["check", str(NAVIGATION / "navigation.vfy")], env)
    assert done.returncode == 0, done.stderr
    broken = tmp_path / "broken.vfy"  # (the error path: Lark's parser, from its own cache)
    broken.write_text("component {\n")
    done = run_apart(["check", str(broken)], env)
    assert done.returncode == 2 and "E001" in done.stderr, done.stderr
    assert sorted(os.listdir(directory)) == names and all((directory / n).is_file() for n in names)


# ------------------------------------------------------------------ files named with -o


OUTPUTS = {
    "fmt": lambda model, out: ["fmt", model, "-o", out],
    "prove": lambda model, out: ["prove", model, "--budget", "50", "-o", out],
    "prove --trace-svg": lambda model, out: ["prove", model.replace("navigation.vfy", "navigation-violated.vfy"),
                                             "--budget", "50", "--trace-svg", out],
    "report": lambda model, out: ["report", model, "--budget", "0", "-o", out],
    "graph": lambda model, out: ["graph", model, "--format", "dot", "-o", out],
    "export": lambda model, out: ["export", "caret", model, "-o", os.path.dirname(out)],
}


def output_path(project: Path, command: str) -> Path:
    return project / "export" / "architecture.yaml" if command == "export" else project / "out.txt"


@pytest.mark.parametrize("command", sorted(OUTPUTS))
def test_an_output_that_is_a_link_to_nothing_creates_nothing_outside(project, tmp_path, capsys, command):
    out = output_path(project, command)
    out.parent.mkdir(exist_ok=True)
    target = tmp_path / "outside" / "planted"
    target.parent.mkdir(exist_ok=True)
    out.symlink_to(target)
    code, output = run(capsys, *OUTPUTS[command](str(project / "navigation.vfy"), str(out)))
    assert code == 2 and "exist" in output and not target.exists() and out.is_symlink()


@pytest.mark.parametrize("command", sorted(OUTPUTS))
def test_an_output_that_is_a_link_is_replaced_with_force_never_written_through(project, secret, capsys, command):
    out = output_path(project, command)
    out.parent.mkdir(exist_ok=True)
    out.symlink_to(secret)
    before = secret.read_text()
    code, output = run(capsys, *OUTPUTS[command](str(project / "navigation.vfy"), str(out)), "--force")
    assert code == (1 if command == "prove --trace-svg" else 0)  # (a violated spec: its counterexample drawn)
    assert not out.is_symlink() and out.is_file() and SECRET not in out.read_text()
    assert secret.read_text() == before and SECRET not in output


def test_a_cache_directory_a_checkout_made_is_never_used(tmp_path, monkeypatch):
    """``$XDG_CACHE_HOME`` inside a repository: a pull request could commit the cache directory with a
    Lark cache (a pickle) in it; git makes directories 0755, verify makes its own 0700."""
    import lark

    planted = tmp_path / "checkout" / ".cache" / parsecache.CACHE_DIR
    planted.mkdir(parents=True)
    os.chmod(planted, 0o755)
    bait = planted / f"lark-{lark.__version__}-parser.cache"
    bait.write_bytes(b"not a pickle of a parser\n")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "checkout" / ".cache"))
    assert parsecache.private_cache_dir() is None and grammar.lark_cache_file() is False
    os.chmod(planted, 0o700)
    assert parsecache.private_cache_dir() == str(planted)
