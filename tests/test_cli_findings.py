"""What a new user met on the command line (issue 34): each finding, fixed, with its behaviour."""
from __future__ import annotations

import verify
from verify.cli import main

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
