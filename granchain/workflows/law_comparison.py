"""granchain compare-laws: the same chain and load under two (or more) contact laws, side by side.

A test of the paper's claim (Sec. III, Fig. 4) that the bilinear Walton-Braun law captures
the key phenomena of a nonlinear elastoplastic law: the peak force along the chain under each law,
with its error bars, and the exponential-then-inverse decay fit (granchain.postprocess.response_regimes
.fit_decay) of each, in one table and one figure.

Comparable laws. A law the scene does not give is set up from the scene's own law so that both load
alike in the plastic range: the plastic slopes are equal, pi p_y R* = k (Thornton's S and the
bilinear loading stiffness), so a Thornton scene gets the bilinear k = pi p_y R* and a bilinear scene
the Thornton p_y = k / (pi R*). The bilinear unloading coefficient, which Thornton's law does not
have, is the paper's beta = 0.8 unless the caller gives one (contacts=). Any other law gets its
registry example (laws.base: example_contact).
"""

from __future__ import annotations

import json
import math
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from granchain.backends import LAMMPS, Backend
from granchain.exceptions import UsageError
from granchain.physics.laws import LAWS
from granchain.physics.materials import YIELD_PRESSURE_FACTOR
from granchain.postprocess.response_regimes import DecayFit, fit_decay
from granchain.rundir import RunDirError, check_output_dir, owned_by_granchain
from granchain.safe_files import UnsafeFileError, atomic_directory
from granchain.scene import scene_from_dict, scene_to_dict
from granchain.workflows.run import run_scene

#: the bilinear unloading coefficient given to a scene that has none (the paper's Figs. 5-8)
DEFAULT_BETA = 0.8


def equivalent_contact(scene, law: str, given: dict | None = None) -> dict:
    """The [contact] table of `scene` under `law` (see the module docstring for the rule)."""
    if law not in LAWS:
        raise UsageError(f"--laws: {law!r} is not a contact law; choose from {', '.join(LAWS)}")
    if given:
        return {"law": law, **given}
    c = scene.contact
    if c.law == law:
        return LAWS[law].contact_to_dict(c)
    r_star = scene.r_star
    if law == "thornton" and c.law == "bilinear":
        return {"law": law, "yield_pressure": float(scene.law.k) / (math.pi * r_star)}
    if law == "bilinear" and c.law == "thornton":
        return {
            "law": law,
            "unloading_coeff": DEFAULT_BETA,
            "plastic_stiffness": math.pi * p_y(scene) * r_star,
        }
    return {"law": law, **LAWS[law].example_contact}


def p_y(scene) -> float:
    """Thornton's limiting pressure of the nominal contact (given, or from bead 1's yield strength)."""
    c = scene.contact
    return (
        float(c.yield_pressure)
        if c.yield_pressure is not None
        else YIELD_PRESSURE_FACTOR * float(scene.chain.material.yield_strength)
    )


def scene_with_law(scene, contact: dict):
    """The scene with its [contact] table replaced by `contact` (a law's equivalent contact)."""
    d = scene_to_dict(scene)
    d["contact"] = contact
    if contact["law"] == "bilinear" and isinstance(d["chain"].get("material"), dict):
        d["chain"]["material"].pop("yield_strength", None)  # the given plastic_stiffness sets k
    return scene_from_dict(d, source=f"{scene.source or '<scene>'} [{contact['law']}]")


@dataclass
class LawRun:
    """The scene under one contact law: its run and the measured peak forces with their errors."""

    law: str
    contact: dict
    result: object  # RunResult
    contacts: np.ndarray  # measured contacts (1-based, complete peaks)
    peak_force: np.ndarray
    peak_force_error: np.ndarray  # nan where not estimated
    fit: DecayFit | None
    why_no_fit: str = ""


@dataclass
class LawComparison:
    """The same chain and load under two or more contact laws, side by side."""

    scene: object
    runs: list[LawRun] = field(default_factory=list)

    def table(self) -> list[dict]:
        """One row per law: its contact, decay fit (rate, exponent, transition contact) with uncertainties."""
        rows = []
        for r in self.runs:
            rows.append(
                {
                    "law": r.law,
                    "contact": r.contact,
                    "first_peak_force": float(r.peak_force[0]) if r.peak_force.size else None,
                    "last_peak_force": float(r.peak_force[-1]) if r.peak_force.size else None,
                    "transition_contact": r.fit.transition_contact if r.fit else None,
                    "transition_contact_range": list(r.fit.transition_range) if r.fit else None,
                    "decay_per_contact": r.fit.decay_per_contact if r.fit else None,
                    "decay_per_contact_stderr": r.fit.decay_per_contact_stderr if r.fit else None,
                    "inverse_power": r.fit.power if r.fit else None,
                    "inverse_power_stderr": r.fit.power_stderr if r.fit else None,
                    "fit_rms_log_residual": r.fit.rms_log_residual if r.fit else None,
                    "why_no_fit": r.why_no_fit or None,
                    "wall_time": r.result.solution.wall_time,
                    "timestep": r.result.solution.timestep,
                }
            )
        return rows


