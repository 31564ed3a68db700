"""``verify lsp``: the language server (pygls, over standard input and output).

On every change of a document the server loads it at once (parse, names, validation: the same
diagnostics as ``verify check``, published immediately) and, ``ANALYSIS_DELAY`` seconds after the last
change, analyses its configured systems in a worker thread (the diagnostics of ``verify analyze``); a
change that arrives meanwhile cancels that analysis, and a result for an older version is dropped. Open
documents are read from the editor's buffers (imports too), never from disk when a buffer exists.
Whatever a request meets, it answers: an internal failure is logged to the client and the request gets
an empty answer, and the server keeps serving.
"""
from __future__ import annotations

import asyncio
import functools
import os
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar, cast

from lsprotocol import types as lsp
from pygls.lsp.server import LanguageServer
from pygls.uris import to_fs_path

from .. import __version__, api
from ..symbols import Symbol
from ..timing import AnalysisResult
from . import features as f

#: seconds after the last change before the timing analysis starts
ANALYSIS_DELAY = 0.3

F = TypeVar("F", bound=Callable[..., Any])


@dataclass
class Document:
    uri: str
    path: str
    version: int = 0
    text: str = ""
    result: api.LoadResult | None = None
    good: api.LoadResult | None = None  # the last load with a valid system (for completion mid-typing)
    analyses: dict[str, AnalysisResult] = field(default_factory=dict)
    analysed: int = -1  # the version ``analyses`` belong to
    pending: asyncio.Task[None] | None = None


class VerifyServer(LanguageServer):
    def __init__(self) -> None:
        super().__init__("verify", __version__)
        self.documents: dict[str, Document] = {}

    # -------------------------------------------------------------- loading

    def buffers(self) -> dict[str, str]:
        return {os.path.realpath(d.path): d.text for d in self.documents.values()}

    def uris(self) -> dict[str, str]:
        return {os.path.realpath(d.path): d.uri for d in self.documents.values()}

    def load(self, doc: Document) -> None:
        buffers = self.buffers()

        def overlay(path: str) -> str | None:
            return buffers.get(os.path.realpath(path))

        doc.result = api.load(doc.path, overlay=overlay)
        if doc.result.models:
            doc.good = doc.result

    def publish(self, doc: Document, with_analysis: bool) -> None:
        assert doc.result is not None
        found = list(doc.result.diagnostics)
        if with_analysis:
            from ..timing import diagnostics_of

            for analysis in doc.analyses.values():
                found += diagnostics_of(analysis)
        lines = f.Lines(doc.text)
        self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(
            uri=doc.uri, version=doc.version, diagnostics=f.diagnostics_for(doc.path, found, lines, self.uris())))

    def changed(self, doc: Document) -> None:
        """Load and publish at once; analyse after ``ANALYSIS_DELAY`` unless the next change comes first."""
        if doc.pending is not None:
            doc.pending.cancel()
        self.load(doc)
        self.publish(doc, with_analysis=False)
        doc.pending = asyncio.get_running_loop().create_task(self.analyse_later(doc, doc.version))

    async def analyse_later(self, doc: Document, version: int) -> None:
        try:
            await asyncio.sleep(ANALYSIS_DELAY)
            result = doc.result
            if result is None or doc.version != version:
                return
            models = [(name, m) for name, m in sorted(result.models.items()) if m.is_configured]
            analyses = await asyncio.get_running_loop().run_in_executor(None, _analyse_all, models)
            if doc.version != version:
                return  # (a newer change: its own analysis follows)
            doc.analyses, doc.analysed = analyses, version
            self.publish(doc, with_analysis=True)
        except asyncio.CancelledError:
            pass
        except Exception:  # an internal failure: logged, never a dead server
            self.log_error("analysis", traceback.format_exc())

    def log_error(self, what: str, trace: str) -> None:
        self.window_log_message(lsp.LogMessageParams(type=lsp.MessageType.Error,
                                                     message=f"verify: internal error in {what}:\n{trace}"))

    def document(self, uri: str) -> Document | None:
        return self.documents.get(uri)


def _analyse_all(models: list[tuple[str, Any]]) -> dict[str, AnalysisResult]:
    from ..timing import analyze

    return {name: analyze(model) for name, model in models}


