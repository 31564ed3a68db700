"""`verify lsp` against a hostile or broken client (issue 37): the real server over pipes, spoken to byte by
byte (``Raw``), so that framing the LSP client libraries would never produce can be sent.

What is held: a message above the size limit is refused at once and never allocated; every bad request
gets its JSON-RPC error response and the connection stays usable; a change range that starts after its
end is rejected (the document never grows), positions past the end are clamped, a byte order mark is not
counted; long work (a slow load, synth) holds up no other request, and a cancelled request is answered
``RequestCancelled`` with its child process killed.
"""
from __future__ import annotations

import json
import os
import queue
import shutil
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

from ..conftest import EXAMPLES

#: a server whose loads of ``slow.vfy`` sleep ``argv[1]`` seconds first and whose synth child sleeps
#: (long work that the tests can count on, however fast the real front end and synth become)
SLOWED = """
import sys, time
from verify.lsp import server, synthchild
real = server.load_document
def load_document(path, buffers):
    if path.endswith("slow.vfy"):
        time.sleep(float(sys.argv[1]))
    return real(path, buffers)
server.load_document = load_document
synthchild.COMMAND = [sys.executable, "-c", "import time; time.sleep(600)  # verify-lsp-test-child"]
sys.exit(server.main())
"""
WAIT = 60  # seconds any one expected message may take (a loaded machine), never reached when all is well


class Raw:
    """The server as a subprocess, with framed JSON (or raw bytes) written to it and its messages read
    in a thread."""

    def __init__(self, cwd: Path, *args: str, command: list[str] | None = None) -> None:
        self.proc = subprocess.Popen(command or [sys.executable, "-m", "verify", "lsp", *args], cwd=cwd,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.messages: queue.Queue[dict[str, Any] | None] = queue.Queue()
        self.seen: list[dict[str, Any]] = []  # every message read, in order
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        out = self.proc.stdout
        assert out is not None
        while True:
            length = None
            while True:
                line = out.readline()
                if not line:
                    self.messages.put(None)
                    return
                if line in (b"\r\n", b"\n"):
                    break
                name, _, value = line.decode("ascii").partition(":")
                if name.strip().lower() == "content-length":
                    length = int(value)
            assert length is not None
            self.messages.put(json.loads(out.read(length)))

    def write(self, data: bytes) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(data)
        self.proc.stdin.flush()

    def send(self, message: dict[str, Any] | bytes) -> None:
        body = message if isinstance(message, bytes) else json.dumps(message).encode("utf-8")
        self.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)

    def request(self, msg_id: int, method: str, params: Any = None) -> None:
        self.send({"jsonrpc": "2.0", "id": msg_id, "method": method, "params": params})

    def notify(self, method: str, params: Any) -> None:
        self.send({"jsonrpc": "2.0", "method": method, "params": params})

    def until(self, wanted: Any) -> dict[str, Any]:
        """The next message for which ``wanted(message)`` holds (the ones before it kept in ``seen``)."""
        while True:
            message = self.messages.get(timeout=WAIT)
            if message is None:
                raise AssertionError(f"the server ended; stderr: {self.stderr()}")
            self.seen.append(message)
            if wanted(message):
                return message

    def response(self, msg_id: int | None = None) -> dict[str, Any]:
        """The response to ``msg_id`` (None: the next response, whatever its id)."""
        return self.until(lambda m: "method" not in m and (msg_id is None or m.get("id") == msg_id))

    def initialize(self, root: Path) -> None:
        self.request(0, "initialize", {"capabilities": {}, "rootUri": root.as_uri()})
        assert "capabilities" in self.response(0)["result"]
        self.notify("initialized", {})

    def open(self, path: Path, text: str, version: int = 1) -> str:
        uri = path.as_uri()
        self.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "vfy", "version": version,
                                                              "text": text}})
        return uri

    def change(self, uri: str, version: int, *changes: dict[str, Any]) -> None:
        self.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": version},
                                               "contentChanges": list(changes)})

    def published(self, uri: str, version: int) -> dict[str, Any]:
        return self.until(lambda m: m.get("method") == "textDocument/publishDiagnostics"
                          and m["params"]["uri"] == uri and m["params"].get("version") == version)["params"]

    def outline(self, msg_id: int, uri: str) -> list[str]:
        self.request(msg_id, "textDocument/documentSymbol", {"textDocument": {"uri": uri}})
        return [s["name"] for s in self.response(msg_id)["result"]]

    def stop(self) -> int:
        """Shut down and exit as a client should; the exit code."""
        self.request(999, "shutdown")
        assert self.response(999)["result"] is None
        self.notify("exit", None)
        return self.proc.wait(timeout=WAIT)

    def stderr(self) -> str:
        if self.proc.poll() is None:
            return "(running)"
        assert self.proc.stderr is not None
        return self.proc.stderr.read().decode("utf-8", "replace")

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


