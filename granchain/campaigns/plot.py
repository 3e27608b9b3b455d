r"""Figures of a campaign table: an observable against a key, one line per value of the other varied
keys (with error bars from ``<observable>_error``), or a 2D map over two keys.

Axes are logarithmic when the values are positive and span at least a factor LOG_SPAN. Each axis, the
colour bar and the legend name a column with its unit (column_unit: a scene key's, scene.limits
SCENE_KEY_UNITS; an observable's and its error's, the observable registry's units(); the table's own),
and a line under the axes counts the points left out for lacking a value, by status. The plotted
numbers are written beside each figure (``<figure>.csv``).

A frequency sweep's figure (x = FREQUENCY_KEY) shades the linear pass bands and gaps that
granchain.physics.bands predicts for the points' chain at its precompression behind the measured
values, with a legend entry each (predicted_bands: where the points' chains have one band structure).

Every text drawn (title, axis labels, legend) is the campaign file's own text, not matplotlib
mathtext (a title ``$\frac{1}{$`` is drawn as it is written) and with control characters escaped.
Files are written aside and renamed, never through a symbolic link (granchain.safe_files).
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

from granchain import safe_files
from granchain.campaigns import workspace as wsp
from granchain.campaigns.model import CampaignError
from granchain.campaigns.table import build_search_table, build_table, build_trials_table, printable, read_record
from granchain.postprocess.observables import units as observable_units
from granchain.scene.limits import scene_key_unit

FORMATS = ("png", "pdf", "svg")
#: values spanning this factor (all > 0) get a log axis
LOG_SPAN = 30.0

#: the table's own numeric columns (table.point_row; a search's runs) -> unit
TABLE_UNITS = {
    "pulses": "pulses",
    "error_estimate": "1",
    "beads": "beads",
    "timestep": "s",
    "steps": "steps",
    "bead_steps": "bead steps",
    "wall_time": "s",
    "runs": "runs",
}


def column_unit(column: str, record: dict | None = None) -> str | None:
    """The unit of a campaign table's column, or None where it has none that is known (a free parameter
    of [derive], a column of text). record: the workspace's (campaign.json), for a search's columns."""
    search = (record or {}).get("search") or {}
    opt = (record or {}).get("optimize") or {}
    if opt.get("objective") and column in ("objective", "objective_error", "best_so_far"):
        return observable_units().get(opt["objective"])
    if opt.get("objective_2") and column in ("objective_2", "objective_2_error"):
        return observable_units().get(opt["objective_2"])
    if column == "trial":
        return "trial"
    key = search.get("key")
    if key and column in ("transition", "transition_error", f"{key}_low", f"{key}_high"):
        return scene_key_unit(key)
    if column.endswith("_error") and column != "transition_error":
        column = column.removesuffix("_error")
    for table in (TABLE_UNITS, observable_units()):
        if column in table:
            return table[column]
    return scene_key_unit(column)


def axis_label(column: str, record: dict | None = None) -> str:
    """An axis label: the column and its unit, "column (unit)"; "(unit unknown)" where there is none known."""
    unit = column_unit(column, record)
    return f"{column} ({unit if unit is not None else 'unit unknown'})"


def _log_axis(values) -> bool:
    v = [float(x) for x in values if x is not None and not (isinstance(x, float) and math.isnan(x))]
    return bool(v) and min(v) > 0 and max(v) / min(v) >= LOG_SPAN


def _label(key: str, value) -> str:
    """A legend's "key = value unit" (the key's unit where it has one)."""
    unit = column_unit(key)
    text = f"{value:.4g}" if isinstance(value, float) else f"{value}"
    return printable(f"{key} = {text}" + (f" {unit}" if unit and not isinstance(value, (bool, str)) else ""))


#: the scene key of a frequency sweep: its figure shades the predicted pass bands behind the data
FREQUENCY_KEY = "loading.frequency"
#: the shading of a pass band and of a gap (matplotlib colours), behind the data (zorder 0)
BAND_COLOUR, GAP_COLOUR = "tab:green", "0.6"


def predicted_bands(ws: Path, record: dict) -> tuple[tuple, tuple, str]:
    """The pass bands and gaps (Hz; physics.bands.band_structure) of a campaign's points' chain and what
    they are, in words for the legend; ((), (), why) where no point has a band structure, or the points'
    chains have different ones (a sweep that varies more than the frequency: one band diagram per line
    would hide the data)."""
    from granchain.physics.bands import BandError, band_structure
    from granchain.scene import SceneError, scene_from_dict

    found: dict[tuple, object] = {}
    why = "no point's scene was read back"
    for entry in record.get("points", []):
        sp = wsp.read_statepoint(ws / "workspace" / str(entry.get("job"))) or {}
        try:
            bands = band_structure(scene_from_dict(sp["scene"]))
        except (KeyError, TypeError, SceneError) as e:
            why = f"a point's scene cannot be read back ({e})"
            continue
        except BandError as e:
            return (), (), str(e)
        key = tuple(f"{v:.9g}" for band in bands.bands for v in band)
        found[key] = bands
    if len(found) != 1:
        return (), (), why if not found else f"the points' chains have {len(found)} different band structures"
    bands = next(iter(found.values()))
    f0 = bands.cell.static_force
    return bands.bands, bands.gaps, f"linearised at F0 = {f0:.4g} N, a cell of {bands.cell.masses.size} bead(s)"


def _shade_bands(ax, bands, gaps, what: str) -> None:
    """Shade the pass bands and gaps behind the data within the axis' x range (it is kept as the data
    chose it), one legend entry each kind."""
    lo, hi = ax.get_xlim()
    for spans, colour, label in ((bands, BAND_COLOUR, "pass band"), (gaps, GAP_COLOUR, "band gap")):
        labelled = False
        for a, b in spans:
            a, b = max(a, lo), min(b, hi)
            if a >= b:
                continue
            text = None if labelled else f"{label} (predicted{', ' + what if label == 'pass band' else ''})"
            ax.axvspan(a, b, color=colour, alpha=0.18, lw=0, zorder=0, label=text)
            labelled = True
    ax.set_xlim(lo, hi)


#: the longest line of a figure's title, characters: a 6.4-inch figure's width at the medium font size
TITLE_WIDTH = 70


def _title(title) -> str:
    """A campaign's title as drawn: printable, wrapped to TITLE_WIDTH (a long title stays on the canvas)."""
    return "\n".join(textwrap.wrap(printable(str(title)), TITLE_WIDTH)) or printable(str(title))


