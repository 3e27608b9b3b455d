"""Every analytic prediction of the paper that applies to a scene, with its domain of validity."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from granchain.physics import models
from granchain.physics.contact import dissipation_per_cycle


@dataclass(frozen=True)
class Prediction:
    name: str
    value: float
    unit: str
    equation: str
    valid: str  # the model's domain of validity, in words
    nondim: float | None = None  # F/(E* R*^2) for forces, I/(E* R*^2 tau) for impulses

    def as_dict(self) -> dict:
        return asdict(self)


def predict(scene) -> list[Prediction]:
    """Predictions for this scene (SI), nondimensional forms where the paper gives them."""
    m, d, k = scene.mass, scene.diameter, scene.stiffness
    fs, isc = scene.force_scale, scene.impulse_scale
    ld = scene.loading
    impulse = scene.input_impulse
    out: list[Prediction] = [
        Prediction("tau", scene.tau, "s", "Eq. 7", "intrinsic time scale of the bead pair"),
        Prediction(
            "impulse", impulse, "N s", "Eq. 4 (I = A T; velocity load: I = m v0)", "always", nondim=impulse / isc
        ),
    ]
    if ld.is_force:
        out.append(Prediction("loading_time_over_tau", ld.duration / scene.tau, "-", "T / tau (Eq. 7)", "always"))
        out.append(Prediction("amplitude", ld.amplitude, "N", "Eq. 4", "always", nondim=ld.amplitude / fs))

    if scene.contact.law == "hertz":
        fp = models.short_load_peak_force(impulse, m, scene.e_star, scene.r_star)
        out.append(
            Prediction(
                "short_load_peak_force",
                fp,
                "N",
                "Eq. 8 (constant 0.719 fitted by the authors)",
                "single-solitary-wave regime: load shorter than the wave's own contact time "
                "(Fig. 1; T/tau ~ 1 at I = 0.4 N s); measured far enough down the chain for the wave to form",
                nondim=fp / fs,
            )
        )
        out.append(
            Prediction(
                "short_load_wave_speed",
                models.solitary_wave_speed(fp, k, m, d),
                "m/s",
                "Nesterenko long-wave relation V = (2/sqrt5) D k^(1/3) F^(1/6) / sqrt(m) (ref. 9) at Eq. 8's force",
                "as Eq. 8; the long-wave relation is approximate for a discrete chain",
            )
        )
        if ld.is_force:
            a = ld.amplitude
            cl = models.front_speed_lower(a, k, m, d)
            cu = models.front_speed_upper(a, k, m, d)
            fl = models.solitary_wave_peak_force(cl, k, m, d)
            fu = models.solitary_wave_peak_force(cu, k, m, d)
            long_valid = "wave-train regime: load much longer than the solitary wave's contact time (e.g. T/tau ~ 100)"
            out += [
                Prediction("front_speed_lower", cl, "m/s", "Eq. 19", long_valid),
                Prediction("front_speed_upper", cu, "m/s", "Eq. 15", long_valid),
                Prediction(
                    "long_load_peak_force_lower", fl, "N", "Eq. 19 + Nesterenko (ref. 9)", long_valid, nondim=fl / fs
                ),
                Prediction(
                    "long_load_peak_force_upper", fu, "N", "Eq. 15 + Nesterenko (ref. 9)", long_valid, nondim=fu / fs
                ),
                Prediction(
                    "bead_velocity_at_lower_speed",
                    models.constant_regime_bead_velocity(a, cl, m, d),
                    "m/s",
                    "Eq. 12 with c = c^l",
                    long_valid + "; beads behind the front",
                ),
                Prediction(
                    "bead_velocity_at_upper_speed",
                    models.constant_regime_bead_velocity(a, cu, m, d),
                    "m/s",
                    "Eq. 12 with c = c^u",
                    long_valid + "; beads behind the front",
                ),
                Prediction(
                    "peak_force_envelope",
                    min(fp, fu),
                    "N",
                    "min(Eq. 8, upper long-load bound): the two regimes of Fig. 3",
                    "upper estimate of the leading peak for any loading time",
                    nondim=min(fp, fu) / fs,
                ),
            ]
        return out

    # ---- bilinear (Sec. III)
    beta = scene.contact.unloading_coeff
    ku = scene.unloading_stiffness
    lin = models.linear_chain_impulse_response(impulse, k, m, beta)
    short_valid = "short loading (T much shorter than the contact time pi sqrt(m/2k)); first contacts"
    out += [
        Prediction("first_contact_peak_force", lin["F_p"], "N", "Eq. A2", short_valid, nondim=lin["F_p"] / fs),
        Prediction("first_beads_velocity_at_peak", lin["v_m"], "m/s", "Eq. A1", short_valid),
        Prediction("second_contact_force_at_peak", lin["F_2"], "N", "Eq. A3", short_valid, nondim=lin["F_2"] / fs),
        Prediction("trailing_velocity", lin["v_t"], "m/s", "Eq. A4", short_valid),
        Prediction(
            "dissipation_first_contact",
            float(dissipation_per_cycle(lin["F_p"], k, beta)),
            "J",
            "Eq. 20",
            "energy dissipated at a contact loaded to the first contact's peak force",
        ),
    ]
    coeffs = models.leading_wave_coefficients(k, m, beta)
    lam = models.exponential_decay_rate(k, m, beta)
    out += [
        Prediction("gamma", coeffs.gamma, "m/(s N)", "Eq. 22 via A1, A2", short_valid),
        Prediction("eta", coeffs.eta, "-", "Eq. 22 via A2, A3", short_valid),
        Prediction("omega", coeffs.omega, "m/(s N)", "Eq. 22 via A1, A2, A4", short_valid),
        Prediction(
            "exponential_decay_per_contact",
            lam,
            "-",
            "Eqs. 26-27 (F_{i+1} = F_i exp(-lambda); Eq. 27 as derived from Eq. 26)",
            "exponential regime: contacts before the transition",
        ),
    ]
    tc = transition_contact(lin["F_p"], lam, ku, m, coeffs.omega, scene.n_contacts)
    if tc is not None:
        out.append(
            Prediction(
                "transition_contact",
                float(tc),
                "-",
                "Eq. 27 meets Eq. 30",
                "first contact where the secondary-wave peak exceeds the leading peak",
            )
        )
    out.append(
        Prediction(
            "inverse_decay_exponent",
            models.inverse_decay_exponent(beta),
            "-",
            "Eq. 34",
            "inverse regime, beyond the transition contact",
        )
    )
    if ld.is_force:
        r = models.long_load_bilinear(ld.amplitude, ld.duration, k, beta, m, d)
        long_valid = "long loading (steady fronts, Sec. III B); until the first collision of the fronts"
        units = {
            "c": "m/s",
            "c_u": "m/s",
            "F_1": "N",
            "v_1": "m/s",
            "v_t": "m/s",
            "x_t": "m",
            "T_t": "s",
            "F_2": "N",
            "v_2": "m/s",
        }
        eqs = {
            "c": "c = D sqrt(k/m) (Sec. III B)",
            "c_u": "c_u = D sqrt(k_u/m) (Sec. III B)",
            "F_1": "F_1 = A",
            "v_1": "Eq. 35",
            "v_t": "v_t = v_1 - 2 F_1 R/(m c_u) (Sec. III B)",
            "x_t": "Eq. 36",
            "T_t": "Eq. 36",
            "F_2": "Eq. 38",
            "v_2": "Eq. 38",
        }
        for key, val in r.items():
            nd = val / fs if units[key] == "N" else None
            out.append(Prediction(f"long_load_{key}", val, units[key], eqs[key], long_valid, nondim=nd))
    return out


def leading_peaks_exponential(first_peak: float, decay: float, n: int):
    """Leading peak force at contacts 1..n in the exponential regime (Eq. 27)."""
    return [first_peak * math.exp(-decay * i) for i in range(n)]


def transition_contact(
    first_peak: float, decay: float, k_u: float, mass: float, omega: float, n_contacts: int
) -> int | None:
    """First contact (1-based) where Eq. 30's secondary peak exceeds Eq. 27's leading peak."""
    lead = leading_peaks_exponential(first_peak, decay, n_contacts)
    for i in range(1, n_contacts):
        fs = models.secondary_wave_peak_force(lead[0] - lead[i], k_u, mass, omega)
        if fs > lead[i]:
            return i + 1
    return None