@pytest.fixture
def work(tmp_path: Path) -> Path:
    shutil.copytree(EXAMPLES / "navigation", tmp_path / "navigation")
    return tmp_path / "navigation"


@pytest.fixture
def started(work: Path):
    servers: list[Raw] = []

    def start(*args: str, command: list[str] | None = None, initialize: bool = True) -> Raw:
        server = Raw(work, *args, command=command)
        servers.append(server)
        if initialize:
            server.initialize(work)
        return server

    yield start
    for server in servers:
        server.kill()


def _error(message: dict[str, Any]) -> tuple[Any, int]:
    return message["id"], message["error"]["code"]


# ------------------------------------------------------------------ framing


def test_a_terabyte_content_length_is_refused_at_once_and_the_server_ends_cleanly(started):
    server = started()
    server.write(b"Content-Length: 1000000000000\r\n\r\n{\"jsonrpc\": ")
    refused = server.response()
    assert _error(refused) == (None, -32600) and "above the limit of 134,217,728 bytes" in refused["error"]["message"]
    shown = server.until(lambda m: m.get("method") == "window/showMessage")
    assert "reopen" in shown["params"]["message"]
    assert server.proc.stdin is not None
    server.proc.stdin.close()  # (the rest of the terabyte never comes)
    assert server.proc.wait(timeout=WAIT) == 0
    assert "Traceback" not in server.stderr() and "MemoryError" not in server.stderr()


def test_a_message_above_the_limit_is_dropped_and_the_next_one_is_answered(started, work):
    server = started("--max-message-bytes", "4000")
    uri = server.open(work / "navigation.vfy", (work / "navigation.vfy").read_text(encoding="utf-8"))
    assert server.published(uri, 1)["diagnostics"] == []
    padded = {"jsonrpc": "2.0", "id": 7, "method": "textDocument/hover", "params": {
        "textDocument": {"uri": uri}, "position": {"line": 0, "character": 0}, "workDoneToken": "x" * 5000}}
    server.send(padded)
    assert _error(server.response()) == (None, -32600)
    assert server.outline(8, uri) == ["Navigation"]
    assert not [m for m in server.seen if m.get("id") == 7]  # (the dropped request itself is never handled)
    assert server.stop() == 0


@pytest.mark.parametrize("header", [
    b"Content-Length: 12" + b"3" * 5000 + b"\r\n\r\n",  # a header line above the limit (4096 bytes)
    b"Content-Length: twelve\r\n\r\n",
    b"Content-Type: application/vscode-jsonrpc; charset=utf-8\r\n\r\n",  # no length
    b"Content-Length: -5\r\n\r\n",
], ids=["overlong-line", "not-a-number", "no-length", "negative"])
def test_a_broken_header_is_answered_and_the_connection_stays_usable(started, header):
    server = started()
    server.write(header)
    assert _error(server.response()) == (None, -32600)
    server.request(5, "textDocument/hover", {"textDocument": {"uri": "file:///nowhere.vfy"},
                                             "position": {"line": 0, "character": 0}})
    assert server.response(5)["result"] is None
    assert server.stop() == 0


