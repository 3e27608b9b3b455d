"""Table I and Fig. 9: a bilinear chain (beta = 0.8, k = 2.43e7 N/m) under A = 8 kN for T = 2.5 ms.

The bundled plastic-long-load-table1 scene (500 beads, snapshots at 2, 3 and 5.2 ms), run in LAMMPS;
the plateau values are measured by granchain.postprocess.fronts.long_load_fronts (as tests/test_fronts.py
does) from the run directory's snapshots and peaks, and set against Eqs. 35-38 as derived
(granchain.physics.models.long_load_bilinear). Quick: timestep 2e-7 s; full: the scene's 5e-8 s.
Error bars: the bilinear law's slope jumps where contacts close, so Verlet's error follows no order
(granchain.richardson); each value's error is its distance to the same measurement on reference RK4
runs (event location) at 2 dt, plus their own error from RK4 at 4 dt (richardson.against_reference).
x_t is resolved to one contact (a bead diameter): its error is at least half of that.
Table I's rows are judged against the paper's numerical column; the "model" column is ours (Eqs. 35-38)
and the paper's predicted value is in the reason.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from granchain.physics import models
from granchain.postprocess.fronts import long_load_fronts
from granchain.reproduce.sections import (
    Context,
    Figure,
    Row,
    SectionResult,
    campaign_section,
    peaks,
    scene_of,
    snapshots,
)

KEY, TITLE = "table1", "Table I and Fig. 9: a long load on a bilinear chain"

#: Table I as printed: variable -> (numerical, its text, predicted, unit)
PRINTED = {
    "v_1": (26.4, "26.4", 26.18, "m/s"),
    "v_t": (14.6, "14.6", 14.47, "m/s"),
    "v_2": (14.75, "14.5-15", 14.84, "m/s"),
    "F_2": (3060.0, "3060", 3056.0, "N"),
    "x_t": (0.333, "0.333", 0.342, "m"),
}
REASONS = {
    "v_2": "Eq. 38 as printed with the paper's own v_t, c, c_u gives 10.00 m/s, not its predicted 14.84; its numerical "
    "14.5-15 matches the beads behind the F_2 block (v_t), not the loaded block (docs/paper-discrepancies.md)",
    "x_t": "Eq. 36 with T = 2.5 ms gives 3.42 m; 0.342 m would put the merge at 0.45 ms, before the load ends: a "
    "misprint by a factor 10, in both of the paper's columns",
    "v_t": "the printed v_t = v_1 - 2 F_1 R / c_u lacks m; with it, 14.48",
}


#: the paper's own "good agreement" in Table I: its largest numerical-vs-predicted difference (x_t)
TABLE1_AGREEMENT = 0.342 / 0.333 - 1
TABLE1_SOURCE = "Table I's largest numerical-vs-predicted gap, which the paper calls good agreement"


def timestep(quick: bool) -> float:
    """The LAMMPS run's time step: 2e-7 s quick, the scene's 5e-8 s full."""
    return 2e-7 if quick else 5e-8


def campaign(quick: bool) -> dict:
    """The bundled plastic-long-load-table1 scene on LAMMPS at the mode's time step."""
    # no Richardson companions: the error bars come from the RK4 campaign (error_bars)
    return {
        "campaign": {
            "base": "plastic-long-load-table1",
            "backend": "lammps",
            "error_estimate": False,
            "title": "Table I, Fig. 9",
        },
        "vary": {"run.timestep": [timestep(quick)]},
    }


def rk4_campaign(quick: bool) -> dict:
    """The same scene on the reference RK4 at 2 dt and 4 dt, snapshots kept: the plateaus' error bars."""
    dt = timestep(quick)
    return {
        "campaign": {
            "base": "plastic-long-load-table1",
            "backend": "reference",
            "method": "rk4",
            "error_estimate": False,
            "title": "Table I, the RK4 runs its error bars are measured against",
        },
        "vary": {"run.timestep": [2 * dt, 4 * dt]},
    }


def error_bars(ctx: Context, res: SectionResult, got: dict) -> dict[str, float | None]:
    """Each measured plateau's error: against the RK4 runs at 2 dt and 4 dt (richardson.against_reference)."""
    from granchain.reproduce.sections import cost_of, points
    from granchain.richardson import against_reference
    from granchain.workflows.errorbars.facts import reference_order

    ws = ctx.campaign("table1-rk4", rk4_campaign(ctx.quick))
    res.campaigns.append(ws.name)
    df = points(ws).sort_values("run.timestep")
    extra = cost_of(df)
    res.cost = {k: res.cost[k] + extra[k] for k in res.cost}
    if not (df["status"] == "done").all() or len(df) != 2:
        res.notes.append("No error bars: an RK4 run failed: " + "; ".join(str(m) for m in df["message"]))
        return {}
    ref = [long_load_fronts(scene_of(r), _solution(r)) for r in df["run"]]
    errors: dict[str, float | None] = {}
    sc = scene_of(df["run"].iloc[0])
    d, order = sc.diameter, reference_order(sc)  # (the bilinear loading line's 2.5)
    for name in got:
        bars = against_reference([got[name]], [ref[0][name]], [ref[1][name]], order=order)
        e = float(bars.error[0]) if bars.reliable[0] else None
        if name == "x_t" and e is not None:
            e = max(e, 0.5 * d)  # one contact's resolution
        errors[name] = e
        if e is None:
            res.notes.append(f"{name}: no error bar ({bars.status[0]})")
    return errors


