"""One function compares two runs of the same scene (any two backends), with the models beside them."""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from granchain.physics import models


@dataclass(frozen=True)
class CompareRow:
    quantity: str
    unit: str
    a: float | None  # first run (LAMMPS in `granchain compare`)
    b: float | None  # second run (reference)
    model: float | None
    model_source: str
    rtol: float

    @property
    def rel_diff(self) -> float | None:
        if self.a is None or self.b is None:
            return None
        scale = max(abs(self.a), abs(self.b))
        return 0.0 if scale == 0 else abs(self.a - self.b) / scale

    @property
    def rel_model(self) -> float | None:
        if self.model is None or self.b is None or self.model == 0:
            return None
        return abs(self.b - self.model) / abs(self.model)

    @property
    def ok(self) -> bool:
        """Within rtol; a quantity one run has and the other lacks is a failure too."""
        if self.a is None and self.b is None:
            return True
        d = self.rel_diff
        return d is not None and d <= self.rtol


def _model_rows(scene, ref_obs: dict) -> dict[str, tuple[float, str]]:
    """Model values for the compared quantities, where a model applies to this scene."""
    out: dict[str, tuple[float, str]] = {}
    m, d, k = scene.mass, scene.diameter, scene.stiffness
    ld = scene.loading
    impulse = scene.input_impulse
    if scene.contact.law == "hertz":
        fp = models.short_load_peak_force(impulse, m, scene.e_star, scene.r_star)
        src = "Eq. 8"
        if ld.is_force:
            fu = models.solitary_wave_peak_force(models.front_speed_upper(ld.amplitude, k, m, d), k, m, d)
            if fu < fp:
                fp, src = fu, "Eq. 15 + Nesterenko (upper bound)"
        out["leading_peak_force"] = (fp, src)
        if ref_obs.get("leading_peak_force"):
            out["wave_speed"] = (
                models.solitary_wave_speed(ref_obs["leading_peak_force"], k, m, d),
                "Nesterenko at the reference's leading peak",
            )
    else:
        beta = scene.contact.unloading_coeff
        contact_time = math.pi * math.sqrt(m / (2.0 * k))  # two beads on a linear spring k
        if not ld.is_force or ld.duration < 0.1 * contact_time:
            out["peak_force_contact_1"] = (
                models.linear_chain_impulse_response(impulse, k, m, beta)["F_p"],
                "Eq. A2 (short loading)",
            )
        if ld.is_force and ld.duration > 10.0 * contact_time:
            out["wave_speed"] = (models.linear_sound_speed(k, m, d), "c = D sqrt(k/m) (Sec. III B, long loading)")
    return out


def compare_runs(a, b, rtol: float = 1e-3) -> list[CompareRow]:
    """Rows comparing two RunResults of the same scene (a: e.g. LAMMPS, b: e.g. reference)."""
    scene = b.scene
    oa, ob = a.observables(), b.observables()
    modl = _model_rows(scene, ob)
    sa, sb = a.solution, b.solution
    w0, w1 = ob["window"]
    rows: list[tuple[str, str, float | None, float | None]] = [
        ("leading_peak_force", "N", oa["leading_peak_force"], ob["leading_peak_force"]),
        ("leading_peak_force_nondim", "-", oa["leading_peak_force_nondim"], ob["leading_peak_force_nondim"]),
        ("wave_speed", "m/s", oa["wave_speed"], ob["wave_speed"]),
        ("max_peak_force", "N", oa["max_peak_force"], ob["max_peak_force"]),
        ("peak_force_contact_1", "N", float(sa.peak_force[0]), float(sb.peak_force[0])),
        (f"peak_force_contact_{w0}", "N", float(sa.peak_force[w0 - 1]), float(sb.peak_force[w0 - 1])),
        (f"time_of_peak_contact_{w1}", "s", _finite(sa.time_of_peak[w1 - 1]), _finite(sb.time_of_peak[w1 - 1])),
        ("final_kinetic_energy", "J", float(sa.kinetic[-1]), float(sb.kinetic[-1])),
        ("momentum", "N s", sa.momentum, sb.momentum),
    ]
    if scene.contact.law == "bilinear" or scene.effects.dashpot:
        rows.append(("dissipated_energy", "J", float(sa.dissipated[-1]), float(sb.dissipated[-1])))
    if scene.effects.far_end == "wall":
        rows.append(("wall_peak_force", "N", sa.wall_peak_force, sb.wall_peak_force))
    out = []
    for q, unit, va, vb in rows:
        mv, msrc = modl.get(q, (None, ""))
        out.append(CompareRow(q, unit, va, vb, mv, msrc, rtol))
    return out


def _finite(x) -> float | None:
    return float(x) if np.isfinite(x) else None


HEADER = [
    "quantity",
    "unit",
    "lammps",
    "reference",
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
        g(r.model),
        g(r.rel_diff),
        g(r.rel_model),
        "yes" if r.ok else "FAIL",
        r.model_source,
    ]


def format_table(rows: list[CompareRow], names=("lammps", "reference")) -> str:
    header = [*HEADER[:2], *names, *HEADER[4:]]
    table = [header] + [_cells(r) for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in table]
    return "\n".join(lines)


def write_compare(rows: list[CompareRow], out_dir: str | Path, names=("lammps", "reference")) -> None:
    out = Path(out_dir)
    header = [*HEADER[:2], *names, *HEADER[4:]]
    with open(out / "compare.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow(_cells(r))
    md = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(c if c != "FAIL" else "**FAIL**" for c in _cells(r)) + " |" for r in rows]
    (out / "compare.md").write_text("\n".join(md) + "\n")
