"""Plots of a finished run directory (PNG, each with the CSV of its data beside it).

histories.png   contact forces and bead velocities vs time at the recorded contacts (Fig. 5a, 5b)
peaks.png       peak force vs contact, log axes, with the models that apply (Figs. 6, 7)
snapshots.png   force and velocity along the chain at the snapshot times, with the running
                peak-force envelope (Figs. 2, 8, 9)
"""

from __future__ import annotations

import csv
import json
import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from granchain.physics import models  # noqa: E402
from granchain.physics.predictions import applicability, transition_contact  # noqa: E402
from granchain.scene import parse_scene  # noqa: E402


def _read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with open(path) as fh:
        header = next(csv.reader(fh))
    return header, np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2)


def _write_csv(path: Path, header: list[str], columns: list[np.ndarray]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in zip(*columns, strict=True):
            w.writerow([repr(float(x)) for x in row])


def _label(summary: dict) -> str:
    return f"{summary['backend']} ({summary['method']}, dt = {summary['timestep']:g} s)"


def plot_histories(run: Path) -> Path | None:
    if not (run / "histories.csv").exists():
        return None
    summary = json.loads((run / "summary.json").read_text())
    header, data = _read_csv(run / "histories.csv")
    t_us = data[:, 0] * 1e6
    fcols = [i for i, h in enumerate(header) if h.startswith("force_")]
    vcols = [i for i, h in enumerate(header) if h.startswith("velocity_")]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for i in fcols:
        ax1.plot(t_us, data[:, i], label=f"contact {header[i].split('_')[1]}")
    for i in vcols:
        ax2.plot(t_us, data[:, i], label=f"bead {header[i].split('_')[1]}")
    ax1.set_ylabel("contact force F (N)")
    ax2.set_ylabel("bead velocity v (m/s)")
    ax2.set_xlabel("time t (µs)")
    ax1.set_title(f"Contact force and bead velocity histories — {_label(summary)}", fontsize=10)
    ax1.legend(fontsize=8)
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    out = run / "histories.png"
    fig.savefig(out, dpi=120)
    plt.close(fig)
    _write_csv(
        run / "histories_plot.csv",
        [header[0], *[header[i] for i in fcols + vcols]],
        [data[:, 0], *[data[:, i] for i in fcols + vcols]],
    )
    return out


def model_curves(scene, contacts: np.ndarray, skipped: dict[str, str] | None = None) -> dict[str, np.ndarray]:
    """Model peak force vs contact, for the models that apply to the scene (predictions.applicability).

    skipped: if given, filled with label -> reason for each model left out because it does not apply.
    """
    m, d, k = scene.mass, scene.diameter, scene.stiffness
    ld = scene.loading
    impulse = scene.input_impulse
    curves: dict[str, np.ndarray] = {}

    def applies(name: str, label: str) -> bool:
        verdict = applicability(name, scene)
        if not verdict.applies and skipped is not None:
            skipped[label] = verdict.reason
        return verdict.applies

    if scene.contact.law == "hertz":
        label = "Eq. 8 (short load)"
        if applies("short_load_peak_force", label):
            curves[label] = np.full(
                contacts.shape, models.short_load_peak_force(impulse, m, scene.e_star, scene.r_star)
            )
        for name, eq, fn in (
            ("long_load_peak_force_lower", "Eq. 19", models.front_speed_lower),
            ("long_load_peak_force_upper", "Eq. 15", models.front_speed_upper),
        ):
            label = f"{eq} + Nesterenko (long load)"
            if applies(name, label) and ld.is_force:
                curves[label] = np.full(
                    contacts.shape, models.solitary_wave_peak_force(fn(ld.amplitude, k, m, d), k, m, d)
                )
    else:
        beta = scene.contact.unloading_coeff
        f1 = models.linear_chain_impulse_response(impulse, k, m, beta)["F_p"]
        lam = models.exponential_decay_rate(k, m, beta)
        coeffs = models.leading_wave_coefficients(k, m, beta)
        tc = transition_contact(f1, lam, scene.unloading_stiffness, m, coeffs.omega, int(contacts.max()))
        label = "Eq. 27 (exponential regime)"
        if applies("exponential_decay_per_contact", label):
            # Eq. 27 holds before the transition; drawn a little past it to show where the two meet
            last = 2 * tc if tc is not None else contacts.max()
            curves[label] = np.where(contacts <= last, f1 * np.exp(-lam * (contacts - 1)), np.nan)
        label = "Eq. 34 slope (1+beta)/2" + (f" from contact {tc}" if tc is not None else "")
        if applies("inverse_decay_exponent", label) and tc is not None:
            p = models.inverse_decay_exponent(beta)
            anchor = f1 * np.exp(-lam * (tc - 1))
            curves[label] = np.where(contacts >= tc, anchor * (contacts / tc) ** (-p), np.nan)
    return curves


def plot_peaks(run: Path, log: bool = True) -> Path:
    summary = json.loads((run / "summary.json").read_text())
    scene = parse_scene((run / "scene.toml").read_text(), source=str(run / "scene.toml"))
    _, data = _read_csv(run / "peaks.csv")
    contacts, peak = data[:, 0], data[:, 1]
    skipped: dict[str, str] = {}
    curves = model_curves(scene, contacts, skipped)
    fig, ax = plt.subplots(figsize=(8, 5))
    ok = peak > 0
    ax.plot(contacts[ok], peak[ok], "o", ms=3, label=f"peak force — {_label(summary)}")
    for name, y in curves.items():
        ax.plot(contacts, y, "-", lw=1.2, label=name)
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel("contact i (between bead i and i+1)")
    ax.set_ylabel("peak contact force F_p (N)")
    sec = ax.secondary_yaxis("right", functions=(lambda f: f / scene.force_scale, lambda g: g * scene.force_scale))
    sec.set_ylabel("F_p / (E* R*^2)")
    ax.set_title(scene.title or "peak force along the chain", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    if skipped:  # say which models are left out, and why
        note = "\n".join(
            textwrap.shorten(f"not drawn, {label}: {reason}", width=160, placeholder=" ...")
            for label, reason in skipped.items()
        )
        fig.text(0.01, 0.01, note, fontsize=6, va="bottom", ha="left", color="0.3")
        fig.tight_layout(rect=(0, 0.025 * (len(skipped) + 1), 1, 1))
    else:
        fig.tight_layout()
    out = run / "peaks.png"
    fig.savefig(out, dpi=120)
    plt.close(fig)
    _write_csv(run / "peaks_plot.csv", ["contact", "peak_force", *curves], [contacts, peak, *curves.values()])
    return out


def plot_snapshots(run: Path) -> Path | None:
    if not (run / "snapshots.csv").exists():
        return None
    summary = json.loads((run / "summary.json").read_text())
    _, data = _read_csv(run / "snapshots.csv")
    _, peaks = _read_csv(run / "peaks.csv")
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    cols = {"time": [], "bead": [], "velocity": [], "contact_force": []}
    for t in np.unique(data[:, 0]):
        rows = data[data[:, 0] == t]
        label = f"t = {t * 1e3:g} ms"
        ax1.plot(rows[:-1, 1], rows[:-1, 4], lw=1, label=label)
        ax2.plot(rows[:, 1], rows[:, 3], lw=1, label=label)
        for k, c in zip(cols, (rows[:, 0], rows[:, 1], rows[:, 3], rows[:, 4]), strict=True):
            cols[k].append(c)
    ax1.plot(peaks[:, 0], peaks[:, 1], "k--", lw=1, label="peak-force envelope (whole run)")
    ax1.set_ylabel("contact force F_{i,i+1} (N)")
    ax2.set_ylabel("bead velocity v_i (m/s)")
    ax2.set_xlabel("bead / contact index i")
    ax1.set_title(f"Force and velocity along the chain — {_label(summary)}", fontsize=10)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    out = run / "snapshots.png"
    fig.savefig(out, dpi=120)
    plt.close(fig)
    _write_csv(run / "snapshots_plot.csv", list(cols), [np.concatenate(v) for v in cols.values()])
    return out


def plot_run(run_dir: str | Path, log: bool = True) -> list[Path]:
    run = Path(run_dir)
    if not (run / "summary.json").exists():
        raise FileNotFoundError(f"{run}: not a complete granchain run directory (no summary.json)")
    made = [plot_peaks(run, log), plot_histories(run), plot_snapshots(run)]
    return [p for p in made if p is not None]
