"""Proof of every spec of a configured system (specs/proof.md): by the compositional bound, by an
exact search over the job-level semantics (enumeration of representative runs, or Z3), or refuted by
a concrete run that the reference simulator replays. Runs are simulated by the integer simulator of
``intsim.py``, which the tests hold to the reference simulator ``verify.prove.sim``.

    from verify.prove import prove
    result = prove(model, budget=1000)      # ProofResult: verdicts, diagnostics, exit_code
    for v in result.verdicts:
        print(v.label, v.status, v.method, v.bound, v.exact, v.margin)
"""
from __future__ import annotations

from .core import DEFAULT_BUDGET, DEFAULT_RLIMIT, prove
from .scenario import ConcreteScenario, Target, replay
from .verdict import METHODS, STATUSES, Counterexample, ProofResult, Verdict

__all__ = ["DEFAULT_BUDGET", "DEFAULT_RLIMIT", "METHODS", "STATUSES", "ConcreteScenario", "Counterexample",
           "ProofResult", "Target", "Verdict", "prove", "replay"]
