"""Thornton's elastic-perfectly-plastic spheres (Thornton 1997, J. Appl. Mech. 64, 383).

Per contact, with k = 4/3 E* sqrt(R*) the Hertz stiffness of the pair and p_y the limiting contact
pressure (not the tensile yield strength):

    yield overlap  d_y = (pi p_y / (2 E*))^2 R*,   F_y = k d_y^(3/2) = (2/3) pi p_y R* d_y
    virgin curve   F = k d^(3/2) up to d_y, then the plastic line F = F_y + S (d - d_y), S = pi p_y R*
                   (= 3/2 k d_y^(1/2), the Hertz slope at d_y: the slope is continuous at yield)
    unloading and reloading below d_max (the largest overlap so far) once d_max > d_y: Hertz with the
                   enlarged radius R_p = R* (F_y/F_max) ((2 F_max + F_y)/(3 F_y))^(3/2), i.e.
                   k_p = k sqrt(R_p/R*), F = k_p (d - d_p)^(3/2) for d > d_p, else 0, with
                   F_max = F_y + S (d_max - d_y) and d_p = max(d_max - (F_max/k_p)^(2/3), 0) (the max only
                   catches round-off just above d_y, where d_p -> 0); beyond d_max the
                   plastic line again. A contact that never passed d_y stays Hertzian.
    stored energy  (2/5) F (d - d_p) on the unloading curve
    dissipated     the area between the loading path and the unloading curve of d_max:
                   W(d_max) - (2/5) F_max (d_max - d_p), W the work along the virgin curve.

The per-contact parameters are k and d_y (F_y, S, F_max, k_p and d_p follow), so a wall contact
(E* of the flat, R* = R) and a striker follow the same law with their own pair's E* and R*. The C++
twin is granchain/lammps/law_thornton.h.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from typing_extensions import override

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.laws.base import ArrayLike, ContactLaw, Kink, LawCoefficients, TimeScale, forbid_others
from granchain.physics.laws.hertz import HertzLaw, hertz_force, hertz_tangent_stiffness


def yield_overlap(yield_pressure: float, e_star: float, r_star: float) -> float:
    """d_y = (pi p_y / (2 E*))^2 R*: the overlap at which the peak pressure of a Hertz contact,
    2 E* a / (pi R*) with a = sqrt(R* d), reaches p_y (Thornton 1997)."""
    return (math.pi * yield_pressure / (2.0 * e_star)) ** 2 * r_star


def restitution_coefficient(v0: float, vy: float) -> float:
    """Thornton's (1997) coefficient of restitution of an impact at relative velocity v0, yield
    velocity vy (see ThorntonLaw.predictions); 1 at and below vy."""
    if v0 <= vy:
        return 1.0
    r = vy / v0
    return (
        math.sqrt(6.0 * math.sqrt(3.0) / 5.0)
        * math.sqrt(1.0 - r * r / 6.0)
        * (r / (r + 2.0 * math.sqrt(6.0 / 5.0 - r * r / 5.0))) ** 0.25
    )


#: the kinks' kinds (ThorntonLaw.kinks, kink_screens)
_ZERO_FORCE, _RELOADING, _YIELD = "zero force at d_p", "reloading meets d_max", "yield at d_y"
_ZERO = np.array(0.0)
_maximum, _greater, _less, _not_equal = np.maximum, np.greater, np.less, np.not_equal
_subtract, _multiply, _sqrt, _cbrt = np.subtract, np.multiply, np.sqrt, np.cbrt
#: up to this many contacts, the unloading constants are computed on Python floats (_unloading1):
#: numpy calls on a few elements cost more than the arithmetic
_SCALAR_CONTACTS = 16


def _unloading(am: np.ndarray, k: np.ndarray, dy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """ThorntonLaw.unloading with k and d_y given per contact (arrays of am's shape)."""
    plastic = am > dy
    fy = k * dy * np.sqrt(dy)
    ap = np.maximum(am, dy)  # the plastic formulas at d_y where the contact is still elastic
    fmax_p = fy + 1.5 * k * np.sqrt(dy) * (ap - dy)
    # x^(3/2) as x sqrt(x) and y^(2/3) as cbrt(y^2), as the C++ kernel (law_thornton.h)
    x = (2.0 * fmax_p + fy) / (3.0 * fy)
    kp = k * np.sqrt((fy / fmax_p) * (x * np.sqrt(x)))
    y = fmax_p / kp
    dp = np.maximum(ap - np.cbrt(y * y), 0.0)  # >= 0 (round-off just above d_y)
    amc = np.maximum(am, 0.0)
    fmax = np.where(plastic, fmax_p, k * amc * np.sqrt(amc))
    return plastic, fmax, np.where(plastic, kp, k), np.where(plastic, dp, 0.0)


def _unloading1(am: float, k: float, dy: float) -> tuple[float, float]:
    """(k_p, d_p) of one contact: _unloading's operations in the same order on Python floats (the
    same numbers to the bit: IEEE arithmetic and a correctly rounded sqrt either way, and numpy's own
    cbrt)."""
    if not am > dy:  # elastic (nan too, as np.where(plastic, ...))
        return k, 0.0
    fy = k * dy * math.sqrt(dy)
    fmax_p = fy + 1.5 * k * math.sqrt(dy) * (am - dy)  # (ap = max(am, dy) = am)
    x = (2.0 * fmax_p + fy) / (3.0 * fy)
    kp = k * math.sqrt((fy / fmax_p) * (x * math.sqrt(x)))
    y = fmax_p / kp
    d = am - float(_cbrt(y * y))
    return kp, (d if d > 0.0 or d != d else 0.0)  # np.maximum(d, 0.0): nan stays, -0.0 becomes 0.0


class _HistoryConstants:
    """A Thornton law's unloading constants of one history array alpha_max (ThorntonLaw.history_constants).

    Attributes
    ----------
    source : weakref.ref
        The history array they belong to.
    am : ndarray
        The alpha_max they were computed for (a copy).
    raw : bytes
        The history array's bytes when last compared: unchanged bytes, unchanged constants.
    kp, dp : ndarray
        k_p and d_p of unloading(am).
    level : ndarray
        max(am, d_y): a contact whose overlap is above it loads on the plastic line.
    plastic, elastic : ndarray of bool
        am > d_y and am < d_y (where the reloading and the yield kinks apply).
    k, dy : ndarray
        The law's k and d_y, one per contact.
    mask, buf : ndarray
        Work arrays of force_into.
    """

    def __init__(self, law: ThorntonLaw, alpha_max: np.ndarray) -> None:
        shape = alpha_max.shape
        self.source = weakref.ref(alpha_max)
        self.k = np.array(np.broadcast_to(np.asarray(law.k, dtype=float), shape))
        self.dy = np.array(np.broadcast_to(np.asarray(law.yield_overlap, dtype=float), shape))
        self.am = np.array(alpha_max, dtype=float)
        self.raw = alpha_max.tobytes()  # alpha_max's bytes when last compared (refresh)
        self.mask = np.empty(shape, dtype=bool)
        self.buf = np.empty(shape)
        _, _, self.kp, self.dp = (np.array(x) for x in _unloading(self.am, self.k, self.dy))
        self.level = np.maximum(self.am, self.dy)
        self.plastic = self.am > self.dy
        self.elastic = self.am < self.dy

    def refresh(self, alpha_max: np.ndarray) -> None:
        """Recompute the constants of the contacts whose alpha_max changed since."""
        raw = alpha_max.tobytes()  # (one call, where a comparison and its nonzero are two)
        if raw == self.raw:
            return
        self.raw = raw
        changed = _not_equal(alpha_max, self.am, self.mask).nonzero()[0]
        if not changed.size:
            return
        am, dy = alpha_max[changed], self.dy[changed]
        self.am[changed] = am
        if changed.size <= _SCALAR_CONTACTS:
            k = self.k
            for i, x, d in zip(changed.tolist(), am.tolist(), dy.tolist(), strict=True):
                self.kp[i], self.dp[i] = _unloading1(x, k.item(i), d)
        else:
            _, _, self.kp[changed], self.dp[changed] = _unloading(am, self.k[changed], dy)
        self.level[changed] = np.maximum(am, dy)
        self.plastic[changed] = am > dy
        self.elastic[changed] = am < dy

    def forces(self, a: np.ndarray, out: np.ndarray) -> None:
        """ThorntonLaw.force(a, am) into out, from these constants.

        Where a <= max(am, d_y), max(am, a) has the constants of am (on the Hertz curve below d_y they
        are k and 0 whichever it is); beyond, the contact loads on the plastic line, with the
        constants at a itself (loading). a is not clipped at 0: a negative one gives
        max(a - d_p, 0) = +0.0 as 0 does (d_p >= 0).
        """
        loading = _greater(a, self.level, self.mask).nonzero()[0]
        _subtract(a, self.dp, out)
        _maximum(out, _ZERO, out=out)
        _sqrt(out, self.buf)
        _multiply(self.kp, out, out)  # (k_p s) sqrt(s), as force
        _multiply(out, self.buf, out)
        if loading.size:
            self.loading(a, loading, out, False)

    def energies(self, a: np.ndarray) -> np.ndarray:
        """ThorntonLaw.energy(a, am) from these constants (as forces)."""
        loading = (a > self.level).nonzero()[0]
        s = np.maximum(a - self.dp, 0.0)
        out = 0.4 * self.kp * s * s * np.sqrt(s)
        if loading.size:
            self.loading(a, loading, out, True)
        return out

    def loading(self, a: np.ndarray, idx: np.ndarray, out: np.ndarray, energy: bool) -> None:
        """The forces (energy: the stored energies) of contacts idx, loading on the plastic line (a
        above max(am, d_y)), into out: force's (energy's) operations with the constants at a itself."""
        if idx.size <= _SCALAR_CONTACTS:
            k, dy = self.k, self.dy
            for i in idx.tolist():
                x = a.item(i)
                kp, dp = _unloading1(x, k.item(i), dy.item(i))
                s = x - dp
                s = s if s > 0.0 or s != s else 0.0  # np.maximum(s, 0.0)
                out[i] = 0.4 * kp * s * s * math.sqrt(s) if energy else kp * s * math.sqrt(s)
            return
        x = a[idx]
        _, _, kp, dp = _unloading(x, self.k[idx], self.dy[idx])
        s = np.maximum(x - dp, 0.0)
        out[idx] = 0.4 * kp * s * s * np.sqrt(s) if energy else kp * s * np.sqrt(s)


@dataclass(frozen=True)
class ThorntonCoefficients(LawCoefficients):
    """The Thornton law's [contact] values."""

    #: p_y in Pa, Thornton's limiting contact pressure; None: 1.6 sigma_y of the softer bead of each
    #: contact (materials.YIELD_PRESSURE_FACTOR)
    yield_pressure: float | None = None


@dataclass(frozen=True)
class ThorntonLaw(ContactLaw):
    """Thornton's elastic-perfectly-plastic contacts: Hertz stiffness k, yield overlap d_y."""

    name: ClassVar[str] = "thornton"
    pair_style: ClassVar[str] = "chain/thornton"
    history: ClassVar[bool] = True
    # reloading meets the plastic line at d_max with another slope: Verlet's error follows no order
    # there (generated scenes, Richardson: 94 of 125 peaks estimated, one 17x off; against RK4: 172 of
    # 179, 0.97-1.54; docs/error-bars.md)
    slope_kinks: ClassVar[bool] = True
    Coefficients: ClassVar[type[LawCoefficients]] = ThorntonCoefficients
    key_units: ClassVar[dict[str, str]] = {"yield_pressure": "Pa"}
    #: p_y = 1.61 sigma_y of the softer body when the scene gives none (for_pair): on a wall of a
    #: material, as between beads of several
    yield_strength_key: ClassVar[str | None] = "yield_pressure"
    parameter_ranges: ClassVar[dict[str, tuple[float, float]]] = {"k": (1e3, 1e12), "yield_overlap": (1e-9, 1e-4)}
    #: brass beads of R = 4.76 mm: p_y = k / (pi R*) makes the plastic slope S = pi p_y R* equal the
    #: paper's bilinear plastic stiffness k = 2.43e7 N/m (the bilinear example), so the two laws load alike
    example_contact: ClassVar[dict[str, float]] = {"yield_pressure": 3.25e9}
    scene_key_ranges: ClassVar[dict[str, tuple[float, float]]] = {"yield_pressure": (3e8, 1e10)}

    yield_overlap: ArrayLike

    # ---- derived per-contact constants
    @property
    def yield_force(self) -> np.ndarray:
        """F_y = k d_y^(3/2)."""
        dy = np.asarray(self.yield_overlap, dtype=float)
        return np.asarray(self.k) * dy * np.sqrt(dy)

    @override
    def plastic_onset_force(self) -> np.ndarray:
        """F_y: the virgin curve leaves Hertz for the plastic line there."""
        return np.asarray(self.yield_force, dtype=float)

    @property
    def plastic_slope(self) -> np.ndarray:
        """S = 3/2 k d_y^(1/2) = pi p_y R*."""
        return 1.5 * np.asarray(self.k) * np.sqrt(np.asarray(self.yield_overlap, dtype=float))

    def unloading(self, alpha_max: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(plastic, F_max, k_p, d_p) of contacts whose largest overlap is alpha_max: plastic where
        alpha_max > d_y; elsewhere F_max on the Hertz curve, k_p = k and d_p = 0."""
        am = np.asarray(alpha_max, dtype=float)
        k = np.broadcast_to(np.asarray(self.k, dtype=float), am.shape)
        dy = np.broadcast_to(np.asarray(self.yield_overlap, dtype=float), am.shape)
        return _unloading(am, k, dy)

    # ---- the law
    @override
    def force(self, alpha, alpha_max=None):
        c = self._kept(alpha, alpha_max)
        if c is not None:  # the solver's history (its peak tracking, stop check, force samples)
            out = np.empty(alpha.shape)
            c.forces(alpha, out)
            return out
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        am = a if alpha_max is None else np.maximum(alpha_max, a)
        _, _, kp, dp = self.unloading(am)
        s = np.maximum(a - dp, 0.0)
        return kp * s * np.sqrt(s)

    @cached_property
    def _histories(self) -> dict[int, _HistoryConstants]:
        """id(alpha_max) -> the unloading constants of that history array (force_into, kink_screens)."""
        return {}

    def __getstate__(self) -> dict:
        """The fields only: the per-history constants hold weak references to arrays of a run."""
        return {k: v for k, v in self.__dict__.items() if k != "_histories"}

    def history_constants(self, alpha_max: np.ndarray) -> _HistoryConstants:
        """The unloading constants (k_p, d_p, ...) of the history array alpha_max, as they are now.

        They depend on alpha_max alone, which changes once a step and in a few contacts (those that
        loaded further or turned), while the solver evaluates the forces four times a step (RK4) and
        screens the kinks once a piece: kept per history array (weakly: they go with the array) and
        recomputed only for the contacts whose alpha_max differs from the one they were made for.
        The same element-wise operations as unloading, so the same numbers to the bit.
        """
        cache = self._histories
        entry = cache.get(id(alpha_max))
        if entry is None or entry.source() is not alpha_max:
            for key, e in list(cache.items()):  # (a copy and pop: another thread may change it)
                if e.source() is None:
                    cache.pop(key, None)
            entry = cache[id(alpha_max)] = _HistoryConstants(self, alpha_max)
        else:
            entry.refresh(alpha_max)
        return entry

    def _kept(self, alpha, alpha_max) -> _HistoryConstants | None:
        """The kept constants of alpha_max where force_into or kink_screens made them (the solver's
        history array) and alpha is a float array of its shape, else None: a history seen once is
        not worth keeping (unloading, as ever)."""
        if not (
            isinstance(alpha_max, np.ndarray)
            and isinstance(alpha, np.ndarray)
            and alpha.dtype == np.float64
            and alpha.shape == alpha_max.shape
        ):
            return None
        entry = self._histories.get(id(alpha_max))
        if entry is None or entry.source() is not alpha_max:
            return None
        entry.refresh(alpha_max)
        return entry

    @override
    def force_into(self, alpha, alpha_max, out, tmp):
        # force(alpha, alpha_max) with the unloading constants of alpha_max kept (history_constants):
        # where alpha <= max(alpha_max, d_y) max(alpha_max, alpha) has the constants of alpha_max (on
        # the Hertz curve below d_y they are k and 0 whichever it is); beyond, the contact loads on the
        # plastic line, whose constants at alpha itself are computed for those few contacts. alpha is
        # not clipped at 0 again: a negative one gives max(alpha - d_p, 0) = +0.0 as 0 does (d_p >= 0)
        shape = out.shape
        if not (
            isinstance(alpha_max, np.ndarray)
            and alpha_max.shape == shape
            and isinstance(alpha, np.ndarray)
            and alpha.shape == shape
        ):
            out[:] = self.force(alpha, alpha_max)
            return
        self.history_constants(alpha_max).forces(alpha, out)

    @override
    def energy(self, alpha, alpha_max=None):
        c = self._kept(alpha, alpha_max)
        if c is not None:  # the solver's history (the energy ledger's rows)
            return c.energies(alpha)
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        am = a if alpha_max is None else np.maximum(alpha_max, a)
        _, _, kp, dp = self.unloading(am)
        s = np.maximum(a - dp, 0.0)
        return 0.4 * kp * s * s * np.sqrt(s)

    @override
    def dissipated(self, alpha_max):
        am = np.maximum(np.asarray(alpha_max, dtype=float), 0.0)
        plastic, fmax, _, dp = self.unloading(am)
        k = np.asarray(self.k, dtype=float)
        dy = np.asarray(self.yield_overlap, dtype=float)
        fy, s = self.yield_force, self.plastic_slope
        x = np.maximum(am - dy, 0.0)
        work = 0.4 * k * dy * dy * np.sqrt(dy) + fy * x + 0.5 * s * x * x  # along the virgin curve
        return np.where(plastic, work - 0.4 * fmax * (am - dp), 0.0)

    @override
    def loading_exponent(self):
        return np.full(np.shape(self.k), 1.5)  # Hertz up to d_y

    @override
    def loading_force(self, alpha):
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        dy = np.asarray(self.yield_overlap, dtype=float)
        return np.where(a > dy, self.yield_force + self.plastic_slope * (a - dy), hertz_force(a, self.k))

    @override
    def static_overlap(self, force):
        f = np.asarray(force, dtype=float)
        fy = self.yield_force
        hertz = (f / np.asarray(self.k, dtype=float)) ** (2.0 / 3.0)
        return np.where(f > fy, np.asarray(self.yield_overlap) + (f - fy) / self.plastic_slope, hertz)

    @override
    def loading_stiffness(self, force):
        """Hertz's 3/2 k^(2/3) F^(1/3) up to the yield force F_y, the plastic line's S = pi p_y R* above
        (Thornton 1997, J. Appl. Mech. 64, 383: dF/dalpha = pi p_y R* once the contact pressure is p_y):
        a chain precompressed beyond F_y is loaded further along the plastic line, several times softer
        than Hertz's slope at the same force (its linear sound speed lower by sqrt of that)."""
        f = np.maximum(np.asarray(force, dtype=float), 0.0)
        return np.where(f > self.yield_force, self.plastic_slope, hertz_tangent_stiffness(f, self.k))

    @override
    def tangent_stiffness(self, force):
        """Unloading from F_max = force is the stiffest: 3/2 k_p^(2/3) F^(1/3) (the plastic line's S and
        the Hertz slope below it are smaller: R_p >= R*)."""
        f = np.maximum(np.asarray(force, dtype=float), 0.0)
        am = self.static_overlap(f)
        _, _, kp, _ = self.unloading(am)
        return 1.5 * np.cbrt(kp * kp * f)

    @override
    def overlap_tangent(self, alpha, alpha_max=None):
        """The plastic slope S on the virgin plastic line (alpha >= alpha_max > d_y), else the Hertz
        un/reloading curve's 3/2 k_p sqrt(alpha - d_p) (below d_y k_p = k, d_p = 0: Hertz's own)."""
        a = np.maximum(np.asarray(alpha, dtype=float), 0.0)
        am = a if alpha_max is None else np.maximum(alpha_max, a)
        plastic, _, kp, dp = self.unloading(am)
        s = np.maximum(a - dp, 0.0)
        slope = np.broadcast_to(self.plastic_slope, np.shape(am))
        return np.where(plastic & (a >= am) & (a > 0.0), slope, 1.5 * kp * np.sqrt(s))

    @override
    def kinks(self, alpha_max):
        am = np.asarray(alpha_max, dtype=float)
        dy = np.broadcast_to(np.asarray(self.yield_overlap, dtype=float), am.shape)
        _, _, _, dp = self.unloading(am)
        return [
            # the force reaches zero at d_p (0 for an elastic contact): F'' is infinite there
            Kink(dp, _ZERO_FORCE),
            # reloading meets the plastic line again at d_max (slope of the unloading curve -> S)
            Kink(am, _RELOADING, where=am > dy, from_below=True),
            # first yield: Hertz -> the plastic line (F' continuous, F'' jumps)
            Kink(np.array(dy), _YIELD, where=am < dy, from_below=True),
        ]

    @override
    def kink_screens(self, alpha_max, a0, a1):
        # ContactLaw.kink_screens over kinks(alpha_max), the same levels and where, from the kept
        # unloading constants (history_constants) instead of unloading at every piece
        if not (isinstance(alpha_max, np.ndarray) and alpha_max.shape == a0.shape):
            return super().kink_screens(alpha_max, a0, a1)
        c = self.history_constants(alpha_max)
        out = []
        for level, kind, where, from_below in (
            (c.dp, _ZERO_FORCE, None, False),
            (alpha_max, _RELOADING, c.plastic, True),
            (c.dy, _YIELD, c.elastic, True),
        ):
            idx = (_less(a0, level) ^ _less(a1, level)).nonzero()[0]
            if idx.size:
                out.append((Kink(level, kind, where=where, from_below=from_below), level, idx))
        return out

    @override
    def turn_level(self, alpha_max):
        # a turn above d_max and d_y leaves the plastic line for a new unloading curve
        return np.maximum(alpha_max, self.yield_overlap)

    # ---- analytic predictions (granchain.physics.predictions asks every law for its own)
    #: model name -> what it needs: "contact" (the nominal bead pair's closed forms: any chain of uniform
    #: beads) or "collision" (two beads, bead 1 given a velocity, the far end free: a two-body impact)
    model_domains: ClassVar[dict[str, str]] = {
        "yield_force": "contact",
        "yield_overlap": "contact",
        "yield_velocity": "contact",
        "restitution_coefficient": "collision",
    }

    @classmethod
    @override
    def predictions(cls, scene) -> list[dict]:
        """Thornton's (1997) closed forms for the nominal bead pair: F_y, d_y, the impact velocity at
        which the contact first yields, (1/2) m* v_y^2 = (2/5) F_y d_y (the Hertz energy at d_y; m* = m/2
        for two equal beads), and his coefficient of restitution for an impact at v0 > v_y,
            e = sqrt(6 sqrt(3) / 5) sqrt(1 - (v_y/v0)^2 / 6)
                * [ (v_y/v0) / ((v_y/v0) + 2 sqrt(6/5 - (v_y/v0)^2 / 5)) ]^(1/4),
        Thornton 1997, J. Appl. Mech. 64, 383, Eq. 43 as quoted in Thornton and Ning (1998), Powder
        Technol. 99, 154 (e = 1 up to v_y). He derived it with the unloading curve used here but an
        approximate loading stage, so it is a model, not an identity, for our runs."""
        law = scene.law
        fy, dy = float(law.yield_force), float(law.yield_overlap)
        m_star = scene.mass / 2.0
        vy = math.sqrt(2.0 * 0.4 * fy * dy / m_star)
        fs = scene.force_scale
        out = [
            dict(
                name="yield_force",
                value=fy,
                unit="N",
                equation="F_y = 4/3 E* sqrt(R*) d_y^(3/2) (Thornton 1997)",
                valid="the force at which a contact first yields",
                nondim=fy / fs,
            ),
            dict(name="yield_overlap", value=dy, unit="m", equation="d_y = (pi p_y / (2 E*))^2 R*", valid="always"),
            dict(
                name="yield_velocity",
                value=vy,
                unit="m/s",
                equation="(1/2) m* v_y^2 = (2/5) F_y d_y, m* = m/2",
                valid="two equal beads: the relative impact velocity at which their contact first yields",
            ),
        ]
        ld = scene.loading
        if ld.kind == "velocity":
            out.append(
                dict(
                    name="restitution_coefficient",
                    value=restitution_coefficient(ld.velocity, vy),
                    unit="1",
                    equation="Thornton 1997 (e = 1 below v_y)",
                    valid="a two-body impact of equal beads at the relative velocity v0 of bead 1",
                )
            )
        return out

    # ---- scenes
    @classmethod
    @override
    def read_contact(cls, s, chain) -> ThorntonCoefficients:
        forbid_others(s, cls)
        if not s.has("yield_pressure"):
            lacking = mat.lacking_yield_strength(chain)
            if lacking:
                raise s.error(
                    "[contact] law = 'thornton' needs yield_pressure: Thornton's limiting contact pressure p_y "
                    "in Pa, the largest pressure plastic flow lets the contact hold (without it, p_y = "
                    f"{mat.YIELD_PRESSURE_FACTOR} sigma_y of the softer bead of each contact, and {lacking}). "
                    "It is not the tensile yield strength sigma_y: a Hertz contact starts to yield at a peak "
                    f"pressure of about {mat.YIELD_PRESSURE_FACTOR} sigma_y"
                )
            s.finish(("law", *cls.scene_keys))
            return ThorntonCoefficients(yield_pressure=None)
        p_y = s.quantity(
            "yield_pressure",
            mat.YIELD_PRESSURE_RANGE,
            what="Thornton's limiting contact pressure p_y in Pa (not the yield strength)",
        )
        ys = chain.material.yield_strength if chain.materials is None else None
        if ys is not None and chain.material_name is None:  # a built-in's yield gives way, as bilinear's
            raise s.error(
                f"[contact] yield_pressure = {p_y!r} and [chain.material] yield_strength = {ys!r} both set p_y "
                f"(p_y = {mat.YIELD_PRESSURE_FACTOR} sigma_y without yield_pressure); give only one"
            )
        s.finish(("law", *cls.scene_keys))
        return ThorntonCoefficients(yield_pressure=p_y)

    @classmethod
    @override
    def for_pair(cls, coefficients, e_star, r_star, nominal_r_star, materials=()):
        # without a given p_y: the softer body's yield sets it (docs/effects.md, mixing rules)
        p_y = coefficients.yield_pressure
        if p_y is None:
            p_y = mat.YIELD_PRESSURE_FACTOR * mat.softer_yield_strength(materials)
        return cls(k=mat.hertz_contact_stiffness(e_star, r_star), yield_overlap=yield_overlap(p_y, e_star, r_star))

    @classmethod
    @override
    def unsupported(cls, chain) -> str | None:
        return None

    # ---- the planner's estimates: the virgin curve is Hertz up to F_y and softer beyond, and the
    # contacts dissipate, so Hertz's estimates bound the force from above
    @classmethod
    def expected_peak_force(cls, scene, impulse: float, step) -> float:
        """The Hertz law's estimate (Eq. 8, capped by Eq. 15's wave for steps, x1.5): Thornton's virgin curve
        is Hertz up to F_y and softer beyond, and its contacts dissipate, so it bounds the force from above."""
        return HertzLaw.expected_peak_force(scene, impulse, step)

    @classmethod
    @override
    def loading_time_scale(cls, scene, amplitude: float, duration: float) -> TimeScale:
        """Hertz's crossover time T_c: the virgin curve starts Hertzian (k d^(3/2) up to d_y)."""
        return HertzLaw.loading_time_scale(scene, amplitude, duration)

    @classmethod
    def wave_speeds(cls, scene, expected_force: float, step) -> tuple[float, float]:
        """Hertz's solitary-wave speeds, widened: a plastic front is slower (plan with 0.6 D sqrt(S/m), S
        the plastic slope, like the bilinear law's 0.6 c) and unloading is faster (D sqrt(k_t/m) at the
        stiffest unloading tangent)."""
        slow, fast = HertzLaw.wave_speeds(scene, expected_force, step)
        law, m, d = scene.law, scene.mass, scene.diameter
        if float(expected_force) > float(law.yield_force):
            slow = min(slow, 0.6 * models.linear_sound_speed(float(law.plastic_slope), m, d))
            fast = max(fast, models.linear_sound_speed(float(law.tangent_stiffness(expected_force)), m, d))
        return slow, fast
