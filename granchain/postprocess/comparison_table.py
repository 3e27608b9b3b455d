"""One function compares two runs of the same scene (any two backends), with the models that apply beside them."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from granchain.integrators import integrator
from granchain.peaks import REACHED_FRACTION
from granchain.physics.effects import unbalanced_forces
from granchain.physics.effects.gravity import scene_static_forces
from granchain.physics.predictions import applicability, predict
from granchain.postprocess.observables import END_PEAKS, OBSERVABLES, SENSOR_OBSERVABLES
from granchain.postprocess.sensors import sensor_values


@dataclass(frozen=True)
class CompareRow:
    """One row of `granchain compare`: a quantity as two runs of the same scene measured it, each run's
    error bar, and the model it is checked against where one applies (the law's ``compare_models``)."""

    quantity: str
    unit: str
    a: float | None  # first run (LAMMPS in `granchain compare`)
    b: float | None  # second run (reference)
    model: float | None  # None where no model is compared (none exists, or it does not apply)
    model_source: str  # the model's equation; "n/a: <model>: <reason>" where it does not apply
    rtol: float
    model_applies: bool | None = None  # None: no model for this quantity
    not_measured: str | None = None  # why a run lacks the quantity; None where both measured it
    error_a: float | None = None  # each run's measured error of the value (absolute; None: none)
    error_b: float | None = None

    @property
    def rel_diff(self) -> float | None:
        """|a - b| / max(|a|, |b|) (0 where both are 0); None unless both runs measured the quantity."""
        if self.a is None or self.b is None:
            return None
        scale = max(abs(self.a), abs(self.b))
        return 0.0 if scale == 0 else abs(self.a - self.b) / scale

    @property
    def rel_model(self) -> float | None:
        """|b - model| / |model| of the second run (the reference); None where no model applies or is 0,
        or the second run did not measure the quantity."""
        if not self.model_applies or self.model is None or self.b is None or self.model == 0:
            return None
        return abs(self.b - self.model) / abs(self.model)

    @property
    def measured(self) -> bool:
        """Whether either run measured the quantity."""
        return self.a is not None or self.b is not None

    @property
    def ok(self) -> bool:
        """Not a failure: the two runs agree within rtol plus their combined measured errors (each
        run's error bar, granchain.workflows.error_estimates; 0 where a run has none), or neither measured the
        quantity (then the row reads "not measured: <reason>", never "yes"). A quantity one run has
        and the other lacks is a failure. The model columns never make a row fail or pass."""
        if not self.measured:
            return True
        if self.a is None or self.b is None:
            return False
        scale = max(abs(self.a), abs(self.b))
        allowed = self.rtol * scale + (self.error_a or 0.0) + (self.error_b or 0.0)
        return abs(self.a - self.b) <= allowed

    @property
    def verdict(self) -> str:
        """The within_rtol cell: "yes", "FAIL" or "not measured: <reason>"."""
        if not self.measured:
            return f"not measured: {self.not_measured or 'neither run reports it'}"
        return "yes" if self.ok else "FAIL"


def _model_rows(scene, ref_obs: dict) -> dict[str, tuple[float | None, str, bool]]:
    """(value, source, applies) of the model for each compared quantity that has one; where none of
    its models applies to the scene: (None, "n/a: <model>: <reason>", False).

    The models and the quantities they check are the scene's contact law's (ContactLaw.compare_models,
    in order of preference: the first that applies is used); those that need a measured value are
    evaluated at the reference run's observables (ContactLaw.measured_models)."""
    law = scene.contact.law_class
    values = {p.name: p.value for p in predict(scene)}
    values.update(law.measured_models(scene, values, ref_obs))
    out: dict[str, tuple[float | None, str, bool]] = {}
    for quantity, candidates in law.compare_models.items():
        first_no = None
        for name, label in candidates:
            verdict = applicability(name, scene, quantity=quantity)
            if verdict.applies and name in values:
                out[quantity] = (values[name], label, True)
                break
            if first_no is None:
                reason = verdict.reason
                if verdict.applies:  # applies, but needs what the run did not measure
                    reason = "needs the reference's leading peak, which it did not measure"
                first_no = (None, f"n/a: {label}: {reason}", False)
        else:
            out[quantity] = first_no
    return out


def _not_measured(sol, obs: dict) -> dict[str, str]:
    """Why a quantity can be missing from a run (keyed like the rows): the reason for every row the run
    could lack, whether or not it lacks it (compare_runs reads it only for a row without a value)."""
    if not obs["window"]:  # one bead: no bead-bead contact (the observables say why)
        ended = f"before the run ended at t = {sol.end_time:g} s"
        return {"striker_peak_force": f"the striker did not touch bead 1 {ended}"}
    w0, w1 = obs["window"]
    ended = f"before the run ended at t = {sol.end_time:g} s"
    out = {
        "leading_peak_force": f"the leading wave did not reach contact {w1} (the window's end) {ended}",
        f"arrival_time_contact_{w1}": f"the leading pulse did not pass contact {w1} {ended}",
        f"peak_force_contact_{w0}": f"the peak at contact {w0} is not complete {ended}",
        "peak_force_contact_1": f"the peak at contact 1 is not complete {ended}",
        **{name: f"{e.not_measured} {ended}" for name, e in END_PEAKS.items()},
    }
    out["leading_peak_force_nondim"] = out["leading_peak_force"]
    out["wave_speed"] = (
        out["leading_peak_force"]
        if obs.get("leading_peak_force") is None
        else f"the times of peak over contacts {w0}-{w1} do not fit a forward-moving wave (fewer than three, "
        "or decreasing)"
    )
    return out


def _end_peak(scene, sol, name: str) -> float | None:
    """An end contact's peak (name: an END_PEAKS row) where it is complete, else None: a contact the
    wave has not reached holds round-off (1e-218 N), one it has not passed its running maximum;
    neither is a peak."""
    obs = END_PEAKS[name]
    value, done = getattr(sol, name), getattr(sol, obs.complete_field)
    if done is None and value is not None:  # a run directory without the flag: reached, at least
        floor = REACHED_FRACTION * float(np.max(sol.peak_force, initial=0.0))
        static = float(scene_static_forces(scene)[-1]) if name == "wall_peak_force" else 0.0  # F0 (+ the weight)
        done = value - static > floor
    return float(value) if done else None


def _end_row(scene, sa, sb, name: str) -> tuple:
    """compare's row of an end peak (END_PEAKS): its name, unit and the two runs' peaks."""
    return (name, END_PEAKS[name].unit, _end_peak(scene, sa, name), _end_peak(scene, sb, name))


#: what an observable reads that makes it a peak row (Observable.needs)
_FROM_PEAKS = {"peaks", "leading_pulses", "fronts"}

#: the rows that are peaks or are measured from peaks' times: each run's peak definition (peak_definition);
#: the registered observables' that read peaks, leading pulses or fronts (peak_rows, at call time)
PEAK_ROWS = (
    "peak_force_contact_",
    "arrival_time_contact_",
    *END_PEAKS,
    "sensor_",
)


def peak_rows() -> tuple[str, ...]:
    """The compare rows whose values are peaks or peaks' times (PEAK_ROWS and the registered
    observables that read them, granchain.postprocess.observables.OBSERVABLES)."""
    return tuple(name for name, obs in OBSERVABLES.items() if obs.needs & _FROM_PEAKS) + PEAK_ROWS


def peak_definition(method: str, scene) -> str:
    """What a run's peak force is on this scene, by its integrator.

    Verlet (the reference's and LAMMPS's) tracks the contact force at step ends: its peak is the total
    force's maximum. RK4 tracks the overlap (reference.observers.HermitePeaks): its peak is the elastic
    force where the overlap turns. Each integrator declares which it tracks
    (granchain.integrators.IntegratorFacts.peaks_by_overlap). Without a dashpot the two are one quantity
    (the force is the law's, monotone in the overlap); with one they are not (the dashpot adds gamma
    alpha' > 0 before the turn):
    /tmp/explore2 s09, a 40-bead chain with gamma = 20 N s/m, read 57.122 N at its window's end with
    RK4 and 57.268 N with the reference's Verlet (57.271 N LAMMPS), 2.6e-3 apart.

    Parameters
    ----------
    method : str
        The run's integrator (ChainSolution.method).
    scene : granchain.scene.Scene
        The scene it ran.

    Returns
    -------
    str
        The definition, in words.
    """
    if scene.damping.velocity_dependent and integrator(method).peaks_by_overlap:  # the integrator matters only then
        return "the elastic force where the overlap turns"
    return "the total force's maximum"


def compare_runs(a, b, rtol: float = 1e-3) -> list[CompareRow]:
    """Rows comparing two RunResults of the same scene (a: e.g. LAMMPS, b: e.g. reference).

    Two runs whose peaks are different quantities (peak_definition: RK4 and Verlet on a scene with a
    dashpot) have their peak rows (peak_rows) marked "not comparable" with the reason, never compared."""
    scene = b.scene
    oa, ob = a.observables(), b.observables()
    modl = _model_rows(scene, ob)
    sa, sb = a.solution, b.solution
    w0, w1 = ob["window"] or (0, 0)  # (one bead: no bead-bead contact, no contact rows)
    rows = _measured_rows(scene, sa, sb, oa, ob, w0, w1)
    why = _missing_reasons(b, sb, ob)
    why_a = _missing_reasons(a, sa, oa)  # a row only the first run lacks says why the first lacks it
    rows = _apart_at_the_end(scene, sa, sb, rows, why, why_a)
    ea, eb = _errors(a, w0, w1), _errors(b, w0, w1)
    rows, ea, eb = _unlike_peaks(scene, sa, sb, rows, why, why_a, ea, eb)
    f0 = float(scene.effects.precompression)
    out = []
    seen: set[str] = set()
    for q, unit, va, vb in rows:
        if q in seen:  # each quantity once (on two beads the window's first contact is contact 1)
            continue
        seen.add(q)
        # no model of a total force applies under precompression (the paper's and the two-body impacts'
        # need an uncompressed chain): a renamed row keeps its n/a
        mv, msrc, applies = modl.get(q, (None, "", None))
        # a reason only where a value is missing: the second run's where it lacks it, else the first's
        reason = why.get(q) if vb is None else why_a.get(q) if va is None else None
        label = dynamic_name(q) if f0 else q
        if label != q:  # the dynamic force F - F0, as the observables are (docs/observables.md)
            va, vb = (None if v is None else v - f0 for v in (va, vb))
        out.append(CompareRow(label, unit, va, vb, mv, msrc, rtol, applies, reason, ea.get(q), eb.get(q)))
    return out


#: a compare row before its model and errors: (quantity, unit, first run's value, second run's)
Row = tuple[str, str, float | None, float | None]


def _measured_rows(scene, sa, sb, oa: dict, ob: dict, w0: int, w1: int) -> list[Row]:
    """The quantities both runs measured, in the table's order: the registered observables', the
    contacts' (contact 1, the window's first, the front's arrival at its last), the striker's, the end
    state's, the dissipated energy, the wall's and the sensors'."""

    def complete(sol, contact: int) -> bool:  # only a complete peak is a number to compare
        return bool(np.isfinite(sol.time_of_peak[contact - 1]) and sol.complete[contact - 1])

    def peak(sol, contact: int) -> float | None:
        return float(sol.peak_force[contact - 1]) if complete(sol, contact) else None

    rows: list[Row] = []
    if scene.n_contacts:
        rows += [  # the registered observables', then the contacts'
            (name, obs.unit, oa.get(name), ob.get(name))  # dimensionless: "1", as everywhere
            for name, obs in OBSERVABLES.items()
            if obs.compared
        ]
        rows += [
            ("peak_force_contact_1", "N", peak(sa, 1), peak(sb, 1)),
            (f"peak_force_contact_{w0}", "N", peak(sa, w0), peak(sb, w0)),
            # the front's arrival: the leading pulse's time (peaks.leading_pulse), not the largest peak's
            (
                f"arrival_time_contact_{w1}",
                "s",
                _finite(sa.leading_pulse_time[w1 - 1]),
                _finite(sb.leading_pulse_time[w1 - 1]),
            ),
        ]
    if END_PEAKS["striker_peak_force"].applies(scene) is None:
        rows.append(_end_row(scene, sa, sb, "striker_peak_force"))
    rows += [
        ("final_kinetic_energy", "J", float(sa.kinetic[-1]), float(sb.kinetic[-1])),
        ("momentum", "N s", sa.momentum, sb.momentum),
    ]
    if scene.contact.law_class.history or scene.damping.dissipated_vectors:
        rows.append(("dissipated_energy", "J", float(sa.dissipated[-1]), float(sb.dissipated[-1])))
    if END_PEAKS["wall_peak_force"].applies(scene) is None:
        rows.append(_end_row(scene, sa, sb, "wall_peak_force"))
    rows += _sensor_rows(scene, sa, sb)
    return rows


def _apart_at_the_end(scene, sa, sb, rows: list[Row], why: dict, why_a: dict) -> list[Row]:
    """The rows with the end states blanked, and why (into why, why_a), where the runs ended at different
    times: each backend ran its own step and stopped on its own check (stop_after_contact, every
    STOP_CHECK_EVERY steps), so their end states are not the same quantity."""
    if np.isclose(sa.end_time, sb.end_time, rtol=1e-9, atol=0.0):
        return rows
    ended = f"the runs ended at different times ({sa.end_time:.6g} s and {sb.end_time:.6g} s)"
    apart = ["final_kinetic_energy", "dissipated_energy"]
    for q in apart:
        why[q] = why_a[q] = f"not comparable: {ended}"
    # the momentum too while it still changes: an effect's external force (a wall, precompression's
    # static forces) or a load still acting at the earlier end; a free chain's is the impulse, kept
    pushed = [e.name for e in unbalanced_forces(scene)]
    if scene.loading.is_force and min(sa.end_time, sb.end_time) < scene.loading.duration:
        pushed.append("the load")
    if pushed:
        apart.append("momentum")
        why["momentum"] = f"not comparable: {ended}, and the momentum changes then ({', '.join(pushed)})"
        why_a["momentum"] = why["momentum"]
    return [(q, u, None, None) if q in apart else (q, u, va, vb) for q, u, va, vb in rows]


def _unlike_peaks(scene, sa, sb, rows: list[Row], why: dict, why_a: dict, ea: dict, eb: dict):
    """(rows, ea, eb) with the peak rows (peak_rows) blanked and their errors dropped, and why, where the
    runs' peaks are different quantities (peak_definition: RK4 and Verlet with a velocity-dependent
    damping force)."""
    da, db = peak_definition(sa.method, scene), peak_definition(sb.method, scene)
    if da == db:
        return rows, ea, eb
    unlike = (
        f"not comparable: the runs' peaks are different quantities on a scene with a {scene.damping.noun} "
        f"({sa.method}: {da}; "
        f"{sb.method}: {db}); Verlet on both compares them"
    )
    peaks = {q for q, *_ in rows if q.startswith(peak_rows())}
    why.update(dict.fromkeys(peaks, unlike))
    why_a.update(dict.fromkeys(peaks, unlike))
    rows = [(q, u, None, None) if q in peaks else (q, u, va, vb) for q, u, va, vb in rows]
    ea = {q: e for q, e in ea.items() if q not in peaks}
    eb = {q: e for q, e in eb.items() if q not in peaks}
    return rows, ea, eb


def _missing_reasons(result, sol, obs: dict) -> dict[str, str]:
    """Why each compared quantity could be missing from a run (_not_measured), with the observables'
    own reasons where the run result gives them; a reason is only read for a row that lacks a value."""
    why = _not_measured(sol, obs)
    if hasattr(result, "observables_missing"):
        why.update(result.observables_missing())
    why.update(sensor_values(result.scene, sol)[1])
    return why


def _sensor_rows(scene, sa, sb) -> list[tuple[str, str, float | None, float | None]]:
    """The sensor beads' rows (postprocess.sensors: each sensor's peak and its time), bead by bead."""
    va, vb = sensor_values(scene, sa)[0], sensor_values(scene, sb)[0]
    keys = [(obs.key(b), obs.unit) for b in scene.outputs.sensors for obs in SENSOR_OBSERVABLES.values()]
    return [(key, unit, va[key], vb[key]) for key, unit in keys]


#: rows whose force is a contact's total force, F0 included on a precompressed chain (peaks.csv's
#: peak_force, summary.json's wall_peak_force); a striker's contact carries no F0
TOTAL_FORCE_ROWS = ("peak_force_contact_", "wall_peak_force")


def dynamic_name(quantity: str) -> str:
    """A compare row's name on a precompressed chain: a total-force row (TOTAL_FORCE_ROWS) compares the
    dynamic force F - F0, named dynamic_<quantity> (peaks.csv's dynamic_peak_force), like every other
    force row there (leading_peak_force and max_peak_force are dynamic already); others keep theirs."""
    return f"dynamic_{quantity}" if quantity.startswith(TOTAL_FORCE_ROWS) else quantity


def _errors(result, w0: int, w1: int) -> dict[str, float]:
    """A run's measured errors (absolute) of the compared quantities that have one (result.errors)."""
    e = getattr(result, "errors", None)
    if e is None or e.peak_force is None:
        return {}
    out = {name: v["error"] for name, v in e.observables.items() if v["error"] is not None}
    out.update({name: v["error"] for name, v in getattr(e, "end_peaks", {}).items() if v["error"] is not None})
    if not w0:  # one bead: no bead-bead contact
        return out
    for c in (1, w0):
        if np.isfinite(e.peak_force.error[c - 1]):
            out[f"peak_force_contact_{c}"] = float(e.peak_force.error[c - 1])
    if np.isfinite(e.arrival_time.error[w1 - 1]):
        out[f"arrival_time_contact_{w1}"] = float(e.arrival_time.error[w1 - 1])
    return out


def _finite(x) -> float | None:
    return float(x) if np.isfinite(x) else None


HEADER = [
    "quantity",
    "unit",
    "lammps",
    "reference",
    "lammps_error",
    "reference_error",
    "model",
    "rel_diff",
    "model_rel_diff",
    "within_rtol",
    "model_source",
]


def _cells(r: CompareRow) -> list[str]:
    def g(x):
        return "" if x is None else f"{x:.6g}"

    return [
        r.quantity,
        r.unit,
        g(r.a),
        g(r.b),
        g(r.error_a),
        g(r.error_b),
        "n/a" if r.model_applies is False else g(r.model),
        g(r.rel_diff),
        g(r.rel_model),
        r.verdict,
        r.model_source,
    ]


def _header(names) -> list[str]:
    return [*HEADER[:2], *names, *(f"{n}_error" for n in names), *HEADER[6:]]


def format_table(rows: list[CompareRow], names=("lammps", "reference")) -> str:
    """The rows as an aligned text table (what `granchain compare` prints), the runs' columns named
    `names`."""
    header = _header(names)
    table = [header] + [_cells(r) for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in table]
    return "\n".join(lines)


def write_compare(rows: list[CompareRow], out_dir: str | Path, names=("lammps", "reference")) -> None:
    """Write the rows to `out_dir` as compare.csv and compare.md (a FAIL in bold), the runs' columns
    named `names`."""
    out = Path(out_dir)
    header = _header(names)
    with open(out / "compare.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow(_cells(r))
    md = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(c if c != "FAIL" else "**FAIL**" for c in _cells(r)) + " |" for r in rows]
    (out / "compare.md").write_text("\n".join(md) + "\n")
