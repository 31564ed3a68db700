"""Untrusted input (docs/guide/untrusted.md): imports are confined to the allowed
directories and refused before any file outside is opened; nothing of a file that is not a model is
shown but its offending token; snippets are cut to a bounded width; every limit is a located E008."""
from __future__ import annotations

import builtins
import json
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.cli import main
from verify.core.limits import Limits
from verify.core.source import SNIPPET_WIDTH

COMPONENT = "component Laser {\n  out scan : Scan\n  task T {\n    produces scan\n    wcet 1 ms\n  }\n}\n"
SECRET = "hunter2-very-secret-value"


@pytest.fixture
def opened(monkeypatch):
    """Every path opened for reading during the test (``os.open`` and ``open``), as real paths (the parser
    is loaded before: its tables come from the user's cache directory)."""
    verify.load_text(COMPONENT)
    seen: list[str] = []
    real_os_open, real_open = os.open, builtins.open

    def os_open(path, flags, *args, **kwargs):
        seen.append(os.path.realpath(path))
        return real_os_open(path, flags, *args, **kwargs)

    def open_(file, *args, **kwargs):
        if isinstance(file, (str, bytes, os.PathLike)):
            seen.append(os.path.realpath(file))
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(os, "open", os_open)
    monkeypatch.setattr(builtins, "open", open_)
    return seen


def _codes(result) -> list[str]:
    return [d.code for d in result.diagnostics]


