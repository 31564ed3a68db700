"""``check --format json``: the diagnostics document (``verify.diagnostics/1``)."""
from __future__ import annotations

from .diagnostics_json import render  # noqa: F401 - the same document
