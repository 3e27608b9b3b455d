"""Materials and the derived quantities of a monodisperse sphere chain (paper Sec. II A).

Everything is SI. The nondimensional forms of Eqs. (5)-(7) are defined here and nowhere else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from granchain.exceptions import GranchainError

#: Plastic loading stiffness of the bilinear law: k = 18.5 sigma_y R* (paper, Sec. III).
PLASTIC_STIFFNESS_FACTOR = 18.5


@dataclass(frozen=True)
class Material:
    """An isotropic bead material."""

    density: float  # kg/m^3
    youngs_modulus: float  # Pa
    poisson_ratio: float  # -
    yield_strength: float | None = None  # Pa, only needed for the bilinear law's k


#: Built-in materials: the bead materials of granular-chain experiments, by name (``material = "<name>"``
#: in a scene; ``granchain materials`` lists them). Values are typical room-temperature ones; a real
#: batch of beads can differ by a few per cent in E (and far more in yield strength, which depends on
#: temper): give a [chain.material] table (or an inline table in a per-bead list) for measured
#: values. yield_strength is None where it is not meaningful (brittle glass and carbide, viscoelastic
#: PTFE) or, for brass, not in the paper.
#: A built-in yield_strength sets the bilinear law's k = 18.5 sigma_y R* when the scene gives none.
MATERIALS: dict[str, Material] = {
    # Pal & Geubelle, Sec. II A (the paper's brass; no yield strength given there). Do not change:
    # the bundled scenes and the tests reproduce the paper with exactly these values.
    "brass": Material(density=8500.0, youngs_modulus=115e9, poisson_ratio=0.30),
    # AISI 316 (non-magnetic) stainless: rho, E, nu as used by Daraio, Nesterenko, Herbold & Jin,
    # Phys. Rev. E 73, 026610 (2006) for their stainless-steel chains; E = 193 GPa is also the ASM
    # handbook value (Callister, App. B). Yield 290 MPa: typical annealed 316 (ASM; ASTM A240
    # minimum 205 MPa); cold-worked or ball-grade stock is stronger.
    "stainless-steel-316": Material(density=8000.0, youngs_modulus=193e9, poisson_ratio=0.30, yield_strength=290e6),
    # AISI 52100 chrome (bearing) steel balls: rho = 7780, E = 203 GPa, nu = 0.3 as used by Coste,
    # Falcon & Fauve, Phys. Rev. E 56, 6104 (1997) for their chain of steel beads. Yield 2.0 GPa:
    # typical handbook value for through-hardened 52100 (HRC 60-64), strongly temper-dependent.
    "chrome-steel-52100": Material(density=7780.0, youngs_modulus=203e9, poisson_ratio=0.30, yield_strength=2.0e9),
    # Aluminium alloy 6061-T6: Aluminum Association typical values (MatWeb / ASM): rho 2.70 g/cm^3,
    # E 68.9 GPa, nu 0.33, tensile yield 276 MPa (T6 temper; annealed 6061-O yields at ~55 MPa).
    "aluminium-6061-t6": Material(density=2700.0, youngs_modulus=68.9e9, poisson_ratio=0.33, yield_strength=276e6),
    # Tungsten carbide (WC): rho 15.6 g/cm^3 (CRC Handbook, pure WC); E = 628 GPa and nu = 0.21 as
    # commonly quoted for WC beads in granular-crystal work, inside the 530-700 GPa handbook range
    # (not checked against a primary paper here). Cemented WC-6% Co balls are lighter (~14.9 g/cm^3):
    # use an inline table for those. Brittle: no yield strength.
    "tungsten-carbide": Material(density=15600.0, youngs_modulus=628e9, poisson_ratio=0.21),
    # Soda-lime glass: rho 2.52 g/cm^3 and E 72 GPa (container glass at 20 C, the property table of
    # Wikipedia's "Soda-lime glass" article); nu 0.22 typical (0.22-0.23 in handbooks). Brittle: no
    # yield strength.
    "soda-lime-glass": Material(density=2520.0, youngs_modulus=72e9, poisson_ratio=0.22),
    # PTFE (Teflon): rho 2200, E 1.46 GPa, nu 0.46 as used by Daraio, Nesterenko, Herbold & Jin,
    # Phys. Rev. E 72, 016603 (2005) and 73, 026610 (2006) for their PTFE chains. Viscoelastic and
    # strain-rate dependent: no yield strength (the bilinear law assumes elastic-plastic yielding).
    "ptfe": Material(density=2200.0, youngs_modulus=1.46e9, poisson_ratio=0.46),
}


@dataclass(frozen=True)
class PlausibleRange:
    """The values a material property of real solid beads takes, in SI, and the unit slips that
    land outside them: a value outside is refused with the slip that would explain it."""

    low: float
    high: float
    unit: str
    #: which solids set the ends (the message quotes it)
    ends: str
    #: (factor, unit) of the slips to suggest: a value v typed in that unit is v * factor in SI
    slips: tuple[tuple[float, str], ...] = ()

    def refusal(self, value: float) -> str | None:
        """None when low <= value <= high; else why the value is refused, with each slip that
        brings it into the range (e.g. "in g/cm^3? write 7800")."""
        if self.low <= value <= self.high:
            return None
        side = "below" if value < self.low else "above"
        span = f"{self.low:g} to {self.high:g} {self.unit}"
        text = f"{value:g} {self.unit} is {side} any solid bead's ({span}: {self.ends})"
        fixes = [f"in {unit}? write {value * f:.6g}" for f, unit in self.slips if self.low <= value * f <= self.high]
        return text + ("; " + "; ".join(fixes) if fixes else f"; give it in {self.unit} and check its digits")


#: Density of a solid bead: the lightest beads of granular-chain experiments are of cork or balsa
#: (about 150-250 kg/m^3), the densest solid is osmium (22,590 kg/m^3, CRC Handbook). Every solid's
#: density in g/cm^3 is below 23, so a value below 100 is one written in g/cm^3.
DENSITY_RANGE = PlausibleRange(
    100.0, 2.5e4, "kg/m^3", "cork and balsa about 200, osmium 22,600", slips=((1e3, "g/cm^3"),)
)
#: Young's modulus: from soft hydrogel beads (about 10 kPa) and silicone elastomers (0.1-3 MPa) to
#: diamond (1,220 GPa). A modulus in GPa (every solid's is below 1,300) or a polymer's in MPa (PTFE
#: 1,460, nylon 3,000) lands below 1e4 Pa. A metal's in MPa (steel 200,000) is inside: the
#: yield-strain check (MAX_YIELD_STRAIN) catches it when a yield strength is given.
YOUNGS_MODULUS_RANGE = PlausibleRange(
    1e4,
    1.5e12,
    "Pa",
    "hydrogels about 1e4, rubber about 1e6, steel 2e11, diamond 1.2e12",
    slips=((1e9, "GPa"), (1e6, "MPa")),
)
#: Tensile yield strength: from the softest metals (indium and lead, about 1-10 MPa) to hardened
#: steels (about 2-5 GPa) and beyond (diamond's compressive yield, about 100 GPa). A yield strength in
#: MPa (every solid's is below 1e5 MPa) or GPa lands below 1e5 Pa.
YIELD_STRENGTH_RANGE = PlausibleRange(
    1e5,
    1.5e11,
    "Pa",
    "lead about 5e6, annealed steel 3e8, hardened steel 2e9",
    slips=((1e6, "MPa"), (1e9, "GPa")),
)
#: Thornton's limiting contact pressure p_y: about 1.6 to 3 times the yield strength (Johnson,
#: Contact Mechanics, Sec. 6.2), so the yield strength's range times 1.6 to 3.
YIELD_PRESSURE_RANGE = PlausibleRange(
    1.6e5,
    4.5e11,
    "Pa",
    "1.6 to 3 times the yield strength: lead about 1e7, brass about 3e9",
    slips=((1e6, "MPa"), (1e9, "GPa")),
)
#: The largest yield strain sigma_y / E a material may give: the ideal strength of a crystal is about
#: E/10 (Kelly & Macmillan, Strong Solids), real solids yield at 0.1-5 % (hardened steel 1 %,
#: polyethylene 5 %), so a larger ratio means one of the two values is in another unit.
MAX_YIELD_STRAIN = 0.1


def yield_strain_refusal(m: Material) -> str | None:
    """None when m has no yield strength or sigma_y / E <= MAX_YIELD_STRAIN; else why not, with the
    unit slip of youngs_modulus that would explain it."""
    if m.yield_strength is None or m.yield_strength <= MAX_YIELD_STRAIN * m.youngs_modulus:
        return None
    fixes = [
        f"youngs_modulus in {unit}? write {m.youngs_modulus * f:.6g}"
        for f, unit in YOUNGS_MODULUS_RANGE.slips
        if YOUNGS_MODULUS_RANGE.refusal(m.youngs_modulus * f) is None
        and m.yield_strength <= MAX_YIELD_STRAIN * m.youngs_modulus * f
    ]
    return (
        f"yield_strength = {m.yield_strength:g} Pa and youngs_modulus = {m.youngs_modulus:g} Pa give a yield "
        f"strain sigma_y / E = {m.yield_strength / m.youngs_modulus:.3g}, above {MAX_YIELD_STRAIN:g}, the ideal "
        "strength of any solid (real ones yield at 0.1 to 5 %): one of them is in another unit; "
        + ("; ".join(fixes) if fixes else "give both in Pa")
    )


#: A short citation per built-in material (the comments above give the detail).
SOURCES: dict[str, str] = {
    "brass": "Pal & Geubelle, Sec. II A (the paper)",
    "stainless-steel-316": "Daraio et al., PRE 73, 026610 (2006); yield: ASM, annealed",
    "chrome-steel-52100": "Coste, Falcon & Fauve, PRE 56, 6104 (1997); yield: handbook, hardened",
    "aluminium-6061-t6": "Aluminum Association typical (MatWeb/ASM), T6 temper",
    "tungsten-carbide": "rho: CRC Handbook; E, nu: typical for WC beads (unverified)",
    "soda-lime-glass": "Wikipedia soda-lime glass table (container glass); nu typical",
    "ptfe": "Daraio et al., PRE 72, 016603 (2005); PRE 73, 026610 (2006)",
}


def material_table() -> list[tuple[str, Material, str]]:
    """(name, material, source) of every built-in material, in MATERIALS order (for listings)."""
    return [(name, m, SOURCES[name]) for name, m in MATERIALS.items()]


def effective_modulus(m: Material) -> float:
    """E* = E / (2 (1 - nu^2)) for two identical spheres (Sec. II A)."""
    return m.youngs_modulus / (2.0 * (1.0 - m.poisson_ratio**2))


def effective_radius(radius: float) -> float:
    """R* = R / 2 for two identical spheres (Sec. II A)."""
    return radius / 2.0


def bead_mass(m: Material, radius: float) -> float:
    """Mass of a bead of material m and radius R: rho 4/3 pi R^3."""
    return m.density * 4.0 / 3.0 * math.pi * radius**3


def hertz_contact_stiffness(e_star: float, r_star: float) -> float:
    """Hertz constant k = 4 E* sqrt(R*) / 3, so that F = k alpha^(3/2) (Eq. 16; defined after Eq. 14;
    Johnson for any pair)."""
    return 4.0 * e_star * math.sqrt(r_star) / 3.0


def hertz_stiffness(m: Material, radius: float) -> float:
    """Hertz constant k of two identical beads (the paper's chain, Eq. 16)."""
    return hertz_contact_stiffness(effective_modulus(m), effective_radius(radius))


def flat_effective_modulus(m: Material) -> float:
    """E* of a sphere on a rigid flat: E / (1 - nu^2) (the flat's compliance is zero)."""
    return m.youngs_modulus / (1.0 - m.poisson_ratio**2)


#: Thornton's limiting contact pressure from the yield strength, p_y = 1.61 sigma_y: the Hertz peak
#: pressure at which a contact first yields (von Mises, nu = 0.3; Johnson, Contact Mechanics, 1985,
#: Sec. 6.2). Used where a scene gives no yield_pressure: the softer body of each contact sets it.
YIELD_PRESSURE_FACTOR = 1.61


def read_material_table(ms) -> Material:
    """A material given by its values: a [chain.material] or [loading.material] table, an inline
    table in a per-bead [chain] material list, or a [boundary] wall_material table; ms is the scene
    reader's section of it (granchain.scene.section._Section: quantity, number, error, finish)."""
    # each value within the range of real solid beads (*_RANGE): outside it, a unit slip (g/cm^3,
    # GPa, MPa) is the likely cause, and the message says which
    material = Material(
        density=ms.quantity("density", DENSITY_RANGE, what="kg/m^3"),
        youngs_modulus=ms.quantity("youngs_modulus", YOUNGS_MODULUS_RANGE, what="Pa"),
        poisson_ratio=ms.number("poisson_ratio", low=-1.0, high=0.5, what="-1 < nu < 0.5"),
        yield_strength=ms.quantity("yield_strength", YIELD_STRENGTH_RANGE, required=False, what="Pa"),
    )
    why = yield_strain_refusal(material)
    if why:
        raise ms.error(f"[{ms.name}] {why}")
    ms.finish(MATERIAL_KEYS)
    return material


#: The keys of a material table, in the order the scene writer gives them.
MATERIAL_KEYS = ("density", "youngs_modulus", "poisson_ratio", "yield_strength")


def material_values(m: Material) -> dict:
    """A material's table as a scene file writes it: density, youngs_modulus, poisson_ratio, and
    yield_strength where it has one (read_material_table reads it back)."""
    out: dict = {"density": m.density, "youngs_modulus": m.youngs_modulus, "poisson_ratio": m.poisson_ratio}
    if m.yield_strength is not None:
        out["yield_strength"] = m.yield_strength
    return out


def wall_contact_pair(
    bead: Material, radius: float, wall: Material | None, wall_radius: float | None
) -> tuple[float, float, tuple]:
    """E*, R* and the materials of a bead (material, radius) on the far-end wall (Johnson).

    A rigid wall (``wall`` None) has no compliance: E* = E/(1-nu^2) of the bead; a wall of a material
    adds its own, 1/E* = (1-nu_b^2)/E_b + (1-nu_w^2)/E_w. A flat (``wall_radius`` None) has infinite
    radius: R* = R; a curved wall 1/R* = 1/R + 1/R_w. The materials are those a plastic law's mixing
    rule reads (the softer one's yield): the bead's alone on a rigid wall.
    """
    e_star = flat_effective_modulus(bead) if wall is None else pair_effective_modulus(bead, wall)
    r_star = float(radius) if wall_radius is None else pair_effective_radius(float(radius), float(wall_radius))
    return e_star, r_star, (bead,) if wall is None else (bead, wall)


class MissingYieldStrength(GranchainError, ValueError):
    """A plastic law's mixing rule needs the yield strength of a material that has none (the scene
    reader says which key gives it)."""


def softer_yield_strength(materials) -> float:
    """The smaller yield strength of the bodies that touch: the plastic laws' mixing rule (the softer
    material yields first); MissingYieldStrength naming the material that has none."""
    for m in materials:
        if m.yield_strength is None:
            name = next((n for n, x in MATERIALS.items() if x == m), m)
            raise MissingYieldStrength(f"{material_label(name)} has no yield_strength")
    return min(m.yield_strength for m in materials)


def bead_material(entry: str | Material) -> Material:
    """The Material of one entry of a per-bead ``[chain] material`` list: a built-in name's, or the
    entry itself (an inline table, read into a Material)."""
    return MATERIALS[entry] if isinstance(entry, str) else entry


def material_label(entry: str | Material) -> str:
    """How messages and tables name a material: a built-in's name, or an inline table's values."""
    if isinstance(entry, str):
        return entry
    ys = "" if entry.yield_strength is None else f", yield_strength = {entry.yield_strength:g}"
    return (
        f"{{density = {entry.density:g}, youngs_modulus = {entry.youngs_modulus:g}, "
        f"poisson_ratio = {entry.poisson_ratio:g}{ys}}}"
    )


def _beads_text(beads: list[int]) -> str:
    """'bead 2', 'beads 2, 5 and 9', 'beads 2, 5, 9, 11, 14 and 30 more' (1-based bead numbers)."""
    if len(beads) == 1:
        return f"bead {beads[0]}"
    shown = ", ".join(str(b) for b in beads[:5])
    rest = len(beads) - 5
    if rest > 0:
        return f"beads {shown} and {rest} more"
    return f"beads {', '.join(str(b) for b in beads[:-1])} and {beads[-1]}"


def lacking_yield_strength(chain) -> str:
    """What the chain's materials lack for a plastic law: "" when every bead material has a
    yield_strength, else what to add, naming the materials without one and where to give it (the
    plastic laws' mixing rules read it)."""
    if chain.materials is None:
        if chain.material.yield_strength is not None:
            return ""
        return (
            f"a yield_strength (Pa) for {chain.material_name or '[chain.material]'!r}: add yield_strength to a "
            "[chain.material] table, or choose materials that have one (granchain materials)"
        )
    names = sorted({e for e in chain.materials if isinstance(e, str) and MATERIALS[e].yield_strength is None})
    tables = [i for i, e in enumerate(chain.materials, 1) if not isinstance(e, str) and e.yield_strength is None]
    if not names and not tables:
        return ""
    fixes = []
    if names:
        m = MATERIALS[names[0]]
        fixes.append(
            f"in the [chain] material list write each {' and each '.join(repr(n) for n in names)} as an inline "
            f"table of its values with a yield_strength (e.g. {{density = {m.density:g}, youngs_modulus = "
            f"{m.youngs_modulus:g}, poisson_ratio = {m.poisson_ratio:g}, yield_strength = ...}} for "
            f"{names[0]!r}), or choose materials that have one (granchain materials)"
        )
    if tables:
        fixes.append(f"add yield_strength = ... to the inline table of {_beads_text(tables)}")
    what = [repr(n) for n in names] + ([f"the inline table of {_beads_text(tables)}"] if tables else [])
    return f"a yield_strength (Pa) for {', '.join(what)}: {'; '.join(fixes)}"


def plastic_stiffness_from_yield(yield_strength: float, radius: float) -> float:
    """Bilinear plastic loading stiffness k = 18.5 sigma_y R* (Sec. III)."""
    return PLASTIC_STIFFNESS_FACTOR * yield_strength * effective_radius(radius)


def time_scale(m: Material, radius: float) -> float:
    """The chain's intrinsic time scale tau = sqrt(pi rho R*^2 / (4 E*)) (Eq. 7)."""
    rs = effective_radius(radius)
    return math.sqrt(math.pi * m.density * rs**2 / (4.0 * effective_modulus(m)))


def force_scale(m: Material, radius: float) -> float:
    """The force scale E* R*^2 of the nondimensional force F~ = F / (E* R*^2) (Eq. 5)."""
    return effective_modulus(m) * effective_radius(radius) ** 2


def impulse_scale(m: Material, radius: float) -> float:
    """The impulse scale E* R*^2 tau of the nondimensional impulse I~ = I / (E* R*^2 tau) (Eq. 6)."""
    return force_scale(m, radius) * time_scale(m, radius)


def pair_effective_modulus(a: Material, b: Material) -> float:
    """E* of two spheres of different materials: 1/E* = (1-nu_a^2)/E_a + (1-nu_b^2)/E_b (Johnson);
    for identical spheres it is E/(2(1-nu^2)), the paper's E*."""
    return 1.0 / ((1.0 - a.poisson_ratio**2) / a.youngs_modulus + (1.0 - b.poisson_ratio**2) / b.youngs_modulus)


def pair_effective_radius(r1: float, r2: float) -> float:
    """R* = R1 R2 / (R1 + R2); R/2 for identical spheres."""
    return r1 * r2 / (r1 + r2)
