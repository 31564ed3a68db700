"""What the language server answers, from the front end's results (``verify.lsp.server`` wires it to
LSP): diagnostics, document symbols (the paper's outline), hover, definitions, references, rename,
completion and code actions. Every function is pure: it reads a ``LoadResult`` (and an analysis) and
returns lsprotocol values. Positions: spans are 1-based lines and code-point columns; LSP counts
UTF-16 code units from 0, a byte order mark not counted; one map converts them (``source.SourceMap``:
``to_range``, ``from_position``, ``offset_at``).
"""
from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from lsprotocol import types as lsp

from ..model import syntax as s
from ..api import LoadResult
from ..core.diagnostics import Diagnostic, Severity
from ..model.system import SystemModel
from ..core.source import SourceMap, Span
from ..frontend.symbols import Symbol
from ..timing import AnalysisResult
from ..timing.report import sampling_marks
from ..model.units import fmt_time

NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_SEVERITY = {Severity.ERROR: lsp.DiagnosticSeverity.Error, Severity.WARNING: lsp.DiagnosticSeverity.Warning,
             Severity.NOTE: lsp.DiagnosticSeverity.Information}


def same_file(a: str, b: str) -> bool:
    return os.path.realpath(a) == os.path.realpath(b)


# ------------------------------------------------------------------ positions


def offset_at(smap: SourceMap, position: lsp.Position) -> int:
    """The index into the text of an LSP position, clamped as LSP asks: a character past the end of
    its line is the line's end, a line past the last one the end of the text."""
    if position.line >= smap.lines:
        return len(smap.text)
    return smap.offset(*smap.from_lsp(position.line, position.character))


def to_range(span: Span, smap: SourceMap) -> lsp.Range:
    (sl, sc), (el, ec) = smap.to_lsp(span.line, span.column), smap.to_lsp(span.end_line, span.end_column)
    return lsp.Range(lsp.Position(sl, sc), lsp.Position(el, ec))


def from_position(position: lsp.Position, smap: SourceMap) -> tuple[int, int]:
    """(1-based line, 1-based code-point column)."""
    return smap.from_lsp(position.line, position.character)


def offset_range(smap: SourceMap, start: int, end: int) -> lsp.Range:
    """The LSP range of ``text[start:end]``."""
    (sl, sc), (el, ec) = smap.to_lsp(*smap.position(start)), smap.to_lsp(*smap.position(end))
    return lsp.Range(lsp.Position(sl, sc), lsp.Position(el, ec))


def reversed_range(change: lsp.TextDocumentContentChangeEvent) -> lsp.Range | None:
    """The range of ``change`` when its start comes after its end (a change no text expresses)."""
    if not isinstance(change, lsp.TextDocumentContentChangePartial):
        return None
    start, end = change.range.start, change.range.end
    return change.range if (start.line, start.character) > (end.line, end.character) else None


def apply_changes(text: str, changes: Iterable[lsp.TextDocumentContentChangeEvent]) -> str:
    """``text`` after ``changes``, in order (``reversed_range`` of each is None): a range is clamped to
    the text (``offset_at``)."""
    for change in changes:
        if isinstance(change, lsp.TextDocumentContentChangePartial):
            smap = SourceMap(text)
            start, end = offset_at(smap, change.range.start), offset_at(smap, change.range.end)
            text = text[:start] + change.text + text[end:]
        else:
            text = change.text
    return text


# ------------------------------------------------------------------ diagnostics


def diagnostics_for(path: str, diagnostics: Iterable[Diagnostic], map_of: Callable[[str], SourceMap],
                    uri_of: Mapping[str, str]) -> list[lsp.Diagnostic]:
    """The diagnostics whose primary location is in ``path``, as LSP diagnostics: the same code,
    message and help as the command line, the secondary locations as related information. ``map_of``
    gives the positions of a file's text (the open buffer's, else the text as loaded)."""
    here = map_of(path)
    out = []
    for d in diagnostics:
        if not same_file(d.span.file, path):
            continue
        message = d.message + "".join(f"\n{n}" for n in d.notes) + (f"\nhelp: {d.help}" if d.help else "")
        related = []
        for lb in d.secondary:
            where = to_range(lb.span, here if same_file(lb.span.file, path) else map_of(lb.span.file))
            uri = uri_of.get(os.path.realpath(lb.span.file), _file_uri(lb.span.file))
            related.append(lsp.DiagnosticRelatedInformation(lsp.Location(uri, where), lb.message or d.message))
        out.append(lsp.Diagnostic(range=to_range(d.span, here), message=message, severity=_SEVERITY[d.severity],
                                  code=d.code, source="verify", related_information=related or None))
    return out


