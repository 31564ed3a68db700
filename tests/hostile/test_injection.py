"""Hostile input, injection (issue 37): what a model, another tool's file or a file name holds never
reaches the terminal or a generated file raw (``verify.core.sanitize``, specs/diagnostics.md "Text from
untrusted input", specs/codegen.md "Names").

Each test runs the command as a user would and looks at what comes out: no control character, no line
that a crafted value starts (a CI log's ``::error`` workflow command), no statement a name adds to an
imported model, YAML whose every name loads as a string, C++ that compiles.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

import verify
from verify.cli import main
from verify.gen import ros1

from ..conftest import in_ci

#: a control character a terminal acts on (C0 but newline and tab, DEL, C1)
CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u2028\u2029]")
#: what a crafted value tries: end the line, start a CI workflow command, recolour, ring, return
PAYLOAD = "\n::error title=pwned::injected\x1b[31m\x07\r"


def _lines_started_by_a_value(text: str) -> list[str]:
    """The lines of ``text`` that a crafted value started (every line break Python knows counts)."""
    return [line for line in text.splitlines() if line.startswith("::")]


def _assert_clean(text: str) -> None:
    assert not CONTROL.search(text), repr(CONTROL.search(text))
    assert not _lines_started_by_a_value(text), _lines_started_by_a_value(text)


# ------------------------------------------------------------------ printed: diagnostics and reports


def test_a_snippet_shows_the_models_control_characters_escaped_and_underlines_the_right_token(tmp_path, capsys):
    model = tmp_path / "main.vfy"
    model.write_text("component C {\n  /*\x1b]0;owned\x07\x1b[2J\r*/ bogus\n}\n", encoding="utf-8")
    assert main(["check", str(model)]) == 2
    err = capsys.readouterr().err
    _assert_clean(err)
    shown = next(line for line in err.splitlines() if line.startswith("2 | "))
    underline = err.splitlines()[err.splitlines().index(shown) + 1]
    assert "\\x1b]0;owned\\x07\\x1b[2J\\r" in shown
    assert underline.index("^") == shown.index("bogus")


def test_a_file_name_never_starts_a_line_of_its_own(tmp_path, capsys):
    bad = tmp_path / f"m{PAYLOAD}.vfy"
    bad.write_text("component C {\n  bogus\n}\n", encoding="utf-8")
    good = tmp_path / f"ok{PAYLOAD}.vfy"
    good.write_text("component C {\n}\n", encoding="utf-8")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    _assert_clean(err)
    assert "m\\n::error title=pwned::injected\\x1b[31m\\x07\\r.vfy:2:3" in err
    assert main(["check", str(good)]) == 0
    out = capsys.readouterr().out
    _assert_clean(out)
    assert out.count("\n") == 1 and out.endswith(": ok (1 component, 0 systems)\n")


def test_a_usage_error_naming_a_file_stays_one_line(tmp_path, capsys):
    model = tmp_path / "main.vfy"
    model.write_text("component C {\n}\nsystem S {\n  core k\n  instance c : C on k\n}\n", encoding="utf-8")
    taken = tmp_path / f"graph{PAYLOAD}.dot"
    taken.write_text("mine", encoding="utf-8")
    assert main(["graph", str(model), "-o", str(taken)]) == 2
    err = capsys.readouterr().err
    _assert_clean(err)
    assert err.count("\n") == 1 and "exists; refusing to overwrite it" in err
    assert taken.read_text(encoding="utf-8") == "mine"


def test_json_keeps_the_file_name_exact_and_escaped(tmp_path, capsys):
    bad = tmp_path / f"m{PAYLOAD}.vfy"
    bad.write_text("component C {\n  bogus\n}\n", encoding="utf-8")
    assert main(["check", str(bad), "--format", "json"]) == 2
    out = capsys.readouterr().out
    _assert_clean(out)
    assert json.loads(out)["diagnostics"][0]["file"] == str(bad)


def _caret_file(directory: Path, node: str, callback: str) -> Path:
    path = directory / "architecture.yaml"
    path.write_text(yaml.safe_dump({"named_paths": [], "executors": [], "nodes": [{
        "node_name": node,
        "callbacks": [{"callback_name": callback, "callback_type": "timer_callback", "period_ns": 1000000,
                       "symbol": "s"}]}]}), encoding="utf-8")
    return path


EVIL_NODE = '/a\nimport "evil.vfy"\ncomponent Evil {}' + PAYLOAD
EVIL_CALLBACK = "/a/cb\n}\ncomponent Evil2 {\n"


def test_sarif_message_texts_of_a_caret_name_hold_no_control_character(tmp_path, capsys):
    arch = _caret_file(tmp_path, EVIL_NODE, EVIL_CALLBACK)
    main(["import", "caret", str(arch), "-o", str(tmp_path / "out.vfy"), "--format", "sarif"])
    out = capsys.readouterr().out
    results = json.loads(out)["runs"][0]["results"]
    texts = [r["message"]["text"] for r in results]
    assert any("evil.vfy" in t for t in texts)
    for text in texts:
        _assert_clean(text)
        assert all(not line.startswith(("import", "component")) for line in text.split("\n"))


# ------------------------------------------------------------------ written: imported models


def test_a_caret_name_cannot_add_an_import_or_a_component(tmp_path, capsys):
    arch = _caret_file(tmp_path, EVIL_NODE, EVIL_CALLBACK)
    out = tmp_path / "out.vfy"
    assert main(["import", "caret", str(arch), "-o", str(out)]) == 2  # (written, but incomplete: no wcet)
    captured = capsys.readouterr()
    _assert_clean(captured.out + captured.err)
    text = out.read_text(encoding="utf-8")
    _assert_clean(text)
    assert not [line for line in text.splitlines() if line.lstrip().startswith("import")]
    result = verify.load_text(text, "out.vfy")
    assert [c.name.text for c in result.project.components] == ["AImportEvilVfyComponentEvilErrorTitlePwnedInjected31m"]
    assert "// node /a\\nimport \"evil.vfy\"\\ncomponent Evil {}\\n::error" in text


SMARTMDSD_COMPONENT = """ComponentDefinition Actor {
\tActivity Act {
\t\tDefaultTrigger PeriodicTimer 20.0 Hz;
\t}
}
"""
SMARTMDSD_SYSTEM = """SystemComponentArchitecture Small {
\tComponentInstance a instantiates Actor {
\t}
}
"""


def test_a_smartmdsd_file_name_cannot_add_an_import_or_a_component(tmp_path, capsys):
    models = tmp_path / "models"
    models.mkdir()
    (models / f'x\nimport "evil.vfy"\ncomponent Evil {{}}{PAYLOAD}.component').write_text(SMARTMDSD_COMPONENT)
    (models / f"S{PAYLOAD}.componentArch").write_text(SMARTMDSD_SYSTEM)
    out = tmp_path / "out.vfy"
    main(["import", "smartmdsd", str(models), "-o", str(out)])
    captured = capsys.readouterr()
    _assert_clean(captured.out + captured.err)
    text = out.read_text(encoding="utf-8")
    _assert_clean(text)
    result = verify.load_text(text, "out.vfy")
    assert [c.name.text for c in result.project.components] == ["Actor"]
    assert [s.name.text for s in result.project.systems] == ["Small"]
    assert not [line for line in text.splitlines() if line.lstrip().startswith("import")]


# ------------------------------------------------------------------ written: generated ROS 1 code

#: names YAML 1.1 reads as booleans and null, a component and a message type named as the glue's
#: namespaces, ports named as macros and as the glue's namespace, a task named as a keyword
HOSTILE = """
component glue {
  out SIGINT : yes
  out msg : null
  out EOF : NULL
  task on {
    produces SIGINT, msg, EOF
    wcet 1 ms
  }
}
component delete {
  in x : yes
  in errno : NULL
  task True {
    reads x
    reads errno optional
    wcet 1 ms
  }
}
component msg {
  in y : null
  task t {
    reads y
    wcet 1 ms
  }
}
system Hostile {
  core cpu0
  instance yes : glue on cpu0 {
    task on priority 2 timer 10 ms
  }
  instance null : delete on cpu0 {
    task True priority 1 trigger x
  }
  instance nodes : msg on cpu0 {
    task t priority 1 trigger y
  }
  connect yes.SIGINT -> null.x
  connect yes.EOF -> null.errno
  connect yes.msg -> nodes.y
}
"""


def _generated(tmp_path: Path, text: str = HOSTILE) -> Path:
    (tmp_path / "main.vfy").write_text(text, encoding="utf-8")
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(tmp_path / "main.vfy"), "-o", str(project)]) == 0
    return project


def _strings(node: object) -> list[object]:
    """Every key of ``node`` (a loaded YAML document) and every value that is neither a number nor a collection."""
    if isinstance(node, dict):
        return [k for k in node] + [x for v in node.values() for x in _strings(v)]
    if isinstance(node, list):
        return [x for v in node for x in _strings(v)]
    return [] if isinstance(node, int) and not isinstance(node, bool) else [node]


def test_parameters_load_every_name_as_a_string(tmp_path, capsys):
    project = _generated(tmp_path)
    params = yaml.safe_load((project / "config" / "parameters.yaml").read_text(encoding="utf-8"))
    assert all(isinstance(x, str) for x in _strings(params)), [x for x in _strings(params) if not isinstance(x, str)]
    system = params["Hostile"]
    assert system["nodes"] == ["yes", "null", "nodes_"]
    assert system["null"]["tasks"]["True"]["trigger"] == "x"
    assert system["null"]["topics"] == {"x": "/Hostile/yes/SIGINT", "errno": "/Hostile/yes/EOF"}
    assert system["yes"]["subscribers"] == {"SIGINT": 1, "msg": 1, "EOF": 1}


def test_reserved_names_are_mangled_in_the_cpp_code(tmp_path, capsys):
    project = _generated(tmp_path)
    glue = (project / "glue" / "glue_.hpp").read_text(encoding="utf-8")
    assert "class glue_ : public verify_ros1::Component" in glue
    assert "virtual void on_on(msg::yes& SIGINT_, msg::null& msg_, msg::NULL_& EOF_) = 0;" in glue
    assert (project / "user" / "types" / "NULL_.hpp").is_file() and (project / "glue" / "msg_.hpp").is_file()
    assert "errno_" in (project / "glue" / "delete_.hpp").read_text(encoding="utf-8")
    launch = (project / "launch" / "Hostile.launch").read_text(encoding="utf-8")
    assert 'type="delete__node" name="null"' in launch and 'name="nodes_"' in launch


@pytest.mark.parametrize("text, code_line, other_line, says", [
    ("component delete {\n}\ncomponent delete_ {\n}\n", 3, 1, "component `delete_` becomes `delete_` in the "
     "generated code, as component `delete` does"),
    ("component Foo {\n}\ncomponent foo {\n}\n", 3, 1, "which a case-insensitive file system takes for `Foo`"),
    ("component C {\n  in delete : T\n  in delete_ : T\n}\n", 3, 2, "component `C`'s port `delete_` becomes"),
    ("component C {\n}\ncomponent D {\n  in a : msg\n  in b : msg_\n}\n", 5, 4, "message type `msg_` becomes"),
])
def test_names_that_become_one_are_refused_where_they_stand_and_nothing_is_written(tmp_path, capsys, text,
                                                                                   code_line, other_line, says):
    system = "system S {\n  core k\n" + "".join(
        f"  instance i{n} : {name} on k\n" for n, name in enumerate(re.findall(r"component (\w+)", text))) + "}\n"
    (tmp_path / "main.vfy").write_text(text + system, encoding="utf-8")
    assert main(["gen", "ros1", str(tmp_path / "main.vfy"), "-o", str(tmp_path / "out"), "--format", "json"]) == 2
    found = json.loads(capsys.readouterr().out)["diagnostics"]
    assert [d["code"] for d in found] == ["E603"]
    assert found[0]["line"] == code_line and found[0]["secondary"][0]["line"] == other_line
    assert says in found[0]["message"]
    assert not (tmp_path / "out").exists()


def test_instances_that_become_one_node_are_refused(tmp_path, capsys):
    (tmp_path / "main.vfy").write_text("component C {\n}\nsystem S {\n  core k\n  instance _a : C on k\n"
                                       "  instance n_a : C on k\n}\n", encoding="utf-8")
    assert main(["gen", "ros1", str(tmp_path / "main.vfy"), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "error[E603]: instance `n_a` becomes `n_a` in the generated code, as instance `_a` does" in err


def test_a_write_that_fails_midway_reports_exactly_what_it_wrote(tmp_path, capsys, monkeypatch):
    from verify.gen import tree

    calls = []
    real = os.replace

    def failing(src: str, dst: str) -> None:
        calls.append(dst)
        if len(calls) == 4:
            raise OSError(28, "No space left on device", dst)
        real(src, dst)

    monkeypatch.setattr(tree.os, "replace", failing)
    (tmp_path / "main.vfy").write_text(HOSTILE, encoding="utf-8")
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(tmp_path / "main.vfy"), "-o", str(project)]) == 2
    err = capsys.readouterr().err
    assert "nothing was changed" not in err
    noted = re.findall(r"= note: (?:made|written) before the failure: (.*)", err)
    on_disk = sorted([str(project)] + [str(p) for p in project.rglob("*")])
    assert sorted(noted) == on_disk and len([p for p in noted if os.path.isfile(p)]) == 3
    assert all(os.path.isdir(p) for p in re.findall(r"= note: made before the failure: (.*)", err))
    assert f"cannot write {calls[-1]}: No space left on device" in err


def test_a_user_file_failing_midway_is_not_left_half_written(tmp_path, capsys, monkeypatch):
    import os

    class Full:
        """A file whose write fails as on a full disk (after it was created)."""

        def __init__(self, fh, path):
            self.fh, self.path = fh, path

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

        def write(self, data):
            self.fh.write(data[:10])
            raise OSError(28, "No space left on device", self.path)

    real_fdopen = os.fdopen

    def opening(fd, mode="r", *args, **kwargs):
        path = os.readlink(f"/proc/self/fd/{fd}")
        fh = real_fdopen(fd, mode, *args, **kwargs)
        return Full(fh, path) if "w" in mode and path.endswith("user.cmake") else fh

    monkeypatch.setattr(os, "fdopen", opening)
    (tmp_path / "main.vfy").write_text(HOSTILE, encoding="utf-8")
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(tmp_path / "main.vfy"), "-o", str(project)]) == 2
    err = capsys.readouterr().err
    assert f"cannot write {project / 'user' / 'user.cmake'}: No space left on device" in err
    assert not (project / "user" / "user.cmake").exists()
    noted = re.findall(r"= note: (?:made|written) before the failure: (.*)", err)
    assert sorted(noted) == sorted([str(project)] + [str(p) for p in project.rglob("*")])
    assert len(noted) > 20


def test_an_export_failing_midway_reports_the_file_it_wrote(tmp_path, capsys):
    from ..conftest import EXAMPLES

    out = tmp_path / "out"
    (out / "Navigation.componentArch").mkdir(parents=True)  # (the second file cannot be written)
    assert main(["export", "smartmdsd", str(EXAMPLES / "navigation" / "navigation.vfy"), "-o", str(out),
                 "--force"]) == 2
    err = capsys.readouterr().err
    assert f"error[E004]: cannot write {out / 'Navigation.componentArch'}: Is a directory" in err
    assert re.findall(r"= note: written before the failure: (.*)", err) == [str(out / "Navigation.activityArch")]
    assert "before the failure only the path in the note changed" in err
    assert sorted(p.name for p in out.iterdir()) == ["Navigation.activityArch", "Navigation.componentArch"]


@pytest.mark.slow
def test_the_hostile_names_glue_compiles(tmp_path, capsys):
    """Every generated translation unit of the hostile model, in one (``main`` renamed per unit), checked
    by g++ against Debian's ROS 1 headers with the warnings the generated CMakeLists.txt turns on."""
    compiler = shutil.which("g++")
    if compiler is None or not Path("/usr/include/ros/ros.h").is_file():
        if in_ci():
            pytest.fail("g++ or ROS 1 missing (scripts/install-tools installs them)")
        pytest.skip("g++ or ROS 1 missing")
    project = _generated(tmp_path)
    mains = sorted((project / "glue").glob("*_main.cpp"))
    assert len(mains) == 3
    unit = project / "all_units.cpp"
    unit.write_text("".join(f'#define main main_{k}\n#include "{m.relative_to(project).as_posix()}"\n#undef main\n'
                            for k, m in enumerate(mains)), encoding="utf-8")
    built = subprocess.run([compiler, "-std=c++17", "-fsyntax-only", "-Wall", "-Wextra", "-Werror",
                            f"-I{project / 'include'}", f"-I{project}", f"-I{project / 'user'}", str(unit)],
                           capture_output=True, text=True, timeout=600)
    assert built.returncode == 0, built.stderr[-4000:]


