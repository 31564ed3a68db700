"""Benchmarks for verify: WATERS-2015-like generated systems (``benchmarks.generate``) and a runner that
times verify's stages on them (``benchmarks.run``; ``python -m benchmarks``). See benchmarks/README.md."""