def _file_uri(path: str) -> str:
    from pygls.uris import from_fs_path

    return from_fs_path(os.path.abspath(path)) or path


# ------------------------------------------------------------------ outline


def _symbol(name: str, kind: lsp.SymbolKind, whole: Span, at: Span, lines: SourceMap, detail: str = "",
            children: list[lsp.DocumentSymbol] | None = None) -> lsp.DocumentSymbol:
    full = to_range(whole, lines)
    sel = to_range(at, lines)
    if (sel.start.line, sel.start.character) < (full.start.line, full.start.character) or \
            (sel.end.line, sel.end.character) > (full.end.line, full.end.character):
        full = sel
    return lsp.DocumentSymbol(name=name, kind=kind, range=full, selection_range=sel, detail=detail or None,
                              children=children or None)


def _whole(node: s.Task | s.Component | s.Instance | s.Chain | s.System) -> Span:
    span = node.span
    end = getattr(node, "end", None)
    return span.to(end) if end is not None and end.file == span.file and end.line >= span.line else span


def task_summary(analysis: AnalysisResult | None, task_id: str) -> str:
    """One line: activation rate, response time, sampling marks (the paper's outline)."""
    if analysis is None:
        return ""
    try:
        t = analysis.task(task_id)
    except StopIteration:
        return ""
    parts = [str(t.rate) if t.rate is not None else "rate unbounded", f"R ≤ {fmt_time(t.wcrt)}"]
    for link in analysis.links:
        if link.reader == task_id:
            port = link.target.split(".", 1)[1]
            parts += [f"{port} {mark}" for mark in sampling_marks(link)]
    return " · ".join(parts)


def chain_summary(analysis: AnalysisResult | None, name: str) -> str:
    if analysis is None:
        return ""
    try:
        c = analysis.chain(name)
    except StopIteration:
        return ""
    parts = [f"reaction ≤ {fmt_time(c.reaction_time.worst)}", f"data age ≤ {fmt_time(c.data_age_reduced.worst)}"]
    for check in c.specs:
        margin = "unbounded" if check.margin is None else fmt_time(check.margin)
        parts.append(f"{check.kind.replace('_', ' ')} spec {fmt_time(check.spec)}: "
                     f"{'margin' if check.ok else 'not proved, margin'} {margin}")
    return " · ".join(parts)


def outline(module: s.Module, lines: SourceMap, analyses: Mapping[str, AnalysisResult]) -> list[lsp.DocumentSymbol]:
    """Components with their ports and tasks; systems with their instances (tasks with their evaluated
    rates and sampling marks) and chains (with their latencies)."""
    out = []
    for comp in module.components:
        kids = [_symbol(p.name.text, lsp.SymbolKind.Interface, p.span, p.name.span, lines, f"in {p.type.text}")
                for p in comp.in_ports]
        kids += [_symbol(p.name.text, lsp.SymbolKind.Interface, p.span, p.name.span, lines, f"out {p.type.text}")
                 for p in comp.out_ports]
        kids += [_symbol(c.name.text, lsp.SymbolKind.Interface, c.span, c.name.span, lines,
                         (" & " if c.mode == "and" else " | ").join(m.text for m in c.members)) for c in comp.compounds]
        kids += [_symbol(t.name.text, lsp.SymbolKind.Method, _whole(t), t.name.span, lines, t.kind) for t in comp.tasks]
        out.append(_symbol(comp.name.text, lsp.SymbolKind.Class, _whole(comp), comp.name.span, lines, "component",
                           kids))
    for system in module.systems:
        analysis = analyses.get(system.name.text)
        kids = [_symbol(c.name.text, lsp.SymbolKind.Constant, c.span, c.name.span, lines, "core") for c in system.cores]
        kids += [_symbol(e.name.text, lsp.SymbolKind.Constant, e.span, e.name.span, lines, f"{e.kind.text} executor")
                 for e in system.executors]
        for inst in system.instances:
            tasks = [_symbol(b.task.text, lsp.SymbolKind.Method, b.span, b.task.span, lines,
                             task_summary(analysis, f"{inst.name.text}.{b.task.text}")) for b in inst.bindings]
            tasks += [_symbol(g.name.text, lsp.SymbolKind.Namespace, g.span, g.name.span, lines,
                              f"{g.kind.text.replace('_', ' ')} callback group") for g in inst.groups]
            kids.append(_symbol(inst.name.text, lsp.SymbolKind.Object, _whole(inst), inst.name.span, lines,
                                inst.component.text, tasks))
        kids += [_symbol(ch.name.text, lsp.SymbolKind.Event, _whole(ch), ch.name.span, lines,
                         chain_summary(analysis, ch.name.text)) for ch in system.chains]
        out.append(_symbol(system.name.text, lsp.SymbolKind.Module, _whole(system), system.name.span, lines, "system",
                           kids))
    return out


