"""What every figure granchain draws must hold (issue 43 item 3), measured on the drawn figure: tick labels
across the data on each log axis, no text outside the canvas, a unit on every axis label."""

from __future__ import annotations

import re

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

#: the units an axis label may end with, in parentheses (the first of its comma-separated words, its
#: mathtext's $ and spaces left out)
UNITS = {"N", "m/s", "s", "ms", r"\mus", "ns", "m", "1", "index", "Ns", "steps", "Hz", "dB"}
#: a data extreme may lie this far (decades) beyond a log axis's nearest tick label, at least: a third of
#: the data's span (a profile of 42-179 N labelled at 40-100 N only misses its top fifth)
LOG_GAP = np.log10(1.5)


def drawn(fig):
    """fig drawn on an Agg canvas, and its renderer."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def _labelled_ticks(axis) -> np.ndarray:
    """The tick positions of an axis with a label (major and minor), inside its view limits."""
    lo, hi = sorted(axis.get_view_interval())
    out = []
    for ticker in (axis.major, axis.minor):
        locs = np.asarray(ticker.locator(), dtype=float)
        locs = locs[(locs >= lo * (1 - 1e-9)) & (locs <= hi * (1 + 1e-9))]
        texts = ticker.formatter.format_ticks(list(locs)) if locs.size else []
        out += [x for x, t in zip(locs, texts, strict=True) if t.strip()]
    return np.asarray(out, dtype=float)


def _data_range(ax, which: str) -> tuple[float, float] | None:
    """The positive data of ax's lines along x or y inside its view limits (None where none)."""
    lo, hi = sorted(ax.get_xlim() if which == "x" else ax.get_ylim())
    vals = [np.asarray(line.get_xdata() if which == "x" else line.get_ydata(), dtype=float) for line in ax.lines]
    v = np.concatenate(vals) if vals else np.zeros(0)
    v = v[np.isfinite(v) & (v > 0) & (v >= lo) & (v <= hi)]
    return (float(v.min()), float(v.max())) if v.size else None


def log_axis_gaps(fig) -> list[str]:
    """Each log axis whose tick labels leave an end of its data unlabelled (more than the larger of a
    third of the data's span and LOG_GAP beyond the nearest label), or that has fewer than 2 labels."""
    bad = []
    main = {id(ax): ax for ax in fig.axes}
    for ax in fig.axes:
        parent = getattr(ax, "_parent", None)  # a secondary axis: its parent's data, rescaled
        for which, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            if axis.get_scale() not in ("log", "functionlog") or not axis.get_visible():
                continue
            if parent is not None and id(parent) in main:
                data = _data_range(parent, which)
                shift = np.log10(sorted(axis.get_view_interval())[0]) - np.log10(
                    sorted(getattr(parent, f"get_{which}lim")())[0]
                )
            else:
                data, shift = _data_range(ax, which), 0.0
            if data is None:  # a colour bar: its scale's range
                data = tuple(sorted(axis.get_view_interval()))
            lo, hi = np.log10(data[0]) + shift, np.log10(data[1]) + shift
            ticks = np.log10(_labelled_ticks(axis))
            gap = max((hi - lo) / 3.0, LOG_GAP)
            if ticks.size < 2 or ticks.min() - lo > gap or hi - ticks.max() > gap:
                bad.append(f"{which} axis of {ax.get_label() or ax}: data 10^{lo:.3g}-10^{hi:.3g}, labels {10**ticks}")
    return bad


def text_outside(fig, renderer) -> list[str]:
    """Every drawn text (axes' titles, labels, tick labels, legends; the figure's own texts) that reaches
    beyond the canvas, by more than a pixel."""
    canvas = fig.bbox
    boxes = [(f"axes {ax.get_label() or ax}", ax.get_tightbbox(renderer)) for ax in fig.axes]
    boxes += [(repr(t.get_text()[:60]), t.get_window_extent(renderer)) for t in fig.texts if t.get_text().strip()]
    boxes += [("legend", leg.get_window_extent(renderer)) for leg in fig.legends]
    return [
        f"{name}: {box.bounds} beyond the canvas {canvas.bounds}"
        for name, box in boxes
        if box is not None
        and (box.x0 < canvas.x0 - 1 or box.y0 < canvas.y0 - 1 or box.x1 > canvas.x1 + 1 or box.y1 > canvas.y1 + 1)
    ]


_UNIT = re.compile(r"\(([^()]*(?:\([^()]*\)[^()]*)*)\)\s*$")


def labels_without_units(fig) -> list[str]:
    """Every axis label (axes, secondary axes, colour bars) that does not end with its unit in parentheses."""
    bad = []
    for ax in fig.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if not label.strip():
                continue
            m = _UNIT.search(label)
            unit = m.group(1).split(",")[0].replace("$", "").replace(" ", "") if m else None
            if unit not in UNITS:
                bad.append(label)
    return bad


def check_figure(fig) -> None:
    """All three rules on one figure, each failure named."""
    renderer = drawn(fig)
    problems = log_axis_gaps(fig) + text_outside(fig, renderer) + labels_without_units(fig)
    assert not problems, problems


def check_every_figure(result, log: bool = True) -> None:
    """check_figure on every figure the run has data for (the heat map, histories and snapshots only
    where it has them; the peaks on log axes or, log=False, linear ones), naming the figure that fails."""
    from granchain.workflows import plots

    for kind in plots.FIGURES:
        try:
            fig = plots.figure(result, kind, **({"log": log} if kind == "peaks" else {}))
        except plots.PlotError:
            continue
        try:
            check_figure(fig)
        except AssertionError as e:
            raise AssertionError(f"{kind}: {e}") from None