def _project(tmp_path: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return tmp_path / next(iter(files))


# ------------------------------------------------------------------ confined imports


@pytest.mark.parametrize("target", ["/proc/self/environ", "/etc/passwd", "/etc/hostname.vfy"])
def test_an_absolute_import_is_refused_before_anything_is_opened(tmp_path, opened, target):
    main_file = _project(tmp_path, {"main.vfy": f'import "{target}"\n'})
    result = verify.load(str(main_file))
    assert _codes(result) == ["E006"]
    (d,) = result.diagnostics
    assert (d.span.line, d.span.column) == (1, 8) and "absolute" in d.message
    assert not [p for p in opened if not p.startswith(str(tmp_path.resolve()))], opened


def test_the_environment_of_the_process_is_never_printed(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("VERIFY_TEST_SECRET", SECRET)
    main_file = _project(tmp_path, {"main.vfy": 'import "/proc/self/environ"\n' + COMPONENT})
    for command in (["check"], ["analyze"], ["prove"], ["synth"], ["prove", "--format", "sarif"],
                    ["check", "--format", "json"], ["prove", "--format", "json"]):
        assert main([*command, str(main_file)]) == 2
        out, err = capsys.readouterr()
        assert SECRET not in out + err and "E006" in out + err
    if os.path.exists("/proc/self/environ"):  # the file itself, named on the command line: one token shown
        assert main(["check", "/proc/self/environ"]) == 2
        out, err = capsys.readouterr()
        assert SECRET not in out + err and "error[E001]" in err and err.count("error[") == 1


@pytest.mark.parametrize("target", ["../../../../../../../../etc/passwd.vfy", "../outside.vfy", "a/../../b.vfy"])
def test_a_dotdot_that_climbs_out_is_refused(tmp_path, opened, target):
    project = tmp_path / "project"
    main_file = _project(project, {"main.vfy": f'import "{target}"\n', "a/x.vfy": ""})
    (tmp_path / "outside.vfy").write_text(COMPONENT)
    result = verify.load(str(main_file))
    assert _codes(result) == ["E006"] and "leads outside the project root" in result.diagnostics[0].message
    assert str((tmp_path / "outside.vfy").resolve()) not in opened


def test_a_dotdot_that_stays_inside_is_followed(tmp_path):
    main_file = _project(tmp_path, {"main.vfy": 'import "sub/../lib/laser.vfy"\n', "lib/laser.vfy": COMPONENT})
    result = verify.load(str(main_file))
    assert result.ok and [c.name.text for c in result.project.components] == ["Laser"]


def test_a_symbolic_link_that_leads_out_is_refused_and_one_inside_followed(tmp_path, opened):
    outside = tmp_path / "secret.vfy"
    outside.write_text(COMPONENT.replace("Laser", "Secret"))
    project = tmp_path / "project"
    main_file = _project(project, {"main.vfy": 'import "link.vfy"\nimport "dir/inner.vfy"\n',
                                   "lib/laser.vfy": COMPONENT})
    (project / "link.vfy").symlink_to(outside)
    (project / "dir").symlink_to(project / "lib")
    (project / "lib" / "inner.vfy").symlink_to(project / "lib" / "laser.vfy")
    result = verify.load(str(main_file))
    assert _codes(result) == ["E006"] and "symbolic link" in result.diagnostics[0].message
    assert str(outside.resolve()) not in opened
    assert [c.name.text for c in result.project.components] == ["Laser"]
    # a directory link that leads out is refused the same way
    (project / "out").symlink_to(tmp_path)
    (project / "main.vfy").write_text('import "out/secret.vfy"\n')
    assert _codes(verify.load(str(main_file))) == ["E006"]


@pytest.mark.parametrize("target", ["components.txt", ".git/config", "Makefile", "x.vfy.bak"])
def test_an_import_of_a_file_that_is_not_vfy_is_refused(tmp_path, opened, target):
    main_file = _project(tmp_path, {"main.vfy": f'import "{target}"\n', target: "[core]\n\ttoken = " + SECRET})
    result = verify.load(str(main_file))
    assert _codes(result) == ["E007"]
    assert str((tmp_path / target).resolve()) not in opened


def test_root_widens_and_include_adds_library_directories(tmp_path, capsys):
    models = tmp_path / "repo" / "models"
    main_file = _project(models, {"main.vfy": 'import "../common/laser.vfy"\nimport "camera.vfy"\n'})
    _project(tmp_path / "repo" / "common", {"laser.vfy": COMPONENT})
    _project(tmp_path / "lib", {"camera.vfy": 'import "sub/cam.vfy"\n',
                                "sub/cam.vfy": COMPONENT.replace("Laser", "Camera")})
    assert _codes(verify.load(str(main_file))) == ["E006", "E004"]  # (camera.vfy: not in the project)
    result = verify.load(str(main_file), root=str(tmp_path / "repo"), include=(str(tmp_path / "lib"),))
    assert result.ok, result.diagnostics
    assert sorted(c.name.text for c in result.project.components) == ["Camera", "Laser"]
    assert main(["check", str(main_file), "--root", str(tmp_path / "repo"), "--include", str(tmp_path / "lib")]) == 0
    capsys.readouterr()
    # the file named on the command line must lie inside --root
    assert main(["check", str(main_file), "--root", str(tmp_path / "lib")]) == 2
    assert "E006" in capsys.readouterr().err
    assert main(["check", str(main_file), "--include", str(tmp_path / "nope")]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_a_library_directory_confines_its_own_imports(tmp_path):
    lib = tmp_path / "lib"
    _project(lib, {"camera.vfy": 'import "../secret.vfy"\n'})
    (tmp_path / "secret.vfy").write_text(COMPONENT)
    main_file = _project(tmp_path / "project", {"main.vfy": 'import "camera.vfy"\n'})
    result = verify.load(str(main_file), include=(str(lib),))
    assert _codes(result) == ["E006"] and result.diagnostics[0].span.file.endswith("camera.vfy")


def test_pyproject_settings_choose_root_and_include_within_their_directory(tmp_path, capsys):
    repo = tmp_path / "repo"
    main_file = _project(repo / "models", {"main.vfy": 'import "../common/laser.vfy"\nimport "camera.vfy"\n'})
    _project(repo, {"common/laser.vfy": COMPONENT, "vendor/camera.vfy": COMPONENT.replace("Laser", "Camera")})
    (repo / ".git").mkdir()
    (repo / "pyproject.toml").write_text('[project]\nname = "robot"\n\n[tool.verify]\nroot = "."\n'
                                         'include = ["vendor"]\n')
    result = verify.load(str(main_file))
    assert result.ok, result.diagnostics
    assert verify.load(str(main_file), config=False).ok is False  # (without the settings: E006)
    # a setting that leads out of the pyproject's directory is refused, located in pyproject.toml
    (repo / "pyproject.toml").write_text('[tool.verify]\ninclude = ["vendor", "../../etc"]\n')
    result = verify.load(str(main_file))
    assert _codes(result) == ["E009"]
    (d,) = result.diagnostics
    assert d.span.file.endswith("pyproject.toml") and (d.span.line, d.span.column) == (2, 1)
    assert main(["check", str(main_file)]) == 2
    assert "pyproject.toml:2:1" in capsys.readouterr().err
    for bad, word in (('[tool.verify]\nroots = "."\n', "did you mean `root`"), ("[tool.verify\n", "not valid TOML"),
                      ("[tool.verify]\nroot = 3\n", "must be a string"), ('[tool]\nverify = "x"\n', "a table")):
        (repo / "pyproject.toml").write_text(bad)
        result = verify.load(str(main_file))
        assert _codes(result) == ["E009"]
        (d,) = result.diagnostics
        assert word in (d.message + (d.help or ""))


def test_the_search_for_pyproject_stops_at_the_repository(tmp_path):
    (tmp_path / "pyproject.toml").write_text('[tool.verify]\nroot = "."\n')
    repo = tmp_path / "repo"
    main_file = _project(repo / "models", {"main.vfy": 'import "../laser.vfy"\n'})
    (repo / "laser.vfy").write_text(COMPONENT)
    (repo / ".git").mkdir()
    assert _codes(verify.load(str(main_file))) == ["E006"]  # the pyproject above the repository is not read
    (repo / ".git").rmdir()
    assert verify.load(str(main_file)).ok


_SEGMENTS = st.sampled_from(["..", ".", "a", "b", "link", "out", "x.vfy", "", "secret.vfy", "lib", "/"])


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(paths=st.lists(st.lists(_SEGMENTS, min_size=1, max_size=6).map("/".join), min_size=1, max_size=4))
def test_no_import_ever_opens_a_file_outside_the_allowed_directories(tmp_path_factory, paths):
    base = tmp_path_factory.mktemp("confine")
    (base / "secret.vfy").write_text(COMPONENT)
    project = base / "project"
    (project / "a" / "b").mkdir(parents=True)
    (project / "lib").mkdir()
    (project / "out").symlink_to(base)
    (project / "link").symlink_to(base / "secret.vfy")
    (project / "a" / "link").symlink_to(project / "lib")
    for name in ("x.vfy", "a/x.vfy", "a/b/x.vfy", "lib/x.vfy"):
        (project / name).write_text("".join(f'import "{p}"\n' for p in paths if '"' not in p))
    main_file = project / "main.vfy"
    main_file.write_text("".join(f'import "{p}"\n' for p in paths))
    seen: list[str] = []
    real_os_open = os.open

    def os_open(path, flags, *args, **kwargs):
        seen.append(os.path.realpath(path))
        return real_os_open(path, flags, *args, **kwargs)

    os.open = os_open
    try:
        verify.load(str(main_file), config=False)
    finally:
        os.open = real_os_open
    allowed = str(project.resolve()) + os.sep
    assert all(p.startswith(allowed) for p in seen), seen


# ------------------------------------------------------------------ no echo


def test_a_file_that_is_not_a_model_shows_only_its_first_token(tmp_path, capsys):
    passwd = "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n"
    env = f"IS_CI=yes TOKEN={SECRET} HOME=/root\n"
    for name, text, token in (("passwd.vfy", passwd, "root"), ("env.vfy", env, "IS_CI"),
                              ("ini.vfy", f"[core]\n\ttoken = {SECRET}\n", "["),
                              ("comment.vfy", f"/* {SECRET}", "/*")):
        path = tmp_path / name
        path.write_text(text)
        assert main(["check", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.count("error[") == 1, err
        assert SECRET not in err and "daemon" not in err and "x:0:0" not in err, err
        snippet = [ln for ln in err.splitlines() if ln.startswith("1 |")]
        assert snippet == ["1 | " + token], err


def test_a_binary_file_shows_nothing_but_the_offending_byte(tmp_path, capsys):
    path = tmp_path / "blob.vfy"
    path.write_bytes(f"KEY={SECRET}".encode() + b"\xff\xfe rest")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert "E003" in err and SECRET not in err and "KEY" not in err
    # a model saved as Latin-1 still shows its line: it is the project's own text
    path.write_bytes("// Télémètre\ncomponent A { }\n".encode("latin-1"))
    assert main(["check", str(path)]) == 2
    assert "1 | // T" in capsys.readouterr().err


def test_snippets_are_cut_to_a_bounded_width_in_every_renderer(tmp_path, capsys):
    long_name = "x" * 5000
    path = tmp_path / "long.vfy"
    path.write_text("component A {\n  " + "in p : T " * 800 + "task T { reads " + long_name + " wcet 1 ms }\n}\n")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    snippet_lines = [ln for ln in err.splitlines() if " | " in ln]
    assert snippet_lines and all(len(ln) <= SNIPPET_WIDTH + 40 for ln in snippet_lines), err
    assert "…" in err
    assert main(["check", str(path), "--format", "json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert all(long_name not in json.dumps(d["label"]) for d in doc["diagnostics"])


# ------------------------------------------------------------------ limits


def test_every_limit_is_a_located_error(tmp_path):
    big = _project(tmp_path / "big", {"main.vfy": 'import "laser.vfy"\n', "laser.vfy": COMPONENT})
    result = verify.load(str(big), limits=Limits(file_bytes=40))
    assert _codes(result) == ["E008"] and "limit for one file" in result.diagnostics[0].message
    assert (result.diagnostics[0].span.line, result.diagnostics[0].span.file) == (1, str(big))
    result = verify.load(str(big), limits=Limits(project_bytes=len(COMPONENT) + 5))
    assert _codes(result) == ["E008"] and "limit for one project" in result.diagnostics[0].message
    assert _codes(verify.load(str(big), limits=Limits(files=1))) == ["E008"]
    chain = {f"f{i}.vfy": f'import "f{i + 1}.vfy"\n' for i in range(5)} | {"f5.vfy": COMPONENT}
    deep = _project(tmp_path / "deep", chain)
    assert verify.load(str(deep), limits=Limits(import_depth=5)).ok
    result = verify.load(str(deep), limits=Limits(import_depth=4))
    assert _codes(result) == ["E008"] and result.diagnostics[0].span.file.endswith("f4.vfy")


@pytest.mark.parametrize("broken", [False, True])
def test_the_token_limit_holds_on_both_parser_paths(broken):
    text = COMPONENT * 3 + ("component B { !!! }" if broken else "")  # (17 tokens a component)
    tokens = 3 * 17 + (4 if broken else 0)
    assert not [d for d in verify.load_text(text, limits=Limits(tokens=tokens)).diagnostics if d.code == "E008"]
    result = verify.load_text(text, limits=Limits(tokens=20))
    e008 = [d for d in result.diagnostics if d.code == "E008"]
    # the 21st token: `out` on line 9, the fourth of the second component
    assert len(e008) == 1 and (e008[0].span.line, e008[0].span.column) == (9, 3), result.diagnostics


def test_a_file_above_the_size_limit_is_not_read_whole(tmp_path, opened):
    path = tmp_path / "huge.vfy"
    with open(path, "wb") as fh:
        fh.truncate(Limits().file_bytes + 10)
    result = verify.load(str(path))
    assert _codes(result) == ["E008"] and "16 MiB" in result.diagnostics[0].message


# ------------------------------------------------------------------ the editor's overlay


def test_an_overlay_takes_the_place_of_the_file_on_disk(tmp_path):
    main_file = _project(tmp_path, {"main.vfy": 'import "laser.vfy"\n', "laser.vfy": "component Old { }\n"})
    unsaved = {str(tmp_path / "laser.vfy"): COMPONENT, str(tmp_path / "new.vfy"): ""}
    result = verify.load(str(main_file), overlay=unsaved)
    assert result.ok and [c.name.text for c in result.project.components] == ["Laser"]
    assert result.sources[str(tmp_path / "laser.vfy")].text == COMPONENT
    seen = []
    result = verify.load(str(main_file), overlay=lambda path: seen.append(path) or unsaved.get(path))
    assert result.ok and str(tmp_path / "laser.vfy") in seen  # a read function in place of a mapping
    (tmp_path / "main.vfy").write_text('import "/abs.vfy"\n')
    assert _codes(verify.load(str(main_file), overlay={"/abs.vfy": COMPONENT})) == ["E006"]
