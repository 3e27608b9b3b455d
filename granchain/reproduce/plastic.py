"""Figs. 5-8: bilinear brass chains (k = 2.43e7 N/m) under I = 0.1 N s over T = 1 us (the bundled
plastic-short-impulse scene), at three unloading coefficients beta = 0.7, 0.8, 0.9 (a grid campaign;
the paper does not print the three betas of its Fig. 7, only Figs. 5's 0.8 and 8's 0.9).

Models, as derived (granchain.physics.predictions): the first peak from A2, the exponential decay per
contact lambda from Eq. 26 (Eq. 27 as derived: F_i = F_1 exp(-lambda (i - 1))), the secondary waves'
peak from Eq. 30 as derived (omega dF), the transition where Eq. 30 first exceeds Eq. 27, and the
inverse regime's exponent (1 + beta)/2 (Eq. 34). Measured: the peak force at every contact with its
error bar, and the exponential-then-inverse fit (granchain.postprocess.response_regimes.fit_decay) for the
transition contact and the exponent. The leading-wave profile of Fig. 6 is read from the histories of
contacts 1-8 at the instant contact 2 peaks.
"""

from __future__ import annotations

import numpy as np

from granchain.physics import models
from granchain.physics.predictions import leading_peaks_exponential, predict
from granchain.postprocess.response_regimes import fit_decay
from granchain.reproduce.sections import (
    NO_CLAIM,
    Context,
    Figure,
    Row,
    SectionResult,
    campaign_section,
    histories,
    peaks,
    scene_of,
    snapshots,
)

KEY, TITLE = "plastic", "Figs. 5-8: bilinear chains under a short impulse"
BETAS = (0.7, 0.8, 0.9)
PAPER_TRANSITIONS = (3, 5, 9)


def campaign(quick: bool) -> dict:
    """The bundled plastic-short-impulse scene at beta = 0.7, 0.8 and 0.9 on LAMMPS with error bars:
    quick 60 beads to 1 ms, full 120 beads to 2 ms; histories of contacts 1-8 every 0.1 us and
    snapshots at 0.2, 0.4 and 0.6 ms."""
    size = {"chain.beads": [60], "run.end_time": [1e-3]} if quick else {"chain.beads": [120], "run.end_time": [2e-3]}
    return {
        "campaign": {
            "base": "plastic-short-impulse",
            "backend": "lammps",
            "error_estimate": True,
            "title": "Figs. 5-8",
        },
        "vary": {
            "contact.unloading_coeff": list(BETAS),
            **size,
            "outputs.histories": [list(range(1, 9))],
            "outputs.history_interval": [1e-7],
            "outputs.snapshots": [[2e-4, 4e-4, 6e-4]],
        },
    }


class Beta:
    """One beta's run: measured peaks, the fit, the models."""

    def __init__(self, run):
        self.run = run
        self.scene = scene_of(run)
        self.beta = float(self.scene.contact.unloading_coeff)
        p = peaks(run)
        ok = p["complete"] & np.isfinite(p["peak_force"]) & (p["peak_force"] > 0)
        n = int(np.argmin(ok)) if not ok.all() else len(ok)  # up to the first incomplete peak
        self.contacts, self.f = p["contact"][:n], p["peak_force"][:n]
        err = p.get("peak_force_error")
        self.err = np.full(n, np.nan) if err is None else np.asarray(err, float)[:n]
        self.fit = fit_decay(self.f)
        pred = {q.name: q.value for q in predict(self.scene)}
        self.f1, self.lam, self.omega = (
            pred["first_contact_peak_force"],
            pred["exponential_decay_per_contact"],
            pred["omega"],
        )
        self.transition_model = pred.get("transition_contact")
        self.ku = self.scene.stiffness / (1 - self.beta)
        self.lead = np.array(leading_peaks_exponential(self.f1, self.lam, len(self.f)))
        self.secondary = np.array(
            [
                models.secondary_wave_peak_force(self.lead[0] - x, self.ku, self.scene.mass, self.omega)
                for x in self.lead
            ]
        )


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def fig5(ctx: Context, b: Beta) -> Figure:
    """Fig. 5: force histories of contacts 1-5 and velocities of beads 1-5 over the first 150 us."""
    plt = _plt()
    h = histories(b.run)
    t = h["time"] * 1e6
    sel = t <= 150
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for i in range(1, 6):
        ax1.plot(t[sel], h[f"force_{i}"][sel], lw=1, label=f"contact {i}")
        ax2.plot(t[sel], h[f"velocity_{i}"][sel], lw=1, label=f"bead {i}")
    ax1.set_ylabel("contact force (N)")
    ax2.set_ylabel("bead velocity (m/s)")
    ax2.set_xlabel("t (us)")
    ax1.legend(fontsize=7)
    ax2.legend(fontsize=7)
    ax1.set_title(f"Fig. 5: beta = {b.beta:g}, I = 0.1 N s over 1 us")
    fig.tight_layout()
    ctx.figure(fig, "fig5")
    return Figure(
        "fig5",
        "(a) Force histories of contacts 1-5 and (b) velocities of beads 1-5. As in the paper: steep unloading after "
        "a slower plastic loading, beads keep a residual velocity to the right (none turns back), and later "
        "collisions of beads in free flight make the secondary waves.",
    )


