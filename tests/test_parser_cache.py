"""The parser's tables are built once per Lark release and kept in the user's cache directory; a later
process loads them, the same parser; a directory that another user could write is never used."""
from __future__ import annotations

import os
import stat

import lark
import lark.lark
import pytest

import verify
from verify import larkparse, parse

from .conftest import EXAMPLES

BROKEN = "component Laser {\n  task LaserTask {\n    wcet 2 mss\n    wcet 3 ms\n  }\n}\nsystem S { core c }\n"


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """An empty cache home, and no parser built yet in this process (restored afterwards)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    larkparse._parser.cache_clear()
    parse._fast_parser.cache_clear()
    yield tmp_path
    larkparse._parser.cache_clear()
    parse._fast_parser.cache_clear()


def _outputs() -> list:
    texts = [(EXAMPLES / "navigation" / "navigation.vfy").read_text(), BROKEN]
    return [(r.module, r.diagnostics) for r in (parse.parse_source(t, "x.vfy") for t in texts)] + \
        [larkparse._parser().parse(texts[0])]


def test_the_tables_are_kept_and_loaded_to_the_same_parser(fresh, monkeypatch):
    built = _outputs()
    directory = fresh / larkparse.CACHE_DIR
    [cached] = list(directory.iterdir())
    assert cached.name == f"lark-{lark.__version__}-parser.cache"
    assert stat.S_IMODE(os.stat(directory).st_mode) == 0o700
    larkparse._parser.cache_clear()
    parse._fast_parser.cache_clear()

    def no_grammar(*args, **kwargs):
        raise AssertionError("the grammar was compiled again although its tables are cached")

    monkeypatch.setattr(lark.lark, "load_grammar", no_grammar)
    assert _outputs() == built
    assert verify.load_text(BROKEN, "b.vfy").diagnostics[0].message == "unknown unit `mss`; did you mean `ms`?"
    cached.unlink()  # (and without the file, the grammar is compiled: the check above can fail)
    larkparse._parser.cache_clear()
    parse._fast_parser.cache_clear()
    with pytest.raises(AssertionError, match="compiled again"):
        larkparse._parser()


def test_a_directory_others_may_write_is_not_used(fresh):
    directory = fresh / larkparse.CACHE_DIR
    directory.mkdir(mode=0o700)
    os.chmod(directory, 0o777)
    assert larkparse._cache_file() is False
    assert _outputs()  # (built without a cache)
    assert list(directory.iterdir()) == []
    os.chmod(directory, 0o700)
    assert larkparse._cache_file() == str(directory / f"lark-{lark.__version__}-parser.cache")
