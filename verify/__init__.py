"""verify: formal verification of the timing of component-based robotics software.

The public façade: ``load`` / ``load_text`` return a :class:`LoadResult` holding the parsed project,
every diagnostic and the semantic model of each valid system. See README.md for a tour.
"""
from .api import LoadResult, SelectionError, load, load_text
from .diagnostics import Diagnostic, Label, Severity

__all__ = ["Diagnostic", "Label", "LoadResult", "SelectionError", "Severity", "load", "load_text"]
__version__ = "0.1.0"
