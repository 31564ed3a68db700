"""The TextMate grammar for editors (editors/vfy.tmLanguage.json), run by the tokenizer VS Code uses
(vscode-textmate with Oniguruma, installed by scripts/install-tools into editors/tmtest)."""
from __future__ import annotations

import json
import re
import shutil
import subprocess

import pytest

from verify.frontend.grammar import keyword_terminals

from .conftest import EXAMPLES, ROOT, in_ci

TMTEST = ROOT / "editors" / "tmtest"


def tokens(path) -> list[tuple[int, str, str]]:
    """(line, text, innermost scope) of every token of the file."""
    node = shutil.which("node")
    if node is None or not (TMTEST / "node_modules" / "vscode-textmate").exists():
        message = "node or editors/tmtest/node_modules missing (scripts/install-tools installs them)"
        if in_ci():
            pytest.fail(message)
        pytest.skip(message)
    done = subprocess.run([node, str(TMTEST / "tokenize.js"), str(path)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return [(line, text, scopes[-1]) for line, _, _, text, scopes in json.loads(done.stdout)]


def scope_of(found, text: str, line: int | None = None) -> str:
    return next(s for ln, t, s in found if t == text and (line is None or ln == line))


def test_the_navigation_example_is_highlighted():
    found = tokens(EXAMPLES / "navigation" / "components.vfy") + tokens(EXAMPLES / "navigation" / "navigation.vfy")
    assert scope_of(found, "component") == "keyword.declaration.vfy"
    assert scope_of(found, "Laser") == "entity.name.type.vfy"
    assert scope_of(found, "LaserTask") == "entity.name.function.vfy"
    assert scope_of(found, "reads") == "keyword.other.structure.vfy"
    assert scope_of(found, "oversampling") == "keyword.other.timing.vfy"
    assert scope_of(found, "40") == "constant.numeric.vfy" and scope_of(found, "Hz") == "keyword.other.unit.vfy"
    assert scope_of(found, '"components.vfy"') == "string.quoted.double.vfy"
    assert scope_of(found, "->") == "keyword.operator.flow.vfy"
    assert scope_of(found, "reactive") == "entity.name.tag.chain.vfy"
    assert any(s == "comment.line.double-slash.vfy" and t.startswith("// The fast reactive loop") for _, t, s in found)


def test_every_keyword_of_the_grammar_is_a_keyword_and_only_as_a_whole_word(tmp_path):
    words = sorted(keyword_terminals())
    sample = tmp_path / "words.vfy"
    sample.write_text("\n".join(words) + "\noutx taskname msx 5 msx 2.5 us /* a\nblock */ ? a.b\n", encoding="utf-8")
    found = tokens(sample)
    for n, word in enumerate(words, 1):  # one per line: never taken for the name after another keyword
        assert scope_of(found, word, n).startswith("keyword."), word
    last = len(words) + 1
    line2 = [(t.strip(), s) for ln, t, s in found if ln == last and t.strip()]
    assert not any(t in ("msx", "outx", "taskname") and s.startswith("keyword") for t, s in line2)
    assert ("us", "keyword.other.unit.vfy") in line2
    assert any(s == "comment.block.vfy" for ln, _, s in found if ln == last + 1)
    assert scope_of(found, "?", last + 1) == "keyword.operator.hole.vfy"


def test_the_grammar_knows_every_keyword_the_parser_knows():
    grammar = (ROOT / "editors" / "vfy.tmLanguage.json").read_text(encoding="utf-8")
    listed = set(re.findall(r"[a-z_]+", " ".join(re.findall(r'\\\\b\(\?:([a-z_|]+)\)', grammar))))
    listed |= {"import"}
    assert listed == set(keyword_terminals())