def _measured(result) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Complete peaks from contact 1 up to the first incomplete one (a decay curve has no holes)."""
    sol = result.solution
    f = np.asarray(sol.peak_force, dtype=float)
    ok = np.asarray(sol.complete, dtype=bool) & np.isfinite(f) & (f > 0)
    n = int(np.argmin(ok)) if not ok.all() else len(ok)
    err = np.full(n, np.nan)
    if getattr(result, "errors", None) is not None and result.errors.peak_force is not None:
        err = np.asarray(result.errors.peak_force.error, dtype=float)[:n]
    return np.arange(1, n + 1), f[:n], err


def compare_laws(
    scene,
    laws: tuple[str, ...] = ("thornton", "bilinear"),
    backend: str | Backend = LAMMPS.name,
    method: str | None = None,
    rtol: float | None = None,
    error_estimate: bool = True,
    contacts: dict[str, dict] | None = None,
) -> LawComparison:
    """Run `scene` under each law (equivalent_contact) and fit each one's peak-force decay."""
    if len(set(laws)) < 2:
        raise UsageError("--laws: give at least two different contact laws, e.g. thornton,bilinear")
    scenes = [scene_with_law(scene, equivalent_contact(scene, law, (contacts or {}).get(law))) for law in laws]
    out = LawComparison(scene=scene)
    for law, sc in zip(laws, scenes, strict=True):  # every scene is valid before anything runs
        res = run_scene(sc, backend=backend, method=method, rtol=rtol, error_estimate=error_estimate)
        c, f, e = _measured(res)
        fit, why = None, ""
        try:
            fit = fit_decay(f)
        except ValueError as exc:
            why = str(exc)
        out.runs.append(LawRun(law, equivalent_contact(scene, law, (contacts or {}).get(law)), res, c, f, e, fit, why))
    return out


def fit_curves(run: LawRun) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fitted exponential (before the transition) and inverse power law (from it on), drawn over
    the measured contacts: (contacts, exponential, inverse)."""
    i = run.contacts.astype(float)
    fit = run.fit
    tc = fit.transition_contact
    y = np.log(run.peak_force)
    early, late = i < tc, i >= tc
    b_exp = float(np.mean(y[early] + fit.decay_per_contact * i[early]))
    b_inv = float(np.mean(y[late] + fit.power * np.log(i[late])))
    expo = np.where(i <= tc, np.exp(b_exp - fit.decay_per_contact * i), np.nan)
    inv = np.where(i >= tc - 1, np.exp(b_inv - fit.power * np.log(i)), np.nan)
    return i, expo, inv


def write_law_comparison(cmp: LawComparison, out: str | Path, overwrite: bool = False, formats=("png",)) -> Path:
    """laws.csv (contact, then peak force and error per law), laws.json (fits, contacts, costs), and
    the figure laws.png; written to a temporary directory and moved into place."""
    check_output_dir(out, overwrite)
    out = Path(out)
    try:
        with atomic_directory(out, "laws", overwrite=overwrite, owned=owned_by_granchain) as tmp:
            _write_laws(cmp, tmp, formats)
    except UnsafeFileError as e:
        raise RunDirError(str(e)) from None
    return out


def _write_laws(cmp, tmp: Path, formats) -> None:
    """laws.csv, laws.json and the figure into the directory being written (a Figure of its own: no
    pyplot, no change of the caller's matplotlib backend)."""
    from matplotlib.figure import Figure

    n = max((r.contacts.size for r in cmp.runs), default=0)
    header = ["contact"]
    cols = [np.arange(1, n + 1, dtype=float)]
    for r in cmp.runs:
        f = np.full(n, np.nan)
        e = np.full(n, np.nan)
        f[: r.contacts.size], e[: r.contacts.size] = r.peak_force, r.peak_force_error
        header += [f"peak_force_{r.law}", f"peak_force_error_{r.law}"]
        cols += [f, e]
    with open(tmp / "laws.csv", "w") as fh:
        fh.write(",".join(header) + "\n")
        for row in zip(*cols, strict=True):
            fh.write(",".join("" if not np.isfinite(x) else repr(float(x)) for x in row) + "\n")
    (tmp / "laws.json").write_text(
        json.dumps({"scene": cmp.scene.title or cmp.scene.source, "laws": cmp.table()}, indent=2)
    )
    fig = Figure(figsize=(6.4, 4.4))
    ax = fig.subplots()
    for r, color in zip(cmp.runs, ("C0", "C3", "C2", "C4"), strict=False):
        err = np.where(np.isfinite(r.peak_force_error), r.peak_force_error, 0.0)
        ax.errorbar(r.contacts, r.peak_force, yerr=err, fmt="o", ms=3, color=color, label=f"{r.law} peak force")
        if r.fit is not None:
            i, expo, inv = fit_curves(r)
            ax.plot(i, expo, "-", color=color, lw=1, label=f"{r.law}: exp(-{r.fit.decay_per_contact:.3g} i)")
            ax.plot(
                i,
                inv,
                "--",
                color=color,
                lw=1,
                label=f"{r.law}: i^-{r.fit.power:.3g} from {r.fit.transition_contact}",
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("contact i")
    ax.set_ylabel("peak force (N)")
    ax.set_title("\n".join(textwrap.wrap(cmp.scene.title or "", 80)), fontsize=8, parse_math=False)
    ax.legend(fontsize=7)
    for fmt in formats:
        fig.savefig(tmp / f"laws.{fmt}", dpi=120)
