"""granchain compare-laws: the same chain and load under two (or more) contact laws, side by side.

A test of the paper's claim (Sec. III, Fig. 4) that the bilinear Walton-Braun law captures
the key phenomena of a nonlinear elastoplastic law: the peak force along the chain under each law,
with its error bars, and the exponential-then-inverse decay fit (granchain.postprocess.response_regimes
.fit_decay) of each, in one table and one figure.

Comparable laws. A law the scene does not give is set up from the scene's own law so that both load
alike in the plastic range: the plastic slopes are equal, pi p_y R* = k (Thornton's S and the
bilinear loading stiffness), so a Thornton scene gets the bilinear k = pi p_y R* and a bilinear scene
the Thornton p_y = k / (pi R*). The bilinear unloading coefficient, which Thornton's law does not
have, is the paper's beta = 0.8 unless the caller gives one (contacts=). A plastic law that neither
the scene nor the other law sets (a Hertz scene) takes its coefficient from the chain's materials by
the scene reader's own rules, as `granchain run` would (p_y = 1.61 sigma_y, k = 18.5 sigma_y R*, of the
softer bead of each contact); on a chain without a yield strength only the paper's brass beads
(R = 4.76 mm) take the paper's values (k = 2.43e7 N/m, and p_y = k / (pi R*)), any other chain is
refused before any run (MissingCoefficientError). Each coefficient's source is reported
(LawRun.coefficients).

The decay fit is the model of a plastic chain: a law's run in which no contact's peak passed the force
at which it deforms plastically (ContactLaw.plastic_onset_force: Thornton's F_y; never, for Hertz) gets
no fit, and why_no_fit says "no contact yielded".
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
from granchain.physics import materials as mat
from granchain.physics.laws import LAWS
from granchain.postprocess.domains import contact_runs
from granchain.postprocess.response_regimes import DecayFit, fit_decay
from granchain.rundir import RunDirError, check_output_dir, owned_by_granchain
from granchain.safe_files import UnsafeFileError, atomic_directory
from granchain.scene import scene_from_dict, scene_to_dict
from granchain.workflows.run import run_scene

#: the bilinear unloading coefficient given to a scene that has none (the paper's Figs. 5-8)
DEFAULT_BETA = 0.8

#: the paper's beads (Sec. II A: brass, R = 4.76 mm), the only chain the laws' example coefficients
#: (the paper's k = 2.43e7 N/m and its equal-slope p_y) are for
PAPER_MATERIAL, PAPER_RADIUS = "brass", 4.76e-3

#: what each plastic coefficient is, for the messages
_COEFFICIENT = {
    "yield_pressure": "Thornton's limiting contact pressure p_y (Pa)",
    "plastic_stiffness": "the bilinear plastic loading stiffness k (N/m)",
}


class MissingCoefficientError(UsageError):
    """A plastic law compare-laws cannot set up: the chain's material has no yield strength to derive
    its coefficient from, and the chain is not the paper's brass."""


#: a law's [contact] table and where each coefficient comes from (contact_and_sources)
Sourced = tuple[dict, dict[str, tuple[float, str]]]


def equivalent_contact(scene, law: str, given: dict | None = None) -> dict:
    """The [contact] table of `scene` under `law` (see the module docstring for the rule)."""
    return contact_and_sources(scene, law, given)[0]


def contact_and_sources(scene, law: str, given: dict | None = None) -> Sourced:
    """The [contact] table of `scene` under `law` and where each of its coefficients comes from.

    Parameters
    ----------
    scene : Scene
        The scene as read.
    law : str
        A contact law's name (granchain.physics.laws.LAWS).
    given : dict, optional
        The caller's [contact] values for `law` (compare_laws' contacts=); they win.

    Returns
    -------
    contact : dict
        The [contact] table (a coefficient the scene reader derives from the materials is left out).
    sources : dict
        coefficient name -> (value of the nominal bead-bead contact, where it comes from).

    Raises
    ------
    UsageError
        `law` is not a contact law.
    MissingCoefficientError
        A plastic coefficient has no source (see the module docstring).
    """
    if law not in LAWS:
        raise UsageError(f"--laws: {law!r} is not a contact law; choose from {', '.join(LAWS)}")
    if given:
        return {"law": law, **given}, {k: (float(v), "given (contacts=)") for k, v in given.items()}
    if scene.contact.law == law:
        return _scene_contact(scene, law)
    converted = _equal_plastic_slope(scene, law)
    if converted is not None:
        return converted
    if law not in ("thornton", "bilinear"):
        example = LAWS[law].example_contact
        return {"law": law, **example}, {k: (float(v), f"the {law} law's example") for k, v in example.items()}
    return _plastic_from_material(scene, law)