BAD_REQUESTS = [  # (what is sent, the id and error code of its answer)
    (b"{not json", None, -32700),
    (b"\xff\xfe{\x00", None, -32700),  # not UTF-8 (nor the UTF-16 its first bytes suggest)
    (b"[" * 100_000 + b"]" * 100_000, None, -32700),  # nested deeper than any decoder recurses
    (b"[1, 2]", None, -32600),  # a batch: not in LSP
    (b'"hover"', None, -32600),
    (b'{"jsonrpc": "2.0", "id": {"a": 1}, "method": "shutdown"}', None, -32600),
    (b'{"jsonrpc": "2.0", "id": 1.5, "method": "shutdown"}', None, -32600),
    (b'{"jsonrpc": "1.0", "id": 11, "method": "textDocument/hover", "params": {}}', 11, -32600),
    (b'{"jsonrpc": "2.0", "id": 12, "method": 5}', 12, -32600),
    (b'{"jsonrpc": "2.0", "id": 13, "method": "textDocument/hover", "params": {"textDocument": {"uri": 5}, '
     b'"position": {"line": -1, "character": "x"}}}', 13, -32602),
    (b'{"jsonrpc": "2.0", "id": 14, "method": "textDocument/hover"}', 14, -32602),
    (b'{"jsonrpc": "2.0", "id": 18, "method": "textDocument/hover", "params": {"textDocument": {"uri": "file:///a"}, '
     b'"position": {"line": 1099511627776, "character": 0}}}', 18, -32602),  # above LSP's uinteger
    (b'{"jsonrpc": "2.0", "id": 15, "method": "textDocument/completion", "params": [1, 2]}', 15, -32602),
    (b'{"jsonrpc": "2.0", "id": 16, "method": "no/such/method", "params": {}}', 16, -32601),
    (b'{"jsonrpc": "2.0", "id": 17, "method": "initialize", "params": {"capabilities": {}}}', 17, -32600),
]


def test_every_bad_request_gets_its_error_response_and_the_server_keeps_serving(started, work):
    server = started()
    for body, msg_id, code in BAD_REQUESTS:
        server.send(body)
        answer = server.response()
        assert _error(answer) == (msg_id, code), (body[:80], answer)
        assert answer["error"]["message"]
    # a notification whose params do not fit: no response (JSON-RPC), a message in the client's log
    server.notify("textDocument/didOpen", {"textDocument": {"uri": 3}})
    logged = server.until(lambda m: m.get("method") == "window/logMessage")
    assert "textDocument/didOpen" in logged["params"]["message"]
    uri = server.open(work / "navigation.vfy", (work / "navigation.vfy").read_text(encoding="utf-8"))
    assert server.outline(20, uri) == ["Navigation"]
    assert server.stop() == 0
    assert "Traceback" not in server.stderr()


def test_requests_before_initialize_and_after_shutdown_are_refused(started, work):
    server = started(initialize=False)
    server.request(1, "textDocument/documentSymbol", {"textDocument": {"uri": (work / "x.vfy").as_uri()}})
    assert _error(server.response(1)) == (1, -32002)
    server.initialize(work)
    server.request(2, "shutdown")
    assert server.response(2)["result"] is None
    server.request(3, "textDocument/documentSymbol", {"textDocument": {"uri": (work / "x.vfy").as_uri()}})
    assert _error(server.response(3)) == (3, -32600)
    server.notify("exit", None)
    assert server.proc.wait(timeout=WAIT) == 0


def test_exit_without_shutdown_ends_the_server_with_1(started):
    server = started()
    server.notify("exit", None)
    assert server.proc.wait(timeout=WAIT) == 1


# ------------------------------------------------------------------ ranges and positions


def _range(start: tuple[int, int], end: tuple[int, int]) -> dict[str, Any]:
    return {"start": {"line": start[0], "character": start[1]}, "end": {"line": end[0], "character": end[1]}}


def test_a_reversed_range_is_rejected_and_the_document_never_grows(started, work):
    server = started()
    uri = server.open(work / "a.vfy", "component A {}\n")
    assert server.published(uri, 1)["diagnostics"] == []
    for version in range(2, 7):
        server.change(uri, version, {"range": _range((0, 5), (0, 0)), "text": ""})
        shown = server.until(lambda m: m.get("method") == "window/showMessage")
        assert "starts (1:6) after it ends (1:1)" in shown["params"]["message"]
    # the whole change is rejected, even the valid part before the reversed range
    server.change(uri, 7, {"range": _range((0, 0), (0, 0)), "text": "component B {}\n"},
                  {"range": _range((3, 0), (1, 0)), "text": "x"})
    server.until(lambda m: m.get("method") == "window/showMessage")
    assert server.outline(1, uri) == ["A"]
    assert not [m for m in server.seen if m.get("method") == "textDocument/publishDiagnostics"
                and m["params"]["version"] != 1]


