"""The default budgets of ``synth`` and ``prove``, in deterministic units: kept apart from the solvers,
so that the command line shows them without importing Z3 or the search."""
from __future__ import annotations

SYNTH_RLIMIT = 50_000_000  #: Z3 resource units for one synthesis run; ``synth --rlimit`` changes it
PROVE_BUDGET = 1000  #: scenarios the exact and falsifying searches of ``prove`` may simulate (``--budget``)
PROVE_RLIMIT = 20_000_000  #: Z3 resource units of ``prove``, per query