def _write_failed(path, e: OSError) -> CampaignError:
    return wsp.WorkspaceWriteError(
        e.errno,
        f"{path}: cannot be written ({e.strerror or e}); make the workspace writable, free some space, or give "
        "--out a path elsewhere",
    )


def _make_dir(d: Path) -> None:
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _write_failed(d, e) from None


def _write_csv(df, path: Path) -> None:
    try:
        with safe_files.open_for_write(path) as fh:
            df.to_csv(fh, index=False)
    except OSError as e:
        raise _write_failed(path, e) from None


def _check_columns(df, ws, **cols) -> None:
    """Every column named is the table's; those on an axis (x, y, map) hold numbers (a key of text
    values, such as peak_force = [true, [5, 10]], can only be --hue)."""
    numeric = [c for c in df.columns if df[c].dtype.kind in "if"]
    for what, col in cols.items():
        if col is not None and col not in df.columns:
            raise CampaignError(f"{ws}: --{what} {col!r} is not a column of the table; columns: {', '.join(numeric)}")
        if col is not None and what != "hue" and col not in numeric:
            raise CampaignError(
                f"{ws}: --{what} {col!r} is not a column of numbers (its values are text); put it on --hue, or "
                f"choose one of: {', '.join(numeric)}"
            )


def _not_drawn(df, y: str) -> str:
    """What the figure leaves out, in words ("" where every point is drawn): the points without a value
    of y, by status (done without a value: its reason is in its summary.json's observables_missing)."""
    left = df[(df["status"] != "done") | df[y].isna()]
    if left.empty:
        return ""
    counts = left["status"].where(left["status"] != "done", "done, no value").value_counts(sort=False)
    by = ", ".join(f"{n} {status}" for status, n in counts.items())
    return f"{len(left)} of {len(df)} points not drawn, without a value of {y} ({by})"


def _lines(ax, done, x: str, y: str, err, groups: list) -> None:
    """y against x, one line per value of the grouping keys (their values and units in the legend)."""
    import numpy as np

    parts = done.groupby(groups, sort=True, dropna=False) if groups else [((), done)]
    for key, part in parts:
        key = key if isinstance(key, tuple) else (key,)
        part = part.sort_values(x)
        yerr = part[err].to_numpy(dtype=float) if err else None
        if yerr is not None and np.all(np.isnan(yerr)):
            yerr = None
        label = ", ".join(_label(k, v) for k, v in zip(groups, key, strict=True)) or None
        ax.errorbar(part[x], part[y], yerr=yerr, marker="o", ms=4, capsize=3, label=label)
    if groups:
        for text in ax.legend(fontsize="small").get_texts():
            text.set_parse_math(False)


