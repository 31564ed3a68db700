"""The language server's side of the LSP base protocol: messages framed by ``Content-Length`` headers on
standard input, answers on standard output, with bounds on what one message may make the server hold.

pygls (``JsonRPCProtocol``) handles the messages; this module reads them, so that nothing a client sends
makes the server allocate more than ``MESSAGE_BYTES`` for a message or ``HEADER_BYTES`` for a header
line, and every request that cannot be handled gets a JSON-RPC error response:

- a header line longer than ``HEADER_BYTES``, a ``Content-Length`` that is not a number, or none:
  ``InvalidRequest`` (-32600) with id null;
- a message longer than ``MESSAGE_BYTES``: ``InvalidRequest`` with id null at once, a message shown to
  the user, and its body read in small pieces and dropped;
- a body that is not JSON (or is nested too deep): ``ParseError`` (-32700) with id null;
- JSON that is no request, notification or response (an array, an id that is neither a string nor an
  integer, a method that is not a string, a ``jsonrpc`` other than "2.0"): ``InvalidRequest``, with the
  id when it is one;
- a request whose params do not fit its method's LSP type: ``InvalidParams`` (-32602), naming what does
  not fit;
- a request before ``initialize``: ``ServerNotInitialized`` (-32002); after ``shutdown``, or a second
  ``initialize``: ``InvalidRequest``;
- a request for a method the server does not know: ``MethodNotFound`` (-32601, from pygls).

A notification gets no response (JSON-RPC): one whose params do not fit is logged to the client
(``window/logMessage``) and dropped. After any of these the connection stays usable: the next message
is read as usual.
"""
from __future__ import annotations

import asyncio
import functools
import json
import logging
import queue
import threading
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import IO, Any, BinaryIO, TypeGuard, TypeVar, cast

import cattrs
from lsprotocol import types as lsp
from pygls.io_ import StdoutWriter
from pygls.protocol import JsonRPCProtocol, JsonRPCRequestMessage, default_converter

from ..core.limits import LSP_HEADER_BYTES as HEADER_BYTES
from ..core.limits import LSP_MESSAGE_BYTES as MESSAGE_BYTES

#: the piece in which the body of an oversize message is read and dropped
DISCARD_CHUNK = 64 * 1024

PARSE_ERROR = lsp.ErrorCodes.ParseError.value
INVALID_REQUEST = lsp.ErrorCodes.InvalidRequest.value
INVALID_PARAMS = lsp.ErrorCodes.InvalidParams.value
NOT_INITIALIZED = lsp.ErrorCodes.ServerNotInitialized.value

T = TypeVar("T")


@dataclass(frozen=True)
class Frame:
    """One framed message: its body, or what was wrong with its framing (its body then dropped)."""

    body: bytes = b""
    problem: str | None = None
    oversize: bool = False
    skip: int = 0  # bytes of its body still to be read and dropped (``FrameReader.drop``)


class FrameReader:
    """Reads framed messages from a binary stream, holding at most ``limit`` bytes of one body."""

    def __init__(self, stream: IO[bytes], limit: int = MESSAGE_BYTES) -> None:
        self.stream = stream
        self.limit = limit

    def next(self) -> Frame | None:
        """The next message, or None at the end of the stream."""
        length: int | None = None
        problem: str | None = None
        while True:
            line = self.stream.readline(HEADER_BYTES + 1)
            if not line:
                return None
            if not line.endswith(b"\n"):
                if len(line) > HEADER_BYTES:
                    problem = problem or f"a header line longer than {HEADER_BYTES} bytes"
                    if not self.skip_line():
                        return None
                    continue
                return None  # (the stream ended inside a header)
            text = line.strip()
            if not text:
                break
            name, colon, value = text.partition(b":")
            if colon and name.strip().lower() == b"content-length":
                digits = value.strip()
                if digits.isdigit() and len(digits) <= 20:
                    length = int(digits)
                else:
                    problem = problem or f"a Content-Length that is not a number: {digits[:40]!r}"
        if length is None:
            return Frame(problem=problem or "a message without a Content-Length header")
        if length > self.limit:
            return Frame(problem=f"a message of {length:,} bytes, above the limit of {self.limit:,} bytes "
                                 "(verify lsp --max-message-bytes)", oversize=True, skip=length)
        if problem is not None:
            return Frame(problem=problem, skip=length)
        body = self.stream.read(length)
        if len(body) < length:
            return None
        return Frame(body)

    def skip_line(self) -> bool:
        """Read past the end of an overlong line; False at the end of the stream."""
        while True:
            piece = self.stream.readline(DISCARD_CHUNK)
            if not piece:
                return False
            if piece.endswith(b"\n"):
                return True

    def drop(self, length: int) -> bool:
        """Read ``length`` bytes in small pieces and forget them; False when the stream ends first."""
        left = length
        while left > 0:
            piece = self.stream.read(min(left, DISCARD_CHUNK))
            if not piece:
                return False
            left -= len(piece)
        return True


