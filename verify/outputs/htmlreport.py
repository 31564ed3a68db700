"""One self-contained HTML page about a configured system (``verify report``): what a design review reads.

The page holds, in this order: a summary of the verdicts; the system diagram (``verify.outputs.diagram``, laid
out by Graphviz as inline SVG; without Graphviz, its DOT text); the outline of the analysis (each task's
activation, rate, execution and response times, and how it samples each input); the cores' loads; the
chain table (bounds, specs, margins, and what ``prove`` established); and the Gantt chart of every
counterexample ``prove`` found (``verify.prove.gantt``). Nothing is loaded at view time: styles are
inline, pictures are inline SVG, there is no script, and the page's content security policy forbids
any request.
"""
from __future__ import annotations

import html
import re
from collections.abc import Iterable

from .. import __version__
from . import diagram
from ..model.system import SystemModel
from ..prove.verdict import ProofResult, Verdict
from ..timing import AnalysisResult
from ..timing.rates import LinkSampling
from ..timing.report import sampling_marks
from ..model.units import fmt_number, fmt_time

STYLE = """
body { font-family: "DejaVu Sans", sans-serif; margin: 24px; color: #222; max-width: 1400px; }
h1 { font-size: 22px; margin-bottom: 4px; } h2 { font-size: 17px; margin-top: 28px; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 13px; margin: 8px 0; }
th { background: #dfe6f0; text-align: left; } th, td { border: 1px solid #bbb; padding: 3px 8px; vertical-align: top; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.proved { color: #1a7f37; font-weight: bold; } .violated { color: #b2182b; font-weight: bold; }
.undecided { color: #9a6700; font-weight: bold; } .mark { color: #b2182b; }
.figure { overflow-x: auto; border: 1px solid #ddd; padding: 8px; background: #fff; }
.meta { color: #666; font-size: 12px; } pre { font-size: 11px; }
"""
#: no request of any kind: the page shows what it holds
POLICY = "default-src 'none'; style-src 'unsafe-inline'; img-src data:"


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _table(head: Iterable[str], rows: Iterable[Iterable[str]], numeric: Iterable[int] = ()) -> str:
    nums = set(numeric)
    out = ["<table>", "<tr>" + "".join(f"<th>{_e(h)}</th>" for h in head) + "</tr>"]
    for row in rows:
        out.append("<tr>" + "".join(f'<td class="num">{c}</td>' if i in nums else f"<td>{c}</td>"
                                    for i, c in enumerate(row)) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def inline_svg(svg: str) -> str:
    """An SVG document as an element of the page: without its XML declaration, DOCTYPE and comments."""
    svg = re.sub(r"<\?xml[^>]*\?>", "", svg)
    svg = re.sub(r"<!DOCTYPE[^>]*>", "", svg, flags=re.DOTALL)
    return re.sub(r"<!--.*?-->", "", svg, flags=re.DOTALL).strip()


# ------------------------------------------------------------------ sections


def _summary(proof: ProofResult) -> str:
    counts = {status: sum(v.status == status for v in proof.verdicts) for status in ("proved", "violated", "undecided")}
    parts = [f'<span class="{s}">{n} {s}</span>' for s, n in counts.items() if n]
    return f"<p>{len(proof.verdicts)} properties checked by <code>prove</code>: {', '.join(parts) or 'none'}.</p>"


def _diagram(model: SystemModel, analysis: AnalysisResult) -> str:
    text = diagram.to_dot(model, analysis)
    try:
        picture = inline_svg(diagram.layout(text, "svg").decode("utf-8"))
    except (diagram.GraphvizMissing, diagram.GraphvizFailed) as err:
        return (f"<p>{_e(err)}: the diagram's DOT text instead (<code>dot -Tsvg</code> lays it out).</p>"
                f"<pre>{_e(text)}</pre>")
    return f'<div class="figure" id="diagram">{picture}</div>'


def _sampling(s: LinkSampling) -> str:
    if s.relation == "matched":
        return "matched" + (" (its trigger)" if s.by_trigger else "")
    if s.relation == "unknown":
        return "rates not bounded"
    return f'<span class="mark">{_e(" or ".join(sampling_marks(s)))}</span>'


def _outline(model: SystemModel, analysis: AnalysisResult) -> str:
    reads: dict[str, list[LinkSampling]] = {}
    for s in analysis.links:
        reads.setdefault(s.reader, []).append(s)
    rows = []
    for t in analysis.tasks:
        sampling = "<br>".join(f"{_e(s.target.split('.', 1)[1])}: {_sampling(s)}" for s in reads.get(t.id, ())) or "–"
        rows.append([f"<b>{_e(t.id)}</b>", _e(t.core), str(t.priority), _e(t.kind),
                     _e(model.task(t.id).activation.describe()),
                     _e(t.rate if t.rate is not None else "unbounded"),
                     f"{_e(fmt_time(t.bcet))} .. {_e(fmt_time(t.wcet))}",
                     f"{_e(fmt_time(t.bcrt))} .. {_e(fmt_time(t.wcrt))}", sampling])
    tasks = _table(["task", "core", "priority", "kind", "activation", "rate", "C (bcet .. wcet)",
                    "R (bcrt .. wcrt)", "inputs sampled"], rows, numeric=(2,))
    cores = _table(["core", "utilisation", "tasks"],
                   [[_e(c.core), _e("unbounded" if c.utilisation is None else fmt_number(c.utilisation)),
                     _e(", ".join(c.tasks))] for c in analysis.cores], numeric=(1,))
    return f'<div id="outline">{tasks}</div>\n<h2>Cores</h2>\n{cores}'


def _verdict_cell(v: Verdict | None) -> str:
    if v is None:
        return "–"
    exact = f", exact worst {_e(fmt_time(v.exact))}" if v.exact is not None else ""
    return f'<span class="{_e(v.status)}">{_e(v.status)}</span> ({_e(v.method)}{exact})'


def _chains(analysis: AnalysisResult, proof: ProofResult) -> str:
    verdicts = {(v.name, v.kind): v for v in proof.verdicts if v.subject == "chain"}
    rows = []
    for c in analysis.chains:
        checks = {s.kind: s for s in c.specs}
        for kind, title, bound in (("reaction_time", "reaction time", c.reaction_time.worst),
                                   ("data_age", "data age", c.data_age_reduced.worst)):
            check = checks.get(kind)
            spec = _e(fmt_time(check.spec)) if check else "–"
            margin = "–" if check is None else _e("unbounded" if check.margin is None else fmt_time(check.margin))
            rows.append([f"<b>{_e(c.name)}</b>", _e(" → ".join(c.tasks)), _e(title), _e(fmt_time(bound)), spec,
                         margin, _verdict_cell(verdicts.get((c.name, kind)))])
    deadlines = [[f"<b>{_e(v.name)}</b>", "", "deadline", _e(fmt_time(v.bound)), _e(fmt_time(v.spec)),
                  _e("–" if v.margin is None else fmt_time(v.margin)), _verdict_cell(v)]
                 for v in proof.verdicts if v.subject == "task"]
    return _table(["chain", "tasks", "metric", "bound (analysis)", "spec", "margin (by the bound)", "prove"],
                  rows + deadlines, numeric=(3, 4, 5))


def _counterexamples(model: SystemModel, proof: ProofResult) -> str:
    drawn = [v for v in proof.verdicts if v.counterexample is not None]
    if not drawn:
        return "<p>No counterexample: no property was violated.</p>"
    from ..prove.gantt import chart_runs, to_svg

    traces = chart_runs(model, drawn)
    parts = []
    for v in drawn:
        assert v.counterexample is not None
        what = f"{v.subject} {v.name}: {v.kind.replace('_', ' ')} {fmt_time(v.counterexample.latency)} " \
               f"against spec {fmt_time(v.spec)}"
        parts.append(f"<h3>{_e(what)}</h3>\n<div class=\"figure gantt\">{inline_svg(to_svg(model, v, traces))}</div>")
    return "\n".join(parts)


def to_html(model: SystemModel, analysis: AnalysisResult, proof: ProofResult, source: str,
            measured: str | None = None) -> str:
    """The report of ``model`` (analysed and proved) as one HTML document; ``measured``: the section of
    a trace's measurements (``verify.trace.html``), after the chains."""
    body = [f"<h1>{_e(model.name)}: timing report</h1>",
            f'<p class="meta">{_e(source)} · verify {_e(__version__)} · data age {_e(analysis.data_age_variant)}</p>',
            _summary(proof), "<h2>System</h2>", _diagram(model, analysis), "<h2>Tasks</h2>", _outline(model, analysis),
            "<h2>Chains and deadlines</h2>", f'<div id="chains">{_chains(analysis, proof)}</div>',
            *(["<h2>Measured on the robot</h2>", measured] if measured is not None else []),
            "<h2>Counterexamples</h2>", _counterexamples(model, proof)]
    return "\n".join(["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
                      f'<meta http-equiv="Content-Security-Policy" content="{POLICY}">',
                      f"<title>{_e(model.name)}: timing report</title>", f"<style>{STYLE}</style>", "</head>",
                      "<body>", *body, "</body>", "</html>"]) + "\n"