def campaign_figure(ws, x: str, y: str, hue: str | None = None, map_key: str | None = None):
    """The figure of y against x (lines, one per value of the other varied keys; hue first) or, with
    map_key, a 2D map of y over (x, map_key), and the table of its plotted points; its axes name each
    column with its unit (column_unit) and a line under them the points left out for lacking a value."""
    from matplotlib.figure import Figure  # a figure of its own: the caller's matplotlib backend untouched

    ws = Path(ws)
    record = read_record(ws)
    df = build_table(ws)
    varied = [k for k in record.get("varied", []) if k in df.columns]
    if y not in df.columns and record.get("kind") == "search":  # a search's transition against its outer keys
        df = build_search_table(ws)
        df["status"] = df["status"].replace({"found": "done"})
        varied = [k for k in varied if k in df.columns]
    if y not in df.columns and record.get("kind") == "optimize":  # an optimize campaign's objective over its trials
        df = build_trials_table(ws)
        df["status"] = df["state"].replace({"complete": "done"})
        varied = [k for k in varied if k in df.columns]
    _check_columns(df, ws, x=x, y=y, hue=hue, map=map_key)
    done = df[(df["status"] == "done") & df[y].notna()]
    if done.empty:
        raise CampaignError(f"{ws}: no complete point has a value of {y!r}; nothing to plot")
    err = f"{y}_error" if f"{y}_error" in df.columns else None
    fig = Figure(figsize=(6.4, 4.6), layout="constrained")
    ax = fig.subplots()
    if map_key is not None:
        grid = done.pivot_table(index=map_key, columns=x, values=y, aggfunc="mean")
        xs, ys = grid.columns.to_numpy(dtype=float), grid.index.to_numpy(dtype=float)
        mesh = ax.pcolormesh(xs, ys, grid.to_numpy(dtype=float), shading="nearest")
        fig.colorbar(mesh, ax=ax).set_label(printable(axis_label(y, record)), parse_math=False)
        ax.set_ylabel(printable(axis_label(map_key, record)), parse_math=False)
        if _log_axis(ys):
            ax.set_yscale("log")
        cols = [x, map_key, y]
    else:
        groups = [k for k in ([hue] if hue else []) + [k for k in varied if k not in (x, hue)]]
        groups = [k for k in groups if done[k].nunique() > 1]
        _lines(ax, done, x, y, err, groups)
        bands, gaps, what = predicted_bands(ws, record) if x == FREQUENCY_KEY else ((), (), "")
        if bands:
            if _log_axis(done[x]):  # the range the log axis will have, before the spans are cut to it
                ax.set_xscale("log")
            _shade_bands(ax, bands, gaps, what)
            for text in ax.legend(fontsize="small").get_texts():
                text.set_parse_math(False)
        ax.set_ylabel(printable(axis_label(y, record)), parse_math=False)
        if _log_axis(done[y]):
            ax.set_yscale("log")
        cols = [x, *groups, y]
    ax.set_xlabel(printable(axis_label(x, record)), parse_math=False)
    if _log_axis(done[x]):
        ax.set_xscale("log")
    title = record.get("title")
    if title:
        ax.set_title(_title(title), fontsize="medium", parse_math=False)
    left = _not_drawn(df, y)
    if left:
        fig.get_layout_engine().set(rect=(0, 0.05, 1, 0.95))  # room under the axes for the line
        fig.text(0.01, 0.01, printable(left), fontsize="small", color="0.3", wrap=True, parse_math=False)
    return fig, done[cols + ([err] if err else [])]


def plot_campaign(ws, x: str, y: str, hue: str | None = None, map_key: str | None = None, out=None, formats=("png",)):
    """Draw y against x (lines, one per value of the other varied keys; hue first) or, with map_key,
    a 2D map of y over (x, map_key) (campaign_figure); returns the paths written."""
    ws = Path(ws)
    for f in formats:
        if f not in FORMATS:
            raise CampaignError(f"--format {f!r}: one of {', '.join(FORMATS)}")
    fig, data = campaign_figure(ws, x, y, hue, map_key)
    stem = f"{y}-vs-{x}" + (f"-map-{map_key}" if map_key else f"-by-{hue}" if hue else "")
    base = str(out) if out is not None else str(ws / "plots" / stem)  # keys have dots: no with_suffix
    _make_dir(Path(base).parent)
    _write_csv(data, Path(base + ".csv"))
    return _save(fig, base, formats)


def _save(fig, base: str, formats) -> list[Path]:
    paths = []
    for f in formats:
        p = Path(f"{base}.{f}")
        try:
            safe_files.save_figure(fig, p, format=f, dpi=150)
        except OSError as e:
            raise _write_failed(p, e) from None
        paths.append(p)
    return paths


