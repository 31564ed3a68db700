"""``verify lsp``: the language server (pygls, over standard input and output; ``transport`` reads the
messages, bounded, and answers every bad request with an error response).

Nothing long runs on the message loop. On every change of a document the server applies it to its
copy (a range whose start comes after its end rejects the whole change, with a message to the user; a
position past the end of its line or of the text is clamped to it) and loads the copy in a worker
thread (parse, names, validation: the diagnostics of ``verify check``, published as soon as they are
ready); ``ANALYSIS_DELAY`` seconds later it analyses the configured systems in a second worker thread
(the diagnostics of ``verify analyze``). Each document has its own two threads. A newer change
supersedes both: a load or analysis not started yet is dropped, one running is left to finish and its
result dropped, so at most one of each runs and one waits per document. Requests about a document
(outline, hover, definition, references, rename, code actions) wait for the load of its latest version;
a client may cancel them (``$/cancelRequest``) meanwhile. Completion answers at once from the last
loads. Formatting runs in a worker thread, "Apply synthesized values" in a child process
(``synthchild``) that a cancelled request kills. Open documents are read from the editor's buffers
(imports too), never from disk when a buffer exists. Whatever a request meets, it answers: an internal
failure is logged to the client and the request gets an empty answer, and the server keeps serving.
"""
from __future__ import annotations

import asyncio
import functools
import inspect
import os
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar, cast

from lsprotocol import types as lsp
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol, lsp_method
from pygls.uris import to_fs_path

from .. import __version__, api
from ..core.source import SourceMap
from ..frontend.symbols import Symbol
from ..timing import AnalysisResult
from . import features as f
from ..core.limits import LSP_MESSAGE_BYTES as MESSAGE_BYTES
from .transport import Worker, serve, shared_converter

#: seconds after the last change before the timing analysis starts
ANALYSIS_DELAY = 0.3

F = TypeVar("F", bound=Callable[..., Any])


@dataclass
class Document:
    uri: str
    path: str
    version: int = 0
    text: str = ""
    map: SourceMap = field(default_factory=lambda: SourceMap(""))  # (positions in ``text``)
    result: api.LoadResult | None = None
    good: api.LoadResult | None = None  # the last load with a valid system (for completion mid-typing)
    loaded: int = -1  # the version ``result`` belongs to
    analyses: dict[str, AnalysisResult] = field(default_factory=dict)
    analysed: int = -1  # the version ``analyses`` belong to
    pending: asyncio.Task[None] | None = None
    ready: asyncio.Event = field(default_factory=asyncio.Event)  # (set: ``result`` is of ``version``)
    workers: dict[str, Worker] = field(default_factory=dict)

    def worker(self, name: str) -> Worker:
        """This document's thread for ``name`` (load, analysis), started when first needed: one document's
        long load or analysis holds up no other document's."""
        if name not in self.workers:
            self.workers[name] = Worker(f"verify-lsp-{name}")
        return self.workers[name]

    def close(self) -> None:
        if self.pending is not None:
            self.pending.cancel()
        for worker in self.workers.values():
            worker.stop()
        self.ready.set()  # (a request waiting for it answers)

    def edit(self, text: str, version: int) -> None:
        self.text, self.version, self.map = text, version, SourceMap(text)
        self.ready.clear()


class VerifyProtocol(LanguageServerProtocol):
    """pygls' protocol without its own copy of every open document (the server keeps one, ``Document``):
    the notifications that open, change and close a document go to the server's handlers alone."""

    @lsp_method(lsp.TEXT_DOCUMENT_DID_OPEN)
    def lsp_text_document__did_open(self, params: lsp.DidOpenTextDocumentParams) -> Any:
        yield from self.user_handler(lsp.TEXT_DOCUMENT_DID_OPEN, params)

    @lsp_method(lsp.TEXT_DOCUMENT_DID_CHANGE)
    def lsp_text_document__did_change(self, params: lsp.DidChangeTextDocumentParams) -> Any:
        yield from self.user_handler(lsp.TEXT_DOCUMENT_DID_CHANGE, params)

    @lsp_method(lsp.TEXT_DOCUMENT_DID_CLOSE)
    def lsp_text_document__did_close(self, params: lsp.DidCloseTextDocumentParams) -> Any:
        yield from self.user_handler(lsp.TEXT_DOCUMENT_DID_CLOSE, params)

    def user_handler(self, method: str, params: Any) -> Any:
        handler = self.fm.features.get(method)
        if handler is not None:
            yield handler, (params,), None


