"""Power-law contacts: F = K alpha^n, stored energy K alpha^(n+1) / (n+1), no history.

``[contact] law = "power"`` with ``exponent = n`` (1 <= n <= 3) and ``stiffness = K`` (N/m^n): a
contact of any elastic exponent (n = 1 a linear spring that opens, n = 3/2 Hertz, n > 3/2 conical or
rough contacts; interfaces and disorder in n: Kekic and Van Gorder, Physica D 2018). K and n are the
scene's, not derived from the bodies' E* and R*: each one number for every contact or a list of one
per bead-bead contact (PER_CONTACT_RULE: the striker's contact takes contact 1's, the wall's the last
contact's; docs/laws.md). The law's model is the elastic two-body impact (power_impact). The C++
twin is granchain/lammps/law_power.h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from typing_extensions import override

from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink, LawCoefficients, forbid_others, two_bodies

#: the exponents the law takes (1: a linear spring; 3: the stiffest the planner's estimates are made for)
EXPONENT_RANGE = (1.0, 3.0)


def power_impact(k: float, n: float, reduced_mass: float, velocity: float) -> dict[str, float]:
    """Two elastic bodies meeting at relative velocity v under F = K delta^n, m* their reduced mass (a
    wall: the bead's mass). Energy gives delta_max = ((n+1) m* v^2 / (2K))^(1/(n+1)), the peak force
    K delta_max^n; the contact time is 2 (delta_max / v) sqrt(pi) Gamma(1 + 1/(n+1)) / Gamma(1/2 +
    1/(n+1)) (the quarter period of m* delta'' = -K delta^n, doubled: 2.9432 delta_max / v at n = 3/2,
    Johnson 1985 Sec. 11.1; pi delta_max / v at n = 1, half a period of the spring)."""
    q = 1.0 / (n + 1.0)
    delta = ((n + 1.0) * reduced_mass * velocity**2 / (2.0 * k)) ** q
    factor = 2.0 * math.sqrt(math.pi) * math.gamma(1.0 + q) / math.gamma(0.5 + q)
    return {"peak_force": k * delta**n, "duration": factor * delta / velocity, "max_overlap": delta}


@dataclass(frozen=True)
class PowerCoefficients(LawCoefficients):
    """The power law's [contact] values: its exponent n and stiffness K (N/m^n), each one number or a
    tuple of one per bead-bead contact (contact 1 between beads 1 and 2 first)."""

    exponent: float | tuple[float, ...]
    stiffness: float | tuple[float, ...]

    @property
    @override
    def varies(self) -> bool:
        return isinstance(self.exponent, tuple) or isinstance(self.stiffness, tuple)

    @override
    def of_contact(self, i: int) -> PowerCoefficients:
        def pick(v):
            return v[i] if isinstance(v, tuple) else v

        return PowerCoefficients(exponent=pick(self.exponent), stiffness=pick(self.stiffness))


@dataclass(frozen=True)
class PowerLaw(ContactLaw):
    """Elastic power-law contacts F = k alpha^n; k (N/m^n) and n each one value or one per contact."""

    name: ClassVar[str] = "power"
    pair_style: ClassVar[str] = "chain/power"
    history: ClassVar[bool] = False
    Coefficients: ClassVar[type[LawCoefficients]] = PowerCoefficients
    key_units: ClassVar[dict[str, str]] = {"exponent": "1", "stiffness": "N/m^n"}
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12), "exponent": EXPONENT_RANGE}
    #: brass beads of R = 4.76 mm: Hertz's own K and n (k = 4/3 E* sqrt(R*))
    example_contact: ClassVar[dict[str, float]] = {"exponent": 1.5, "stiffness": 4.11e9}
    #: (independent draws: K and n that keep a brass-like chain's overlaps small for any n of the range)
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {"exponent": (1.3, 1.8), "stiffness": (1e10, 1e11)}
    label: ClassVar[str] = "power-law"
    model_domains: ClassVar[dict[str, str]] = {
        **dict.fromkeys(("power_pair_impact_peak_force", "power_pair_impact_duration"), "pair_impact"),
        **dict.fromkeys(("power_striker_impact_peak_force", "power_striker_impact_duration"), "striker_impact"),
        **dict.fromkeys(("power_wall_impact_peak_force", "power_wall_impact_duration"), "wall_impact"),
        # Nesterenko's V ~ F^((n-1)/(2n)) on a uniform uncompressed chain, at a force (WAVE_SPEED_DOMAIN)
        **dict.fromkeys(("power_wave_speed", "power_wave_speed_at_impact"), "any"),
    }
    compare_models: ClassVar[dict[str, tuple[tuple[str, str], ...]]] = {
        "leading_peak_force": (("power_pair_impact_peak_force", "power-law impact (two beads)"),),
        "striker_peak_force": (("power_striker_impact_peak_force", "power-law impact (two bodies)"),),
        "wall_peak_force": (("power_wall_impact_peak_force", "power-law impact (bead on the flat)"),),
        "wave_speed": (("power_wave_speed", "Nesterenko's V(F) on F = K alpha^n at the reference's leading peak"),),
    }

    exponent: ArrayLike = 1.5

    @cached_property
    def _operands(self) -> tuple[np.ndarray, np.ndarray]:
        """k and n as arrays (0-d for scalars), the inner loop's operands."""
        return np.array(self.k, dtype=float), np.array(self.exponent, dtype=float)

    @override
    def loading_exponent(self):
        return np.asarray(self.exponent, dtype=float)

    @cached_property
    def _halves(self) -> tuple[np.ndarray, np.ndarray]:
        """(m, h) with n = m + h/2 where n is whole or half-whole (m = -1 elsewhere), as integer arrays
        (0-d for a scalar n): the C++ kernel's derive() d[4], d[5]."""
        n = np.array(self.exponent, dtype=float)
        twice = 2.0 * n
        halves = twice == np.floor(twice)
        m = np.where(halves, np.floor(n), -1.0)
        h = np.where(halves, twice - 2.0 * np.floor(n), 0.0)
        return m.astype(int), h.astype(int)

    def power(self, alpha: ArrayLike) -> np.ndarray:
        """alpha^n at overlaps alpha >= 0 in the C++ kernel's arithmetic (LawPower::power): where n = m +
        h/2 is whole or half-whole, (sqrt(alpha) or 1) times (1, alpha, alpha^2 or alpha^2 alpha); pow
        (np.power) for any other n. Both backends then round alike (1, 3/2, 2, 5/2 and 3 need no pow:
        a contact in force costs a pow's time otherwise, benchmarks/RESULTS.md, 2026-12-03)."""
        a = np.asarray(alpha, dtype=float)
        m, h = self._halves
        out = np.empty(np.broadcast_shapes(a.shape, m.shape))
        self._power_into(a, out, np.empty_like(out))
        return out

    def _power_into(self, a: np.ndarray, out: np.ndarray, tmp: np.ndarray) -> None:
        """power(a) into out (tmp: scratch of its shape)."""
        _, n = self._operands
        m, h = self._halves
        if m.ndim:  # one exponent per contact: each contact's products, pow where n is neither
            a2 = a * a
            out[...] = np.choose(np.maximum(m, 0), (1.0, a, a2, a2 * a))
            out *= np.where(h > 0, np.sqrt(a), 1.0)
            if np.any(m < 0):
                out[...] = np.where(m < 0, np.power(a, n), out)
            return
        if m < 0:
            np.power(a, n, out=out)
            return
        if m == 0:
            out.fill(1.0)
        elif m == 1:
            out[...] = a
        else:
            np.multiply(a, a, out=out)
            if m == 3:
                np.multiply(out, a, out=out)
        if h:
            np.sqrt(a, out=tmp)
            np.multiply(tmp, out, out=out)

    @override
    def force(self, alpha, alpha_max=None):
        k, _ = self._operands
        return k * self.power(np.maximum(alpha, 0.0))

    @override
    def force_into(self, alpha, alpha_max, out, tmp):
        k, _ = self._operands
        self._power_into(alpha, out, tmp)
        np.multiply(out, k, out=out)

    @override
    def energy(self, alpha, alpha_max=None):
        k, n = self._operands
        return k / (n + 1.0) * np.maximum(alpha, 0.0) ** (n + 1.0)  # (the C++ kernel's order)

    @override
    def loading_force(self, alpha):
        return self.force(alpha)

    @override
    def static_overlap(self, force):
        k, n = self._operands
        return (np.asarray(force, dtype=float) / k) ** (1.0 / n)

    @override
    def tangent_stiffness(self, force):
        # dF/dalpha = n k alpha^(n-1) = n k^(1/n) F^((n-1)/n)
        k, n = self._operands
        return n * k ** (1.0 / n) * np.maximum(np.asarray(force, dtype=float), 0.0) ** ((n - 1.0) / n)

    @override
    def loading_stiffness(self, force):
        return self.tangent_stiffness(force)

    @override
    def overlap_tangent(self, alpha, alpha_max=None):
        # n k alpha^(n-1) (the C++ kernel's order); apart 0, also where n = 1
        k, n = self._operands
        a = np.asarray(alpha, dtype=float)
        return np.where(a > 0.0, n * k * np.maximum(a, 0.0) ** (n - 1.0), 0.0)

    @override
    def damping_tangent(self, alpha, alpha_max, force):
        # n F / alpha from the force there, as the C++ kernel's tangent (no second pow); apart 0
        _, n = self._operands
        a = np.asarray(alpha, dtype=float)
        nf = n * np.asarray(force, dtype=float)
        out = np.zeros(np.broadcast_shapes(a.shape, nf.shape))
        np.divide(nf, a, out=out, where=a > 0.0)
        return out

    @override
    def kinks(self, alpha_max):
        # a derivative of F jumps (or is infinite) at zero overlap unless n is an integer: open or close
        return [Kink(np.zeros(np.shape(alpha_max)), "zero overlap")]

    # ---- scenes
    @classmethod
    @override
    def read_contact(cls, s, chain) -> PowerCoefficients:
        low, high = EXPONENT_RANGE
        forbid_others(s, cls)
        n = _number_or_list(s, chain, "exponent", dict(low=low, low_open=False, high=high, high_open=False), "n")
        k = _number_or_list(
            s, chain, "stiffness", dict(low=0.0, high=1e30), "K in N/m^n (up to 1e30: n = 3 takes ~1e19)"
        )
        s.finish(("law", *cls.scene_keys))
        return PowerCoefficients(exponent=n, stiffness=k)

    @classmethod
    @override
    def contact_to_dict(cls, contact) -> dict:
        values = {k: getattr(contact.coefficients, k) for k in cls.scene_keys}
        return {"law": cls.name, **{k: list(v) if isinstance(v, tuple) else v for k, v in values.items()}}

    @classmethod
    @override
    def for_pair(cls, coefficients, e_star, r_star, nominal_r_star, materials=()):
        return cls(k=float(coefficients.stiffness), exponent=float(coefficients.exponent))

    # ---- the planner's estimates: the two-body impact of bead 1 on bead 2 at the load's momentum
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """The impact of bead 1, given the load's momentum, on bead 2 (m* = m/2): the first contact
        carries at most about that; a long load cannot push it much past 2 A; x1.5 margin."""
        law = scene.law
        f = power_impact(float(law.k), float(law.exponent), scene.mass / 2.0, impulse / scene.mass)["peak_force"]
        if step is not None:
            f = min(f, 2.0 * step[0])
        return 1.5 * f

    @classmethod
    @override
    def two_body_contact_time(cls, scene, amplitude: float) -> tuple[float, str]:
        """t_c: the two-body contact time (power_impact, m* = m/2) at the bead speed behind a long load's
        front, v = D A / (m c) (Eq. 12) with c the front speed of Eq. 19 on this law
        (models.power_front_speed). It depends on v unless n = 1, where it is the loading line's pi
        sqrt(m/2k). With per-contact n the smallest over the contacts: the shortest contact time is the
        first a load outlasts (long sooner)."""
        laws = scene.contact_laws if scene.contact.coefficients.varies else [scene.law]
        m, d = scene.mass, scene.diameter
        times = []
        for law in laws:
            k, n = float(law.k), float(np.max(law.loading_exponent()))
            v = d * amplitude / (m * models.power_front_speed(amplitude, k, n, m, d))
            times.append(power_impact(k, n, m / 2.0, v)["duration"])
        how = "two beads' F = K alpha^n impact at the front's bead speed v = D A / (m c), c of Eq. 19"
        return min(times), how

    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """(slowest, fastest) wave speeds, m/s: the linearised chain's D sqrt(k_t/m) at the expected force
        bounds every wave from above; a decayed front at a hundredth of it, halved, from below."""
        law, m, d = scene.law, scene.mass, scene.diameter
        fast = models.linear_sound_speed(float(law.tangent_stiffness(expected_force)), m, d)
        slow = 0.5 * models.linear_sound_speed(float(law.tangent_stiffness(0.01 * expected_force)), m, d)
        return min(slow, fast), fast

    # ---- the law's models (ContactLaw rule 8)
    @classmethod
    @override
    def predictions(cls, scene) -> list[dict]:
        """The elastic two-body impact (power_impact) of the scene's two bodies, where it is one, and
        Nesterenko's wave speed at the first contact's two-body peak of a kicked chain (_wave_speed)."""
        hit = two_bodies(scene)
        if hit is None:
            return _wave_speed(scene)
        name, law, m_star, words = hit
        out = power_impact(float(law.k), float(law.exponent), m_star, scene.loading.velocity)
        valid = f"a two-body impact of {words}, power-law contact, no dashpot or precompression"
        return [
            dict(
                name=f"power_{name}_peak_force",
                value=out["peak_force"],
                unit="N",
                equation="K delta_max^n, delta_max = ((n+1) m* v^2 / (2K))^(1/(n+1))",
                valid=valid,
                nondim=out["peak_force"] / scene.force_scale,
            ),
            dict(
                name=f"power_{name}_duration",
                value=out["duration"],
                unit="s",
                equation="2 (delta_max / v) sqrt(pi) Gamma(1 + 1/(n+1)) / Gamma(1/2 + 1/(n+1))",
                valid=valid,
            ),
        ]

    @classmethod
    @override
    def measured_models(cls, scene, values, observables):
        """Nesterenko's wave speed (models.power_solitary_wave_speed) at the run's leading peak."""
        f = observables.get("leading_peak_force")
        if not f:
            return {}
        law = scene.law
        n = float(law.exponent)
        return {"power_wave_speed": models.power_solitary_wave_speed(f, float(law.k), n, scene.mass, scene.diameter)}


#: where Nesterenko's wave speed on F = K alpha^n holds, in words (predict's "valid")
WAVE_SPEED_DOMAIN = (
    "a solitary wave on a uniform uncompressed chain, n > 1 (V ~ F^((n-1)/(2n)), the constant the long-wave "
    "approximation's); at n = 1 the chain is linear: no solitary wave, the front moves at the sound speed "
    "D sqrt(K/m), which the formula gives there"
)


def _wave_speed(scene) -> list[dict]:
    """Nesterenko's speed at the force of the first contact's two-body impact (bead 1 on bead 2 at the
    load's velocity, an impulse's I / m: its zero-duration limit; an estimate: the formed wave's force
    is lower, and `compare` takes the measured leading peak's, measured_models) on a chain of three
    beads or more given a velocity or an impulse."""
    if scene.loading.kind not in ("velocity", "impulse") or scene.chain.beads is not None and scene.chain.beads < 3:
        return []
    law, m = scene.law, scene.mass
    k, n = float(law.k), float(law.exponent)
    f = power_impact(k, n, m / 2.0, scene.input_impulse / m)["peak_force"]
    equation = "sqrt(2/(n+1)) D K^(1/(2n)) F^((n-1)/(2n)) / sqrt(m), F the two-body impact's peak at v = I / m"
    if n == 1.0:
        equation = "D sqrt(K/m): n = 1, a linear chain's sound speed (no solitary wave)"
    value = models.power_solitary_wave_speed(f, k, n, m, scene.diameter)
    return [
        dict(name="power_wave_speed_at_impact", value=value, unit="m/s", equation=equation, valid=WAVE_SPEED_DOMAIN)
    ]


#: what the per-contact lists mean, for their messages and docs/laws.md
PER_CONTACT_RULE = (
    "one value per bead-bead contact, contact 1 (beads 1 and 2) first; a striker's contact takes contact 1's "
    "value, a wall's contact (bead N on the wall) the last contact's"
)


def _number_or_list(s, chain, key: str, bounds: dict, what: str) -> float | tuple[float, ...]:
    """[contact] `key`: a number, or a list of one number per bead-bead contact (PER_CONTACT_RULE),
    each inside `bounds` (Section.number's); a list of one value throughout is that number."""
    what = f"{what} of F = K alpha^n, or a list of {PER_CONTACT_RULE}"
    v = s.table.get(key)
    if not isinstance(v, list):
        return s.number(key, **bounds, what=what)
    s.raw(key)  # (read)
    contacts = None if chain.beads is None else chain.beads - 1
    if not contacts:
        need = 'a given [chain] beads = N (not "auto")' if contacts is None else "a chain of two beads or more"
        raise s.fail(key, v, f"a number: a list ({PER_CONTACT_RULE}) needs {need}")
    if len(v) != contacts:
        raise s.fail(key, v, f"a list of {contacts} values for the {chain.beads} beads' {contacts} contacts ({what})")
    one = type(s)(s.file, s.name, {})
    values = []
    for i, x in enumerate(v):
        one.table = {f"{key}[{i + 1}]": x}
        values.append(one.number(f"{key}[{i + 1}]", **bounds, what=what))
    return values[0] if len(set(values)) == 1 else tuple(values)