def fig6(ctx: Context, b: Beta) -> tuple[Figure, float]:
    """Fig. 6: the first contacts' peak forces against Eq. 27 as derived, and the leading wave's
    forces on contacts 1-8 when contact 2 peaks; also returns the largest relative difference from
    Eq. 27 before the fitted transition (the paper: about 10%)."""
    plt = _plt()
    h = histories(b.run)
    i2 = int(np.argmax(h["force_2"]))
    profile = np.array([h[f"force_{i}"][i2] for i in range(1, 9)])
    n = min(10, len(b.f))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax1.errorbar(b.contacts[:n], b.f[:n], yerr=np.nan_to_num(b.err[:n]), fmt="o", mfc="none", label="measured")
    ax1.plot(b.contacts[:n], b.lead[:n], "-", label=f"Eq. 27 as derived (lambda = {b.lam:.3f})")
    ax1.set_yscale("log")
    ax1.set_xlabel("contact")
    ax1.set_ylabel("peak force (N)")
    ax1.legend(fontsize=8)
    ax1.set_title(f"Fig. 6: peak force, beta = {b.beta:g}")
    ax2.bar(np.arange(1, 9), profile, color="0.6")
    ax2.set_xlabel("contact")
    ax2.set_ylabel("force (N)")
    ax2.set_title(f"leading wave when contact 2 peaks (t = {h['time'][i2] * 1e6:.2f} us)")
    fig.tight_layout()
    ctx.figure(fig, "fig6")
    exp = b.contacts < b.fit.transition_contact
    diff = float(np.max(np.abs(b.f[exp] / b.lead[exp] - 1))) if exp.any() else float("nan")
    return (
        Figure(
            "fig6",
            f"Peak force over the first contacts against Eq. 27 (as derived, prefactor from A2), and the leading wave "
            f"(forces of contacts 1-8) when contact 2 peaks: it spans about three contacts, as the paper's histogram. "
            f"Largest difference in the exponential regime: {100 * diff:.0f}% (the paper: about 10%).",
        ),
        diff,
    )


def fig7(ctx: Context, runs: list[Beta]) -> Figure:
    """Fig. 7: peak force along the chain at each beta with Eq. 27 (leading wave) and Eq. 30
    (secondary waves); their crossing is the model's transition, beside the fitted one."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for b in runs:
        n = min(25, len(b.f))
        line = ax.errorbar(b.contacts[:n], b.f[:n], yerr=np.nan_to_num(b.err[:n]), fmt="o", ms=4, mfc="none",
                           label=f"beta = {b.beta:g}")  # fmt: skip
        c = line[0].get_color()
        ax.plot(b.contacts[:n], b.lead[:n], "-", color=c, lw=1)
        ax.plot(b.contacts[1:n], b.secondary[1:n], "--", color=c, lw=1)
        if b.transition_model:
            ax.annotate("", xy=(b.transition_model, 30), xytext=(b.transition_model, 300),
                        arrowprops={"arrowstyle": "->", "color": c, "ls": ":"})  # fmt: skip
        ax.plot([b.fit.transition_contact], [12], "o", color=c, ms=10, mfc="none", clip_on=False)
    ax.set_yscale("log")
    ax.set_ylim(10, 1e4)
    ax.set_xlabel("contact")
    ax.set_ylabel("peak force (N)")
    ax.set_title("Fig. 7: symbols measured, solid Eq. 27, dashed Eq. 30; arrows: model transition, circles: fitted")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    ctx.figure(fig, "fig7")
    return Figure(
        "fig7",
        "Peak force along the chain at three betas with Eq. 27 (solid) and Eq. 30 (dashed, as derived: omega dF); "
        "their crossing (arrows) predicts the transition, the circles on the bottom mark the fitted one. The paper's "
        "betas are not printed, so its transitions (3, 5, 9) cannot be matched beta for beta.",
    )


def fig8(ctx: Context, b: Beta) -> Figure:
    """Fig. 8: bead velocities along the chain at the snapshots, in the inverse-decay regime."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
    for t, s in snapshots(b.run):
        ax.plot(s["bead"], s["velocity"], lw=1, label=f"t = {t * 1e3:g} ms")
    ax.set_xlabel("bead")
    ax.set_ylabel("velocity (m/s)")
    ax.set_title(f"Fig. 8: beta = {b.beta:g}, bead velocities in the inverse regime")
    ax.legend(fontsize=8)
    fig.tight_layout()
    ctx.figure(fig, "fig8")
    return Figure(
        "fig8",
        "Bead velocities at three instants (beta = 0.9): nearly uniform behind the leading wave, decreasing as the "
        "wave spreads, as in the paper's Fig. 8.",
    )


