"""Language-server stage: what an editor's user waits for after a keystroke (issue 15).

``lsp-keystroke`` starts ``verify lsp`` as a subprocess, talks to it with pygls's own LSP client over
stdio, opens a generated system (WATERS, the stage's size) and then types: each keystroke is a
``didChange`` that edits a comment. It measures, per keystroke, the time from sending the change to
the first ``publishDiagnostics`` of that version (syntax, names and validation: what the server
publishes at once) and to the second (the timing analysis, which starts ``ANALYSIS_DELAY`` after the last
change, so a keystroke's analysis includes that pause). Goals: syntax and names on a 200-task system
within 100 ms, the full analysis within 1 s.
"""
from __future__ import annotations

import asyncio
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
KEYSTROKES = 10


async def _type(text: str, path: Path, keystrokes: int) -> tuple[list[float], list[float]]:
    from lsprotocol import types as lsp
    from pygls.lsp.client import LanguageClient

    client = LanguageClient("benchmark", "1")
    published: dict[int, list[float]] = {}

    @client.feature(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    def on_diagnostics(params: lsp.PublishDiagnosticsParams) -> None:
        published.setdefault(params.version or 0, []).append(time.perf_counter())

    await client.start_io(sys.executable, "-m", "verify", "lsp")
    try:
        await client.initialize_async(lsp.InitializeParams(capabilities=lsp.ClientCapabilities()))
        client.initialized(lsp.InitializedParams())
        uri = path.resolve().as_uri()
        client.text_document_did_open(lsp.DidOpenTextDocumentParams(lsp.TextDocumentItem(uri, "vfy", 1, text)))
        await _wait(published, 1, 2)
        first, analysed = [], []
        for version in range(2, keystrokes + 2):
            text = text + ("/" if version % 2 else "x")  # (typing in the comment at the end of the file)
            sent = time.perf_counter()
            client.text_document_did_change(lsp.DidChangeTextDocumentParams(
                lsp.VersionedTextDocumentIdentifier(version, uri), [lsp.TextDocumentContentChangeWholeDocument(text)]))
            await _wait(published, version, 2)
            first.append(published[version][0] - sent)
            analysed.append(published[version][1] - sent)
        await client.shutdown_async(None)
        client.exit(None)
    finally:
        await client.stop()
    return first, analysed


async def _wait(published: dict[int, list[float]], version: int, count: int) -> None:
    for _ in range(3000):
        if len(published.get(version, ())) >= count:
            return
        await asyncio.sleep(0.002)
    raise RuntimeError(f"no diagnostics for version {version} within 6 s")


def register(stage: Callable[..., Callable], error: type[Exception], unavailable: dict[str, str]) -> None:
    try:
        import pygls  # noqa: F401
    except ImportError as err:
        unavailable["lsp-keystroke"] = f"pygls is not installed ({err})"
        return

    @stage("lsp-keystroke", "`verify lsp` over stdio, a real LSP client typing in a comment of a generated system: "
           "time from a change to its syntax-and-names diagnostics and to its analysed ones (median of 10 "
           "keystrokes; the analysis starts 0.3 s after the last change)", sizes=(200,), quick_sizes=(10,))
    def lsp_keystroke(inst) -> dict:
        OUT.mkdir(parents=True, exist_ok=True)
        path = OUT / f"lsp-{inst.name}"
        text = inst.text + "\n// typing: "
        path.write_text(text, encoding="utf-8")
        try:
            first, analysed = asyncio.run(_type(text, path, KEYSTROKES))
        except (OSError, RuntimeError) as err:
            raise error(f"{type(err).__name__}: {err}", {}) from None
        return {"syntax and names (median)": f"{statistics.median(first) * 1000:.1f} ms",
                "max": f"{max(first) * 1000:.1f} ms",
                "analysed (median)": f"{statistics.median(analysed) * 1000:.0f} ms",
                "max analysed": f"{max(analysed) * 1000:.0f} ms"}