def frame(message: dict[str, Any]) -> bytes:
    """``message`` as the bytes of one framed message."""
    body = json.dumps(message, ensure_ascii=False).encode("utf-8")
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


def error_response(msg_id: int | str | None, code: int, message: str) -> dict[str, Any]:
    return {"jsonrpc": "2.0", "id": msg_id, "error": {"code": code, "message": message}}


@functools.cache
def shared_converter() -> cattrs.Converter:
    """pygls' converter (lsprotocol's types and pygls' own), made once: making one compiles a function per
    type the first time it meets the type, which a server per fuzzed input would pay each time."""
    return cast(Callable[[], cattrs.Converter], default_converter)()


def _valid_id(value: object) -> TypeGuard[int | str]:
    return isinstance(value, str) or (isinstance(value, int) and not isinstance(value, bool))


class Connection:
    """Hands the framed messages of one client to pygls' ``protocol``, answering with an error
    response every request that pygls would leave unanswered or answer wrongly (module docstring)."""

    def __init__(self, protocol: JsonRPCProtocol, write: Callable[[bytes], Any]) -> None:
        self.protocol = protocol
        self.write = write
        self.converter = shared_converter()
        self.initialized = False
        self.shut_down = False

    async def serve(self, reader: FrameReader) -> None:
        """Read and handle messages until the stream ends (or ``exit`` ends the process)."""
        reading = Worker("verify-lsp-read")
        while True:
            message = await reading.run(reader.next)
            if message is None:
                return
            self.receive(message)  # (a message too large is answered before its body is dropped)
            if message.skip and not await reading.run(reader.drop, message.skip):
                return

    def receive(self, message: Frame) -> None:
        if message.problem is not None:
            self.reply(None, INVALID_REQUEST, f"verify lsp: {message.problem}")
            if message.oversize:
                self.notify(lsp.WINDOW_SHOW_MESSAGE, f"verify: the editor sent {message.problem}; it was "
                                                     "dropped, so an open document may be out of step: reopen it")
            return
        try:
            data = json.loads(message.body)
        except (ValueError, RecursionError) as exc:  # (not JSON, not UTF-8, or nested too deep)
            self.reply(None, PARSE_ERROR, f"verify lsp: the message is not JSON ({str(exc)[:200]})")
            return
        structured = self.structure(data)
        if structured is not None:
            self.protocol.handle_message(structured)

    def structure(self, data: object) -> Any | None:
        """The typed message of ``data``, or None when it got an error response or was dropped."""
        if not isinstance(data, dict):
            self.reply(None, INVALID_REQUEST, "verify lsp: a message must be a JSON object")
            return None
        if "method" not in data:
            return self.response(data)
        method, msg_id = data.get("method"), data.get("id")
        request = "id" in data
        if request and not _valid_id(msg_id):
            self.reply(None, INVALID_REQUEST, "verify lsp: a request id must be a string or an integer")
            return None
        wrong = self.refusal(data, method, request)
        if wrong is not None:
            if request:
                self.reply(msg_id, *wrong)
            elif method != lsp.EXIT:
                self.notify(lsp.WINDOW_LOG_MESSAGE, f"verify: dropped a notification: {wrong[1]}",
                            lsp.MessageType.Warning)
            return None
        assert isinstance(method, str)
        kind = self.protocol.get_message_type(method)
        if kind is None:
            if not _valid_id(msg_id):
                return None  # (an unknown notification: dropped, as JSON-RPC allows)
            return JsonRPCRequestMessage(id=msg_id, method=method, jsonrpc="2.0", params=None)  # (MethodNotFound)
        try:
            typed = self.converter.structure(data, kind)
        except Exception as exc:  # (cattrs' errors: what does not fit, with its place in the message)
            what = "; ".join(cattrs.transform_error(exc))[:500] if isinstance(exc, cattrs.BaseValidationError) \
                else str(exc)[:500]
            text = f"verify lsp: the params of {method} do not fit its LSP type: {what}"
            if request:
                self.reply(msg_id, INVALID_PARAMS, text)
            else:
                self.notify(lsp.WINDOW_LOG_MESSAGE, f"{text}; the notification was dropped", lsp.MessageType.Error)
            return None
        if request:
            self.note(method)
        return typed

    def refusal(self, data: dict[str, Any], method: object, request: bool) -> tuple[int, str] | None:
        """The error code and message for a request (or notification) that is refused before its params
        are looked at; None when it may go on."""
        if not isinstance(method, str):
            return INVALID_REQUEST, "verify lsp: a message's method must be a string"
        if data.get("jsonrpc") != "2.0":
            return INVALID_REQUEST, f"verify lsp: {method}: only JSON-RPC 2.0 messages are understood"
        if method == lsp.EXIT:
            return None
        if self.shut_down:
            return INVALID_REQUEST, f"verify lsp: {method} after shutdown"
        if not self.initialized and method != lsp.INITIALIZE:
            return NOT_INITIALIZED, f"verify lsp: {method} before initialize"
        if method == lsp.INITIALIZE and (self.initialized or not request):
            return INVALID_REQUEST, "verify lsp: initialize was sent twice"
        return None

    def note(self, method: str) -> None:
        """Keep track of ``initialize`` and ``shutdown`` (requests that were accepted)."""
        self.initialized = self.initialized or method == lsp.INITIALIZE
        self.shut_down = self.shut_down or method == lsp.SHUTDOWN

    def response(self, data: dict[str, Any]) -> Any | None:
        """A client's response to a request of the server, typed by pygls (which knows what it asked)."""
        if not _valid_id(data.get("id")):
            return None  # (a response to nothing: JSON-RPC allows no answer)
        try:
            return self.protocol.structure_message(data)
        except Exception:
            return None

    def reply(self, msg_id: object, code: int, message: str) -> None:
        self.write(frame(error_response(msg_id if _valid_id(msg_id) else None, code, message)))

    def notify(self, method: str, message: str, kind: lsp.MessageType = lsp.MessageType.Error) -> None:
        self.write(frame({"jsonrpc": "2.0", "method": method, "params": {"type": kind.value, "message": message}}))