def _scene_contact(scene, law: str) -> Sourced:
    """The scene's own [contact] table (its law is `law`), with the coefficients derived from the yield."""
    contact = LAWS[law].contact_to_dict(scene.contact)
    sources = {k: (float(v), "the scene's [contact]") for k, v in contact.items() if k != "law"}
    if law == "thornton" and "yield_pressure" not in contact:
        sources["yield_pressure"] = (p_y(scene), _from_yield(scene, "p_y = 1.61 sigma_y"))
    if law == "bilinear" and _is_from_yield(scene, contact.get("plastic_stiffness")):
        sources["plastic_stiffness"] = (float(scene.law.k), _from_yield(scene, "k = 18.5 sigma_y R*"))
    return contact, sources


def _equal_plastic_slope(scene, law: str) -> Sourced | None:
    """Thornton from the scene's bilinear law or the bilinear law from its Thornton law, by equal plastic
    slopes (k = pi p_y R*, Sec. III); None for any other pair of laws."""
    c, r_star = scene.contact, scene.r_star
    if law == "thornton" and c.law == "bilinear":
        k = float(scene.law.k)
        v = k / (math.pi * r_star)
        return {"law": law, "yield_pressure": v}, {
            "yield_pressure": (v, f"k / (pi R*): the plastic slope of the scene's bilinear law, k = {k:.4g} N/m")
        }
    if law == "bilinear" and c.law == "thornton":
        py = p_y(scene)
        v = math.pi * py * r_star
        return {"law": law, "unloading_coeff": DEFAULT_BETA, "plastic_stiffness": v}, {
            "unloading_coeff": (DEFAULT_BETA, "the paper's beta (default)"),
            "plastic_stiffness": (v, f"pi p_y R*: the plastic slope of the scene's Thornton law, p_y = {py:.4g} Pa"),
        }
    return None


def _plastic_from_material(scene, law: str) -> Sourced:
    """A plastic law's coefficient from the chain's yield strength, or the paper's brass values on the
    paper's chain; else MissingCoefficientError (the module docstring)."""
    sources: dict[str, tuple[float, str]] = {}
    contact: dict = {"law": law}
    if law == "bilinear":
        contact["unloading_coeff"] = DEFAULT_BETA
        sources["unloading_coeff"] = (DEFAULT_BETA, "the paper's beta (default)")
    key = "yield_pressure" if law == "thornton" else "plastic_stiffness"
    if not mat.lacking_yield_strength(scene.chain):  # the scene reader derives it, pair by pair
        ys = float(scene.chain.material.yield_strength)
        if law == "thornton":
            sources[key] = (mat.YIELD_PRESSURE_FACTOR * ys, _from_yield(scene, "p_y = 1.61 sigma_y"))
        else:
            sources[key] = (
                mat.plastic_stiffness_from_yield(ys, scene.chain.radius),
                _from_yield(scene, "k = 18.5 sigma_y R*"),
            )
        return contact, sources
    if _is_paper_chain(scene):
        v = float(LAWS[law].example_contact[key])
        contact[key] = v
        sources[key] = (
            v,
            "the paper's brass k = 2.43e7 N/m (Sec. III)"
            if law == "bilinear"
            else "the paper's brass k = 2.43e7 N/m by equal plastic slopes, p_y = k / (pi R*)",
        )
        return contact, sources
    raise MissingCoefficientError(
        f"--laws {law}: the {law} law needs {key}, {_COEFFICIENT[key]}, and the chain has no yield strength "
        "to derive it from (p_y = 1.61 sigma_y, k = 18.5 sigma_y R*); the paper's values are for its "
        f"{PAPER_MATERIAL} beads of radius {PAPER_RADIUS} m only. Give it in the scene: "
        f"{mat.lacking_yield_strength(scene.chain)}; or [contact] law = 'thornton' with yield_pressure (or "
        "law = 'bilinear' with plastic_stiffness), from which the other law gets the equal plastic slope"
    )


def _from_yield(scene, rule: str) -> str:
    """The source of a coefficient the scene reader derives from the materials' yield strength."""
    ch = scene.chain
    if ch.materials is not None:
        return f"{rule} of the softer bead of each contact (shown: beads 1-2)"
    name = ch.material_name or "[chain.material]"
    return f"{rule}, {name}'s sigma_y = {float(ch.material.yield_strength):.4g} Pa"


def _is_from_yield(scene, k) -> bool:
    """The scene's bilinear k is 18.5 sigma_y R* of its material (the scene reader's default)."""
    ys = scene.chain.material.yield_strength
    if k is None:  # several materials: each contact's k from the softer bead's yield strength
        return True
    return ys is not None and math.isclose(
        float(k), mat.plastic_stiffness_from_yield(float(ys), scene.chain.radius), rel_tol=1e-12
    )


