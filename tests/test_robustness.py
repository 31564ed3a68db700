"""Bad input never crashes: every malformed input yields located diagnostics, never an exception."""
from __future__ import annotations

import os
import random
import re

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import verify
from verify.cli import main

from .conftest import EXAMPLES

NAVIGATION = (EXAMPLES / "navigation" / "navigation.vfy").read_text()
COMPONENTS = (EXAMPLES / "navigation" / "components.vfy").read_text()
FORBIDDEN = ("__ANON", "$END", "Token(", "Traceback", "Tree(")


def _assert_located(result: verify.LoadResult) -> None:
    inputs = [s.text for s in result.sources.values()]
    forbidden = [bad for bad in FORBIDDEN if not any(bad in text for text in inputs)]  # (not the user's own words)
    for d in result.diagnostics:
        assert d.code and d.message
        assert d.span.line >= 1 and d.span.column >= 1, d
        text = d.message + (d.help or "")
        assert not any(bad in text for bad in forbidden), text


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=400))
@example("Traceback")  # (a model's own word, quoted back in the message, is no leak)
def test_random_text_never_raises(text):
    _assert_located(verify.load_text(text))


@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_never_raise(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("bin") / "junk.vfy"
    path.write_bytes(data)
    result = verify.load(str(path))
    _assert_located(result)


def _mutations(text: str, rng: random.Random) -> str:
    chars = list(text)
    for _ in range(rng.randint(1, 6)):
        op = rng.randrange(4)
        pos = rng.randrange(len(chars) + 1)
        if op == 0 and chars:
            del chars[min(pos, len(chars) - 1)]
        elif op == 1:
            chars.insert(pos, rng.choice("{}:;.->?&|\"/*0123456789 \nabcHzms"))
        elif op == 2 and chars:
            i = rng.randrange(len(chars))
            j = rng.randrange(len(chars))
            chars[i], chars[j] = chars[j], chars[i]
        else:
            a = rng.randrange(len(chars) + 1)
            b = min(len(chars), a + rng.randint(1, 30))
            del chars[a:b]
    return "".join(chars)


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_mutated_examples_never_raise(seed):
    rng = random.Random(seed)
    source = COMPONENTS + "\n" + NAVIGATION.replace('import "components.vfy"', "")
    _assert_located(verify.load_text(_mutations(source, rng)))


def test_deep_nesting_and_huge_numbers():
    _assert_located(verify.load_text("component A {" * 5000))
    _assert_located(verify.load_text("{" * 10000 + "}" * 10000))
    result = verify.load_text("component A { task T { wcet " + "9" * 5000 + " ms } }")
    assert [d.code for d in result.diagnostics] == ["E005"]
    result = verify.load_text("component A { task T { wcet 1/0 ms } }")
    assert [d.code for d in result.diagnostics] == ["E005"]


@pytest.mark.slow
def test_every_syntax_error_has_a_help_and_an_accepted_expected_set():
    from verify.frontend.grammar import describe_token_type

    rng = random.Random(2026)
    source = COMPONENTS + "\n" + NAVIGATION.replace('import "components.vfy"', "")
    seen = 0
    for _ in range(120):
        result = verify.load_text(_mutations(source, rng))
        _assert_located(result)
        for d in result.diagnostics:
            if d.code in ("E001", "E002"):
                seen += 1
                assert d.help, (d.code, d.message)
                # merged LALR lookaheads never leak into a list: after a quantity in a task, no system word
                if "'bcet'" in d.message:
                    assert "'chain'" not in d.message and "'connect'" not in d.message, d.message
    assert seen > 50
    assert describe_token_type("NAME") == "a name"


def test_keywords_glued_to_names_in_mutants_are_never_accepted():
    # removing the blank after a keyword must never leave a valid model (`outx` is no `out x`)
    for text in (COMPONENTS, NAVIGATION):
        source = re.sub(r"//[^\n]*|/\*[\s\S]*?\*/", "", text)  # (a keyword in a comment is no keyword)
        matches = re.finditer(r"\b(out|in|task|reads|produces|core|instance|trigger|connect|chain|timer|on) "
                              r"(?=[A-Za-z_])", source)
        for match in random.Random(3).sample(list(matches), 12):
            glued = source[:match.end() - 1] + source[match.end():]
            result = verify.load_text(glued)
            assert any(d.code == "E001" for d in result.diagnostics), glued[match.start():match.end() + 10]


def test_non_utf8_missing_directory_and_cycles(write, tmp_path):
    bad = write({"bad.vfy": b"component A {\n  \xff\xfe }"})
    assert [d.code for d in verify.load(bad).diagnostics] == ["E003"]
    assert [d.code for d in verify.load(str(tmp_path / "nope.vfy")).diagnostics] == ["E004"]
    assert [d.code for d in verify.load(str(tmp_path)).diagnostics] == ["E004"]
    a = write({"a.vfy": 'import "b.vfy"\n', "b.vfy": 'import "a.vfy"\n'})
    assert [d.code for d in verify.load(a).diagnostics] == ["E103"]
    self_import = write({"self.vfy": 'import "self.vfy"\n'})
    assert [d.code for d in verify.load(self_import).diagnostics] == ["E103"]


def test_cli_never_tracebacks(write, capsys):
    bad = write({"bad.vfy": b"\x00\x01\x02 system { instance"})
    assert main(["check", bad]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "error[" in err


def test_a_nul_character_in_an_import_is_a_located_error(write, capsys):
    main_file = write({"m.vfy": 'import "a\0b.vfy"\n'})
    result = verify.load(main_file)
    assert [d.code for d in result.diagnostics] == ["E004"]
    (d,) = result.diagnostics
    assert d.span.line == 1 and "NUL" in d.message and "\0" not in d.message
    assert main(["check", main_file]) == 2
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_fifo_is_refused_without_blocking(write, tmp_path, capsys):
    main_file = write({"m.vfy": 'import "pipe.vfy"\n'})
    os.mkfifo(tmp_path / "pipe.vfy")  # nobody ever writes to it: reading it would block forever
    import signal

    def hung(*_):
        raise TimeoutError("reading a FIFO blocked")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(20)  # (fail, rather than hang the test run, if the FIFO were opened)
    try:
        _fifo_checks(main_file, str(tmp_path / "pipe.vfy"), capsys)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _fifo_checks(main_file, fifo, capsys):
    result = verify.load(main_file)
    assert [d.code for d in result.diagnostics] == ["E004"]
    assert result.diagnostics[0].span.line == 1 and "not a regular file" in result.diagnostics[0].message
    assert [d.code for d in verify.load(fifo).diagnostics] == ["E004"]  # the main file argument too
    assert main(["check", fifo]) == 2
    assert main(["fmt", fifo]) == 2
    err = capsys.readouterr().err
    assert "error[E004]" in err and "Traceback" not in err


def test_the_snippet_under_a_diagnostic_is_the_line_it_names(write, capsys):
    """Lines are counted at "\\n" only, as the lexer counts them: a form feed (whitespace) or a U+2028
    in a comment does not shift the source line shown under a diagnostic."""
    from verify.cli import main

    text = "\f// a page break above\ncomponent A { // note \u2028 still the comment\n  out x : T\n  bad here\n}\n"
    path = write({"ff.vfy": text})
    assert main(["check", path]) == 2
    err = capsys.readouterr().err
    assert "ff.vfy:4:" in err
    assert "4 |   bad here" in err
