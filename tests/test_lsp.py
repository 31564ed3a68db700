"""`verify lsp` end to end: a real LSP client (pytest-lsp) talks to the server over stdio."""
from __future__ import annotations

import asyncio
import shutil
import sys
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types as lsp
from pytest_lsp import ClientServerConfig, LanguageClient

from verify.lsp import server as lsp_server

from .conftest import EXAMPLES

pytestmark = pytest.mark.asyncio(loop_scope="module")

WORK = Path(__file__).resolve().parent / "out" / "lsp"
#: every publication of diagnostics the client received, in order
PUBLISHED: list[lsp.PublishDiagnosticsParams] = []


@pytest_lsp.fixture(scope="module", config=ClientServerConfig(server_command=[sys.executable, "-m", "verify", "lsp"]))
async def client(lsp_client: LanguageClient):
    shutil.rmtree(WORK, ignore_errors=True)
    shutil.copytree(EXAMPLES / "navigation", WORK)
    features = lsp_client.protocol.fm.features
    keep = features.pop(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)  # (pytest-lsp's own: it keeps the last only)

    @lsp_client.feature(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    def published(params: lsp.PublishDiagnosticsParams) -> None:
        PUBLISHED.append(params)
        keep(params)

    await lsp_client.initialize_session(lsp.InitializeParams(capabilities=lsp.ClientCapabilities(),
                                                             root_uri=WORK.as_uri()))
    yield
    await lsp_client.shutdown_session()


def _open(client: LanguageClient, name: str, text: str | None = None, version: int = 1) -> str:
    """Open ``name`` in the work directory with ``text`` (default: the file there, else the navigation
    system, which imports the components beside it)."""
    path = WORK / name
    uri = path.as_uri()
    client.text_document_did_open(lsp.DidOpenTextDocumentParams(lsp.TextDocumentItem(
        uri, "vfy", version, text if text is not None else
        path.read_text(encoding="utf-8") if path.exists() else NAVIGATION)))
    return uri


def _change(client: LanguageClient, uri: str, text: str, version: int) -> None:
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(version, uri), [lsp.TextDocumentContentChangeWholeDocument(text)]))


async def _diagnostics(client: LanguageClient, uri: str, version: int, analysed: bool = False) -> list[lsp.Diagnostic]:
    """The diagnostics published for ``uri`` at ``version``: the first publication (syntax, names,
    validation), or with ``analysed`` the second (the timing analysis' added)."""
    wanted = 2 if analysed else 1
    for _ in range(1000):
        found = [p.diagnostics for p in PUBLISHED if p.uri == uri and p.version == version]
        if len(found) >= wanted:
            return list(found[wanted - 1])
        await asyncio.sleep(0.02)
    raise AssertionError(f"no diagnostics for {uri} version {version}")


async def _outline(client: LanguageClient, uri: str) -> list[lsp.DocumentSymbol]:
    return await client.text_document_document_symbol_async(lsp.DocumentSymbolParams(lsp.TextDocumentIdentifier(uri)))