def _rows(res: SectionResult, runs: dict[float, Beta], eq27_diff: float | None) -> None:
    res.rows.append(
        Row("plastic.eq27_difference", "Eq. 27 vs numerical peaks, exponential regime (beta 0.8)", "%", 10.0, "10",
            ours=None if eq27_diff is None else 100 * eq27_diff, tol=0.5,
            tol_source="'around 10%', read as 5-15%",
            reason="largest relative difference over the contacts before the fitted transition; Eq. 27 as derived "
            "(the printed form is not dimensionless and lacks F_1)")
    )  # fmt: skip
    ours = ", ".join(f"beta {b:g}: {r.fit.transition_contact}" for b, r in runs.items())
    model = ", ".join(f"beta {b:g}: {r.transition_model:g}" for b, r in runs.items() if r.transition_model)
    for k, pt in enumerate(PAPER_TRANSITIONS):
        b = BETAS[k] if BETAS[k] in runs else None
        res.rows.append(
            Row(f"plastic.transition_{k + 1}", f"Fig. 7 transition contact #{k + 1}", "contact", float(pt), str(pt),
                ours=None if b is None else float(runs[b].fit.transition_contact),
                model=None if b is None or not runs[b].transition_model else float(runs[b].transition_model),
                verdict=NO_CLAIM if b is not None else "",
                reason=f"the paper does not print the betas of Fig. 7; ours (fitted) {ours}; model {model}")
        )  # fmt: skip
    if 0.9 in runs:
        r = runs[0.9]
        res.rows.append(
            Row("plastic.inverse_exponent", "inverse-regime exponent, beta 0.9 (Eq. 34)", "-", 0.95,
                "(1+beta)/2 = 0.95", ours=r.fit.power, model=models.inverse_decay_exponent(0.9), tol=0.1,
                tol_source="none stated; 10%, the paper's Eq. 27 standard",
                reason=f"fit of a i^-p from the fitted transition (contact {r.fit.transition_contact}) to the last "
                "complete peak")
        )  # fmt: skip


def run(ctx: Context) -> SectionResult:
    """The section: Figs. 5-8, Eq. 27's agreement in the exponential regime, the transition
    contacts of Fig. 7 and the inverse-regime exponent (Eq. 34), each against the paper's."""
    res, df = campaign_section(ctx, KEY, TITLE, "plastic", campaign(ctx.quick), __doc__)
    res.paper_cost = "RK4 at 5e-9 s; chain length not given (60 beads to 1 ms: 2e5 steps, 1.2e7 bead-steps per beta)"
    res.paper_bead_steps = 3 * 60 * 1e-3 / 5e-9
    runs = {}
    for _, row in df[df["status"] == "done"].iterrows():
        b = Beta(row["run"])
        runs[round(b.beta, 6)] = b
    eq27 = None
    if 0.8 in runs:
        res.figures.append(fig5(ctx, runs[0.8]))
        f6, eq27 = fig6(ctx, runs[0.8])
        res.figures.append(f6)
    if runs:
        res.figures.append(fig7(ctx, list(runs.values())))
    if 0.9 in runs:
        res.figures.append(fig8(ctx, runs[0.9]))
    _rows(res, runs, eq27)
    return res


def campaign_specs(quick: bool) -> dict[str, dict]:
    """The section's campaigns by workspace name (without the mode prefix)."""
    return {"plastic": campaign(quick)}
