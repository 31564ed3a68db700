"""The registry of diagnostic codes: one place, stable numbers.

E0xx syntax and files, E1xx names, E2xx structure, E3xx timing, E4xx synthesis, E5xx proof, E6xx code generation,
E7xx import and export, E8xx measurements (``verify trace``).
Every code has a section ``## <code>`` in ``specs/diagnostics.md`` with a minimal failing example that
``tests/test_diagnostic_examples.py`` runs; ``verify explain CODE`` prints that section.
"""
from __future__ import annotations

from dataclasses import dataclass

from .severity import Severity


@dataclass(frozen=True)
class Code:
    code: str
    title: str
    severity: Severity = Severity.ERROR


_ALL = [
    # E0xx: files and syntax
    Code("E001", "unexpected token"),
    Code("E002", "unexpected character"),
    Code("E003", "file is not UTF-8 text"),
    Code("E004", "file cannot be read"),
    Code("E005", "invalid number"),
    Code("E006", "import leads outside the project"),
    Code("E007", "import does not name a .vfy file"),
    Code("E008", "input exceeds a limit"),
    Code("E009", "invalid [tool.verify] settings"),
    # E1xx: names
    Code("E101", "unknown name"),
    Code("E102", "duplicate name"),
    Code("E103", "import cycle"),
    Code("E104", "task uses a port its component does not declare"),
    Code("E105", "no such system"),
    Code("E106", "unknown scheduling policy"),
    Code("E107", "wrong kind of port or member"),
    Code("E108", "unknown executor or callback-group kind"),
    Code("E109", "invalid ROS message name"),
    # E2xx: structure
    Code("E201", "connection type mismatch"),
    Code("E202", "out-port produced by no task"),
    Code("E203", "out-port produced by more than one task"),
    Code("E204", "more than one activation binding for a task"),
    Code("E205", "data trigger on an unconnected in-port"),
    Code("E206", "required in-port is not connected"),
    Code("E207", "task has no activation binding"),
    Code("E208", "chain link is not reachable"),
    Code("E209", "chain end is ambiguous"),
    Code("E210", "data-trigger cycle without a timer or sporadic source"),
    Code("E211", "in-port with more than one incoming connection"),
    Code("E212", "clause given more than once"),
    Code("E213", "task has no priority"),
    Code("E214", "task has no core"),
    Code("E215", "trigger port is not read by the task"),
    Code("E216", "synthesis hole on a task whose rate is fixed"),
    Code("E217", "task has no worst-case execution time"),
    Code("E218", "synthesis hole where a configured system is needed"),
    Code("E219", "executor has no core or no priority"),
    Code("E220", "priority or core given for a task bound to an executor"),
    Code("E221", "activation a ROS 2 executor callback cannot have"),
    Code("E222", "two threads share a priority on a core with an executor"),
    Code("E223", "callback group that does not fit its callbacks"),
    Code("E224", "executor's threads that do not fit its kind or cores"),
    # E3xx: timing
    Code("E301", "best-case execution time exceeds worst case"),
    Code("E302", "time where a frequency is expected, or vice versa"),
    Code("E303", "empty or inverted range"),
    Code("E304", "prescaler is not an integer of at least 1"),
    Code("E305", "activation outside the task's activation constraints"),
    Code("E306", "activation contradicts a fixed (non-changeable) rate"),
    Code("E307", "time or frequency must be positive"),
    Code("E308", "phase outside [0, period)"),
    Code("E309", "priority is not a non-negative integer"),
    Code("E310", "sampling tolerance violated"),
    Code("E311", "core utilisation above 1"),
    Code("E312", "no response-time bound"),
    Code("E313", "synthesis hole has no candidate values"),
    Code("E314", "compound in-port activated outside its activation constraint"),
    Code("E315", "response-time bound below the worst-case execution time"),
    Code("E316", "response-time bound above the deadline", Severity.WARNING),
    # E4xx: synthesis
    Code("E401", "synthesis is unsatisfiable"),
    Code("E402", "synthesis is undecided"),
    Code("E403", "synthesis hole has too many candidate values"),
    # E5xx: proof
    Code("E501", "latency spec violated"),
    Code("E502", "spec undecided within the budget", Severity.WARNING),
    Code("E503", "deadline miss"),
    # E6xx: code generation
    Code("E601", "file in the way of generated code"),
    Code("E602", "system the code-generation target cannot run"),
    Code("E603", "names that become one in generated code"),
    Code("E604", "construct the target's runtime would run unlike the analysis"),
    Code("E605", "generated code whose timing the analysis does not cover", Severity.WARNING),
    # E7xx: import and export of other tools' models
    Code("E701", "syntax error in an imported model"),
    Code("E702", "unresolved reference in an imported model", Severity.WARNING),
    Code("E703", "construct has no counterpart", Severity.WARNING),
    Code("E704", "imported model lacks what the timing model needs", Severity.WARNING),
    Code("E705", "inconsistent imported model"),
    Code("E706", "construct cannot be exported"),
    Code("E707", "export approximates the model", Severity.WARNING),
    # E8xx: measurements held against the model (`verify trace`, specs/trace.md)
    Code("E801", "measured execution time above the worst case"),
    Code("E802", "measured activation period off the model"),
    Code("E803", "measured latency above its bound", Severity.WARNING),
    Code("E804", "measured latency above its spec"),
    Code("E805", "task or callback not found in the trace", Severity.WARNING),
    Code("E806", "trace cannot be read"),
    Code("E807", "measured connection delay outside the model's", Severity.WARNING),
]

CODES: dict[str, Code] = {c.code: c for c in _ALL}


def heading_anchor(heading: str) -> str:
    """The anchor GitHub (and most Markdown renderers) give a heading: lower case, punctuation other
    than hyphens and underscores dropped, each space a hyphen (``E306 a fixed (non-changeable) rate``
    → ``e306-a-fixed-non-changeable-rate``)."""
    kept = "".join(ch for ch in heading.strip().lower() if ch.isalnum() or ch in "-_ ")
    return kept.replace(" ", "-")


def spec_anchor(code: str) -> str:
    """The section of specs/diagnostics.md that explains ``code`` (its heading is ``## CODE title``)."""
    known = CODES.get(code)
    return "specs/diagnostics.md#" + heading_anchor(f"{code} {known.title}" if known else code)