def _position(text: str, needle: str, delta: int = 0) -> lsp.Position:
    at = text.index(needle) + delta
    line = text.count("\n", 0, at)
    return lsp.Position(line, len(text[text.rfind("\n", 0, at) + 1:at].encode("utf-16-le")) // 2)


NAVIGATION = (EXAMPLES / "navigation" / "navigation.vfy").read_text(encoding="utf-8")


async def test_a_valid_model_has_no_diagnostics_and_an_error_is_located(client: LanguageClient):
    uri = _open(client, "navigation.vfy")
    assert await _diagnostics(client, uri, 1) == []
    broken = NAVIGATION.replace("instance laser : Laser on cpu0", "/* é😀 */ instance laser : Lazer on cpu0")
    _change(client, uri, broken, 2)
    found = await _diagnostics(client, uri, 2)
    unknown = next(d for d in found if d.code == "E101")
    assert "unknown component `Lazer`" in unknown.message and "did you mean `Laser`?" in unknown.message
    line = broken.splitlines()[unknown.range.start.line]
    # UTF-16 columns: the emoji counts two units, the é one
    assert unknown.range.start.character == line.index("Lazer") + 1
    assert unknown.range.end.character - unknown.range.start.character == 5
    actions = await client.text_document_code_action_async(lsp.CodeActionParams(
        lsp.TextDocumentIdentifier(uri), unknown.range, lsp.CodeActionContext([unknown])))
    fix = next(a for a in actions if a.title == "Replace with `Laser`")
    assert list(fix.edit.changes[uri]) == [lsp.TextEdit(unknown.range, "Laser")]
    _change(client, uri, NAVIGATION, 3)
    assert await _diagnostics(client, uri, 3) == []


async def test_the_analysis_follows_and_its_diagnostics_arrive_after_a_pause(client: LanguageClient):
    uri = _open(client, "late.vfy", NAVIGATION.replace("timer 50 ms", "timer 50 ms deadline 5 ms"))
    assert await _diagnostics(client, uri, 1) == []  # valid: syntax, names, structure
    found = await _diagnostics(client, uri, 1, analysed=True)
    late = next(d for d in found if d.code == "E316" and "`oa.OATask`" in d.message)
    assert "above its deadline 5 ms" in late.message


async def test_completion_offers_the_keywords_the_parser_expects(client: LanguageClient):
    text = NAVIGATION.replace("    task RobotTask priority 9 trigger navvel\n", "    task RobotTask priority 9 \n")
    uri = _open(client, "complete.vfy", text)
    await _diagnostics(client, uri, 1)
    items = await client.text_document_completion_async(lsp.CompletionParams(
        lsp.TextDocumentIdentifier(uri), _position(text, "priority 9 ", len("priority 9 "))))
    labels = {i.label for i in items}
    assert {"timer", "trigger", "sporadic", "deadline"} <= labels and "component" not in labels


async def test_completion_after_an_instance_gives_its_ports_and_in_a_chain_only_reachable_ones(
        client: LanguageClient):
    uri = _open(client, "members.vfy")
    await _diagnostics(client, uri, 1)
    text = NAVIGATION.replace("  chain planning:", "  connect laser.\n  chain planning:")
    _change(client, uri, text, 2)
    await _diagnostics(client, uri, 2)
    items = await client.text_document_completion_async(lsp.CompletionParams(
        lsp.TextDocumentIdentifier(uri), _position(text, "connect laser.", len("connect laser."))))
    assert {i.label for i in items} == {"odom", "scan", "LaserTask"}
    text = NAVIGATION.replace("chain planning: laser.scan -> mapper.map", "chain planning: laser.scan -> oa.")
    _change(client, uri, text, 3)
    await _diagnostics(client, uri, 3)
    items = await client.text_document_completion_async(lsp.CompletionParams(
        lsp.TextDocumentIdentifier(uri), _position(text, "planning: laser.scan -> oa.", len("planning: laser.scan -> "
                                                                                            "oa."))))
    assert {i.label for i in items} == {"scan", "OATask", "navvel"}  # not odom, not path


async def test_hover_shows_rates_response_times_and_chain_latencies(client: LanguageClient):
    uri = _open(client, "hover.vfy")
    await _diagnostics(client, uri, 1, analysed=True)
    on_chain = await client.text_document_hover_async(lsp.HoverParams(
        lsp.TextDocumentIdentifier(uri), _position(NAVIGATION, "chain reactive", len("chain r"))))
    text = on_chain.contents.value
    assert "reaction time ≤ 189.3 ms" in text and "margin 60.7 ms" in text and "jitter ≤" in text
    on_task = await client.text_document_hover_async(lsp.HoverParams(
        lsp.TextDocumentIdentifier(uri), _position(NAVIGATION, "task CurMapTask", len("task C"))))
    assert "`mapper.CurMapTask`" in on_task.contents.value and "4 Hz" in on_task.contents.value
    assert "R ≤ 172 ms" in on_task.contents.value


async def test_definition_references_and_rename_across_files(client: LanguageClient):
    uri = _open(client, "navigation.vfy")
    await _diagnostics(client, uri, 1)
    at = _position(NAVIGATION, "instance laser : Laser", len("instance laser : "))
    where = await client.text_document_definition_async(lsp.DefinitionParams(lsp.TextDocumentIdentifier(uri), at))
    assert where.uri == (WORK / "components.vfy").as_uri()
    refs = await client.text_document_references_async(lsp.ReferenceParams(
        text_document=lsp.TextDocumentIdentifier(uri), position=at,
        context=lsp.ReferenceContext(include_declaration=True)))
    assert len(refs) == 2 and {r.uri for r in refs} == {uri, where.uri}
    edit = await client.text_document_rename_async(lsp.RenameParams(
        text_document=lsp.TextDocumentIdentifier(uri), position=at, new_name="Lidar"))
    assert set(edit.changes) == {uri, where.uri}
    assert all(e.new_text == "Lidar" for edits in edit.changes.values() for e in edits)
    bad = await client.text_document_rename_async(lsp.RenameParams(
        text_document=lsp.TextDocumentIdentifier(uri), position=at, new_name="no way"))
    assert bad is None


async def test_the_outline_has_rates_sampling_marks_and_latencies(client: LanguageClient):
    uri = _open(client, "outline.vfy")
    await _diagnostics(client, uri, 1, analysed=True)
    symbols = await _outline(client, uri)
    (system,) = symbols
    assert system.name == "Navigation"
    kids = {k.name: k for k in system.children}
    oa = {t.name: t for t in kids["oa"].children}
    assert oa["OATask"].detail.startswith("20 Hz · R ≤ 8 ms") and "scan undersampled ×2" in oa["OATask"].detail
    assert kids["reactive"].detail.startswith("reaction ≤ 189.3 ms · data age ≤ 139.3 ms")


async def test_formatting_and_applying_synthesized_values(client: LanguageClient):
    holes = (WORK / "navigation-holes.vfy").read_text(encoding="utf-8")
    uri = _open(client, "navigation-holes.vfy")
    await _diagnostics(client, uri, 1)
    actions = await client.text_document_code_action_async(lsp.CodeActionParams(
        lsp.TextDocumentIdentifier(uri), lsp.Range(lsp.Position(0, 0), lsp.Position(0, 0)), lsp.CodeActionContext([])))
    apply = next(a for a in actions if a.title.startswith("Apply synthesized values"))
    resolved = await client.code_action_resolve_async(apply)
    edits = resolved.edit.changes[uri]
    assert len(edits) == 3 and {e.new_text for e in edits} >= {"100 ms", "20"}
    messy = holes.replace("  core cpu0 policy fixed_priority", "  core   cpu0    policy fixed_priority")
    _change(client, uri, messy, 2)
    await _diagnostics(client, uri, 2)
    edits = await client.text_document_formatting_async(lsp.DocumentFormattingParams(
        lsp.TextDocumentIdentifier(uri), lsp.FormattingOptions(tab_size=2, insert_spaces=True)))
    assert len(edits) == 1 and edits[0].new_text == "  core cpu0 policy fixed_priority\n"


async def test_junk_and_huge_buffers_are_answered_and_the_server_keeps_serving(client: LanguageClient):
    uri = _open(client, "junk.vfy", "\x00\x01 component { \udcff" * 3 + "\u202e")
    found = await _diagnostics(client, uri, 1)
    assert found and all(d.source == "verify" for d in found)
    _change(client, uri, "component C {\n" + "  // " + "x" * 10_500_000 + "\n}\n", 2)  # a 10 MB paste
    assert await _diagnostics(client, uri, 2) == []
    symbols = await _outline(client, uri)
    assert [s.name for s in symbols] == ["C"]
    _change(client, uri, "component C {\n" + "  // " + "x" * 17_000_000 + "\n}\n", 3)  # above the file limit
    found = await _diagnostics(client, uri, 3)
    assert [d.code for d in found] == ["E008"]
    symbols = await _outline(client, uri)
    assert symbols == []
    hover = await client.text_document_hover_async(lsp.HoverParams(lsp.TextDocumentIdentifier(uri),
                                                                   lsp.Position(10_000, 10_000)))
    assert hover is None
    unknown = await client.text_document_hover_async(lsp.HoverParams(
        lsp.TextDocumentIdentifier((WORK / "never-opened.vfy").as_uri()), lsp.Position(0, 0)))
    assert unknown is None


async def test_a_newer_change_cancels_the_analysis_of_an_older_one(client: LanguageClient):
    uri = _open(client, "fast.vfy")
    for version in range(2, 8):  # quicker than the analysis delay
        _change(client, uri, NAVIGATION + "\n" * version, version)
    assert await _diagnostics(client, uri, 7, analysed=True) == []
    await asyncio.sleep(lsp_server.ANALYSIS_DELAY * 3)
    published = [p.version for p in PUBLISHED if p.uri == uri]
    # at most one load of each version (a superseded one is dropped) and one analysis, of the last version
    assert published[-2:] == [7, 7] and published[:-1] == sorted(set(published[:-1]))
    assert not [m for m in client.log_messages if m.type == lsp.MessageType.Error]


async def test_a_cancelled_request_leaves_the_server_serving(client: LanguageClient):
    uri = _open(client, "cancel.vfy")
    await _diagnostics(client, uri, 1)
    task = asyncio.ensure_future(client.text_document_completion_async(lsp.CompletionParams(
        lsp.TextDocumentIdentifier(uri), lsp.Position(0, 0))))
    task.cancel()  # the client sends $/cancelRequest
    with pytest.raises(asyncio.CancelledError):
        await task
    symbols = await _outline(client, uri)
    assert symbols and symbols[0].name == "Navigation"


async def test_an_internal_failure_of_a_request_is_logged_and_answered_empty():
    """(No client needed: the wrapper every handler has.)"""
    logged = []

    class Server:
        def log_error(self, what: str, trace: str) -> None:
            logged.append((what, trace))

    @lsp_server.guarded(list)
    def broken(ls, params):
        raise ZeroDivisionError("a bug")

    assert broken(Server(), None) == []
    assert logged[0][0] == "broken" and "ZeroDivisionError: a bug" in logged[0][1]


async def test_an_incremental_change_is_applied_at_its_utf16_range(client: LanguageClient):
    text = NAVIGATION.replace("instance laser : Laser on cpu0", "/* 😀 */ instance laser : Laser on cpu0")
    uri = _open(client, "incremental.vfy", text)
    assert await _diagnostics(client, uri, 1) == []
    start = _position(text, "instance laser : Laser", len("instance laser : "))
    end = lsp.Position(start.line, start.character + len("Laser"))
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(2, uri),
        [lsp.TextDocumentContentChangePartial(range=lsp.Range(start, end), text="Lazer")]))
    found = await _diagnostics(client, uri, 2)
    unknown = next(d for d in found if d.code == "E101")
    assert unknown.range.start == start and "unknown component `Lazer`" in unknown.message