class VerifyServer(LanguageServer):
    def __init__(self) -> None:
        super().__init__("verify", __version__, protocol_cls=VerifyProtocol, converter_factory=shared_converter)
        self.documents: dict[str, Document] = {}
        self.formatter: Worker | None = None

    def worker(self) -> Worker:
        """The thread that formats documents, started when first needed."""
        if self.formatter is None:
            self.formatter = Worker("verify-lsp-format")
        return self.formatter

    # -------------------------------------------------------------- loading

    def buffers(self) -> dict[str, str]:
        return {os.path.realpath(d.path): d.text for d in self.documents.values()}

    def uris(self) -> dict[str, str]:
        return {os.path.realpath(d.path): d.uri for d in self.documents.values()}

    def map_of(self, result: api.LoadResult | None) -> Callable[[str], SourceMap]:
        """Positions in a file: of its open buffer, else of its text as ``result`` loaded it."""
        maps = {os.path.realpath(d.path): d.map for d in self.documents.values()}

        def of(path: str) -> SourceMap:
            found = maps.get(os.path.realpath(path))
            if found is not None:
                return found
            source = result.sources.get(path) if result is not None else None
            return source.map if source is not None else SourceMap("")

        return of

    def publish(self, doc: Document, with_analysis: bool) -> None:
        assert doc.result is not None
        found = list(doc.result.diagnostics)
        if with_analysis:
            from ..timing import diagnostics_of

            for analysis in doc.analyses.values():
                found += diagnostics_of(analysis)
        self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(
            uri=doc.uri, version=doc.version,
            diagnostics=f.diagnostics_for(doc.path, found, self.map_of(doc.result), self.uris())))

    def changed(self, doc: Document) -> None:
        """Load and publish, then analyse after ``ANALYSIS_DELAY``, unless a newer change comes first."""
        if doc.pending is not None:
            doc.pending.cancel()
        doc.pending = asyncio.get_running_loop().create_task(self.follow(doc, doc.version))

    async def follow(self, doc: Document, version: int) -> None:
        """Load ``version`` of ``doc`` and publish its diagnostics, then analyse it and publish again."""
        try:
            result = await doc.worker("load").run(load_document, doc.path, self.buffers())
            if doc.version != version:
                return  # (a newer change: its own load follows)
            doc.result, doc.loaded = result, version
            if result.models:
                doc.good = result
            doc.ready.set()
            self.publish(doc, with_analysis=False)
            await asyncio.sleep(ANALYSIS_DELAY)
            models = [(name, m) for name, m in sorted(result.models.items()) if m.is_configured]
            analyses = await doc.worker("analysis").run(_analyse_all, models)
            if doc.version != version:
                return
            doc.analyses, doc.analysed = analyses, version
            self.publish(doc, with_analysis=True)
        except Exception:  # an internal failure: logged, never a dead server (nor a request left waiting)
            self.log_error("analysis", traceback.format_exc())
            if doc.version == version:
                doc.ready.set()

    async def current(self, uri: str) -> Document | None:
        """The open document ``uri`` once the load of its latest version is in (None if not open)."""
        doc = self.document(uri)
        while doc is not None and doc.loaded != doc.version:
            await doc.ready.wait()
            if self.documents.get(uri) is not doc:
                return None  # (closed meanwhile)
            if doc.loaded != doc.version and doc.ready.is_set():
                break  # (its load failed: answer from the last one)
        return doc

    def log_error(self, what: str, trace: str) -> None:
        self.window_log_message(lsp.LogMessageParams(type=lsp.MessageType.Error,
                                                     message=f"verify: internal error in {what}:\n{trace}"))

    def document(self, uri: str) -> Document | None:
        return self.documents.get(uri)


def load_document(path: str, buffers: dict[str, str]) -> api.LoadResult:
    return api.load(path, overlay=lambda p: buffers.get(os.path.realpath(p)))


def _analyse_all(models: list[tuple[str, Any]]) -> dict[str, AnalysisResult]:
    from ..timing import analyze

    return {name: analyze(model) for name, model in models}


def guarded(default: Callable[[], Any]) -> Callable[[F], F]:
    """A handler (a function or a coroutine function) whose internal failure is logged and answered
    with ``default()``; a cancelled request stays cancelled."""

    def wrap(handler: F) -> F:
        if inspect.iscoroutinefunction(handler):
            @functools.wraps(handler)
            async def run_async(ls: VerifyServer, params: Any) -> Any:
                try:
                    return await handler(ls, params)
                except Exception:
                    ls.log_error(handler.__name__, traceback.format_exc())
                    return default()

            return cast(F, run_async)

        @functools.wraps(handler)
        def run(ls: VerifyServer, params: Any) -> Any:
            try:
                return handler(ls, params)
            except Exception:
                ls.log_error(handler.__name__, traceback.format_exc())
                return default()

        return cast(F, run)

    return wrap


