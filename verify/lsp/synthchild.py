"""The language server's "Apply synthesized values" in a process of its own, so that the server can stop
it (``$/cancelRequest``, a closed document, the end of the session) and answers other requests while
it runs: ``python -m verify.lsp.synthchild`` reads one JSON request on standard input, ``{"path":
PATH, "buffers": {PATH: TEXT}}`` (the open documents, which take the place of files on disk), and
writes one JSON answer on standard output: ``{"edits": [[START, END, TEXT], ...]}`` (offsets into the
root file's text: only the holes change, ``synth.writeback.hole_edits``) or ``{"warning": MESSAGE}``
when some system has no configuration.
"""
from __future__ import annotations

import asyncio
import json
import os
import sys
from typing import Any

#: the child's command line (a test may put a slower one in its place)
COMMAND = [sys.executable, "-m", "verify.lsp.synthchild"]


def synthesized_edits(path: str, buffers: dict[str, str]) -> dict[str, Any]:
    """The edits that fill the holes of every system of the project at ``path`` (the answer above)."""
    from .. import api
    from ..synth.driver import synthesize
    from ..synth.writeback import hole_edits

    result = api.load(path, overlay=lambda p: buffers.get(os.path.realpath(p)))
    root = result.project.root_module
    if root is None or result.project.root not in result.project.sources:
        return {"edits": []}
    source = result.project.sources[result.project.root]
    edits: list[list[Any]] = []
    for name, model in sorted(result.models.items()):
        if model.is_configured:
            continue
        outcome = synthesize(result, name)
        if outcome.status != "sat":
            return {"warning": f"synth: no configuration of {name} was found ({outcome.status}); run `synth` "
                               "for the explanation"}
        edits += [[e.start, e.end, e.text] for e in hole_edits(source, root, name, outcome.choices)]
    return {"edits": edits}


async def synthesize_in_child(path: str, buffers: dict[str, str]) -> dict[str, Any]:
    """``synthesized_edits`` in a child process, killed when the awaiting task is cancelled."""
    pipe = asyncio.subprocess.PIPE
    child = await asyncio.create_subprocess_exec(*COMMAND, stdin=pipe, stdout=pipe, stderr=pipe)
    try:
        request = json.dumps({"path": path, "buffers": buffers}).encode("utf-8")
        out, err = await child.communicate(request)
    finally:
        if child.returncode is None:  # (cancelled: the work is not wanted any more)
            child.kill()
            await asyncio.shield(child.wait())
    try:
        answer = json.loads(out)
    except ValueError:
        answer = None
    if child.returncode != 0 or not isinstance(answer, dict):
        raise RuntimeError(f"synth failed (exit {child.returncode}): {err.decode('utf-8', 'replace')[-2000:]}")
    return answer


def main() -> int:
    request = json.loads(sys.stdin.buffer.read())
    answer = synthesized_edits(str(request["path"]), {str(k): str(v) for k, v in request["buffers"].items()})
    sys.stdout.write(json.dumps(answer))
    return 0


if __name__ == "__main__":  # (importing the module, as tools that walk the package do, runs nothing)
    sys.exit(main())