async def test_a_byte_order_mark_and_an_astral_character_on_one_line_are_counted_as_lsp_counts(
        client: LanguageClient):
    # line 0 holds the mark (no position of its own: the editor does not show it) and an emoji (two UTF-16
    # units, one code point), both before a misspelt keyword
    text = "\ufeff/* 😀 */ componnt Extra { }\n" + NAVIGATION
    uri = _open(client, "bom-astral.vfy", text)
    typo = next(d for d in await _diagnostics(client, uri, 1) if d.code == "E001")
    start = len("/* 😀 */ ".encode("utf-16-le")) // 2
    assert start == 9 and "did you mean `component`?" in typo.message
    assert typo.range == lsp.Range(lsp.Position(0, start), lsp.Position(0, start + len("componnt")))
    # the same range, sent back as an incremental change, replaces exactly the word
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(2, uri), [lsp.TextDocumentContentChangePartial(range=typo.range,
                                                                                           text="component")]))
    assert await _diagnostics(client, uri, 2) == []

GROUPS = """component Node {
  in data : M
  out r : M
  task Tick { produces r wcet 2 ms }
  task Sub { reads data wcet 3 ms }
}
system S {
  core c1
  core c2
  executor mt multi_threaded 2 threads on c1, c2 priority 5
  instance n : Node {
    group fast reentrant
    task Tick executor mt timer 20 ms
    task Sub executor mt group fast trigger data
  }
  connect n.r -> n.data
}
"""


