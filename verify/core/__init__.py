"""The leaves every layer uses: source spans and maps, diagnostics and their registry, file access, limits,
integer time, identifiers. Nothing here imports another layer of verify."""
