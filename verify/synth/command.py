"""The ``synth`` command is ``verify.commands.synth``; ``too_many`` stays here for its callers."""
from __future__ import annotations

from ..core.diagnostics import Diagnostic
from .candidates import TooManyCandidates


def too_many(err: TooManyCandidates) -> Diagnostic:
    """E403 for a hole with too many candidate values (``TooManyCandidates.diagnostic``)."""
    return err.diagnostic()