def convergence_figure(ws):
    """An optimize campaign's convergence: each trial's objective against its number (with its error
    bar; a failed or infeasible trial as a mark on the lower axis), and the best so far as a step line;
    and the table of its plotted points."""
    from matplotlib.figure import Figure

    ws = Path(ws)
    record = read_record(ws)
    if record.get("kind") != "optimize":
        raise CampaignError(f"{ws}: is a {record.get('kind')} campaign; --convergence is an optimize campaign's")
    df = build_trials_table(ws)
    if df.empty or df["objective"].isna().all():
        raise CampaignError(f"{ws}: no trial has a measured objective yet; nothing to plot")
    if (record.get("optimize") or {}).get("objective_2"):
        return pareto_figure(record, df)
    done = df[df["state"] == "complete"]
    fig = Figure(figsize=(6.4, 4.6), layout="constrained")
    ax = fig.subplots()
    yerr = done["objective_error"].to_numpy(dtype=float)
    ax.errorbar(
        done["trial"],
        done["objective"],
        yerr=None if all(yerr != yerr) else yerr,
        fmt="o",
        ms=4,
        capsize=3,
        label="trial",
    )
    ax.step(df["trial"], df["best_so_far"], where="post", color="C3", label="best so far")
    other = df[df["state"] != "complete"]
    if not other.empty:
        ax.plot(
            other["trial"],
            [0.0] * len(other),
            "x",
            color="0.4",
            transform=ax.get_xaxis_transform(),
            clip_on=False,
            label="failed or infeasible",
        )
    objective = str((record.get("optimize") or {}).get("objective", "objective"))
    ax.set_xlabel("trial (evaluation)")
    ax.set_ylabel(printable(axis_label("objective", record).replace("objective", objective, 1)), parse_math=False)
    for text in ax.legend(fontsize="small").get_texts():
        text.set_parse_math(False)
    if record.get("title"):
        ax.set_title(_title(record["title"]), fontsize="medium", parse_math=False)
    return fig, df[["trial", "state", "objective", "objective_error", "best_so_far"]]


def pareto_figure(record: dict, df):
    """Two objectives: every complete trial's pair, the Pareto front (optimize.pareto_front) joined as
    a step line, each with its error bars; and the table of the front."""
    import pandas as pd
    from matplotlib.figure import Figure

    from granchain.campaigns.optimize import pareto_front

    opt = record.get("optimize") or {}
    done = df[df["state"] == "complete"]
    front = pd.DataFrame(pareto_front(df.to_dict("records"), (opt.get("direction", "minimize"), opt["direction_2"])))
    fig = Figure(figsize=(6.4, 4.6), layout="constrained")
    ax = fig.subplots()
    bars = {c: done[f"{c}_error"].to_numpy(dtype=float) for c in ("objective", "objective_2")}
    ax.errorbar(
        done["objective"],
        done["objective_2"],
        xerr=bars["objective"],
        yerr=bars["objective_2"],
        fmt="o",
        ms=4,
        color="0.6",
        label="trial",
    )
    ax.plot(
        front["objective"], front["objective_2"], "o-", color="C3", ms=5, drawstyle="steps-post", label="Pareto front"
    )
    for set_label, column in ((ax.set_xlabel, "objective"), (ax.set_ylabel, "objective_2")):
        set_label(printable(axis_label(column, record).replace(column, str(opt.get(column)), 1)), parse_math=False)
    for text in ax.legend(fontsize="small").get_texts():
        text.set_parse_math(False)
    if record.get("title"):
        ax.set_title(_title(record["title"]), fontsize="medium", parse_math=False)
    return fig, front[["trial", "objective", "objective_error", "objective_2", "objective_2_error", "job"]]


def plot_convergence(ws, out=None, formats=("png",)) -> list[Path]:
    """Draw an optimize campaign's convergence (convergence_figure) into WS/plots/convergence.*
    (or out), its numbers beside it as .csv; returns the paths written. With two objectives: the
    Pareto figure (pareto_figure), into WS/plots/pareto.*."""
    ws = Path(ws)
    for f in formats:
        if f not in FORMATS:
            raise CampaignError(f"--format {f!r}: one of {', '.join(FORMATS)}")
    fig, data = convergence_figure(ws)
    name = "pareto" if (read_record(ws).get("optimize") or {}).get("objective_2") else "convergence"
    base = str(out) if out is not None else str(ws / "plots" / name)
    _make_dir(Path(base).parent)
    _write_csv(data, Path(base + ".csv"))
    return _save(fig, base, formats)
