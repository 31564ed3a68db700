"""The seed corpus: the examples, the minimal failing example of every diagnostic code and the golden
files of their reports, each as one file's bytes (a system's imports are inlined: the targets parse
text in memory)."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
_IMPORT = re.compile(r'^import "([^"]*)"[^\n]*\n', re.MULTILINE)
_BLOCK = re.compile(r"^```vfy([^\n]*)\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)


def _inlined(path: Path, seen: set[Path] | None = None) -> str:
    """The text of ``path`` with every import replaced by the imported file's text (once each)."""
    seen = set() if seen is None else seen
    seen.add(path)
    text = path.read_text(encoding="utf-8")

    def include(match: re.Match) -> str:
        target = (path.parent / match.group(1)).resolve()
        if target in seen or not target.is_file():
            return ""
        return _inlined(target, seen) + "\n"

    return _IMPORT.sub(include, text)


def _spec_examples() -> dict[str, bytes]:
    text = (ROOT / "specs" / "diagnostics.md").read_text(encoding="utf-8")
    seeds = {}
    for part in re.split(r"^## ", text, flags=re.MULTILINE)[1:]:
        code = part.split(None, 1)[0]
        blocks = _BLOCK.findall(part)
        body = "\n".join(_IMPORT.sub("", b) for _, b in reversed(blocks))  # imported files first
        encoding = "latin-1" if any("encoding=latin-1" in attrs for attrs, _ in blocks) else "utf-8"
        seeds[f"spec-{code}"] = body.encode(encoding, errors="replace")
    return seeds


def seeds() -> dict[str, bytes]:
    """Every seed by a name, in a fixed order."""
    out: dict[str, bytes] = {}
    for path in sorted((ROOT / "examples").rglob("*.vfy")):
        out[f"example-{path.stem}"] = _inlined(path).encode("utf-8")
    out.update(_spec_examples())
    for path in sorted((ROOT / "tests" / "golden" / "diagnostics").rglob("*.txt")):
        out[f"golden-{path.stem}"] = path.read_bytes()
    out.update(_smartmdsd())
    out.update(_caret())
    out.update(_lsp())
    return out


def _smartmdsd() -> dict[str, bytes]:
    """SmartMDSD inputs for the ``smartmdsd`` target: each system of examples/smartmdsd with every
    component (files after ``// file NAME`` lines), and the SmartMDSD examples of specs/diagnostics.md."""
    from .targets import SMARTMDSD_FILE

    out: dict[str, bytes] = {}
    models = ROOT / "examples" / "smartmdsd"
    components = sorted((models / "components").glob("*.component"))
    for arch in sorted((models / "systems").glob("*.componentArch")):
        files = components + sorted(p for p in (models / "systems").glob(arch.stem + ".*"))
        out[f"smartmdsd-{arch.stem}"] = "".join(f"{SMARTMDSD_FILE}{p.name}\n{p.read_text(encoding='utf-8')}\n"
                                                for p in files).encode("utf-8")
    text = (ROOT / "specs" / "diagnostics.md").read_text(encoding="utf-8")
    for part in re.split(r"^## ", text, flags=re.MULTILINE)[1:]:
        blocks = re.findall(r"^```smartmdsd[^\n]*file=(\S+)[^\n]*\n(.*?)^```[ \t]*$", part, re.MULTILINE | re.DOTALL)
        if blocks:
            out[f"smartmdsd-spec-{part.split(None, 1)[0]}"] = "".join(
                f"{SMARTMDSD_FILE}{name}\n{body}" for name, body in blocks).encode("utf-8")
    return out


def _caret() -> dict[str, bytes]:
    """CARET architecture files for the ``caret`` target: the test suite's (tests/caret)."""
    return {f"caret-{p.stem}": p.read_bytes() for p in sorted((ROOT / "tests" / "caret").glob("*.yaml"))}


def _lsp() -> dict[str, bytes]:
    """Client sessions for the ``lsp`` target (``lspstream.session``) on a few small examples of
    specs/diagnostics.md: a syntax error, a misspelt name, a missed deadline, holes for synth."""
    from .lspstream import session

    examples = _spec_examples()
    return {f"lsp-{code}": session(examples[f"spec-{code}"].decode("utf-8", "replace"))
            for code in ("E001", "E101", "E316", "E401") if f"spec-{code}" in examples}


def dictionary() -> list[str]:
    """libFuzzer dictionary entries: the keywords, punctuation and units of the grammar."""
    from verify.frontend.grammar import literal_words

    words = sorted({w[1:-1] for w in literal_words().values()} | {"ms", "us", "ns", "s", "Hz", "kHz", "?"})
    return [json_quote(w) for w in words]


def json_quote(word: str) -> str:
    return '"' + word.replace("\\", "\\\\").replace('"', '\\"') + '"'
