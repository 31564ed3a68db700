"""From text to model: loading files and imports, parsing (with error recovery), formatting, name resolution,
validation and building the semantic model."""