def _path_of(uri: str) -> str:
    path = to_fs_path(uri)
    return path if path else os.path.join(os.getcwd(), uri.rsplit("/", 1)[-1] or "untitled.vfy")


# ------------------------------------------------------------------ document lifecycle


@guarded(lambda: None)
def did_open(ls: VerifyServer, params: lsp.DidOpenTextDocumentParams) -> None:
    item = params.text_document
    old = ls.documents.get(item.uri)
    if old is not None:
        old.close()
    doc = Document(item.uri, _path_of(item.uri))
    doc.edit(item.text, item.version)
    ls.documents[item.uri] = doc
    ls.changed(doc)


@guarded(lambda: None)
def did_change(ls: VerifyServer, params: lsp.DidChangeTextDocumentParams) -> None:
    """Apply the changes (all or, when one has a reversed range, none: the user is told)."""
    doc = ls.document(params.text_document.uri)
    if doc is None:
        return
    bad = next((r for r in map(f.reversed_range, params.content_changes) if r is not None), None)
    if bad is not None:
        ls.window_show_message(lsp.ShowMessageParams(type=lsp.MessageType.Error, message=(
            f"verify: the editor sent a change to {doc.uri} whose range starts ({bad.start.line + 1}:"
            f"{bad.start.character + 1}) after it ends ({bad.end.line + 1}:{bad.end.character + 1}); the change "
            "was ignored, so the server's copy may differ from the editor's: close and reopen the document")))
        return
    doc.edit(f.apply_changes(doc.text, params.content_changes), params.text_document.version)
    ls.changed(doc)


@guarded(lambda: None)
def did_close(ls: VerifyServer, params: lsp.DidCloseTextDocumentParams) -> None:
    doc = ls.documents.pop(params.text_document.uri, None)
    if doc is not None:
        doc.close()
    ls.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=params.text_document.uri, diagnostics=[]))


# ------------------------------------------------------------------ requests


async def _symbol_at(ls: VerifyServer, uri: str,
                     position: lsp.Position) -> tuple[Document, Symbol, api.LoadResult] | None:
    """The open document, the symbol named at ``position`` in it and the load that resolved it."""
    doc = await ls.current(uri)
    if doc is None:
        return None
    result = doc.result if doc.result is not None and doc.result.resolution is not None else doc.good
    if result is None:
        return None
    line, column = f.from_position(position, doc.map)
    symbol = result.symbols.at(doc.path, line, column)
    return None if symbol is None else (doc, symbol, result)


@guarded(list)
async def document_symbol(ls: VerifyServer, params: lsp.DocumentSymbolParams) -> list[lsp.DocumentSymbol]:
    doc = await ls.current(params.text_document.uri)
    if doc is None or doc.result is None:
        return []
    project = doc.result.project
    module = next((m for m in project.modules if f.same_file(m.path, doc.path)), None)
    if module is None:
        module = next((m for p, m in project.partials.items() if f.same_file(p, doc.path)), None)
    return f.outline(module, doc.map, doc.analyses) if module is not None else []


@guarded(lambda: None)
async def hover(ls: VerifyServer, params: lsp.HoverParams) -> lsp.Hover | None:
    found = await _symbol_at(ls, params.text_document.uri, params.position)
    if found is None:
        return None
    doc, symbol, result = found
    text = f.hover_text(symbol, result, doc.analyses)
    return lsp.Hover(lsp.MarkupContent(lsp.MarkupKind.Markdown, text))


@guarded(lambda: None)
async def definition(ls: VerifyServer, params: lsp.DefinitionParams) -> lsp.Location | None:
    found = await _symbol_at(ls, params.text_document.uri, params.position)
    return None if found is None else _location(ls, found[1].span, found[2])


def _location(ls: VerifyServer, span: Any, result: api.LoadResult) -> lsp.Location:
    key = os.path.realpath(span.file)
    return lsp.Location(ls.uris().get(key, f._file_uri(span.file)), f.to_range(span, ls.map_of(result)(span.file)))


@guarded(list)
async def references(ls: VerifyServer, params: lsp.ReferenceParams) -> list[lsp.Location]:
    found = await _symbol_at(ls, params.text_document.uri, params.position)
    if found is None:
        return []
    _, symbol, result = found
    spans = ([symbol.span] if params.context.include_declaration else []) + result.symbols.references_to(symbol)
    return [_location(ls, span, result) for span in spans]


@guarded(lambda: None)
async def rename(ls: VerifyServer, params: lsp.RenameParams) -> lsp.WorkspaceEdit | None:
    found = await _symbol_at(ls, params.text_document.uri, params.position)
    if found is None:
        return None
    _, symbol, result = found
    return f.rename_edits(symbol, result, params.new_name, ls.uris(), ls.buffers())


