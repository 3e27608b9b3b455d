"""The paper's claim (Sec. III, Fig. 4; Conclusions) that the bilinear law "captures the key phenomena
associated with a more complex nonlinear model", tested with Thornton's (1997) elastic-perfectly-
plastic law (docs/laws.md): the Fig. 5 load (I = 0.1 N s over 1 us, 60 brass beads) on the
bundled thornton-short-impulse scene and on its bilinear equivalent (equal plastic slopes,
pi p_y R* = k, beta = 0.8: granchain.workflows.law_comparison.equivalent_contact), each a campaign point (LAMMPS,
planned for rtol 1e-3, error bars), each peak-force curve fitted exponential-then-inverse
(granchain.postprocess.response_regimes.fit_decay). The paper's own nonlinear law is not printed: this tests the
claim against one nonlinear law, not against the paper's.
"""

from __future__ import annotations

import numpy as np

from granchain.postprocess.response_regimes import fit_decay
from granchain.reproduce.sections import Context, Figure, Row, SectionResult, cost_of, peaks, points

KEY, TITLE = "laws", "Thornton vs bilinear: does the bilinear law capture the nonlinear law's phenomena?"
LAWS = ("thornton", "bilinear")


def campaigns() -> dict[str, dict]:
    """One campaign per law, by law name: the bundled thornton-short-impulse scene under Thornton's
    law and under its bilinear equivalent (granchain.workflows.law_comparison.equivalent_contact), each on
    LAMMPS planned for rtol 1e-3, with error bars. The same in both modes."""
    from granchain.scene import load_scene, scene_to_dict
    from granchain.workflows.law_comparison import equivalent_contact, scene_with_law

    base = load_scene("thornton-short-impulse")
    out = {}
    for law in LAWS:
        contact = equivalent_contact(base, law)
        d = scene_to_dict(scene_with_law(base, contact))
        key, val = next((k, v) for k, v in contact.items() if k != "law")
        out[law] = {
            "campaign": {"backend": "lammps", "rtol": 1e-3, "error_estimate": True, "title": f"laws: {law}"},
            "vary": {f"contact.{key}": [val]},
            "scene": d,
        }
    return out


def _curve(run) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p = peaks(run)
    ok = p["complete"] & np.isfinite(p["peak_force"]) & (p["peak_force"] > 0)
    n = int(np.argmin(ok)) if not ok.all() else len(ok)
    err = p.get("peak_force_error")
    return p["contact"][:n], p["peak_force"][:n], (np.full(n, np.nan) if err is None else np.asarray(err, float)[:n])


def run(ctx: Context) -> SectionResult:
    """The section: each law's peak force along the chain fitted exponential-then-inverse, the fits
    side by side (no printed numbers: the paper's nonlinear law is not printed), a verdict in the
    notes, and the figure."""
    res = SectionResult(KEY, TITLE)
    curves, fits, tables = {}, {}, []
    for law, spec in campaigns().items():
        ws = ctx.campaign(f"laws-{law}", spec)
        res.campaigns.append(ws.name)
        df = points(ws)
        tables.append(df)
        if df["status"].iloc[0] != "done":
            res.notes.append(f"{law}: the run failed: {df['message'].iloc[0]}")
            continue
        curves[law] = _curve(df["run"].iloc[0])
        fits[law] = fit_decay(curves[law][1])
    res.cost = cost_of(*tables)
    res.paper_cost = "not run in the paper (its nonlinear law is a fit to finite elements it does not print)"
    res.notes.append(__doc__.strip())
    for law, f in fits.items():
        c, fp, _ = curves[law]
        res.rows += [
            Row(f"laws.{law}.decay", f"{law}: exponential decay per contact", "-", None, "", ours=f.decay_per_contact,
                reason="fit_decay, contacts before the transition"),
            Row(f"laws.{law}.power", f"{law}: inverse-decay exponent", "-", None, "", ours=f.power,
                model=0.9 if law == "bilinear" else None, reason="fit_decay, from the transition on; Eq. 34 for "
                "the bilinear law"),
            Row(f"laws.{law}.transition", f"{law}: transition contact", "contact", None, "",
                ours=float(f.transition_contact), reason="fit_decay"),
            Row(f"laws.{law}.F1", f"{law}: first peak force", "N", None, "", ours=float(fp[0]),
                reason="contact 1"),
        ]  # fmt: skip
    if len(fits) == 2:
        t, b = fits["thornton"], fits["bilinear"]
        both = all(f.transition_contact > 2 and f.decay_per_contact > 0 and f.power > 0 for f in fits.values())
        n = min(len(curves["thornton"][1]), len(curves["bilinear"][1]))
        gap = curves["thornton"][1][n - 1] / curves["bilinear"][1][n - 1]
        res.notes.append(
            ("Verdict: qualitatively yes, " if both else "Verdict: not even qualitatively: ")
            + f"both laws show an exponential decay (per contact: Thornton {t.decay_per_contact:.3f}, bilinear "
            f"{b.decay_per_contact:.3f}) then an inverse power law (exponent {t.power:.2f} vs {b.power:.2f}), the "
            f"transition at contact {t.transition_contact} vs {b.transition_contact}; quantitatively no: Thornton's "
            f"wave decays more slowly and is {gap:.1f}x the bilinear one at contact {n}. Thornton's law dissipates a "
            "fraction of a contact's work that grows with the force, the bilinear law the fixed fraction beta "
            "(docs/laws.md)."
        )
        res.figures.append(_figure(ctx, curves, fits))
    return res


def _figure(ctx: Context, curves, fits) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for law, (c, f, e) in curves.items():
        fit = fits[law]
        label = f"{law}: decay {fit.decay_per_contact:.3f}/contact, then i^-{fit.power:.2f}"
        line = ax.errorbar(c, f, yerr=np.nan_to_num(e), fmt="o", ms=4, mfc="none", label=label)
        ax.axvline(fit.transition_contact, color=line[0].get_color(), ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("contact")
    ax.set_ylabel("peak force (N)")
    ax.set_title("Fig. 5 load under Thornton's law and its bilinear equivalent (dotted: fitted transitions)")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    ctx.figure(fig, "laws")
    return Figure(
        "laws",
        "Peak force along the chain under Thornton's law and the bilinear law with the same plastic slope "
        "(log-log: the inverse regime is a straight line). Both show the two regimes; Thornton's decays more slowly.",
    )


def campaign_specs(quick: bool) -> dict[str, dict]:
    """The section's campaigns by workspace name (without the mode prefix); `quick` changes nothing."""
    return {f"laws-{law}": spec for law, spec in campaigns().items()}