def test_positions_past_the_end_are_clamped(started, work):
    server = started()
    uri = server.open(work / "a.vfy", "component A {}\n")
    server.change(uri, 2, {"range": _range((1000, 7), (1000, 9)), "text": "component B {}\n"})  # after the end
    server.change(uri, 3, {"range": _range((0, 999), (0, 999)), "text": "\ncomponent C {}"})  # past the line
    published = server.published(uri, 3)
    assert published["diagnostics"] == []
    assert server.outline(1, uri) == ["A", "C", "B"]


NAVIGATION = (EXAMPLES / "navigation" / "navigation.vfy").read_text(encoding="utf-8")


def test_a_byte_order_mark_is_not_counted_in_positions(started, work):
    server = started()
    text = "\ufeff" + NAVIGATION.replace("instance laser : Laser on cpu0", "instance laser : Lazer on cpu0")
    uri = server.open(work / "bom.vfy", text)
    (unknown,) = [d for d in server.published(uri, 1)["diagnostics"] if d["code"] == "E101"]
    line = text.lstrip("\ufeff").split("\n")[unknown["range"]["start"]["line"]]
    assert unknown["range"]["start"]["character"] == line.index("Lazer")
    first = text.lstrip("\ufeff").split("\n")[0]
    # an edit at the start of the first line goes after the mark: the line counts from its first character
    server.change(uri, 2, {"range": _range((0, 0), (0, len(first))), "text": "// " + first})
    moved = [d for d in server.published(uri, 2)["diagnostics"] if d["code"] == "E101"]
    assert [d["range"] for d in moved] == [unknown["range"]]
    server.request(3, "textDocument/definition", {"textDocument": {"uri": uri}, "position": {
        "line": NAVIGATION.split("\n").index(next(x for x in NAVIGATION.split("\n") if "instance oa" in x)),
        "character": next(x for x in NAVIGATION.split("\n") if "instance oa" in x).index(": ") + 2}})
    where = server.response(3)["result"]
    assert where is not None and where["uri"].endswith("components.vfy")


# ------------------------------------------------------------------ long work off the message loop


def test_a_slow_load_holds_up_no_other_document_and_a_waiting_request_can_be_cancelled(started, work):
    server = started(command=[sys.executable, "-c", SLOWED, "4"])
    slow = server.open(work / "slow.vfy", NAVIGATION)
    fast = server.open(work / "fast.vfy", NAVIGATION)
    assert server.outline(1, fast) == ["Navigation"]  # (answered while slow.vfy loads)
    server.request(2, "textDocument/documentSymbol", {"textDocument": {"uri": slow}})  # waits for the load
    server.notify("$/cancelRequest", {"id": 2})
    assert _error(server.response(2)) == (2, -32800)
    assert not [m for m in server.seen if m.get("method") == "textDocument/publishDiagnostics"
                and m["params"]["uri"] == slow]
    assert server.published(slow, 1)["diagnostics"] == []
    assert server.stop() == 0


def test_a_newer_change_supersedes_a_pending_load(started, work):
    server = started(command=[sys.executable, "-c", SLOWED, "2"])
    uri = server.open(work / "slow.vfy", NAVIGATION)
    for version in range(2, 6):  # while the load of version 1 sleeps
        server.change(uri, version, {"text": NAVIGATION + "\n" * version})
    assert server.outline(1, uri) == ["Navigation"]  # (after the load of version 5, and its publication)
    server.published(uri, 5)  # (its analysis)
    # versions 1 to 4 never published: 1 dropped when its load ended, 2 to 4 before their loads started
    assert [m["params"]["version"] for m in server.seen if m.get("method") == "textDocument/publishDiagnostics"] \
        == [5, 5]
    assert server.stop() == 0