async def test_callback_groups_in_the_outline_definition_and_completion(client: LanguageClient):
    """A callback group is a member of its instance in the outline, `group NAME` on a task leads to its
    declaration, and completion after `group` offers the groups."""
    uri = _open(client, "groups.vfy", GROUPS)
    assert await _diagnostics(client, uri, 1) == []
    system = next(k for k in await _outline(client, uri) if k.name == "S")
    instance = next(k for k in system.children if k.name == "n")
    group = next(k for k in instance.children if k.name == "fast")
    assert group.detail == "reentrant callback group" and group.kind == lsp.SymbolKind.Namespace
    at = _position(GROUPS, "group fast trigger", len("group "))
    where = await client.text_document_definition_async(lsp.DefinitionParams(lsp.TextDocumentIdentifier(uri), at))
    assert where.range.start == _position(GROUPS, "group fast reentrant", len("group "))
    text = GROUPS.replace("task Tick executor mt timer", "task Tick executor mt group \n    timer")
    _change(client, uri, text, 2)
    await _diagnostics(client, uri, 2)
    items = await client.text_document_completion_async(lsp.CompletionParams(
        lsp.TextDocumentIdentifier(uri), _position(text, "executor mt group ", len("executor mt group "))))
    assert "fast" in {i.label for i in items}
