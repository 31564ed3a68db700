"""The model's types: the syntax tree of a file (`syntax`), the semantic model of a system (`system`), the
activation kinds (`activations/`) and quantities (`units`)."""
