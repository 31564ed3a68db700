"""Bad input never crashes: every malformed input yields located diagnostics, never an exception."""
from __future__ import annotations

import random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.cli import main

from .conftest import EXAMPLES

NAVIGATION = (EXAMPLES / "navigation" / "navigation.vfy").read_text()
COMPONENTS = (EXAMPLES / "navigation" / "components.vfy").read_text()
FORBIDDEN = ("__ANON", "$END", "Token(", "Traceback", "Tree(")


def _assert_located(result: verify.LoadResult) -> None:
    for d in result.diagnostics:
        assert d.code and d.message
        assert d.span.line >= 1 and d.span.column >= 1, d
        text = d.message + (d.help or "")
        assert not any(bad in text for bad in FORBIDDEN), text


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=400))
def test_random_text_never_raises(text):
    _assert_located(verify.load_text(text))


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
