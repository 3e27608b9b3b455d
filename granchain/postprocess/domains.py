"""Where a run left its contact law's domain: an elastic law's contacts loaded beyond yield.

The Hertz law is elastic at any force, the beads are not: a contact of two beads whose materials have
a yield strength sigma_y starts to yield once its peak Hertz pressure reaches p_y = 1.61 sigma_y of the
softer one (von Mises, nu = 0.3; Johnson, Contact Mechanics, 1985, Sec. 6.2), at the force
F_y = pi^3 p_y^3 R*^2 / (6 E*^2), where Thornton's law leaves Hertz (ThorntonLaw.yield_force of the
same pair). A peak above F_y is the elastic law's answer outside its domain: the real contact flows
plastically, dissipates and carries less. Such peaks are marked, with the contacts and by how much;
where a material has no yield strength (brass in the paper, glass, PTFE) nothing is said.
"""

from __future__ import annotations

import numpy as np

from granchain.physics import materials as mat
from granchain.physics.laws.thornton import ThorntonCoefficients, ThorntonLaw


def yield_force(e_star: float, r_star: float, materials: tuple) -> float | None:
    """F_y of a contact of effective modulus E* and radius R* between `materials` (one for a bead on a
    rigid flat): where Thornton's law with p_y = 1.61 sigma_y of the softer body leaves Hertz; None
    when one of them has no yield strength."""
    if any(m.yield_strength is None for m in materials):
        return None
    law = ThorntonLaw.for_pair(ThorntonCoefficients(yield_pressure=None), e_star, r_star, r_star, materials)
    return float(law.yield_force)


def _chain_yield_forces(scene) -> np.ndarray:
    """F_y of every bead-bead contact (nan where a material has no yield strength)."""
    n = scene.n_contacts
    if not scene.per_bead:
        m = scene.chain.material
        fy = yield_force(scene.e_star, scene.r_star, (m, m))
        return np.full(n, np.nan if fy is None else fy)
    kinds, kind_of = scene.bead_kinds
    of_pair: dict[tuple[int, int], float] = {}
    out = np.empty(n)
    for i, pair in enumerate(zip(kind_of[:-1], kind_of[1:], strict=True)):
        if pair not in of_pair:
            (r1, m1), (r2, m2) = kinds[pair[0]], kinds[pair[1]]
            fy = yield_force(mat.pair_effective_modulus(m1, m2), mat.pair_effective_radius(r1, r2), (m1, m2))
            of_pair[pair] = np.nan if fy is None else fy
        out[i] = of_pair[pair]
    return out


def contact_runs(contacts) -> str:
    """1-based contacts as runs of consecutive numbers: "1-57, 59"."""
    out, c = [], [int(x) for x in contacts]
    start = prev = c[0]
    for x in [*c[1:], None]:
        if x is not None and x == prev + 1:
            prev = x
            continue
        out.append(f"{start}" if start == prev else f"{start}-{prev}")
        if x is not None:
            start = prev = x
    return ", ".join(out)


def _kn(force: float) -> str:
    return f"{force / 1e3:.3g} kN" if abs(force) >= 1e3 else f"{force:.3g} N"


def beyond_yield(scene, solution) -> list[str]:
    """One line per kind of contact (the beads', the striker's, the wall's) whose peak force under an
    elastic law passed the force F_y at which it starts to yield (see the module docstring), naming the
    contacts, the largest excess and that the law is outside its domain there; [] under a plastic law,
    where no material has a yield strength, or where every peak stayed below F_y."""
    if not np.all(np.isinf(scene.law.plastic_onset_force())):
        return []  # the law yields on its own (bilinear, Thornton)
    law = scene.contact.law
    lines = []
    f = np.asarray(solution.peak_force, dtype=float)
    fy = _chain_yield_forces(scene)
    over = np.flatnonzero(np.isfinite(f) & np.isfinite(fy) & (f > fy))
    if over.size:
        worst = int(over[np.argmax(f[over] / fy[over])])
        ratio = f[worst] / fy[worst]
        beads = scene.bead_materials[worst : worst + 2]
        p_y = mat.YIELD_PRESSURE_FACTOR * min(m.yield_strength for m in beads)
        lines.append(
            f"{law} law beyond yield at {over.size} of {f.size} contacts ({contact_runs(over + 1)}): at contact "
            f"{worst + 1} the peak {_kn(f[worst])} is {ratio:.3g}x F_y = {_kn(fy[worst])}, the force at which "
            f"it starts to yield (its peak pressure {p_y * ratio ** (1 / 3) / 1e9:.3g} GPa against p_y = "
            f"{mat.YIELD_PRESSURE_FACTOR} sigma_y = {p_y / 1e9:.3g} GPa); the elastic law is outside its domain "
            "there: the real contacts yield and carry less, the more so the further beyond F_y (a plastic law: "
            "[contact] law = 'thornton')"
        )
    ends = []
    if scene.loading.kind == "striker" and solution.striker_peak_force is not None:
        ld = scene.loading
        e_star = mat.pair_effective_modulus(ld.striker_material, scene.chain.material)
        r_star = mat.pair_effective_radius(ld.striker_radius, scene.chain.radius)
        ends.append(
            (
                "striker's",
                solution.striker_peak_force,
                yield_force(e_star, r_star, (ld.striker_material, scene.chain.material)),
            )
        )
    if scene.effects.far_end == "wall" and solution.wall_peak_force is not None:
        m, r = scene.bead_materials[-1], float(scene.bead_radii[-1])
        ends.append(("wall's", solution.wall_peak_force, yield_force(mat.flat_effective_modulus(m), r, (m,))))
    for who, peak, limit in ends:
        if limit is not None and peak > limit:
            lines.append(
                f"{law} law beyond yield at the {who} contact: its peak {_kn(peak)} is {peak / limit:.3g}x F_y = "
                f"{_kn(limit)}, the force at which it starts to yield; the elastic law is outside its domain there"
            )
    return lines