server = VerifyServer()


def guarded(default: Callable[[], Any]) -> Callable[[F], F]:
    """A handler whose internal failure is logged and answered with ``default()``."""

    def wrap(handler: F) -> F:
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


@server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
@guarded(lambda: None)
def did_open(ls: VerifyServer, params: lsp.DidOpenTextDocumentParams) -> None:
    item = params.text_document
    doc = Document(item.uri, _path_of(item.uri), item.version, item.text)
    ls.documents[item.uri] = doc
    ls.changed(doc)


@server.feature(lsp.TEXT_DOCUMENT_DID_CHANGE)
@guarded(lambda: None)
def did_change(ls: VerifyServer, params: lsp.DidChangeTextDocumentParams) -> None:
    doc = ls.document(params.text_document.uri)
    if doc is None:
        return
    text = doc.text
    for change in params.content_changes:
        if isinstance(change, lsp.TextDocumentContentChangePartial):
            lines = f.Lines(text)
            start = lines.offset(change.range.start.line, change.range.start.character)
            end = lines.offset(change.range.end.line, change.range.end.character)
            text = text[:start] + change.text + text[end:]
        else:
            text = change.text
    doc.text, doc.version = text, params.text_document.version
    ls.changed(doc)


@server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
@guarded(lambda: None)
def did_close(ls: VerifyServer, params: lsp.DidCloseTextDocumentParams) -> None:
    doc = ls.documents.pop(params.text_document.uri, None)
    if doc is not None and doc.pending is not None:
        doc.pending.cancel()
    ls.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=params.text_document.uri, diagnostics=[]))


# ------------------------------------------------------------------ requests


def _symbol_at(ls: VerifyServer, uri: str, position: lsp.Position) -> tuple[Document, Symbol, api.LoadResult] | None:
    """The open document, the symbol named at ``position`` in it and the load that resolved it."""
    doc = ls.document(uri)
    if doc is None:
        return None
    result = doc.result if doc.result is not None and doc.result.resolution is not None else doc.good
    if result is None:
        return None
    line, column = f.from_position(position, f.Lines(doc.text))
    symbol = result.symbols.at(doc.path, line, column)
    return None if symbol is None else (doc, symbol, result)


@server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
@guarded(list)
def document_symbol(ls: VerifyServer, params: lsp.DocumentSymbolParams) -> list[lsp.DocumentSymbol]:
    doc = ls.document(params.text_document.uri)
    if doc is None or doc.result is None:
        return []
    project = doc.result.project
    module = next((m for m in project.modules if f.same_file(m.path, doc.path)), None)
    if module is None:
        module = next((m for p, m in project.partials.items() if f.same_file(p, doc.path)), None)
    return f.outline(module, f.Lines(doc.text), doc.analyses) if module is not None else []


@server.feature(lsp.TEXT_DOCUMENT_HOVER)
@guarded(lambda: None)
def hover(ls: VerifyServer, params: lsp.HoverParams) -> lsp.Hover | None:
    found = _symbol_at(ls, params.text_document.uri, params.position)
    if found is None:
        return None
    doc, symbol, result = found
    text = f.hover_text(symbol, result, doc.analyses)
    return lsp.Hover(lsp.MarkupContent(lsp.MarkupKind.Markdown, text))


@server.feature(lsp.TEXT_DOCUMENT_DEFINITION)
@guarded(lambda: None)
def definition(ls: VerifyServer, params: lsp.DefinitionParams) -> lsp.Location | None:
    found = _symbol_at(ls, params.text_document.uri, params.position)
    return None if found is None else _location(ls, found[1].span, found[2])


def _location(ls: VerifyServer, span: Any, result: api.LoadResult) -> lsp.Location:
    key = os.path.realpath(span.file)
    text = ls.buffers().get(key)
    if text is None:
        source = result.sources.get(span.file)
        text = source.text if source is not None else ""
    return lsp.Location(ls.uris().get(key, f._file_uri(span.file)), f.to_range(span, f.Lines(text)))