def serve(protocol: JsonRPCProtocol, stdin: BinaryIO, stdout: BinaryIO, limit: int = MESSAGE_BYTES) -> int:
    """Serve one client over ``stdin`` and ``stdout`` until the stream ends (0) or the client sends
    ``exit`` (0 after ``shutdown``, else 1, as LSP asks)."""
    logging.getLogger("pygls").addHandler(logging.NullHandler())  # (what pygls logs, the client is told)
    writer = StdoutWriter(stdout)
    protocol.set_writer(writer)
    connection = Connection(protocol, writer.write)
    try:
        asyncio.run(connection.serve(FrameReader(stdin, limit)))
    except SystemExit as exc:  # (pygls' ``exit`` handler)
        return exc.code if isinstance(exc.code, int) else 0
    except BrokenPipeError:  # (the client went away)
        return 0
    return 0


class Worker:
    """One daemon thread that runs the calls given to it in order. A call not yet started is dropped
    when its future is cancelled (``asyncio.wrap_future`` cancels it with the awaiting task); one that
    has started runs to its end. The thread never holds up the exit of the process."""

    def __init__(self, name: str) -> None:
        self.calls: queue.SimpleQueue[tuple[Future[Any], Callable[..., Any], tuple[Any, ...]] | None] = \
            queue.SimpleQueue()
        threading.Thread(target=self.serve, name=name, daemon=True).start()

    def stop(self) -> None:
        """End the thread once the calls given before are done."""
        self.calls.put(None)

    def submit(self, fn: Callable[..., T], *args: Any) -> Future[T]:
        future: Future[T] = Future()
        self.calls.put((future, fn, args))
        return future

    async def run(self, fn: Callable[..., T], *args: Any) -> T:
        """``fn(*args)`` in the thread, awaited."""
        return await asyncio.wrap_future(self.submit(fn, *args))

    def serve(self) -> None:
        while True:
            call = self.calls.get()
            if call is None:
                return
            future, fn, args = call
            if not future.set_running_or_notify_cancel():
                continue
            try:
                future.set_result(fn(*args))
            except BaseException as exc:  # (handed to whoever awaits the future)
                future.set_exception(exc)