def _is_paper_chain(scene) -> bool:
    """The chain is the paper's: brass beads of R = 4.76 mm (bead 1's radius is the nominal)."""
    ch = scene.chain
    return ch.materials is None and ch.material_name == PAPER_MATERIAL and ch.radius == PAPER_RADIUS


def p_y(scene) -> float:
    """Thornton's limiting pressure of the nominal contact (given, or from bead 1's yield strength)."""
    c = scene.contact
    return (
        float(c.yield_pressure)
        if c.yield_pressure is not None
        else mat.YIELD_PRESSURE_FACTOR * float(scene.chain.material.yield_strength)
    )


def scene_with_law(scene, contact: dict):
    """The scene with its [contact] table replaced by `contact` (a law's equivalent contact)."""
    d = scene_to_dict(scene)
    d["contact"] = contact
    if "plastic_stiffness" in contact and isinstance(d["chain"].get("material"), dict):
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
    #: coefficient name -> (value of the nominal bead-bead contact, where it comes from)
    coefficients: dict = field(default_factory=dict)
    #: peaks the decay curve leaves out: (contact, force) of the peaks from the first one not complete
    #: on (a lower bound of the peak: the force had not fallen back by the end of the run)
    not_complete: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros(0))


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
                    "coefficients": {k: {"value": v, "source": src} for k, (v, src) in r.coefficients.items()},
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
                    "contacts_not_complete": [int(i) for i in r.not_complete[0]],
                    "peak_force_not_complete": [float(x) for x in r.not_complete[1]],
                    "wall_time": r.result.solution.wall_time,
                    "timestep": r.result.solution.timestep,
                }
            )
        return rows


def _measured(result) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """Complete peaks from contact 1 up to the first incomplete one (a decay curve has no holes), and
    the positive peaks from there on that are not on it (not complete: lower bounds)."""
    sol = result.solution
    f = np.asarray(sol.peak_force, dtype=float)
    ok = np.asarray(sol.complete, dtype=bool) & np.isfinite(f) & (f > 0)
    n = int(np.argmin(ok)) if not ok.all() else len(ok)
    err = np.full(n, np.nan)
    if getattr(result, "errors", None) is not None and result.errors.peak_force is not None:
        err = np.asarray(result.errors.peak_force.error, dtype=float)[:n]
    rest = np.arange(n + 1, f.size + 1)
    shown = np.isfinite(f[n:]) & (f[n:] > 0)
    return np.arange(1, n + 1), f[:n], err, (rest[shown], f[n:][shown])


def _why_no_curve(n_complete: int, n_contacts: int) -> str:
    """Why a law's decay curve is short: its first contacts' peaks are not complete."""
    return (
        f"{n_complete} of {n_contacts} peaks complete from contact 1 on (the next had not fallen back to 3% "
        "of its peak by the end of the run: a step or long load keeps the contacts loaded)"
    )


def _why_elastic(scene, solution) -> str:
    """Why the plastic decay model does not apply: no contact's peak force passed the force at which
    its law deforms plastically (ContactLaw.plastic_onset_force); "" when one did. The exponential
    then inverse decay is the paper's model of a chain whose contacts dissipate in plastic flow
    (Sec. IV); on a chain that stayed elastic its coefficients would describe nothing."""
    f = np.asarray(solution.peak_force, dtype=float)
    laws = scene.contact_laws if scene.per_bead else [scene.law]
    onset = np.concatenate([np.ravel(law.plastic_onset_force()) for law in laws])
    onset = np.broadcast_to(onset, f.shape) if onset.size == 1 else onset
    reached = np.isfinite(f) & (f > 0)
    if np.any(reached & (f > onset)):
        return ""
    if np.all(np.isinf(onset)):
        return f"no contact yielded: the {scene.contact.law} law is elastic, so the plastic decay model does not apply"
    largest = int(np.argmax(np.where(reached, f, -np.inf))) if reached.any() else 0
    return (
        "no contact yielded: the plastic decay model does not apply (the largest peak, "
        f"{f[largest]:.4g} N at contact {largest + 1}, is under its yield force {onset[largest]:.4g} N)"
    )


