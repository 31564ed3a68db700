"""The process atheris runs: ``python -m fuzz.harness TARGET [libFuzzer options] CORPUS_DIR``.

verify is imported under atheris' instrumentation, so that coverage of its code guides the mutations.
Lark, a dependency with its own tests, is not: instrumenting it too made the ``parse`` target 1.6 times
slower (69 against 111 executions a second) for coverage of Lark's own code. A finding
(``fuzz.targets``) is an uncaught exception, which libFuzzer saves as a ``crash-*`` file, a run longer
than ``-timeout`` a ``timeout-*`` file.
"""
from __future__ import annotations

import importlib
import pkgutil
import sys

import atheris

with atheris.instrument_imports(include=["verify"]):
    import verify

    for info in pkgutil.walk_packages(verify.__path__, "verify."):
        importlib.import_module(info.name)

from fuzz.targets import TARGETS, run  # noqa: E402


def main() -> None:
    if len(sys.argv) < 2 or sys.argv[1] not in TARGETS:
        sys.exit(f"usage: python -m fuzz.harness {{{','.join(TARGETS)}}} [libFuzzer options] [CORPUS_DIR]")
    target = sys.argv.pop(1)
    atheris.Setup(sys.argv, lambda data: run(target, data))
    atheris.Fuzz()


if __name__ == "__main__":
    main()
