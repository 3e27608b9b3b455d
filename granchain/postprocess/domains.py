"""Where an elastic law's contacts were loaded beyond first yield.

The Hertz law is elastic at any force, the beads are not: a contact of two beads whose materials have
a yield strength sigma_y starts to yield once its peak Hertz pressure reaches p_y = 1.61 sigma_y of the
softer one (von Mises, nu = 0.3; Johnson, Contact Mechanics, 1985, Sec. 6.2), at the force
F_y = pi^3 p_y^3 R*^2 / (6 E*^2), where Thornton's law leaves Hertz (ThorntonLaw.yield_force of the
same pair). First yield is where a small plastic zone appears under the surface; it grows with
F / F_y (Johnson, Ch. 6) until the contact is fully plastic, and the elastic law ignores it: a
deformation and a dissipation that are small near F_y and grow with F / F_y. Peaks above F_y are
marked, with the contacts and by how much (and on a precompressed chain whether F0 alone passes F_y),
as a fact about the run, not a verdict on its numbers; where a material has no yield strength (brass
in the paper, glass, PTFE) nothing is said.
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


def _sigma_y(materials) -> str:
    """The softer material's sigma_y as the note gives it: with its name where it is a built-in one."""
    m = min(materials, key=lambda x: x.yield_strength)
    name = next((k for k, v in mat.MATERIALS.items() if v == m), None)
    where = f"the library's for {name}" if name else "the scene's"
    return f"sigma_y = {m.yield_strength / 1e6:.4g} MPa, {where}"


#: what every note says the elastic law leaves out, and which laws model it
IGNORED = (
    "the elastic law ignores the plastic deformation this implies, small near F_y and growing with F/F_y "
    "([contact] law = 'thornton' or 'bilinear' models it)"
)


def beyond_yield(scene, solution) -> list[str]:
    """One line per kind of contact (the beads', the striker's, the wall's) whose peak force under an
    elastic law passed Johnson's first-yield force F_y (see the module docstring): the contacts, the
    largest F / F_y, the yield strength used, on a precompressed chain whether F0 alone passes F_y, and
    that the law leaves out the plastic deformation; [] under a plastic law, where no material has a
    yield strength, or where every peak stayed below F_y. First yield is not a failure of the law: the
    plastic zone starts small under the surface and grows with F / F_y, so the note says how far
    beyond first yield a run went and does not call its numbers wrong."""
    if not np.all(np.isinf(scene.law.plastic_onset_force())):
        return []  # the law yields on its own (bilinear, Thornton)
    law = scene.contact.law
    ignored = IGNORED  # said once, on the first line
    f0 = float(scene.effects.precompression)
    lines = []
    f = np.asarray(solution.peak_force, dtype=float)
    fy = _chain_yield_forces(scene)
    over = np.flatnonzero(np.isfinite(f) & np.isfinite(fy) & (f > fy))
    if over.size:
        worst = int(over[np.argmax(f[over] / fy[over])])
        beads = scene.bead_materials[worst : worst + 2]
        static = ""
        if f0 and np.nanmin(fy) < f0:  # the chain's contacts start beyond first yield before the wave
            static = f"; F0 = {_kn(f0)} alone is {f0 / np.nanmin(fy):.3g}x F_y, at rest"
        total = " (total force, F0 included)" if f0 else ""
        lines.append(
            f"{law} law beyond first yield at {over.size} of {f.size} contacts ({contact_runs(over + 1)}): the "
            f"largest peak{total}, {_kn(f[worst])} at contact {worst + 1}, is {f[worst] / fy[worst]:.3g}x "
            f"F_y = {_kn(fy[worst])} (Johnson's first yield, p_y = {mat.YIELD_PRESSURE_FACTOR} sigma_y, "
            f"{_sigma_y(beads)}){static}; {ignored}"
        )
        ignored = ""
    ends = []
    if scene.loading.kind == "striker" and solution.striker_peak_force is not None:
        ld = scene.loading
        e_star = mat.pair_effective_modulus(ld.striker_material, scene.chain.material)
        r_star = mat.pair_effective_radius(ld.striker_radius, scene.chain.radius)
        pair = (ld.striker_material, scene.chain.material)
        ends.append(("striker's", solution.striker_peak_force, yield_force(e_star, r_star, pair), 0.0))
    if scene.effects.far_end == "wall" and solution.wall_peak_force is not None:
        m, r = scene.bead_materials[-1], float(scene.bead_radii[-1])
        ends.append(("wall's", solution.wall_peak_force, yield_force(*scene.wall_pair(r, m)), f0))
    for who, peak, limit, static in ends:
        if limit is not None and peak > limit:
            at_rest = f"; F0 = {_kn(static)} alone is {static / limit:.3g}x F_y" if static > limit else ""
            lines.append(
                f"{law} law beyond first yield at the {who} contact: its peak {_kn(peak)} is {peak / limit:.3g}x "
                f"F_y = {_kn(limit)}{at_rest}" + (f"; {ignored}" if ignored else "")
            )
            ignored = ""
    return lines
