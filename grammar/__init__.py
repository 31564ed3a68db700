"""The verify language grammar, shipped as package data (``verify.grammar``)."""
