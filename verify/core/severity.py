"""How serious a diagnostic is: the one leaf the diagnostics (``verify.core.diagnostics``) and their
registry (``verify.core.codes``) share."""
from __future__ import annotations

from enum import StrEnum


class Severity(StrEnum):
    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"
