"""The ``lsp`` fuzz target: the input is what a client writes to ``verify lsp`` — framed messages, or
any bytes — and a fresh server (``verify.lsp.server.build``) reads it through its transport
(``verify.lsp.transport``: the same ``FrameReader`` and ``Connection`` as over standard input).

Invariants: nothing escapes the transport but the ``exit`` notification's end of the process; what the
server writes is framed JSON; every request that reached the server (framed, a JSON object with a
string or integer id and a method) gets a response within ``SETTLE`` seconds of the last message
(the documents' loads included); no handler fails internally (``verify: internal error`` in the log,
or pygls' ``Error in server``).
"""
from __future__ import annotations

import asyncio
import io
import json
from typing import Any

from .targets import Finding

#: the message size limit of the fuzzed server (a mutant's Content-Length reaches it without its bytes)
MESSAGE_BYTES = 1024 * 1024
#: seconds the requests and loads of one input may take after its last message
SETTLE = 20.0


class Capture:
    """The server's standard output, in memory."""

    def __init__(self) -> None:
        self.data = bytearray()

    def write(self, data: bytes) -> None:
        self.data += data

    def close(self) -> None:
        pass


def session(text: str) -> bytes:
    """A client's session on ``text`` (a seed, in compact JSON to stay within libFuzzer's input size):
    initialize, open it, ask what an editor asks, change it, shut down and exit."""
    doc = {"uri": "file:///f/a.vfy"}
    at = {"textDocument": doc, "position": {"line": 2, "character": 9}}
    start = {"start": {"line": 0, "character": 0}, "end": {"line": 1, "character": 0}}
    messages: list[tuple[str, Any]] = [
        ("initialize", {"capabilities": {}}),
        ("textDocument/didOpen", {"textDocument": {**doc, "languageId": "vfy", "version": 1, "text": text}}),
        ("textDocument/documentSymbol", {"textDocument": doc}), ("textDocument/hover", at),
        ("textDocument/completion", at), ("textDocument/references", {**at, "context": {"includeDeclaration": True}}),
        ("textDocument/codeAction", {"textDocument": doc, "range": start, "context": {"diagnostics": []}}),
        ("textDocument/formatting", {"textDocument": doc, "options": {"tabSize": 2, "insertSpaces": True}}),
        ("textDocument/didChange", {"textDocument": {**doc, "version": 2},
                                    "contentChanges": [{"range": start, "text": "// x\n"}]}),
        ("shutdown", None), ("exit", None)]
    out = b""
    for n, (method, params) in enumerate(messages):
        message = {"jsonrpc": "2.0", "method": method, "params": params}
        if method not in ("exit", "textDocument/didOpen", "textDocument/didChange"):
            message["id"] = n
        body = json.dumps(message, separators=(",", ":")).encode("utf-8")
        out += b"Content-Length: %d\r\n\r\n" % len(body) + body
    return out


def written(data: bytes) -> list[dict[str, Any]]:
    """The messages in the server's output (a broken frame or body is a finding)."""
    from verify.lsp.transport import FrameReader

    reader, out = FrameReader(io.BytesIO(data), limit=len(data) + 1), []
    while (frame := reader.next()) is not None:
        if frame.problem is not None:
            raise Finding(f"the server wrote a broken frame: {frame.problem}")
        try:
            message = json.loads(frame.body)
        except ValueError as exc:
            raise Finding(f"the server wrote a body that is not JSON: {exc}") from exc
        out.append(message)
    return out


def request_id(body: bytes) -> int | str | None:
    """The id of the request ``body`` holds, if it is one that the server must answer."""
    try:
        data = json.loads(body)
    except (ValueError, RecursionError):
        return None
    if not isinstance(data, dict) or "method" not in data:
        return None
    msg_id = data.get("id")
    return msg_id if isinstance(msg_id, str) or (isinstance(msg_id, int) and not isinstance(msg_id, bool)) else None


async def feed(data: bytes) -> tuple[bytes, list[int | str]]:
    """Serve ``data`` to a fresh server, one message at a time (the next once the server is idle, so that
    a run is the same every time): what it wrote, and the ids of the requests it was sent."""
    from verify.lsp.server import build
    from verify.lsp.transport import Connection, FrameReader

    out, server = Capture(), build()
    server.protocol.set_writer(out)
    connection = Connection(server.protocol, out.write)
    reader, asked = FrameReader(io.BytesIO(data), MESSAGE_BYTES), []
    try:
        while (message := reader.next()) is not None:
            if message.problem is None and (msg_id := request_id(message.body)) is not None:
                asked.append(msg_id)
            connection.receive(message)
            if message.skip and not reader.drop(message.skip):
                break
            await idle(server)
    except SystemExit:  # (``exit``: the end of the session, as the process would end)
        pass
    await idle(server)
    for doc in list(server.documents.values()):
        doc.close()
    return bytes(out.data), asked


async def idle(server: Any) -> None:
    """Wait until every load and request is done (at most ``SETTLE`` seconds; an analysis, which waits
    for a pause in the changes, is not waited for)."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + SETTLE
    await asyncio.sleep(0)
    while loop.time() < deadline:
        follows = {d.pending for d in server.documents.values()}
        busy = [t for t in asyncio.all_tasks() if t is not asyncio.current_task() and t not in follows]
        if not busy and all(d.ready.is_set() for d in server.documents.values()):
            await asyncio.sleep(0)  # (the callbacks of the tasks that just ended: their responses)
            return
        await asyncio.sleep(0.001)


def lsp(data: bytes) -> None:
    output, asked = asyncio.run(feed(data))
    messages = written(output)
    answered = {m.get("id") for m in messages if "method" not in m}
    missing = [i for i in asked if i not in answered]
    if missing:
        raise Finding(f"requests without a response: {missing[:5]}")
    for m in messages:
        params = m.get("params")
        text = str(params.get("message", "")) if isinstance(params, dict) else ""
        if text.startswith(("verify: internal error", "Error in server")):
            raise Finding(f"a handler failed: {text[:2000]}")
