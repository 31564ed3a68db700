"""The parser's tables are built once per Lark release and kept in the user's cache directory; a later
process loads them, the same parser; a directory that another user could write is never used. The fast
path's own tables are kept as JSON beside them (``verify.frontend.parsecache``): valid text then parses without
Lark being imported at all."""
from __future__ import annotations

import json
import os
import stat
import subprocess
import sys

import lark
import lark.lark
import pytest

import verify
from verify.frontend import grammar, parse, parsecache

from .conftest import EXAMPLES

BROKEN = "component Laser {\n  task LaserTask {\n    wcet 2 mss\n    wcet 3 ms\n  }\n}\nsystem S { core c }\n"


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """An empty cache home, and no parser built yet in this process (restored afterwards)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()
    yield tmp_path
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()


def _outputs() -> list:
    texts = [(EXAMPLES / "navigation" / "navigation.vfy").read_text(), BROKEN]
    return [(r.module, r.diagnostics) for r in (parse.parse_source(t, "x.vfy") for t in texts)] + \
        [grammar.lark_parser().parse(texts[0])]


def test_the_tables_are_kept_and_loaded_to_the_same_parser(fresh, monkeypatch):
    built = _outputs()
    directory = fresh / parsecache.CACHE_DIR
    [cached] = [f for f in directory.iterdir() if f.name.startswith("lark-")]
    assert cached.name == f"lark-{lark.__version__}-parser.cache"
    assert stat.S_IMODE(os.stat(directory).st_mode) == 0o700
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()

    def no_grammar(*args, **kwargs):
        raise AssertionError("the grammar was compiled again although its tables are cached")

    monkeypatch.setattr(lark.lark, "load_grammar", no_grammar)
    assert _outputs() == built
    assert verify.load_text(BROKEN, "b.vfy").diagnostics[0].message == "unknown unit `mss`; did you mean `ms`?"
    cached.unlink()  # (and without the file, the grammar is compiled: the check above can fail)
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()
    with pytest.raises(AssertionError, match="compiled again"):
        grammar.lark_parser()


def test_a_directory_others_may_write_is_not_used(fresh):
    directory = fresh / parsecache.CACHE_DIR
    directory.mkdir(mode=0o700)
    os.chmod(directory, 0o777)
    assert grammar.lark_cache_file() is False
    assert _outputs()  # (built without a cache)
    assert list(directory.iterdir()) == []
    os.chmod(directory, 0o700)
    assert grammar.lark_cache_file() == str(directory / f"lark-{lark.__version__}-parser.cache")


def test_valid_text_parses_from_the_kept_fast_tables_without_lark(fresh, monkeypatch):
    built = _outputs()
    directory = fresh / parsecache.CACHE_DIR
    [table] = [f for f in directory.iterdir() if f.name.startswith("fast-")]
    assert table == directory / os.path.basename(parsecache.table_file(str(directory)))
    assert stat.S_IMODE(os.stat(table).st_mode) == 0o600
    grammar.lark_parser.cache_clear()
    parse.fast_parser.cache_clear()

    def no_lark():
        raise AssertionError("Lark's parser was built although the fast tables are kept")

    no_lark.cache_clear = lambda: None  # type: ignore[attr-defined]  # (the fixture clears it afterwards)
    monkeypatch.setattr(grammar, "lark_parser", no_lark)
    nav = (EXAMPLES / "navigation" / "navigation.vfy").read_text()
    assert parse.parse_source(nav, "x.vfy").module == built[0][0]
    # a later process: valid text never imports Lark (an error would)
    code = ("import sys, verify; r = verify.load(sys.argv[1]); assert r.ok, r.diagnostics; "
            "print('lark' in sys.modules)")
    env = {**os.environ, "XDG_CACHE_HOME": str(fresh)}
    done = subprocess.run([sys.executable, "-c", code, str(EXAMPLES / "navigation" / "navigation.vfy")],
                          capture_output=True, text=True, env=env, check=True)
    assert done.stdout.strip() == "False", done.stderr


def test_a_kept_table_that_is_not_one_is_built_again(fresh):
    built = _outputs()
    directory = fresh / parsecache.CACHE_DIR
    [table] = [f for f in directory.iterdir() if f.name.startswith("fast-")]
    data = json.loads(table.read_text().partition("\n")[2])
    for junk in ("{", "[]", json.dumps({"rows": [], "start": 0}), json.dumps({**data, "shapes": [[0, "x"]]})):
        for text in (junk, parsecache.stamped_table(junk)):  # (changed after it was written, or written so)
            table.write_text(text)
            parse.fast_parser.cache_clear()
            assert _outputs() == built
            assert parsecache.read_table(str(table)) is not None  # (written anew)
    with pytest.raises(ValueError, match="not a parser description"):
        parsecache.FastParser.from_data({"rows": [], "start": 0})


def test_the_kept_table_is_the_parser_lark_builds(fresh):
    from verify.frontend.fastparse import FastParser

    fast = FastParser.build(grammar.lark_parser())
    again = FastParser.from_data(json.loads(json.dumps(fast.to_data())))
    assert again.to_data() == fast.to_data()
    assert again.lexeme.pattern == fast.lexeme.pattern
    assert [r[:3] + r[4:] for r in again.rules] == [r[:3] + r[4:] for r in fast.rules]