@guarded(list)
def completion(ls: VerifyServer, params: lsp.CompletionParams) -> list[lsp.CompletionItem]:
    """From the text as typed and the last loads (it does not wait for the load of the latest version)."""
    doc = ls.document(params.text_document.uri)
    if doc is None:
        return []
    ctx = f.context_at(doc.text, f.offset_at(doc.map, params.position))
    good = doc.good
    if ctx.member_of is not None:
        if good is None:
            return []
        return [item for model in good.models.values() for item in f.member_items(model, ctx.member_of, ctx.before)]
    return f.keyword_items(ctx.before) + f.name_items(doc.result if doc.result and doc.result.resolution else good,
                                                      ctx.before)


@guarded(list)
async def formatting(ls: VerifyServer, params: lsp.DocumentFormattingParams) -> list[lsp.TextEdit]:
    from ..frontend.fmt import format_text

    doc = ls.document(params.text_document.uri)
    if doc is None:
        return []
    text, version = doc.text, doc.version
    formatted, _ = await ls.worker().run(format_text, text, doc.path)
    if formatted is None or doc.version != version:
        return []  # (not valid, or changed meanwhile: the edits would be for older text)
    return f.text_edits(text, formatted)


@guarded(list)
async def code_action(ls: VerifyServer, params: lsp.CodeActionParams) -> list[lsp.CodeAction]:
    doc = await ls.current(params.text_document.uri)
    if doc is None:
        return []
    actions = f.quick_fixes(doc.uri, params.context.diagnostics)
    if doc.result is not None and any(not m.is_configured for m in doc.result.models.values()):
        actions.append(lsp.CodeAction(title="Apply synthesized values (synth)", kind=lsp.CodeActionKind.QuickFix,
                                      data={"uri": doc.uri, "version": doc.version}))
    return actions


@guarded(lambda: lsp.CodeAction(title="Apply synthesized values (synth): failed"))
async def resolve_code_action(ls: VerifyServer, action: lsp.CodeAction) -> lsp.CodeAction:
    """Run ``synth`` on the document (only when the editor asks for this action, in a child process that
    a cancelled request kills) and offer its edits: only the holes change (``synth.writeback.hole_edits``)."""
    from .synthchild import synthesize_in_child

    data = action.data if isinstance(action.data, dict) else {}
    doc = await ls.current(str(data.get("uri", "")))
    if doc is None or doc.result is None:
        return action
    version = doc.version
    answer = await synthesize_in_child(doc.path, ls.buffers())
    if doc.version != version or ls.documents.get(doc.uri) is not doc:
        ls.window_show_message(lsp.ShowMessageParams(type=lsp.MessageType.Warning, message=(
            "synth: the document changed while synth ran; ask for the action again")))
        return action
    if "warning" in answer:
        ls.window_show_message(lsp.ShowMessageParams(type=lsp.MessageType.Warning, message=str(answer["warning"])))
        return action
    edits = [lsp.TextEdit(f.offset_range(doc.map, start, end), text) for start, end, text in answer["edits"]]
    action.edit = lsp.WorkspaceEdit(changes={doc.uri: edits})
    return action


FEATURES: list[tuple[str, Callable[..., Any], Any]] = [
    (lsp.TEXT_DOCUMENT_DID_OPEN, did_open, None), (lsp.TEXT_DOCUMENT_DID_CHANGE, did_change, None),
    (lsp.TEXT_DOCUMENT_DID_CLOSE, did_close, None), (lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL, document_symbol, None),
    (lsp.TEXT_DOCUMENT_HOVER, hover, None), (lsp.TEXT_DOCUMENT_DEFINITION, definition, None),
    (lsp.TEXT_DOCUMENT_REFERENCES, references, None), (lsp.TEXT_DOCUMENT_RENAME, rename, None),
    (lsp.TEXT_DOCUMENT_COMPLETION, completion, lsp.CompletionOptions(trigger_characters=["."])),
    (lsp.TEXT_DOCUMENT_FORMATTING, formatting, None), (lsp.TEXT_DOCUMENT_CODE_ACTION, code_action, None),
    (lsp.CODE_ACTION_RESOLVE, resolve_code_action, None),
]


def build() -> VerifyServer:
    """A server with every feature."""
    server = VerifyServer()
    for method, handler, options in FEATURES:
        server.feature(method, options)(handler)
    return server


def main(max_message_bytes: int = MESSAGE_BYTES) -> int:
    """Serve over standard input and output until the client exits (``transport.serve``)."""
    return serve(build().protocol, sys.stdin.buffer, sys.stdout.buffer, max_message_bytes)
