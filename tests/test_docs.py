"""The documentation site builds with ``mkdocs build --strict`` (a broken link, a missing anchor or a page
left out of the navigation fails it), serves the specs and the benchmark page from where they live, and
the manual's prose holds no numbers that age: those belong to benchmarks/README.md, which is dated."""
from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys

import pytest

from .conftest import ROOT, in_ci

DOCS = ROOT / "docs"
#: the manual's prose: the README and the site's own pages (the specs are normative text, and the
#: benchmark page is where dated numbers live)
PROSE = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def mkdocs_available() -> bool:
    return importlib.util.find_spec("mkdocs") is not None and importlib.util.find_spec("material") is not None


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    if not mkdocs_available():
        if in_ci():
            pytest.fail("mkdocs and mkdocs-material are in the test extra: pip install -e '.[test]'")
        pytest.skip("mkdocs and mkdocs-material are not installed")
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                           str(ROOT / "mkdocs.yml"), "--site-dir", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, NO_MKDOCS_2_WARNING="1"))
    assert done.returncode == 0, done.stdout + done.stderr
    return out


@pytest.mark.slow
def test_the_site_builds_strictly_with_the_specs_and_the_benchmarks(site):
    for spec in sorted((ROOT / "specs").glob("*.md")):
        assert (site / "specs" / spec.stem / "index.html").is_file(), f"specs/{spec.name} is not in the site"
    assert (site / "contributing" / "benchmarks" / "index.html").is_file()
    assert not (site / "hooks").exists()


def section_headings(markdown: str) -> int:
    """The ``## `` headings of a Markdown text outside its fenced blocks."""
    count, fence = 0, ""
    for line in markdown.splitlines():
        opening = re.match(r"^\s*(`{3,}|~{3,})", line)
        if opening and (not fence or opening.group(1).startswith(fence)):
            fence = "" if fence else opening.group(1)
        elif not fence and line.startswith("## "):
            count += 1
    return count


@pytest.mark.slow
def test_every_section_of_a_served_file_is_a_section_of_its_page(site):
    """What the site's Markdown would not take for a fence (```` ```vfy file=a.vfy ````) would swallow the
    sections after it: every ``##`` section of a spec and of the benchmark page is one on the site."""
    pages = {ROOT / "specs" / f"{p.stem}.md": site / "specs" / p.stem for p in (ROOT / "specs").glob("*.md")}
    pages[ROOT / "benchmarks" / "README.md"] = site / "contributing" / "benchmarks"
    for source, page in sorted(pages.items()):
        html = (page / "index.html").read_text(encoding="utf-8")
        assert html.count("<h2 id=") == section_headings(source.read_text(encoding="utf-8")), source.name


@pytest.mark.slow
def test_the_command_line_reference_is_the_help_of_every_command(site):
    top = subprocess.run([sys.executable, "-m", "verify", "--help"], capture_output=True, text=True,
                         check=True).stdout
    listing = top.split("positional arguments:", 1)[1].split("options:", 1)[0]
    names = re.findall(r"^    ([a-z][a-z0-9-]*)(?:\s|$)", listing, flags=re.MULTILINE)
    assert {"check", "analyze", "synth", "prove"} <= set(names)
    page = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    for name in names:
        assert f'id="verify-{name}"' in page, f"`verify {name}` has no section in reference/cli.md"


def test_the_nav_names_every_page_of_docs():
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md") if "hooks" not in p.parts}
    assert pages and all(f": {page}" in nav for page in pages), sorted(p for p in pages if f": {p}" not in nav)


def test_the_readme_is_short():
    assert len((ROOT / "README.md").read_text(encoding="utf-8").splitlines()) <= 200


#: what reads as a diary or ages in prose: commit hashes, test counts, "this session"
AGING = [
    (re.compile(r"`[0-9a-f]{7,40}`"), "a commit hash"),
    (re.compile(r"\b\d[\d,]* (?:slow )?tests\b"), "a test count"),
    (re.compile(r"\bthis session\b", re.IGNORECASE), "a session"),
    (re.compile(r"\b20\d\d-\d\d-\d\d\b"), "a date"),
]


def test_the_manual_holds_no_numbers_that_age():
    found = [f"{path.relative_to(ROOT)}:{n}: {what}: {line.strip()}"
             for path in PROSE for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             for pattern, what in AGING if pattern.search(line)]
    assert not found, "\n".join(found)


def test_the_benchmark_page_describes_every_stage():
    """benchmarks/README.md's table of stages names every stage the runner registers."""
    from benchmarks.run import STAGES

    text = (ROOT / "benchmarks" / "README.md").read_text(encoding="utf-8")
    described = set(re.findall(r"^\| `([a-z0-9+-]+)`", text, flags=re.MULTILINE))
    described |= {n for row in re.findall(r"^\| (`[a-z0-9+-]+`(?:, `[a-z0-9+-]+`)+) \|", text, flags=re.MULTILINE)
                  for n in re.findall(r"`([a-z0-9+-]+)`", row)}
    assert set(STAGES) and set(STAGES) <= described, sorted(set(STAGES) - described)


def test_every_link_of_the_readme_leads_to_a_file_of_the_repository():
    """The README is read on a forge, outside the site: its relative links name files of the clone."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = [t for t in re.findall(r"\]\(([^)\s#]+)(?:#[^)]*)?\)", text) if "://" not in t]
    assert targets, "the README links its documentation"
    missing = [t for t in targets if not (ROOT / t).exists()]
    assert not missing, missing
