"""Synthesis of periods, prescalers and activation kinds with Z3, or an explanation of the conflict.

    from verify.synth import synthesize
    result = synthesize(verify.load("examples/navigation/navigation-holes.vfy"))
    result.status, result.choices, result.values, result.optimal

``synthesize`` (``driver``) is the API, ``brute_force`` the naive baseline (enumerate and analyse),
``specs/synthesis.md`` the method, ``command`` the ``synth`` command line. Names are imported lazily
so that the command line does not load Z3 for other commands.
"""
from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "BruteResult": "driver", "DEFAULT_RLIMIT": "driver", "Goal": "driver", "ObjectiveError": "driver",
    "SynthResult": "driver", "brute_force": "driver", "parse_objective": "driver", "synthesize": "driver",
    "Candidate": "candidates", "DEFAULT_PERIODS": "candidates", "DEFAULT_PRESCALERS": "candidates",
    "TooManyCandidates": "candidates",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:  # (a class, a function or a constant of a submodule)
    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
