"""granchain.postprocess.spectra on synthetic records and on a time-integrated linear chain.

Bounds are derived, not tuned: on whole periods the lock-in is the projection Z = (2/N) sum x
exp(-i w t) (its columns orthogonal to within 2/N), so a transient g adds at most 2 mean|g| over the
window, and white noise of standard deviation s adds |dZ| with P(|dZ| > r) = exp(-r^2 N / (4 s^2))
(a and b each of variance 2 s^2 / N): r = 5 s sqrt(4 / N) is passed with probability 1 - 1.4e-11.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.stats import t as student_t

from granchain.exceptions import GranchainError
from granchain.postprocess.spectra import (
    SpectraError,
    lock_in,
    spatial_decay,
    spectrum,
    steady_window,
    transmission,
)
from tests.linear_chain import state_matrix, steady_state

#: the slack over the orthogonal-projection bound for the cos/sin columns' 2/N non-orthogonality
PROJECTION_SLACK = 1.1
NOISE_SIGMAS = 5.0


def noise_bound(sigma: float, samples: int) -> float:
    return NOISE_SIGMAS * sigma * math.sqrt(4.0 / samples)


@st.composite
def records(draw):
    """A sinusoid plus offset, a second harmonic, white noise and a decaying transient, sampled uniformly."""
    f = draw(st.floats(1.0, 1e4))
    per_period = draw(st.floats(8.0, 60.0))
    periods = draw(st.integers(6, 40))
    ramp = draw(st.floats(0.0, 3.0))
    tau = draw(st.floats(0.05, 1.0)) / f  # the transient's decay time
    transit = draw(st.floats(3.0, 12.0)) * tau
    dt = 1.0 / (f * per_period)
    n = int((ramp / f + transit + (periods + 0.5) / f) / dt) + 1
    t = np.arange(n) * dt
    amp, phi = draw(st.floats(0.1, 10.0)), draw(st.floats(-3.1, 3.1))
    amp2, phi2 = draw(st.floats(0.0, 1.0)) * amp, draw(st.floats(-3.1, 3.1))
    sigma = draw(st.floats(0.0, 0.05)) * amp
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    transient = draw(st.floats(0.0, 2.0)) * amp * np.exp(-t / tau) * np.cos(2 * math.pi * 0.37 * f * t)
    x = 0.3 * amp + amp * np.cos(2 * math.pi * f * t + phi) + amp2 * np.cos(4 * math.pi * f * t + phi2)
    x = x + transient + sigma * rng.standard_normal(n)
    return dict(
        t=t, x=x, f=f, amp=amp, phi=phi, amp2=amp2, phi2=phi2, sigma=sigma, g=transient, ramp=ramp, transit=transit
    )


@settings(max_examples=60, deadline=None)
@given(records())
def test_lock_in_recovers_amplitude_and_phase_within_the_windows_bound(r):
    win = steady_window(r["t"], None, r["f"], r["ramp"], r["transit"])
    got = lock_in(r["t"], r["x"], r["f"], harmonics=(1, 2), window=win)
    eps = 1e-9 * (r["t"][1] - r["t"][0])  # the window's ends, moved against round-off in t
    inside = (r["t"] >= win.start - eps) & (r["t"] < win.end - eps)
    assert got.samples == np.count_nonzero(inside)
    assert win.periods >= 2
    assert math.isclose((win.end - win.start) * r["f"], win.periods)
    assert win.start >= r["ramp"] / r["f"] + r["transit"] - 1e-12
    assert win.end <= r["t"][-1]
    bound = PROJECTION_SLACK * 2 * np.mean(np.abs(r["g"][inside])) + noise_bound(r["sigma"], got.samples)
    bound += 1e-9 * r["amp"]
    for h, (a, p) in enumerate([(r["amp"], r["phi"]), (r["amp2"], r["phi2"])]):
        assert abs(got.complex_amplitude[h] - a * np.exp(1j * p)) <= bound
        if a > 4 * bound:
            assert abs(np.angle(np.exp(1j * (got.phase[h] - p)))) <= math.asin(bound / a) * 1.0001
    # the error bar: the second half's own noise and transient bound added
    half = (r["t"] >= win.end - (win.periods // 2) / r["f"] - eps) & inside
    bound_half = PROJECTION_SLACK * 2 * np.mean(np.abs(r["g"][half])) + noise_bound(r["sigma"], half.sum())
    assert np.all(got.error <= bound + bound_half + 1e-9 * r["amp"])


@settings(max_examples=30, deadline=None)
@given(st.floats(0.1, 10.0), st.floats(-0.5, 0.5), st.integers(4, 30), st.floats(-3.1, 3.1))
def test_the_error_bar_sees_an_amplitude_still_growing(amp, rate, periods, phi):
    # A(t) = amp (1 + rate f t / periods) over the window: Z(whole) - Z(second half) is the change in
    # the mean amplitude between the two, amp rate (mid-window - mid second half) f / periods
    f, dt = 50.0, 1.0 / (50.0 * 40)
    t = np.arange(int(periods / f / dt) + 2) * dt
    x = amp * (1 + rate * f * t / periods) * np.cos(2 * math.pi * f * t + phi)
    got = lock_in(t, x, f, window=(0.0, periods / f))
    half = periods // 2
    mid_whole, mid_half = periods / 2, periods - half / 2
    expected = amp * abs(rate) * (mid_half - mid_whole) / periods
    assert got.error[0] == pytest.approx(expected, rel=0.05, abs=1e-9 * amp)


@settings(max_examples=40, deadline=None)
@given(
    st.sampled_from([256, 1000, 4096]),
    st.floats(-0.45, 0.45),
    st.floats(0.1, 10.0),
    st.floats(-3.1, 3.1),
    st.floats(0.0, 0.02),
    st.integers(0, 2**32 - 1),
)
def test_spectrum_peaks_at_the_nearest_bin(n, offset, amp, phi, noise, seed):
    dt = 1e-4
    df = 1.0 / (n * dt)
    k = np.random.default_rng(seed).integers(10, n // 2 - 10)
    f = (k + offset) * df
    t = np.arange(n) * dt
    x = amp * np.cos(2 * math.pi * f * t + phi) + noise * amp * np.random.default_rng(seed).standard_normal(n)
    s = spectrum(t, x)
    assert s.window == "hann"
    assert s.resolution == pytest.approx(df)
    assert s.enbw == pytest.approx(1.5)
    assert s.peak_frequency == pytest.approx(k * df)
    # Hann's response at `offset` bins from a tone (Harris 1978): sinc(d) / (1 - d^2); leakage of the
    # negative-frequency image, >= 20 bins away, below 1e-4 (Hann's side lobes fall as d^-3)
    response = np.sinc(offset) / (1 - offset**2)
    noise_bin = 5 * noise * amp * math.sqrt(2 * 1.5 / n) * 2
    assert abs(s.amplitude.max() - amp * response) <= 2e-3 * amp + noise_bin


@pytest.mark.parametrize("window", ["boxcar", "hann", "hamming", "blackman", "flattop"])
def test_every_window_reads_a_centred_tone_at_its_amplitude(window):
    n, dt, k, amp = 2048, 1e-3, 123, 2.5
    t = np.arange(n) * dt
    s = spectrum(t, amp * np.sin(2 * math.pi * k / (n * dt) * t), window=window)
    assert int(np.argmax(s.amplitude)) == k
    assert s.amplitude[k] == pytest.approx(amp, rel=1e-9)


# ------------------------------------------------------------------------- refusals


def test_bad_input_is_refused_naming_the_argument():
    t = np.arange(1000) * 1e-3
    x = np.cos(2 * math.pi * 10 * t)
    bad_t = t.copy()
    bad_t[500] += 3e-4
    cases = [
        (lambda: lock_in(bad_t, x, 10.0), "t:"),
        (lambda: spectrum(bad_t, x), "t:"),
        (lambda: lock_in(t, x, 400.0), "frequency:"),  # 400 Hz: Nyquist is 500, under 4 samples a period
        (lambda: lock_in(t, x, 600.0), "above the Nyquist"),
        (lambda: lock_in(t, x, 1.5), "whole drive period"),
        (lambda: steady_window(t, 0.5, 10.0, 2, 0.4), "t:"),
        (lambda: lock_in(t, x[:-1], 10.0), "x:"),
        (lambda: lock_in(t, x, 10.0, harmonics=(0,)), "harmonics:"),
        (lambda: spectrum(t, x, window="kaiser"), "window:"),
        (lambda: spatial_decay([0, 1], [1.0, 0.5]), "at least 3"),
        (lambda: spatial_decay([0, 1, 2], [1.0, 0.0, 0.5]), "amplitudes:"),
        (lambda: transmission(1.0, 0.0), "drive:"),
    ]
    for call, words in cases:
        with pytest.raises(SpectraError, match=words) as info:
            call()
        assert isinstance(info.value, GranchainError)


@settings(max_examples=40, deadline=None)
@given(st.floats(-2.0, 2.0), st.floats(1e-3, 1e3), st.integers(3, 30), st.floats(0.0, 0.1), st.integers(0, 2**32))
def test_spatial_decay_recovers_the_rate_within_its_error_bar(rate, a0, n, noise, seed):
    x = np.arange(n, dtype=float)
    eps = noise * np.random.default_rng(seed).standard_normal(n)
    got = spatial_decay(x, a0 * np.exp(-rate * x + eps))
    # ordinary least squares on ln A: (slope - rate) / its standard error is Student's t with n - 2
    # degrees of freedom, beyond its 1 - 1e-7 quantile with probability 2e-7
    quantile = student_t.ppf(1 - 1e-7, n - 2)
    assert abs(got.rate - rate) <= quantile * got.rate_error + 1e-9 * (1 + abs(rate))
    assert got.db_per_unit == pytest.approx(20 * got.rate / math.log(10))
    if noise == 0:
        assert got.amplitude0 == pytest.approx(a0, rel=1e-9)


# ------------------------------------------------------------------------- a linear chain, integrated


@st.composite
def damped_chains(draw):
    n = draw(st.integers(2, 6))
    masses = np.array(draw(st.lists(st.floats(0.5, 2.0), min_size=n, max_size=n)))
    springs = np.array(draw(st.lists(st.floats(0.5, 2.0), min_size=n - 1, max_size=n - 1)))
    dashpots = draw(st.floats(0.0, 0.3)) * springs
    wall = draw(st.floats(0.5, 2.0))
    omega = draw(st.floats(0.3, 2.5))
    # dashpots to the ground, c_j = alpha m_j, damp every mode at a rate of at least alpha / 2
    ground = draw(st.floats(0.2, 0.5)) * masses
    extra = dict(dashpots=dashpots, walls=(0.0, wall), wall_dashpots=(0.0, 0.2 * wall), ground_dashpots=ground)
    return masses, springs, extra, omega


@settings(max_examples=6, deadline=None)
@given(damped_chains())
def test_lock_in_on_an_integrated_chain_matches_the_exact_steady_state(chain):
    masses, springs, extra, omega = chain
    n = masses.size
    force = np.zeros(n, dtype=complex)
    force[0] = 1.0
    exact = steady_state(masses, springs, omega, force, **extra)
    a = state_matrix(masses, springs, **extra)
    slowest = -np.max(np.linalg.eigvals(a).real)  # the slowest transient's decay rate
    assert slowest > 0
    f = omega / (2 * math.pi)
    settle = math.log(1e10) / slowest  # the transient from rest is down by 1e-10 of its start
    end = settle + 12 / f
    rhs_force = np.zeros(2 * n)

    def rhs(t, y):
        rhs_force[n] = math.cos(omega * t) / masses[0]
        return a @ y + rhs_force

    dt = 1 / (f * 32)
    t = np.arange(int(end / dt) + 1) * dt
    sol = solve_ivp(rhs, (0, t[-1]), np.zeros(2 * n), method="DOP853", t_eval=t, rtol=1e-11, atol=1e-13)
    assert sol.success
    win = steady_window(t, None, f, 0, settle)
    scale = np.max(np.abs(exact))
    locks = [lock_in(t, sol.y[j], f, window=win) for j in range(n)]
    for j in range(n):
        assert abs(locks[j].complex_amplitude[0] - exact[j]) <= 1e-6 * scale
        assert locks[j].error[0] <= 1e-6 * scale
    tr = transmission(locks[-1], locks[0])
    assert tr.ratio == pytest.approx(abs(exact[-1] / exact[0]), rel=1e-5)
    assert abs(np.angle(np.exp(1j * tr.phase) * exact[0] / exact[-1])) <= 1e-5