def _solution(run) -> SimpleNamespace:
    snaps = snapshots(run)
    p = peaks(run)
    return SimpleNamespace(
        snapshot_time=np.array([t for t, _ in snaps]),
        snapshot_force=[s["contact_force"][:-1] for _, s in snaps],
        snapshot_velocity=[s["velocity"] for _, s in snaps],
        peak_force=p["peak_force"],
    )


def _figure(ctx: Context, run, sc, got: dict, model: dict) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    snaps = snapshots(run)
    p = peaks(run)
    d = sc.diameter
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for t, s in snaps:
        x = (s["bead"] - 1) * d
        ax1.plot(x[:-1] + d / 2, s["contact_force"][:-1], lw=0.9, label=f"t = {t * 1e3:g} ms")
        ax2.plot(x, s["velocity"], lw=0.9, label=f"t = {t * 1e3:g} ms")
    ax1.plot((p["contact"] - 0.5) * d, p["peak_force"], "k-", lw=1.2, label="peak force")
    for name, ax in (("F_2", ax1), ("v_1", ax2), ("v_t", ax2), ("v_2", ax2)):
        ax.axhline(model[name], color="0.5", ls=":", lw=0.8)
    ax1.axvline(got["x_t"], color="r", ls="--", lw=0.8, label=f"x_t measured {got['x_t']:.3g} m")
    ax1.axvline(model["x_t"], color="b", ls=":", lw=0.8, label=f"x_t Eq. 36 {model['x_t']:.3g} m")
    ax1.set_ylabel("contact force (N)")
    ax2.set_ylabel("bead velocity (m/s)")
    ax2.set_xlabel("x (m)")
    ax1.legend(fontsize=7)
    ax2.legend(fontsize=7)
    ax1.set_title("Fig. 9: bilinear beta = 0.8, A = 8 kN, T = 2.5 ms (dotted: Eqs. 35-38)")
    fig.tight_layout()
    ctx.figure(fig, "fig9")
    return Figure(
        "fig9",
        "Contact force (top) and bead velocity (bottom) at 2, 3 and 5.2 ms, the peak force at every contact, and the "
        "model's plateaus (dotted). As in the paper: one front at 2 ms, a faster unloading front behind it at 3 ms, "
        "two fronts moving apart at 5.2 ms. Unlike the paper's Table I, the fronts meet near x = 3.4 m, not 0.33 m.",
    )


def run(ctx: Context) -> SectionResult:
    """The section: Table I's v_1, v_t, v_2, F_2 and x_t measured with error bars, against the
    paper's numerical column, beside Eqs. 35-38 as derived; F_1 (not printed); and Fig. 9."""
    res, df = campaign_section(ctx, KEY, TITLE, "table1", campaign(ctx.quick), __doc__)
    res.paper_cost = "RK4 at 5e-9 s to 5.2 ms on a chain the fronts do not leave: about 500 beads, 1.04e6 steps"
    res.paper_bead_steps = 500 * 5.2e-3 / 5e-9
    from granchain.scene import load_scene

    base = load_scene("plastic-long-load-table1")
    ld = base.loading
    model = models.long_load_bilinear(
        ld.amplitude, ld.duration, base.stiffness, base.contact.unloading_coeff, base.mass, base.diameter
    )
    got = dict.fromkeys(PRINTED, None)
    errors: dict[str, float | None] = {}
    if df["status"].iloc[0] == "done":
        run_dir = df["run"].iloc[0]
        sc = scene_of(run_dir)
        got = long_load_fronts(sc, _solution(run_dir))
        errors = error_bars(ctx, res, got)
        res.figures.append(_figure(ctx, run_dir, sc, got, model))
    else:
        res.notes.append(f"The run failed: {df['message'].iloc[0]}")
    for name, (num, text, pred, unit) in PRINTED.items():
        # the paper's own standard: it calls Table I's largest numerical-vs-predicted gap (x_t, 2.7%) "good
        # agreement"; v_2's printed range 14.5-15 is wider than that
        tol, src = (0.25 / 14.75, "the printed range") if name == "v_2" else (TABLE1_AGREEMENT, TABLE1_SOURCE)
        res.rows.append(
            Row(
                f"table1.{name}",
                f"Table I {name}",
                unit,
                num,
                text,
                ours=got.get(name),
                ours_error=errors.get(name),
                model=model[name],
                tol=tol,
                tol_source=src,
                reason=(REASONS.get(name, "") + f"; paper's predicted {pred:g}").lstrip("; "),
            )
        )
    res.rows.append(
        Row("table1.F_1", "F_1 (plateau while loading)", "N", None, "", ours=got.get("F_1"),
            ours_error=errors.get("F_1"), model=model["F_1"], reason="not printed; Eq. 35 takes F_1 = A")
    )  # fmt: skip
    res.notes.append(
        "Our own model agreement (the paper's standard: Table I's largest difference is 2.7%): "
        + ", ".join(
            f"{k} {got[k]:.4g} vs {model[k]:.4g}" for k in ("v_1", "v_t", "v_2", "F_2", "x_t") if got.get(k) is not None
        )
    )
    return res


def campaign_specs(quick: bool) -> dict[str, dict]:
    """The section's campaigns by workspace name (without the mode prefix)."""
    return {"table1": campaign(quick), "table1-rk4": rk4_campaign(quick)}