def _children(pid: int, marker: str) -> list[int]:
    """The processes whose parent is ``pid`` and whose command line holds ``marker``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            parent = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            command = (entry / "cmdline").read_bytes().decode("utf-8", "replace")
        except (OSError, IndexError, ValueError):
            continue
        if parent == pid and marker in command:
            found.append(int(entry.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
def test_synth_runs_in_a_child_process_that_a_cancelled_request_kills(started, work):
    server = started(command=[sys.executable, "-c", SLOWED, "0"])
    holes = (work / "navigation-holes.vfy").read_text(encoding="utf-8")
    uri = server.open(work / "navigation-holes.vfy", holes)
    server.published(uri, 1)
    server.request(1, "textDocument/codeAction", {"textDocument": {"uri": uri}, "range": _range((0, 0), (0, 0)),
                                                  "context": {"diagnostics": []}})
    (action,) = [a for a in server.response(1)["result"] if a["title"].startswith("Apply synthesized values")]
    server.request(2, "codeAction/resolve", action)
    marker = "verify-lsp-test-child"
    for _ in range(WAIT * 10):
        if _children(server.proc.pid, marker):
            break
        threading.Event().wait(0.1)
    assert _children(server.proc.pid, marker), "the synth child did not start"
    assert server.outline(3, uri) == ["NavigationHoles"]  # (answered while synth runs)
    server.notify("$/cancelRequest", {"id": 2})
    assert _error(server.response(2)) == (2, -32800)
    for _ in range(WAIT * 10):
        if not _children(server.proc.pid, marker):
            break
        threading.Event().wait(0.1)
    assert not _children(server.proc.pid, marker), "the synth child outlived its cancelled request"
    assert server.stop() == 0


def test_the_message_limit_option_is_checked(work):
    done = subprocess.run([sys.executable, "-m", "verify", "lsp", "--max-message-bytes", "0"], cwd=work,
                          capture_output=True, text=True, stdin=subprocess.DEVNULL, env=dict(os.environ))
    assert done.returncode == 2 and "positive number of bytes" in done.stderr and "Traceback" not in done.stderr


# ------------------------------------------------------------------ the position helpers, without a server


def _partial(start: tuple[int, int], end: tuple[int, int], text: str):
    from lsprotocol import types as lsp

    return lsp.TextDocumentContentChangePartial(range=lsp.Range(lsp.Position(*start), lsp.Position(*end)), text=text)


@pytest.mark.parametrize("before,start,end,text,after", [
    ("ab\ncd\n", (1, 1), (1, 2), "X", "ab\ncX\n"),
    ("ab\ncd", (0, 99), (0, 99), "!", "ab!\ncd"),  # past the line: its end
    ("ab\ncd", (7, 0), (9, 3), "!", "ab\ncd!"),  # past the text: its end
    ("ab\ncd", (0, 1), (99, 0), "", "a"),
    ("\ufeffab", (0, 0), (0, 0), "X", "\ufeffXab"),  # a byte order mark is not counted: after it
    ("\ufeffab", (0, 1), (0, 2), "", "\ufeffa"),
    ("😀b", (0, 2), (0, 3), "X", "😀X"),  # UTF-16: the emoji counts two units
    ("😀b", (0, 1), (0, 3), "", "😀"),  # inside a surrogate pair: the next whole character
])
def test_a_change_is_applied_at_its_clamped_utf16_range(before, start, end, text, after):
    from verify.lsp.features import apply_changes, reversed_range

    change = _partial(start, end, text)
    assert reversed_range(change) is None
    assert apply_changes(before, [change]) == after


def test_a_reversed_range_is_recognised_and_a_whole_document_change_is_not_one():
    from lsprotocol import types as lsp

    from verify.lsp.features import reversed_range

    assert reversed_range(_partial((1, 0), (0, 5), "")) is not None
    assert reversed_range(_partial((0, 5), (0, 4), "")) is not None
    assert reversed_range(_partial((0, 4), (0, 4), "")) is None
    assert reversed_range(lsp.TextDocumentContentChangeWholeDocument(text="x")) is None