def compare_laws(
    scene,
    laws: tuple[str, ...] = ("thornton", "bilinear"),
    backend: str | Backend = LAMMPS.name,
    method: str | None = None,
    rtol: float | None = None,
    error_estimate: bool = True,
    contacts: dict[str, dict] | None = None,
) -> LawComparison:
    """Run `scene` under each law (contact_and_sources) and fit each one's peak-force decay.

    Every law's scene is set up, and a missing coefficient refused (MissingCoefficientError), before
    any run.
    """
    if len(set(laws)) < 2:
        raise UsageError("--laws: give at least two different contact laws, e.g. thornton,bilinear")
    setups = [contact_and_sources(scene, law, (contacts or {}).get(law)) for law in laws]
    scenes = [scene_with_law(scene, contact) for contact, _ in setups]
    out = LawComparison(scene=scene)
    for law, sc, (contact, sources) in zip(laws, scenes, setups, strict=True):  # all valid before any run
        res = run_scene(sc, backend=backend, method=method, rtol=rtol, error_estimate=error_estimate)
        c, f, e, rest = _measured(res)
        fit, why = None, _why_elastic(sc, res.solution)
        if not why:
            try:
                fit = fit_decay(f)
            except ValueError as exc:
                why = str(exc)
                if rest[0].size:
                    why += "; " + _why_no_curve(c.size, c.size + rest[0].size)
        out.runs.append(LawRun(law, contact, res, c, f, e, fit, why, sources, rest))
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


#: the figure's left margin (a fraction of its width): room for the peak forces' tick labels and the axis label
LEFT_MARGIN = 0.14


def fit_labels(law: str, fit: DecayFit) -> tuple[str, str]:
    """The legend's labels of a law's decay fit: its exponential, exp(-lambda i), and its inverse power,
    i^-p from the transition contact, each sign printed once (a growing fit, lambda or p < 0, reads
    exp(+0.01 i) or i^+0.05, not exp(--0.01 i))."""
    return (
        f"{law}: exp({-fit.decay_per_contact:+.3g} i)",
        f"{law}: i^{-fit.power:+.3g} from {fit.transition_contact}",
    )


def _write_laws(cmp, tmp: Path, formats) -> None:
    """laws.csv, laws.json and the figure into the directory being written (a Figure of its own: no
    pyplot, no change of the caller's matplotlib backend)."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import LogFormatter

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
    notes, drawn = [], False
    for r, color in zip(cmp.runs, ("C0", "C3", "C2", "C4"), strict=False):
        if r.contacts.size:
            err = np.where(np.isfinite(r.peak_force_error), r.peak_force_error, 0.0)
            ax.errorbar(r.contacts, r.peak_force, yerr=err, fmt="o", ms=3, color=color, label=f"{r.law} peak force")
            drawn = True
        rest, force = r.not_complete
        if rest.size and not r.contacts.size:  # no decay curve: its lower bounds, drawn open, not fitted
            ax.plot(rest, force, "o", ms=3, mfc="none", color=color, label=f"{r.law} peak not complete")
            drawn = True
            notes.append(
                f"{r.law}: contacts {contact_runs(rest)} drawn open: not complete by the end of the run (force not "
                "back to 3% of its peak), lower bounds"
            )
        elif rest.size:  # past the decay curve (its end, the contacts the wave had not passed): left out
            notes.append(
                f"{r.law}: contacts {contact_runs(rest)} not drawn: not complete by the end of the run (force not back "
                "to 3% of its peak)"
            )
        if r.fit is not None:
            i, expo, inv = fit_curves(r)
            expo_label, inv_label = fit_labels(r.law, r.fit)
            ax.plot(i, expo, "-", color=color, lw=1, label=expo_label)
            ax.plot(i, inv, "--", color=color, lw=1, label=inv_label)
        else:
            notes.append(f"{r.law}: no decay fit ({r.why_no_fit.split(';')[0]})")
    if drawn:  # log axes only over positive data
        ax.set_xscale("log")
        ax.set_yscale("log")
        # plain numbers: a log axis over less than a decade labels its minor ticks 1.7 x 10^2 ..., wide
        # enough to push the axis label off the figure (LogFormatter: "170"; minor ticks labelled only
        # over a short range, as the default's)
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(LogFormatter())
            axis.set_minor_formatter(LogFormatter(labelOnlyBase=False))
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "no positive peak force measured", ha="center", va="center", transform=ax.transAxes)
        notes.append("no law has a positive peak force on any contact: nothing drawn")
    ax.set_xlabel("contact i")
    ax.set_ylabel("peak force (N)")
    ax.set_title("\n".join(textwrap.wrap(cmp.scene.title or "", 80)), fontsize=8, parse_math=False)
    if notes:
        lines = [line for note in notes for line in textwrap.wrap(note, 110)]
        fig.subplots_adjust(bottom=0.12 + 0.03 * len(lines))
        fig.text(0.01, 0.01, "\n".join(lines), fontsize=6, va="bottom", parse_math=False)
    fig.subplots_adjust(left=LEFT_MARGIN)
    for fmt in formats:
        fig.savefig(tmp / f"laws.{fmt}", dpi=120)