# ------------------------------------------------------------------ hover


def hover_text(symbol: Symbol, result: LoadResult, analyses: Mapping[str, AnalysisResult]) -> str:
    """Markdown about ``symbol``: for a task its rate, response time and sampling in every instance; for a
    chain its reaction time, data age, jitter and margins; for an instance its tasks."""
    lines = [f"**{symbol.kind}** `{symbol.name}`" + (f" of `{symbol.container}`" if symbol.container else "")]
    for name, model in sorted(result.models.items()):
        analysis = analyses.get(name)
        if symbol.kind == "task":
            for t in model.tasks:
                if t.name == symbol.name and t.component == symbol.container:
                    lines.append(f"- `{t.id}` ({t.core}, priority {t.priority}): {t.activation.describe()}"
                                 + (f" · {task_summary(analysis, t.id)}" if analysis else ""))
        elif symbol.kind == "chain" and symbol.container == name:
            chain = next((c for c in model.chains if c.name == symbol.name), None)
            if chain is not None:
                lines.append(" → ".join(f"`{t}`" for t in chain.tasks))
                if analysis is not None:
                    c = analysis.chain(chain.name)
                    jitter = c.data_age_reduced.worst - c.data_age_reduced.best \
                        if c.data_age_reduced.worst is not None else None
                    lines.append(f"- reaction time ≤ {fmt_time(c.reaction_time.worst)} "
                                 f"(best {fmt_time(c.reaction_time.best)})")
                    lines.append(f"- data age ≤ {fmt_time(c.data_age_reduced.worst)} "
                                 f"(best {fmt_time(c.data_age_reduced.best)}), jitter ≤ {fmt_time(jitter)}")
                    for check in c.specs:
                        margin = "unbounded" if check.margin is None else fmt_time(check.margin)
                        verdict = "proved by the bound" if check.ok else "not proved by the bound"
                        lines.append(f"- {check.kind.replace('_', ' ')} ≤ {fmt_time(check.spec)}: {verdict}, "
                                     f"margin {margin}")
        elif symbol.kind == "instance" and symbol.container == name:
            for t in model.tasks:
                if t.instance == symbol.name:
                    lines.append(f"- `{t.name}`: {t.activation.describe()}"
                                 + (f" · {task_summary(analysis, t.id)}" if analysis else ""))
    return "\n".join(lines)


# ------------------------------------------------------------------ rename


def rename_edits(symbol: Symbol, result: LoadResult, new_name: str, uri_of: Mapping[str, str],
                 buffers: Mapping[str, str]) -> lsp.WorkspaceEdit | None:
    """Every use and the declaration of ``symbol`` renamed, across the files of the project."""
    if not NAME_RE.fullmatch(new_name):
        return None
    spans = [symbol.span, *result.symbols.references_to(symbol)]
    changes: dict[str, list[lsp.TextEdit]] = {}
    for span in spans:
        text = buffers.get(os.path.realpath(span.file))
        if text is None:
            source = result.sources.get(span.file)
            text = source.text if source is not None else ""
        uri = uri_of.get(os.path.realpath(span.file), _file_uri(span.file))
        edit = lsp.TextEdit(to_range(span, SourceMap(text)), new_name)
        if edit not in changes.setdefault(uri, []):
            changes[uri].append(edit)
    return lsp.WorkspaceEdit(changes=changes)


# ------------------------------------------------------------------ completion


@dataclass(frozen=True)
class Context:
    """Where the cursor is, for completion: the word being typed, and what comes before it."""

    prefix: str  # the part of the name before the cursor
    before: str  # the text before the prefix
    member_of: str | None  # ``inst`` when the cursor follows ``inst.``


def context_at(text: str, offset: int) -> Context:
    start = offset
    while start > 0 and (text[start - 1].isalnum() or text[start - 1] == "_"):
        start -= 1
    before = text[:start]
    member = re.search(r"([A-Za-z_]\w*)\s*\.\s*$", before)
    return Context(text[start:offset], before, member.group(1) if member else None)


def _chain_prefix(before: str) -> list[tuple[str, str]] | None:
    """The chain elements already written when the cursor is in a chain (``chain c: a.x -> b.``)."""
    at = before.rfind("chain")
    if at < 0 or "{" in before[at:] or "}" in before[at:]:
        return None
    body = before[at:].split(":", 1)
    if len(body) < 2:
        return None
    return [(m.group(1), m.group(2)) for m in re.finditer(r"([A-Za-z_]\w*)\s*\.\s*([A-Za-z_]\w*)", body[1])]


