"""MkDocs hook: the pages of the site that are not written in docs/.

- ``specs/NAME.md``: the normative specs, served from ``specs/`` as they are (one text, in one place);
- ``contributing/benchmarks.md``: ``benchmarks/README.md``, the harness and its latest table;
- ``reference/cli.md``: the ``--help`` of ``verify`` and of each of its commands, as the installed
  command line prints it, so that the reference cannot drift from the code.

MkDocs reads only ``docs_dir``; ``on_files`` adds these as virtual files (``File.generated``). Links are
written as they work in the repository (``docs/guide/prove.md`` links ``../../specs/proof.md``), so that
the pages read on a forge as well; ``on_page_markdown`` points each link to a served file at that file's
place in the site, and leaves every other link to MkDocs' own checks (``--strict`` fails on a broken one).
"""
from __future__ import annotations

import os
import posixpath
import re
import subprocess
import sys
from pathlib import Path, PurePosixPath

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files
from mkdocs.structure.pages import Page

ROOT = Path(__file__).resolve().parents[2]

#: files of the repository served as pages of the site: page path -> file
SOURCES = {f"specs/{p.name}": p for p in sorted((ROOT / "specs").glob("*.md"))} | {
    "contributing/benchmarks.md": ROOT / "benchmarks" / "README.md",
}

#: the opening of a fenced block with words after its language
FENCE_INFO = re.compile(r"^([ \t]*`{3,})([A-Za-z][\w+-]*)[ \t]+([^`{\n][^`\n]*?)[ \t]*$", re.MULTILINE)
#: a Markdown link or image: ``[text](target#anchor)``
LINK = re.compile(r"(!?\[[^\]]*\])\(([^)\s#]+)(#[^)\s]*)?\)")


def on_files(files: Files, config: MkDocsConfig) -> Files:
    for page, path in SOURCES.items():
        files.append(File.generated(config, page, abs_src_path=str(path)))
    files.append(File.generated(config, "reference/cli.md", content=cli_page()))
    return files


def on_page_markdown(markdown: str, page: Page, config: MkDocsConfig, files: Files) -> str:
    served = {Path(f.abs_src_path).resolve(): f.src_uri for f in files if f.abs_src_path}
    here = Path(page.file.abs_src_path or Path(config.docs_dir) / page.file.src_uri).resolve().parent
    page_dir = PurePosixPath(page.file.src_uri).parent

    def relink(match: re.Match[str]) -> str:
        target, anchor = match.group(2), match.group(3) or ""
        if "://" in target or target.startswith(("/", "mailto:")):
            return match.group(0)
        uri = served.get((here / target).resolve())
        if uri is None:
            return match.group(0)
        return f"{match.group(1)}({posixpath.relpath(uri, page_dir)}{anchor})"

    return FENCE_INFO.sub(titled, LINK.sub(relink, markdown))


def titled(match: re.Match[str]) -> str:
    """A fence with words after its language (```` ```vfy file=a.vfy ````, as specs/diagnostics.md marks its
    examples) as the fence with those words for its title: the Markdown of the site would not take it
    for a fence otherwise, and a forge shows the words as they are."""
    words = match.group(3).replace('"', "'")
    return f'{match.group(1)}{match.group(2)} title="{words}"'


def help_text(*command: str) -> str:
    """What ``verify COMMAND... --help`` prints (80 columns, no colour)."""
    env = dict(os.environ, COLUMNS="80", NO_COLOR="1")
    done = subprocess.run([sys.executable, "-m", "verify", *command, "--help"], capture_output=True,
                          text=True, env=env, check=True)
    return done.stdout


def commands(top_help: str) -> list[str]:
    """The commands ``verify --help`` lists (the indented names under ``COMMAND``)."""
    listing = top_help.split("positional arguments:", 1)[1].split("options:", 1)[0]
    return re.findall(r"^    ([a-z][a-z0-9-]*)(?:\s|$)", listing, flags=re.MULTILINE)


def cli_page() -> str:
    top = help_text()
    parts = ["# Command-line help", "",
             "Generated when the site is built: what `verify --help` and `verify COMMAND --help` print. "
             "`synth FILE` and `prove FILE` are the same as `verify synth FILE` and `verify prove FILE`. "
             "What the commands do, with examples: [Commands](commands.md).", "",
             "```text", top.rstrip(), "```", ""]
    for name in commands(top):
        parts += [f"## `verify {name}`", "", "```text", help_text(name).rstrip(), "```", ""]
    return "\n".join(parts)
