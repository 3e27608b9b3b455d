"""Analytic models: internal consistency (each model against its own defining equations)."""

import math

import pytest

from granchain.physics import materials as mat
from granchain.physics import models
from granchain.physics.predictions import predict

from .conftest import BILINEAR, make_scene

BRASS = mat.MATERIALS["brass"]
R = 4.76e-3
M = mat.bead_mass(BRASS, R)
K = mat.hertz_stiffness(BRASS, R)
D = 2 * R


def test_tau_matches_paper_ratio():
    # the paper states T/tau = 1.29 for T = 1 us (Sec. II B): a check of Eq. 7 and E*, R*
    assert 1e-6 / mat.time_scale(BRASS, R) == pytest.approx(1.29, abs=0.005)


def test_eq8_scales_as_impulse_to_six_fifths():
    f1 = models.short_load_peak_force(0.1, M, mat.effective_modulus(BRASS), R / 2)
    f2 = models.short_load_peak_force(0.2, M, mat.effective_modulus(BRASS), R / 2)
    assert f2 / f1 == pytest.approx(2**1.2, rel=1e-12)


def test_front_speed_bounds_ratio_and_nesterenko_inverse():
    cl = models.front_speed_lower(40.0, K, M, D)
    cu = models.front_speed_upper(40.0, K, M, D)
    assert cu / cl == pytest.approx(math.sqrt(10 / 9))
    f = models.solitary_wave_peak_force(cl, K, M, D)
    assert models.solitary_wave_speed(f, K, M, D) == pytest.approx(cl)
    # Eq. 19 + Nesterenko: F = (5/4)^3 A exactly, whatever the material
    assert f == pytest.approx(40.0 * (5 / 4) ** 3)


def test_eq12_with_eq18_gives_eq19():
    # Eq. 12 (m v = D A / c) and Eq. 18 (D v / c = (A/k)^(2/3)) together must give c = c^l
    cl = models.front_speed_lower(40.0, K, M, D)
    v = models.constant_regime_bead_velocity(40.0, cl, M, D)
    assert D * v / cl == pytest.approx((40.0 / K) ** (2 / 3))


def test_exponential_decay_rate_solves_eq26():
    k, beta = 2.43e7, 0.8
    lam = models.exponential_decay_rate(k, M, beta)
    c = models.leading_wave_coefficients(k, M, beta)
    ku = k / (1 - beta)
    y = -lam  # D dF/dx / F
    b = (1 + c.eta**2) / (2 * k) + M * c.gamma**2
    cc = 0.5 * (1 / k - 1 / ku) + 0.5 * M * c.omega**2
    assert (y**2 + 2 * y) * b + cc == pytest.approx(0.0, abs=1e-12 * cc)
    assert 0 < lam < 1


def test_long_load_fronts_satisfy_eq35_and_eq37():
    k, beta, a, t = 2.43e7, 0.8, 8000.0, 2.5e-3
    r = models.long_load_bilinear(a, t, k, beta, M, D)
    assert M * r["v_1"] == pytest.approx(2 * r["F_1"] * R / r["c"])  # Eq. 35
    assert M * (r["v_2"] - r["v_t"]) == pytest.approx(-r["F_2"] * D / r["c_u"])  # Eq. 37, first
    assert M * r["v_2"] == pytest.approx(r["F_2"] * D / r["c"])  # Eq. 37, second (with c)
    assert r["x_t"] / r["c"] == pytest.approx(r["T_t"])
    # the fronts merge after the load ends (the trailing front starts at t = T)
    assert r["T_t"] > t


def test_eq29_linear_collision():
    # two equal beads on a linear spring of stiffness k_u: peak force sqrt(k_u m / 2) dv (Eq. 29)
    ku, dv = 1.2e8, 3.0
    omega = math.sqrt(2 * ku / M)  # reduced mass m/2
    amplitude = dv / omega
    assert models.collision_peak_force(dv, ku, M) == pytest.approx(ku * amplitude)


def test_predictions_cover_the_scene():
    names = {p.name for p in predict(make_scene())}
    assert {"short_load_peak_force", "front_speed_lower", "front_speed_upper", "peak_force_envelope"} <= names
    names_b = {p.name for p in predict(make_scene(law="bilinear", contact_extra=BILINEAR))}
    assert {
        "first_contact_peak_force",
        "exponential_decay_per_contact",
        "inverse_decay_exponent",
        "long_load_v_1",
        "long_load_F_2",
        "gamma",
        "eta",
        "omega",
    } <= names_b
    for p in predict(make_scene(law="bilinear", contact_extra=BILINEAR)):
        assert math.isfinite(p.value)
        assert p.valid
        assert p.equation
