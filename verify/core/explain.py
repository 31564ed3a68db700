"""``verify explain CODE``: the section of specs/diagnostics.md for a code, with its failing example."""
from __future__ import annotations

import re
from .codes import CODES, spec_anchor
from .resources import data_text


def spec_sections() -> dict[str, str]:
    """Every ``## CODE`` section of specs/diagnostics.md, by code."""
    text = data_text("specs", "diagnostics.md")
    sections: dict[str, str] = {}
    parts = re.split(r"^## ", text, flags=re.MULTILINE)
    for part in parts[1:]:
        heading = part.split("\n", 1)[0]
        code = heading.split()[0]
        sections[code] = "## " + part.rstrip() + "\n"
    return sections


def explain(code: str) -> str:
    section = spec_sections().get(code)
    if section is None:
        return f"{code}: {CODES[code].title}\n(see {spec_anchor(code)})\n"
    return section
