"""The paper's analytic models, one function per equation (all SI).

Where the printed paper and a careful derivation disagree, the derivation is implemented and
the disagreement is stated in the docstring (and in docs/paper-discrepancies.md). No constant
here was tuned to reproduce a printed number.

Notation: m bead mass, D = 2R bead diameter, k contact stiffness (Hertz: F = k alpha^1.5,
bilinear: plastic loading slope), k_u = k/(1-beta) the unloading slope, A load amplitude,
T load duration, I = A T impulse.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Eq. 8's constant, fitted by the paper's authors from numerical experiments.
EQ8_CONSTANT = 0.719

#: Appendix constants for a linear spring chain (mass m, stiffness k) hit by an impulse I,
#: fitted by the authors: v_m = A1 I/m, F_p = A2 sqrt(k/m) I, F_2 = A3 sqrt(k/m) I,
#: v_t = v_m - A4 sqrt(1-beta) I/m.
APPENDIX_A1 = 0.482
APPENDIX_A2 = 0.721
APPENDIX_A3 = 0.199
APPENDIX_A4 = 0.599


# ---------------------------------------------------------------- elastic chains (Sec. II)


def short_load_peak_force(impulse: float, mass: float, e_star: float, r_star: float) -> float:
    """Eq. 8: peak force of the solitary wave formed by a short load of impulse I.

    F_p = 0.719 (E*^2 R* I^6 / m^3)^(1/5), the same as an initial velocity v_0 = I/m given to
    bead 1 (the zero-duration limit). Valid when the load is shorter than the solitary wave's own
    contact time (single-solitary-wave regime, Fig. 1), and far enough down the chain for the
    wave to have formed.
    """
    return EQ8_CONSTANT * (e_star**2 * r_star * impulse**6 / mass**3) ** 0.2


def constant_regime_bead_velocity(amplitude: float, front_speed: float, mass: float, diameter: float) -> float:
    """Eq. 12: m v = 2 R A / c, velocity of the beads behind the front of a long load."""
    return diameter * amplitude / (mass * front_speed)


def front_speed_upper(amplitude: float, k: float, mass: float, diameter: float) -> float:
    """Eq. 15: c^u = sqrt(10 A^(1/3) k^(2/3) D^2 / (9 m)), upper bound of the long-load front speed."""
    return math.sqrt(10.0 * amplitude ** (1 / 3) * k ** (2 / 3) * diameter**2 / (9.0 * mass))


def front_speed_lower(amplitude: float, k: float, mass: float, diameter: float) -> float:
    """Eq. 19: c^l = sqrt(A^(1/3) k^(2/3) D^2 / m), lower bound of the long-load front speed.

    With the paper's brass beads and A = 40 N this gives 455.3 m/s (and Eq. 15 gives 479.9 m/s);
    the paper prints 668.0 and 704.0 m/s, which do not follow from its own Eqs. 15 and 19 with the
    parameters of Sec. II A. Its printed forces (78.15 N and 107.2 N) do follow from ours through
    Nesterenko's relation below.
    """
    return math.sqrt(amplitude ** (1 / 3) * k ** (2 / 3) * diameter**2 / mass)


#: Nesterenko's long-wavelength solitary wave: V_s = (2/sqrt(5)) c_0 xi_m^(1/4), with
#: c_0^2 = (k/m) D^(5/2) the chain's sound-speed parameter and xi_m = alpha_m / D the peak strain
#: (Nesterenko 1983, ref. 9; Nesterenko 2001, ref. 3, Ch. 1). With F = k alpha^(3/2) it reads
#: V_s = (2/sqrt(5)) D k^(1/3) F_m^(1/6) / sqrt(m).
NESTERENKO_SPEED_CONSTANT = 2.0 / math.sqrt(5.0)


def solitary_wave_speed(peak_force: float, k: float, mass: float, diameter: float) -> float:
    """Nesterenko's relation (ref. 9), speed of a solitary wave of peak force F_m.

    The long-wavelength approximation; the discrete chain's constant differs slightly (our
    reference solver measures it: see the tests).
    """
    return NESTERENKO_SPEED_CONSTANT * diameter * k ** (1 / 3) * peak_force ** (1 / 6) / math.sqrt(mass)


def power_solitary_wave_speed(peak_force: float, k: float, exponent: float, mass: float, diameter: float) -> float:
    """Nesterenko's solitary wave on an uncompressed chain of F = k alpha^n (n > 1; Nesterenko 2001,
    Sec. 1.2): V_s = sqrt(2/(n+1)) D k^(1/(2n)) F_m^((n-1)/(2n)) / sqrt(m), the long-wavelength
    approximation (its largest overlap alpha_m = (F_m/k)^(1/n): V_s^2 = 2/(n+1) D^2 (k/m) alpha_m^(n-1);
    Hertz's 2/sqrt(5) at n = 3/2). The scaling V ~ F^((n-1)/(2n)) holds for the discrete chain
    exactly (the equations of motion scale), the constant approximately. At n = 1 the chain is linear:
    no solitary wave, and the speed is the sound speed D sqrt(k/m), which the formula gives there
    (the exponent of F is 0, nothing divides by n - 1)."""
    n = float(exponent)
    return (
        math.sqrt(2.0 / (n + 1.0)) * diameter * k ** (0.5 / n) * peak_force ** ((n - 1.0) / (2.0 * n)) / math.sqrt(mass)
    )


def solitary_wave_peak_force(speed: float, k: float, mass: float, diameter: float) -> float:
    """Inverse of :func:`solitary_wave_speed`: F_m = m^3 V_s^6 / ((2/sqrt5)^6 D^6 k^2)."""
    return mass**3 * speed**6 / (NESTERENKO_SPEED_CONSTANT**6 * diameter**6 * k**2)


# ---------------------------------------------------------- elastoplastic chains (Sec. III)


def linear_chain_impulse_response(impulse: float, k: float, mass: float, beta: float = 0.0) -> dict[str, float]:
    """Appendix Eqs. A1-A4 for a linear chain hit by an impulse I.

    v_m: velocity of beads 1 and 2 when contact 1 reaches its peak (A1);
    F_p: peak force of contact 1 (A2); F_2: force of contact 2 at that instant (A3);
    v_t: trailing (residual) velocity of bead 1 after contact 1 unloads with coefficient beta (A4).
    """
    s = math.sqrt(k / mass) * impulse
    return {
        "v_m": APPENDIX_A1 * impulse / mass,
        "F_p": APPENDIX_A2 * s,
        "F_2": APPENDIX_A3 * s,
        "v_t": (APPENDIX_A1 - APPENDIX_A4 * math.sqrt(1.0 - beta)) * impulse / mass,
    }


@dataclass(frozen=True)
class LeadingWaveCoefficients:
    """Eq. 22: F_a = eta F, v_m = gamma F, v_r = omega F, from the Appendix relations A1-A4."""

    gamma: float  # (m/s)/N
    eta: float  # -
    omega: float  # (m/s)/N


def leading_wave_coefficients(k: float, mass: float, beta: float) -> LeadingWaveCoefficients:
    """gamma, eta, omega of Eq. 22, eliminating I between A1-A4 and A2."""
    r = linear_chain_impulse_response(1.0, k, mass, beta)
    return LeadingWaveCoefficients(gamma=r["v_m"] / r["F_p"], eta=r["F_2"] / r["F_p"], omega=r["v_t"] / r["F_p"])


def exponential_decay_rate(k: float, mass: float, beta: float) -> float:
    """Decay per contact, lambda, of the leading peak force in the exponential regime (Eqs. 25-27).

    F_{i+1} = F_i exp(-lambda). Solving Eq. 26 as a quadratic in D dF/dx gives
    D dF/dx = F (-1 + sqrt(1 - C/B)), with C = 1/k - 1/k_u + m omega^2 and
    B = (1 + eta^2)/k + 2 m gamma^2, so lambda = 1 - sqrt(1 - C/B). The printed Eq. 27 has the
    product D C B under the root (not dimensionless) and no prefactor F_1; we use the ratio,
    which is what Eq. 26 gives.
    """
    ku = k / (1.0 - beta)
    c = leading_wave_coefficients(k, mass, beta)
    big_c = 1.0 / k - 1.0 / ku + mass * c.omega**2
    big_b = (1.0 + c.eta**2) / k + 2.0 * mass * c.gamma**2
    return 1.0 - math.sqrt(1.0 - big_c / big_b)


def collision_peak_force(relative_velocity: float, k_u: float, mass: float) -> float:
    """Eq. 29: F_s = sqrt(k_u m / 2) dv, peak force of two equal beads colliding on the reloading line."""
    return math.sqrt(k_u * mass / 2.0) * relative_velocity


def secondary_wave_peak_force(delta_peak_force: float, k_u: float, mass: float, omega: float) -> float:
    """Eq. 30: secondary-wave peak force at contact i+1, dF^i = F_1 - F_{i+1} (leading peaks).

    The residual velocities are v = omega F (Eq. 22), so the colliding beads' relative velocity is
    omega dF. The paper prints dF/omega, which is not a force; we use omega dF.
    """
    return collision_peak_force(abs(omega) * delta_peak_force, k_u, mass)


def inverse_decay_exponent(beta: float) -> float:
    """Eq. 34: F = (a/x)^((1+beta)/2) in the second (inverse) decay regime."""
    return (1.0 + beta) / 2.0


def leading_peaks_exponential(first_peak: float, decay: float, n: int):
    """Leading peak force at contacts 1..n in the exponential regime (Eq. 27)."""
    return [first_peak * math.exp(-decay * i) for i in range(n)]


def transition_contact(
    first_peak: float, decay: float, k_u: float, mass: float, omega: float, n_contacts: int
) -> int | None:
    """First contact (1-based) where Eq. 30's secondary peak exceeds Eq. 27's leading peak."""
    lead = leading_peaks_exponential(first_peak, decay, n_contacts)
    for i in range(1, n_contacts):
        fs = secondary_wave_peak_force(lead[0] - lead[i], k_u, mass, omega)
        if fs > lead[i]:
            return i + 1
    return None


#: Hertz impact: the contact lasts HERTZ_IMPACT_DURATION delta_max / v (Johnson, Contact Mechanics,
#: 1985, Sec. 11.1: t = 2.94 delta_max / v, the integral 2 int_0^1 dx / sqrt(1 - x^(5/2)))
HERTZ_IMPACT_DURATION = 2.9432


def hertz_impact(k: float, reduced_mass: float, velocity: float) -> dict[str, float]:
    """Two elastic bodies meeting at relative velocity v (a striker on bead 1, a bead on a wall): F =
    k delta^(3/2), m* the reduced mass (a wall: the bead's mass). The largest overlap delta_max =
    (5 m* v^2 / (4 k))^(2/5), peak force F = k delta_max^(3/2) = k^(2/5) (5/4 m* v^2)^(3/5) and
    contact duration 2.943 delta_max / v (Johnson 1985, Sec. 11.1)."""
    delta = (5.0 * reduced_mass * velocity**2 / (4.0 * k)) ** 0.4
    return {"peak_force": k * delta**1.5, "duration": HERTZ_IMPACT_DURATION * delta / velocity, "max_overlap": delta}


def two_body_impact(law, reduced_mass: float, velocity: float) -> dict[str, float]:
    """The same impact under any contact law (its loading, plastic and unloading branches), integrated:
    velocity Verlet on m* delta'' = -F(delta, delta_max) from delta = 0 at v until the bodies part, at
    about 2000 steps per contact. Returns peak_force, duration, max_overlap and the rebound velocity."""
    k = float(np.max(np.asarray(law.k, dtype=float)))
    guess = max(k**0.4 * (1.25 * reduced_mass * velocity**2) ** 0.6, velocity * math.sqrt(k * reduced_mass))
    stiff = float(np.max(np.asarray(law.max_stiffness(2.0 * guess), dtype=float)))
    dt = 2e-3 * math.sqrt(reduced_mass / stiff)
    x, v, xmax, t, fpeak = 0.0, velocity, 0.0, 0.0, 0.0
    f = 0.0
    for _ in range(2_000_000):
        v -= 0.5 * dt * f / reduced_mass
        x += dt * v
        t += dt
        if x <= 0.0 and v < 0.0:
            break
        xmax = max(xmax, x)
        f = float(law.force(np.array([x]), np.array([xmax]))[0])
        fpeak = max(fpeak, f)
        v -= 0.5 * dt * f / reduced_mass
    return {"peak_force": fpeak, "duration": t, "max_overlap": xmax, "rebound_velocity": -v}


def precompressed_sound_speed(k: float, static_force: float, mass: float, spacing: float) -> float:
    """c0 = a sqrt(k_lin / m), k_lin = 3/2 k^(2/3) F0^(1/3): the long-wave sound speed of a Hertz chain
    linearised about the static force F0, a the distance between neighbouring centres (Nesterenko,
    Dynamics of Heterogeneous Materials, 2001, Sec. 1.1; Daraio et al., PRE 72, 016603, 2005, Eq. 1)."""
    k_lin = 1.5 * k ** (2.0 / 3.0) * static_force ** (1.0 / 3.0)
    return spacing * math.sqrt(k_lin / mass)


def precompressed_solitary_wave_speed(c0: float, force_ratio: float) -> float:
    """V_s = c0 / (f_r^(2/3) - 1) sqrt(4/15 (3 + 2 f_r^(5/3) - 5 f_r^(2/3))): the solitary wave of a
    precompressed Hertz chain, f_r = F_m / F0 the ratio of its largest contact force (static force
    included) to F0; c0 as f_r -> 1 (Nesterenko 2001, Sec. 1.3; Daraio et al., PRE 72, 016603, Eq. 2).

    Evaluated without cancellation: with u = f_r^(1/3), 3 + 2 u^5 - 5 u^2 = (u - 1)^2 (2 u^3 + 4 u^2 +
    6 u + 3) and f_r^(2/3) - 1 = (u - 1)(u + 1), so V_s = c0 sqrt(4/15 (2 u^3 + 4 u^2 + 6 u + 3)) / (u + 1)
    (the printed form loses every digit below f_r - 1 ~ 1e-7: 1.03 c0 at 1e-7, where V_s = (1 + 5.6e-9) c0).
    """
    if force_ratio <= 1.0:
        return c0
    u = force_ratio ** (1.0 / 3.0)
    return c0 * math.sqrt(4.0 / 15.0 * (((2.0 * u + 4.0) * u + 6.0) * u + 3.0)) / (u + 1.0)


#: The relative tolerance within which the sound speed c0 stands for a precompressed chain's wave
#: speed: granchain's default tolerance (the planner's and `granchain compare`'s rtol).
SOUND_SPEED_RTOL = 1e-3


@functools.cache
def weakly_nonlinear_ratio(rtol: float = SOUND_SPEED_RTOL) -> float:
    """The largest dynamic force over the static force, F / F0 = f_r - 1, at which Nesterenko's
    solitary wave V_s(f_r) (precompressed_solitary_wave_speed) moves within `rtol` of the sound speed
    c0: below it a wave is a perturbation small against F0 (weakly nonlinear) and c0 is its speed.

    V_s / c0 - 1 grows as (f_r - 1) / 18 for small f_r - 1, and monotonically: the ratio is the root
    of V_s(1 + x) / c0 - 1 = rtol (0.0181 at rtol = 1e-3, 0.189 at 1e-2).

    Parameters
    ----------
    rtol : float
        The relative difference from c0 allowed.

    Returns
    -------
    float
        F / F0 at which V_s(1 + F / F0) = (1 + rtol) c0.
    """
    lo, hi = 0.0, 1.0
    while precompressed_solitary_wave_speed(1.0, 1.0 + hi) - 1.0 < rtol:
        hi *= 2.0
    for _ in range(200):  # bisection to the last digit
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        lo, hi = (mid, hi) if precompressed_solitary_wave_speed(1.0, 1.0 + mid) - 1.0 < rtol else (lo, mid)
    return hi


def linear_sound_speed(k: float, mass: float, diameter: float) -> float:
    """c = D sqrt(k/m) (Sec. III B): the plastic loading front's speed, and the largest group
    velocity of a linear chain of stiffness k (nothing enters an undisturbed chain faster)."""
    return diameter * math.sqrt(k / mass)


def piston_step_amplitude(velocity: float, k: float, mass: float, diameter: float, exponent: float = 1.5) -> float:
    """The step load A a piston at speed V acts like on a chain of F = k alpha^n (n = `exponent`):
    behind a long-load front the beads move at v = D A / (m c) (Eq. 12); with v = V and the front
    speed of Eq. 19, c^2 = D^2 (A / alpha_A) / m with alpha_A = (A / k)^(1/n) the static overlap under
    A (Hertz: c^2 = A^(1/3) k^(2/3) D^2 / m), so c = ((m V / D)^((n-1)/n) k^(1/n) D^2 / m)^(n/(n+1))
    (Hertz: ((m V / D)^(1/3) k^(2/3) D^2 / m)^(3/5); n = 1, a linear loading line: D sqrt(k/m)),
    A = m V c / D."""
    n = float(exponent)
    if n == 1.0:
        c = linear_sound_speed(k, mass, diameter)
    else:
        c = ((mass * velocity / diameter) ** ((n - 1.0) / n) * k ** (1.0 / n) * diameter**2 / mass) ** (n / (n + 1.0))
    return mass * velocity * c / diameter


def power_front_speed(amplitude: float, k: float, exponent: float, mass: float, diameter: float) -> float:
    """Eq. 19 on a chain of F = k alpha^n: c = D sqrt((A / alpha_A) / m), alpha_A = (A / k)^(1/n) the
    static overlap under A (the secant stiffness; Hertz's c^l, D sqrt(k/m) at n = 1)."""
    n = float(exponent)
    return diameter * math.sqrt(amplitude ** ((n - 1.0) / n) * k ** (1.0 / n) / mass)


def long_load_bilinear(
    amplitude: float, duration: float, k: float, beta: float, mass: float, diameter: float
) -> dict[str, float]:
    """Eqs. 35-38: loading and unloading fronts of a bilinear chain under a long step load.

    Returns c (leading front, plastic loading), c_u (trailing front, unloading), F_1 = A,
    v_1 (Eq. 35), v_t, x_t and T_t (Eq. 36), F_2 and v_2 (Eq. 38).

    Notes on the printed paper: v_t = v_1 - 2 F_1 R/(m c_u) (the printed form lacks m); Eq. 37's
    second relation must read m v_2 = F_2 2R/c for Eq. 38 to follow; with the paper's Table I
    case this gives v_2 = 10.0 m/s where Table I prints 14.84 m/s, and x_t = 3.42 m where Table I
    prints 0.342 m (x_t = 0.342 m would put the merge at T_t = 0.45 ms, before the load ends).
    """
    ku = k / (1.0 - beta)
    c = linear_sound_speed(k, mass, diameter)
    cu = linear_sound_speed(ku, mass, diameter)
    f1 = amplitude
    v1 = f1 * diameter / (mass * c)
    vt = v1 - f1 * diameter / (mass * cu)
    xt = duration / (1.0 / c - 1.0 / cu)
    f2 = mass * vt / diameter / (1.0 / c + 1.0 / cu)
    v2 = vt / (1.0 + c / cu)
    return {"c": c, "c_u": cu, "F_1": f1, "v_1": v1, "v_t": vt, "x_t": xt, "T_t": xt / c, "F_2": f2, "v_2": v2}


def dissipation_per_cycle(peak_force, k, beta):
    """Eq. 20: energy dissipated at a contact loaded to peak force F, F^2/2 (1/k - 1/k_u) = beta F^2 / (2k).

    The paper prints the last form of Eq. 20 as beta F^2 / (2k (1 - beta)), which does not follow
    from its own first form (1/k - 1/k_u = beta/k) and disagrees with the area of the
    load-unload loop; we use the first form (checked against the loop's area in the tests).
    """
    k = np.asarray(k)
    ku = k / (1.0 - np.asarray(beta))
    return 0.5 * np.asarray(peak_force) ** 2 * (1.0 / k - 1.0 / ku)