@server.feature(lsp.TEXT_DOCUMENT_REFERENCES)
@guarded(list)
def references(ls: VerifyServer, params: lsp.ReferenceParams) -> list[lsp.Location]:
    found = _symbol_at(ls, params.text_document.uri, params.position)
    if found is None:
        return []
    _, symbol, result = found
    spans = ([symbol.span] if params.context.include_declaration else []) + result.symbols.references_to(symbol)
    return [_location(ls, span, result) for span in spans]


@server.feature(lsp.TEXT_DOCUMENT_RENAME)
@guarded(lambda: None)
def rename(ls: VerifyServer, params: lsp.RenameParams) -> lsp.WorkspaceEdit | None:
    found = _symbol_at(ls, params.text_document.uri, params.position)
    if found is None:
        return None
    _, symbol, result = found
    return f.rename_edits(symbol, result, params.new_name, ls.uris(), ls.buffers())


@server.feature(lsp.TEXT_DOCUMENT_COMPLETION, lsp.CompletionOptions(trigger_characters=["."]))
@guarded(list)
def completion(ls: VerifyServer, params: lsp.CompletionParams) -> list[lsp.CompletionItem]:
    doc = ls.document(params.text_document.uri)
    if doc is None:
        return []
    lines = f.Lines(doc.text)
    ctx = f.context_at(doc.text, lines.offset(params.position.line, params.position.character))
    good = doc.good
    if ctx.member_of is not None:
        if good is None:
            return []
        return [item for model in good.models.values() for item in f.member_items(model, ctx.member_of, ctx.before)]
    return f.keyword_items(ctx.before) + f.name_items(doc.result if doc.result and doc.result.resolution else good,
                                                      ctx.before)


@server.feature(lsp.TEXT_DOCUMENT_FORMATTING)
@guarded(list)
def formatting(ls: VerifyServer, params: lsp.DocumentFormattingParams) -> list[lsp.TextEdit]:
    from ..fmt import format_text

    doc = ls.document(params.text_document.uri)
    if doc is None:
        return []
    formatted, _ = format_text(doc.text, doc.path)
    return [] if formatted is None else f.text_edits(doc.text, formatted)


@server.feature(lsp.TEXT_DOCUMENT_CODE_ACTION)
@guarded(list)
def code_action(ls: VerifyServer, params: lsp.CodeActionParams) -> list[lsp.CodeAction]:
    doc = ls.document(params.text_document.uri)
    if doc is None:
        return []
    actions = f.quick_fixes(doc.uri, params.context.diagnostics)
    if doc.result is not None and any(not m.is_configured for m in doc.result.models.values()):
        actions.append(lsp.CodeAction(title="Apply synthesized values (synth)", kind=lsp.CodeActionKind.QuickFix,
                                      data={"uri": doc.uri, "version": doc.version}))
    return actions


@server.feature(lsp.CODE_ACTION_RESOLVE)
@guarded(lambda: lsp.CodeAction(title="Apply synthesized values (synth): failed"))
def resolve_code_action(ls: VerifyServer, action: lsp.CodeAction) -> lsp.CodeAction:
    """Run ``synth`` on the document (only when the editor asks for this action) and offer its edits:
    only the holes change (``synth.writeback.hole_edits``)."""
    data = action.data if isinstance(action.data, dict) else {}
    doc = ls.document(str(data.get("uri", "")))
    root = doc.result.project.root_module if doc is not None and doc.result is not None else None
    if doc is None or doc.result is None or root is None:
        return action
    from ..synth.driver import synthesize
    from ..synth.writeback import hole_edits

    result = doc.result
    source = result.project.sources[result.project.root]
    edits = []
    for name, model in sorted(result.models.items()):
        if model.is_configured:
            continue
        outcome = synthesize(result, name)
        if outcome.status != "sat":
            ls.window_show_message(lsp.ShowMessageParams(
                type=lsp.MessageType.Warning, message=f"synth: no configuration of {name} was found "
                                                      f"({outcome.status}); run `synth` for the explanation"))
            return action
        edits += hole_edits(source, root, name, outcome.choices)
    action.edit = lsp.WorkspaceEdit(changes={doc.uri: [lsp.TextEdit(f.offset_range(source.text, e.start, e.end),
                                                                    e.text) for e in edits]})
    return action


def main() -> int:
    """Serve over standard input and output until the client exits."""
    server.start_io()
    return 0
