"""Coverage-guided fuzzing of every pipeline stage with atheris (docs/contributing/fuzzing.md).

    python -m fuzz --total 1000000             # every target, seeded from examples/ and the spec examples
    python -m fuzz --targets parse --runs 5000 # one target
    python -m fuzz --smoke                     # what tests/test_fuzz.py runs

``targets`` holds the stages (no atheris needed), ``seeds`` the seed corpus, ``harness`` the process that
atheris runs, ``run`` the driver that starts the harnesses and sums up what they found.
"""