def test_the_generator_names_what_it_mangles():
    for name in ("SIGINT", "NULL", "EOF", "ROS_INFO", "M_PIf", "errno", "assert", "glue", "msg", "ros", "std",
                 "delete", "_x", "a__b", "st_mtime"):
        assert ros1.cpp(name) == name + "_", name
    for name in ("scan", "Laser", "GPSDriver", "A", "x1"):
        assert ros1.cpp(name) == name, name


@pytest.mark.parametrize("value", ["yes", "on", "null", "True", "~", "1e3", "0x10", 'a"b\\c', "x\ny\x1b[31m\x07\r",
                                   "tab\there", "é€😀", "\x85\u2028", ""])
def test_a_yaml_string_loads_back_as_the_same_string(value):
    from verify.core.sanitize import yaml_string

    assert yaml.safe_load(f"key: {yaml_string(value)}") == {"key": value}
    assert "\n" not in yaml_string(value)


@pytest.mark.parametrize("value", ['a"b', "back\\slash", "x\ny", "\x1b[31m", "é", "??="])
def test_a_cpp_string_literal_holds_printable_ascii_only(value):
    from verify.core.sanitize import c_string

    literal = c_string(value)
    assert literal.startswith('"') and literal.endswith('"')
    assert all(0x20 <= ord(ch) < 0x7F for ch in literal)
    body = literal[1:-1]
    assert '"' not in body.replace('\\"', "") and "??" not in body
    # the literal means the value's UTF-8 bytes: undo the escapes as a C++ compiler does
    decoded = re.sub(rb"\\([0-7]{3}|.)", lambda m: bytes([int(m[1], 8)]) if len(m[1]) == 3 else m[1],
                     body.encode("ascii"))
    assert decoded == value.encode("utf-8")
