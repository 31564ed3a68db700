"""What a new user met on the command line (issue 34): each finding, fixed, with its behaviour."""
from __future__ import annotations

import verify
from verify.cli import main
from verify.core.codes import CODES

from .conftest import EXAMPLES

LIB = "component A {\n  task T { wcet 1 ms }\n\ncomponent B { }\n"  # (A's closing brace is missing)
MAIN = ('import "lib.vfy"\nsystem S {\n  core c\n  instance a : A on c { task T priority 1 timer 10 ms }\n'
        "  instance b : B on c\n}\n")


def test_a_missing_file_named_on_the_command_line_is_reported_as_such(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["check", "nosuch.vfy"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error[E004]: file not found: nosuch.vfy\n --> nosuch.vfy\n")
    assert ":1:1" not in err and "import" not in err and str(tmp_path) in err  # (the working directory)


def test_a_missing_import_keeps_its_location_and_its_help(write):
    path = write({"main.vfy": 'import "gone.vfy"\n'})
    result = verify.load(path)
    [d] = result.diagnostics
    assert d.code == "E004" and d.span.line == 1 and "relative to the importing file" in (d.help or "")


def test_a_syntax_error_in_an_import_is_the_one_error(write):
    """The components the damaged file declares are not also reported unknown where they are used."""
    path = write({"main.vfy": MAIN, "lib.vfy": LIB})
    result = verify.load(path)
    assert [d.code for d in result.diagnostics] == ["E001"]
    assert result.diagnostics[0].span.file.endswith("lib.vfy")


def test_an_unreadable_import_is_the_one_error(write):
    path = write({"main.vfy": MAIN.replace("lib.vfy", "gone.vfy")})
    assert [d.code for d in verify.load(path).diagnostics] == ["E004"]


def test_unknown_names_are_reported_when_every_file_is_read(write):
    path = write({"main.vfy": MAIN, "lib.vfy": LIB.replace("\n\ncomponent B", "\n}\ncomponent Bee")})
    result = verify.load(path)
    assert [(d.code, d.message) for d in result.diagnostics] == [("E101", "unknown component `B`")]


def test_other_files_keep_their_errors_beside_a_syntax_error(write):
    """Only E101 and the damaged file's own follow-on errors are left out: another file's error stays."""
    path = write({"main.vfy": MAIN.replace("instance b : B on c", "instance a : A on c"),
                  "lib.vfy": "component A {\n  task T { wcet 1 ms }\n}\ncomponent B {\n  task U { wcet }\n}\n"})
    found = [(d.code, d.span.file.rsplit("/", 1)[-1]) for d in verify.load(path).diagnostics]
    assert ("E102", "main.vfy") in found and ("E001", "lib.vfy") in found


NAVIGATION = str(EXAMPLES / "navigation" / "navigation.vfy")


def test_graph_refuses_an_extension_it_cannot_write(tmp_path, capsys):
    out = tmp_path / "nav.jpeg"
    assert main(["graph", NAVIGATION, "-o", str(out)]) == 2
    assert "name it .dot (or .gv), .svg, .png or .pdf" in capsys.readouterr().err and not out.exists()


def test_graph_writes_dot_to_dot_and_gv_and_says_so(tmp_path, capsys):
    for name in ("nav.dot", "nav.gv", "nav"):
        out = tmp_path / name
        assert main(["graph", NAVIGATION, "-o", str(out)]) == 0
        assert out.read_text(encoding="utf-8").startswith("digraph")
        assert capsys.readouterr().err == f"wrote {out}\n"


def test_graph_lays_out_a_pdf_through_graphviz(tmp_path, monkeypatch):
    """`-o x.pdf` is Graphviz's `dot -Tpdf` (here a stand-in `dot` records what it was asked)."""
    import verify.outputs.diagram

    calls = []

    def fake_dot(argv, input, **kwargs):
        import subprocess

        calls.append(argv[1])
        return subprocess.CompletedProcess(argv, 0, b"%PDF-1.7 ...", b"")

    monkeypatch.setattr(verify.outputs.diagram.shutil, "which", lambda name: "/usr/bin/dot")
    monkeypatch.setattr(verify.outputs.diagram.subprocess, "run", fake_dot)
    out = tmp_path / "nav.PDF"
    assert main(["graph", NAVIGATION, "-o", str(out)]) == 0
    assert calls == ["-Tpdf"] and out.read_bytes().startswith(b"%PDF")


def test_every_file_written_is_confirmed_on_stderr(tmp_path, capsys):
    import shutil

    shutil.copytree(EXAMPLES / "navigation", tmp_path / "navigation")
    holes = str(tmp_path / "navigation" / "navigation-holes.vfy")
    configured = tmp_path / "navigation" / "configured.vfy"
    assert main(["synth", holes, "-o", str(configured)]) == 0
    assert f"wrote {configured}\n" in capsys.readouterr().err
    formatted = tmp_path / "f.vfy"
    assert main(["fmt", NAVIGATION, "-o", str(formatted)]) == 0
    assert capsys.readouterr().err == f"wrote {formatted}\n"
    report = tmp_path / "proof.json"
    assert main(["prove", str(configured), "--format", "json", "-o", str(report)]) == 0
    out = capsys.readouterr()
    assert out.out == "" and f"wrote {report}\n" in out.err
    exported = tmp_path / "caret"
    assert main(["export", "caret", str(configured), "-o", str(exported)]) == 0
    out = capsys.readouterr()
    assert out.out == "" and f"wrote {exported / 'architecture.yaml'}\n" in out.err


def test_export_caret_without_from_warns_that_the_file_is_new(tmp_path, capsys):
    completed = str(EXAMPLES / "caret-talker-listener" / "completed.vfy")
    assert main(["export", "caret", completed, "-o", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "warning[E707]" in err and "placeholders" in err and "--from ARCHITECTURE.yaml" in err
    original = str(EXAMPLES / "caret-talker-listener" / "architecture.yaml")
    completed_configured = str(EXAMPLES / "caret-talker-listener" / "completed.vfy")
    assert main(["export", "caret", completed_configured, "-o", str(tmp_path / "b"), "--from", original]) == 0
    assert "E707" not in capsys.readouterr().err


# ------------------------------------------------------------------ check of several files, completion, --list, --color


def test_check_takes_several_files_and_directories_with_one_exit_code(write, tmp_path, capsys):
    write({"main.vfy": MAIN, "lib.vfy": LIB, "ok/a.vfy": "component A {\n  task T {\n    wcet 1 ms\n  }\n}\n",
           ".hidden/b.vfy": "junk"})
    good = str(tmp_path / "ok")
    assert main(["check", good]) == 0
    assert capsys.readouterr().out == f"{tmp_path / 'ok' / 'a.vfy'}: ok (1 component, 0 systems)\n"
    assert main(["check", good, str(tmp_path / "main.vfy"), str(tmp_path / "lib.vfy")]) == 2
    out = capsys.readouterr()
    assert out.out.count(": ok (") == 1 and out.err.count("error[E001]") == 1  # (lib.vfy's, shown once)
    assert main(["check", str(tmp_path)]) == 2  # the directory: a.vfy, lib.vfy, main.vfy; not .hidden
    out = capsys.readouterr()
    assert out.err.count("error[") == 1 and "junk" not in out.err


def test_check_of_several_files_as_json_is_one_document(write, tmp_path, capsys):
    import json

    write({"main.vfy": MAIN, "lib.vfy": LIB})
    assert main(["check", str(tmp_path / "main.vfy"), str(tmp_path / "lib.vfy"), "--format", "json"]) == 2
    document = json.loads(capsys.readouterr().out)
    assert [d["code"] for d in document["diagnostics"]] == ["E001"]


def test_check_of_an_empty_directory_is_a_usage_error(tmp_path, capsys):
    assert main(["check", str(tmp_path)]) == 2
    assert "holds no .vfy file" in capsys.readouterr().err


def test_explain_lists_every_code(capsys):
    from verify.core.codes import CODES

    assert main(["explain", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(CODES) and lines[0] == f"E001  {CODES['E001'].title}"
    assert main(["explain"]) == 2 and "--list" in capsys.readouterr().err


def test_color_always_never_and_no_color(write, monkeypatch, capsys):
    path = write({"main.vfy": "system S { instance x : Nope }"})
    monkeypatch.delenv("NO_COLOR", raising=False)
    assert main(["--color", "always", "check", path]) == 2
    assert "\x1b[" in capsys.readouterr().err
    assert main(["check", path]) == 2  # auto: not a terminal
    assert "\x1b[" not in capsys.readouterr().err
    monkeypatch.setenv("NO_COLOR", "1")
    assert main(["check", path, "--color", "always"]) == 2  # the command line overrides NO_COLOR
    assert "\x1b[" in capsys.readouterr().err
    assert main(["--color", "always", "check", path, "--color", "never"]) == 2  # the later one wins
    assert "\x1b[" not in capsys.readouterr().err


def _bash_complete(script: str, words: list[str]) -> list[str]:
    import subprocess

    line = " ".join(f"'{w}'" for w in words)
    done = subprocess.run(["bash", "-c", f'{script}\nCOMP_WORDS=({line}); COMP_CWORD={len(words) - 1}; '
                           '_verify_complete; printf "%s\\n" "${COMPREPLY[@]}"'],
                          capture_output=True, text=True, timeout=30, check=True)
    return done.stdout.split()


def test_bash_completion_completes_commands_options_and_choices(capsys):
    assert main(["completion", "bash"]) == 0
    script = capsys.readouterr().out
    assert _bash_complete(script, ["verify", "ch"]) == ["check"]
    assert _bash_complete(script, ["verify", "check", "--format", ""]) == ["text", "json", "sarif"]
    assert _bash_complete(script, ["verify", "--color", "check", "--fo"]) == ["--format"]
    assert _bash_complete(script, ["verify", "gen", "r"]) == ["ros1", "ros2"]
    assert _bash_complete(script, ["verify", "explain", "E10"]) == sorted(c for c in CODES if c.startswith("E10"))
    assert _bash_complete(script, ["synth", "--objective", "x"]) == []  # (no choices: no file named x here)
    assert "--objective" in _bash_complete(script, ["synth", "--obj"])


def test_zsh_and_fish_scripts_name_every_command(capsys):
    from verify.commands import COMMANDS

    assert main(["completion", "zsh"]) == 0
    zsh = capsys.readouterr().out
    assert zsh.startswith("#compdef verify synth prove\n") and "bashcompinit" in zsh
    assert main(["completion", "fish"]) == 0
    fish = capsys.readouterr().out
    assert all(f" -a {name} -d " in fish for name in COMMANDS)
    assert "__fish_seen_subcommand_from graph' -l format -x -a 'dot svg png pdf'" in fish
    assert main(["completion", "tcsh"]) == 2


def test_graph_writes_a_real_pdf_with_graphviz(tmp_path, capsys):
    from .test_graph import require_graphviz

    require_graphviz()
    out = tmp_path / "nav.pdf"
    assert main(["graph", NAVIGATION, "-o", str(out)]) == 0
    assert out.read_bytes().startswith(b"%PDF-") and capsys.readouterr().err == f"wrote {out}\n"
