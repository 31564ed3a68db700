"""The measurements of a trace as a section of the HTML report (``verify report --trace``): per task and
per chain, the measured distribution as a box plot — whiskers from the least to the greatest value, the
box from the median to the 99th percentile — drawn over what the model says: a task's [bcet, wcet] as
a band, a chain's bound and spec as lines. Inline SVG, no script."""
from __future__ import annotations

import html
from fractions import Fraction

from ..model.units import fmt_time
from .metrics import Distribution
from .run import TraceResult

WIDTH, ROW, LEFT = 640, 34, 8  # (pixels)


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _axis(values: list[Fraction]) -> tuple[Fraction, Fraction]:
    """The range drawn: from 0, or — when every value lies far from 0 (a reaction time near a period) —
    from a little below the least, so that the values are told apart; to a little above the greatest."""
    lo, hi = min(values), max(values)
    pad = (hi - lo) / 10 or hi / 100 or Fraction(1, 10**9)
    return (Fraction(0) if lo < hi / 2 else lo - pad), hi + pad


def _x(value: Fraction, axis: tuple[Fraction, Fraction]) -> float:
    low, high = axis
    return round(LEFT + float((value - low) / (high - low)) * (WIDTH - 2 * LEFT), 1)


def box_plot(d: Distribution | None, band: tuple[Fraction, Fraction] | None, lines: list[tuple[str, Fraction]],
             label: str) -> str:
    """One row: the distribution ``d`` over the model's ``band`` and ``lines`` (name, value)."""
    values = [v for _, v in lines] + ([d.min, d.max] if d else []) + (list(band) if band else [])
    scale = _axis(values or [Fraction(1, 10**9)])
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{ROW + 28}" role="img" '
             f'aria-label="{_e(label)}">',
             f'<text x="{LEFT}" y="{ROW + 24}" font-size="9" fill="#666">{_e(fmt_time(scale[0]))}</text>']
    if band is not None:
        x0, x1 = _x(band[0], scale), _x(band[1], scale)
        parts.append(f'<rect class="model" x="{x0}" y="4" width="{max(x1 - x0, 1)}" height="{ROW - 8}" '
                     'fill="#dfe6f0"/>')
    for k, (name, value) in enumerate(lines):
        x = _x(value, scale)
        parts.append(f'<line class="{_e(name)}" x1="{x}" y1="2" x2="{x}" y2="{ROW - 2}" stroke="#555" '
                     f'stroke-dasharray="{"4 2" if name == "bound" else "none"}"/>'
                     f'<text x="{min(x + 2, WIDTH - 150)}" y="{ROW + 10 + 12 * k}" font-size="10">{_e(name)} '
                     f'{_e(fmt_time(value))}</text>')
    if d is not None:
        over = any(d.max > v for _, v in lines) or (band is not None and d.max > band[1])
        colour = "#b2182b" if over else "#1a7f37"
        y = ROW // 2
        lo, p50, p99, hi = (_x(v, scale) for v in (d.min, d.p50, d.p99, d.max))
        parts.append(f'<g class="measured" stroke="{colour}"><line x1="{lo}" y1="{y}" x2="{hi}" y2="{y}"/>'
                     f'<rect x="{p50}" y="{y - 7}" width="{max(p99 - p50, 1)}" height="14" fill="{colour}" '
                     f'fill-opacity="0.35"/><line x1="{lo}" y1="{y - 5}" x2="{lo}" y2="{y + 5}"/>'
                     f'<line x1="{hi}" y1="{y - 5}" x2="{hi}" y2="{y + 5}"/></g>')
    parts.append("</svg>")
    return "".join(parts)


def _words(d: Distribution | None) -> str:
    if d is None:
        return "not measured"
    return (f"{d.count} values: min {fmt_time(d.min)}, p50 {fmt_time(d.p50)}, p99 {fmt_time(d.p99)}, "
            f"max {fmt_time(d.max)}")


def section(result: TraceResult) -> str:
    """The section: where the measurements come from, then a row per task and per chain metric."""
    rec = result.recording
    rows = []
    for m in result.measured.tasks:
        t = result.analysis.task(m.task)
        rows.append(f"<tr><td><b>{_e(m.task)}</b><br><span class=\"meta\">{_e(m.callback)}</span></td>"
                    f"<td>execution time{' (CPU)' if m.cpu_jobs else ''}</td><td>{_e(_words(m.execution))}</td>"
                    f"<td>{box_plot(m.execution, (t.bcet, t.wcet), [], m.task)}</td></tr>")
    for k in result.delays.connections:
        rows.append(f"<tr><td><b>{_e(k.connection)}</b></td><td>delay</td><td>{_e(_words(k.delays))}</td>"
                    f"<td>{box_plot(k.delays, (k.delay_min, k.delay_max), [], k.connection)}</td></tr>")
    for c in result.measured.chains:
        bounds = result.analysis.chain(c.chain)
        specs = {s.kind: s.spec for s in bounds.specs}
        for kind, d, bound in (("reaction_time", c.reaction_time, bounds.reaction_time.worst),
                               ("data_age", c.data_age, bounds.data_age.worst)):
            lines = ([("bound", bound)] if bound is not None else []) + \
                ([("spec", specs[kind])] if kind in specs else [])
            rows.append(f"<tr><td><b>{_e(c.chain)}</b></td><td>{_e(kind.replace('_', ' '))}</td>"
                        f"<td>{_e(c.missing or _words(d))}</td>"
                        f"<td>{box_plot(d, None, lines, c.chain + ' ' + kind)}</td></tr>")
    partial = f"<p class=\"violated\">Read in part: {_e('; '.join(rec.partial))}</p>" if rec.partial else ""
    findings = "".join(f"<li>{_e(d.severity.value)}[{_e(d.code)}]: {_e(d.message)}</li>" for d in result.diagnostics)
    return (f'<div id="measured"><p class="meta">{_e(rec.events)} events ({_e(rec.source)}) from '
            f"{_e(', '.join(rec.paths))}. Box: median to 99th percentile; whiskers: least to greatest; band: the "
            "model's [bcet, wcet] (a connection's delay range); lines: the analysis' bound (dashed) and the spec.</p>"
            f"{partial}<table><tr><th>task or chain</th><th>metric</th><th>measured</th><th>against the model</th></tr>"
            + "".join(rows) + "</table>" + (f"<ul>{findings}</ul>" if findings else "") + "</div>")