def member_items(model: SystemModel, instance: str, before: str) -> list[lsp.CompletionItem]:
    """The members of ``instance`` after ``instance.``; in a chain, only those reachable from the
    previous element (the paper's scope provider)."""
    try:
        inst = model.instance(instance)
    except KeyError:
        return []
    comp = model.component(inst.component)
    chain = _chain_prefix(before)
    if chain:
        previous = ".".join(chain[-1])
        producer = model.producer(previous)
        if producer is None:  # the previous element is a task: its out-ports
            producer_task = previous
            outs = [f"{producer_task.split('.')[0]}.{p}" for p in model.task(producer_task).produces] \
                if producer_task in {t.id for t in model.tasks} else []
        else:
            outs = [previous]
        targets = [lk for port in outs for lk in model.links_from(port) if lk.target.split(".")[0] == instance]
        names: list[tuple[str, str]] = []
        for lk in targets:
            port = lk.target.split(".", 1)[1]
            names.append((port, f"in-port {port} (closes the chain)"))
            for reader in lk.readers:
                task = model.task(reader)
                names.append((task.name, f"task reading {port}"))
                names += [(o, f"out-port produced by {task.name}") for o in task.produces]
        return [lsp.CompletionItem(n, kind=lsp.CompletionItemKind.Field, detail=d) for n, d in dict(names).items()]
    items = [lsp.CompletionItem(p.name, kind=lsp.CompletionItemKind.Field, detail=f"{p.direction} {p.message_type}")
             for p in comp.ports]
    items += [lsp.CompletionItem(t.name, kind=lsp.CompletionItemKind.Method, detail="task") for t in comp.tasks]
    return items


def keyword_items(before: str) -> list[lsp.CompletionItem]:
    """The keywords the parser accepts at the cursor (its expected tokens), or every keyword when the
    text before it does not parse."""
    from ..frontend.grammar import expected_keywords

    return [lsp.CompletionItem(k, kind=lsp.CompletionItemKind.Keyword) for k in expected_keywords(before)]


def name_items(result: LoadResult | None, before: str) -> list[lsp.CompletionItem]:
    """Names in scope: components after ``instance x :``, cores after ``on``, instances elsewhere in a
    system."""
    if result is None:
        return []
    symbols = result.symbols.symbols
    if re.search(r"instance\s+\w+\s*:\s*$", before):
        kinds = {"component"}
    elif re.search(r"\bon\s*$|\bcore\s*$", before):
        kinds = {"core"}
    elif re.search(r"\bexecutor\s*$", before):
        kinds = {"executor"}
    elif re.search(r"\bgroup\s*$", before):
        kinds = {"group"}
    else:
        kinds = {"instance"}
    seen: dict[str, lsp.CompletionItem] = {}
    for sym in symbols:
        if sym.kind in kinds and sym.name not in seen:
            seen[sym.name] = lsp.CompletionItem(sym.name, kind=lsp.CompletionItemKind.Variable
                                                if sym.kind == "instance" else lsp.CompletionItemKind.Class,
                                                detail=sym.kind)
    return list(seen.values())


# ------------------------------------------------------------------ code actions


_DID_YOU_MEAN = re.compile(r"did you mean `([^`]+)`\?")


def quick_fixes(uri: str, diagnostics: Iterable[lsp.Diagnostic]) -> list[lsp.CodeAction]:
    """For each diagnostic whose help says ``did you mean `X`?``: replace its range by X."""
    actions = []
    for d in diagnostics:
        if d.source != "verify":
            continue
        m = _DID_YOU_MEAN.search(d.message)
        if m is None:
            continue
        actions.append(lsp.CodeAction(title=f"Replace with `{m.group(1)}`", kind=lsp.CodeActionKind.QuickFix,
                                      diagnostics=[d], is_preferred=True,
                                      edit=lsp.WorkspaceEdit(changes={uri: [lsp.TextEdit(d.range, m.group(1))]})))
    return actions


def text_edits(old: str, new: str) -> list[lsp.TextEdit]:
    """Edits that turn ``old`` into ``new``, one per run of changed lines (none when they are equal):
    an editor keeps its cursor and undo history everywhere else."""
    import difflib

    a, b = old.splitlines(keepends=True), new.splitlines(keepends=True)
    starts = [0]
    for line in a:
        starts.append(starts[-1] + len(line))
    edits = []
    smap = SourceMap(old)
    for tag, i1, i2, j1, j2 in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if tag != "equal":
            edits.append(lsp.TextEdit(offset_range(smap, starts[i1], starts[i2]), "".join(b[j1:j2])))
    return edits
