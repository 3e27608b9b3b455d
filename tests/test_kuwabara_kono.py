"""Kuwabara-Kono damping ([damping] kuwabara_kono = A): its restitution's exponent 1/5 on both backends,
its two-body series (Ramirez et al. 1999) against the impact's ODE, a KK chain against an independent
DOP853 solver written here, LAMMPS = reference Verlet step for step for every law, and the refusals."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from granchain.lammps.runner import run_lammps
from granchain.physics import materials as mat
from granchain.physics.damping import DAMPING
from granchain.physics.damping.kuwabara_kono import RAMIREZ_C1, restitution, restitution_parameter
from granchain.physics.models import hertz_impact
from granchain.scene import SceneError, parse_scene
from granchain.workflows.run import run_reference, run_scene

from .conftest import LAW_NAMES, make_scene, make_scene_text

KK = DAMPING["kuwabara_kono"]


def wall_impact_scene(material: str, radius: float, velocity: float, damping: float):
    """One bead of a material given a velocity against the rigid wall, Kuwabara-Kono damping A; run to
    1.5 contact times at 1500 steps a contact."""
    text = make_scene_text(beads=1, loading=f'kind = "velocity"\nvelocity = {velocity!r}', end_time=1e-3, timestep=1e-9)
    text = text.replace('material = "brass"', f'material = "{material}"').replace(
        "radius = 4.76e-3", f"radius = {radius!r}"
    )
    sc = parse_scene(text + '[boundary]\nfar_end = "wall"\n', source="kk.toml")
    m = float(sc.bead_masses[0])
    contact = hertz_impact(float(sc.wall_law.k), m, velocity)["duration"]
    text = text.replace(
        "end_time = 0.001\ntimestep = 1e-09", f"end_time = {1.5 * contact!r}\ntimestep = {contact / 1500!r}"
    )
    text += f'[boundary]\nfar_end = "wall"\n[damping]\nkuwabara_kono = {damping!r}\n'
    return parse_scene(text, source="kk.toml")


def restitution_of(sc, backend: str) -> float:
    """-v_after / v_before of the bead off the wall."""
    sol = run_lammps(sc)[0].solution if backend == "lammps" else run_reference(sc, "verlet").solution
    return -float(sol.velocity[0]) / sc.loading.velocity


@pytest.mark.parametrize("backend", ["reference", "lammps"])
@settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck))
@given(material=st.sampled_from(sorted(mat.MATERIALS)), radius=st.floats(2e-3, 1e-2))
def test_restitution_falls_as_the_fifth_root_of_the_impact_speed(backend, material, radius):
    """1 - e ~ v^(1/5) over two decades of impact speed at small damping (delta <= 0.01, where the series'
    second term changes the slope by under 0.002), with the no-pull clipping on: its slope in log-log within
    0.01 of 1/5 (Brilliantov et al. 1996; Schwager & Poeschel 2008: clipping changes e, not the exponent)."""
    speeds = (0.1, 1.0, 10.0)
    probe = wall_impact_scene(material, radius, 1.0, 1e-9)
    k, m = float(probe.wall_law.k), float(probe.bead_masses[0])
    damping = 0.005 / restitution_parameter(1.0, k, m, 1.0)  # delta = 0.005 at 1 m/s, 0.003-0.008 over the range
    loss = [1.0 - restitution_of(wall_impact_scene(material, radius, v, damping), backend) for v in speeds]
    slope = np.polyfit(np.log(speeds), np.log(loss), 1)[0]
    print(f"{backend} {material} R = {radius:.3g}: 1 - e = {loss}, slope {slope:.5f}")
    assert slope == pytest.approx(0.2, abs=0.01)
    # and the series is the model of these runs: the clip's change is of higher order (docs/damping.md)
    for v, lost in zip(speeds, loss, strict=True):
        assert lost == pytest.approx(1.0 - restitution(damping, k, m, v)["e"], rel=2e-3)


def unclipped_restitution(delta_scale: float) -> float:
    """e of xi'' + xi^(3/2) + (3/2) A sqrt(xi) xi' = 0 (K/m = 1, v = 1), the force not clipped: the
    Ramirez et al. series' problem; delta = (3/2) A here."""
    a = delta_scale / 1.5

    def rhs(t, y):
        x = max(y[0], 0.0)
        return [y[1], -(x**1.5) - 1.5 * a * math.sqrt(x) * y[1]]

    def apart(t, y):
        return y[0]

    apart.terminal, apart.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 50.0), [0.0, 1.0], method="DOP853", rtol=1e-12, atol=1e-15, events=apart)
    return -float(sol.y_events[0][0][1])


@pytest.mark.parametrize("delta", [1e-3, 3e-3])
def test_the_series_is_the_unclipped_impact_to_second_order(delta):
    """restitution()'s e = 1 - C1 delta + C2 delta^2 against the unclipped impact solved here: the
    difference is third order (below 2 delta^3), so the constants' mapping delta = (3/2) A (K/m)^(2/5)
    v^(1/5) is right."""
    exact = unclipped_restitution(delta)
    series = restitution(delta / 1.5, 1.0, 1.0, 1.0)
    assert series["delta"] == pytest.approx(delta, rel=1e-12)
    assert abs(series["e"] - exact) < 2.0 * delta**3
    assert (1.0 - exact) / delta == pytest.approx(RAMIREZ_C1, rel=2.0 * delta)


# ---- a KK chain against an independent solver


def dop853_peaks(masses, k: float, a: float, v0: float, t_end: float) -> np.ndarray:
    """Each contact's largest total force of a free chain of Hertz contacts F = K alpha^(3/2) with
    Kuwabara-Kono damping (3/2) A K sqrt(alpha) alpha', never pulling, bead 1 given v0: DOP853 with dense
    output, each contact's maximum located on the interpolant (not granchain's code)."""
    m = np.asarray(masses, dtype=float)
    n = m.size

    def forces(y):
        u, v = y[:n], y[n:]
        alpha, rate = u[:-1] - u[1:], v[:-1] - v[1:]
        a_pos = np.maximum(alpha, 0.0)
        f = k * a_pos**1.5 + 1.5 * a * k * np.sqrt(a_pos) * rate
        return np.where(alpha > 0.0, np.maximum(f, 0.0), 0.0)

    def rhs(t, y):
        f = forces(y)
        acc = np.zeros(n)
        acc[:-1] -= f
        acc[1:] += f
        return np.concatenate((y[n:], acc / m))

    y0 = np.zeros(2 * n)
    y0[n] = v0
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-11, atol=1e-16, dense_output=True)
    ts = np.linspace(0.0, t_end, 40001)
    f = np.array([forces(sol.sol(t)) for t in ts])
    peaks = []
    for c in range(n - 1):
        i = int(np.argmax(f[:, c]))
        lo, hi = ts[max(i - 1, 0)], ts[min(i + 1, ts.size - 1)]
        best = minimize_scalar(
            lambda t, c=c: -forces(sol.sol(t))[c], bounds=(lo, hi), method="bounded", options={"xatol": 1e-14 * t_end}
        )
        peaks.append(max(-best.fun, f[i, c]))
    return np.array(peaks)


def test_a_kuwabara_kono_chain_matches_an_independent_dop853_solver():
    """10 brass beads, bead 1 at 1 m/s, A = 1e-6 s: granchain's contact peak forces (the planned step for
    rtol 1e-3, reference Verlet: the default on a damped scene) within that rtol of DOP853's, and their
    error bars within 1/3 - 3 of the true error (measured 1.02 - 1.05)."""
    rtol = 1e-3
    text = make_scene_text(beads=10, loading='kind = "velocity"\nvelocity = 1.0', end_time=3e-4, timestep=1e-8)
    text = text.replace("timestep = 1e-08", 'timestep = "auto"') + "[damping]\nkuwabara_kono = 1e-6\n"
    sc = parse_scene(text, source="kk-chain.toml")
    result = run_scene(sc, backend="reference", rtol=rtol, error_estimate=True)
    assert result.solution.method == "verlet"
    exact = dop853_peaks(sc.bead_masses, float(sc.law.k), 1e-6, 1.0, 3e-4)
    got = np.asarray(result.solution.peak_force, dtype=float)
    print("relative errors", np.abs(got - exact) / exact)
    assert np.all(np.abs(got - exact) <= rtol * exact)
    ratio = np.asarray(result.errors.peak_force.error, dtype=float) / np.abs(got - exact)
    assert np.all((ratio >= 1 / 3) & (ratio <= 3)), ratio


# ---- both backends step for step


def damped_scene(law: str, wall: bool, damping: float = 1e-6):
    extra = ('[boundary]\nfar_end = "wall"\n' if wall else "") + f"[damping]\nkuwabara_kono = {damping!r}\n"
    return make_scene(
        beads=30,
        law=law,
        loading='kind = "impulse"\nimpulse = 0.1\nduration = 1e-6',
        outputs="histories = [1, 29]\nsnapshots = [1e-4]\n" + extra,
        end_time=2e-4,
        timestep=1e-8,
    )


@pytest.mark.parametrize(
    ("law", "wall"),
    [("hertz", False)]
    + [
        pytest.param(law, wall, marks=pytest.mark.slow)
        for law in LAW_NAMES
        for wall in (False, True)
        if (law, wall) != ("hertz", False)
    ],
)
def test_lammps_equals_reference_verlet_with_kuwabara_kono(law, wall):
    """Every law's tangent of the branch in force (numpy overlap_tangent, C++ tangent) gives the same
    damping: peaks to 1e-9, velocities to 1e-8, the dissipated energy to 1e-9, and the energy balance
    within Verlet's first-order booking (1e-4 of the work at 1e-8 s steps)."""
    sc = damped_scene(law, wall)
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    scale = np.max(np.abs(ref.peak_force))
    assert np.max(np.abs(lam.peak_force - ref.peak_force)) < 1e-9 * scale
    assert np.max(np.abs(lam.velocity - ref.velocity)) < 1e-8 * np.max(np.abs(ref.velocity))
    assert lam.dissipated[-1] == pytest.approx(ref.dissipated[-1], rel=1e-9)
    assert ref.dissipated[-1] > 0.0
    for s in (lam, ref):
        assert np.max(np.abs(s.energy_balance_error)) < 2e-4 * ref.work[-1]


def test_the_energy_balance_holds_with_rk4():
    """RK4 books the damping's power with its own weights: the balance to 1e-8 of the work."""
    sol = run_reference(damped_scene("hertz", True), "rk4").solution
    assert sol.dissipated[-1] > 0.0
    assert np.max(np.abs(sol.energy_balance_error)) < 1e-8 * sol.work[-1]


def test_the_deck_names_the_part():
    from granchain.templates import render_deck

    deck = render_deck(damped_scene("hertz", False, 2e-7)).deck
    assert " kuwabara_kono 2e-07" in deck
    assert "comm_modify     vel yes" in deck
    assert "Kuwabara-Kono damping (d_edash)" in deck


# ---- the scene


def test_dashpot_and_kuwabara_kono_together_are_refused_with_one_message():
    text = make_scene_text() + "[damping]\ndashpot = 3.0\nkuwabara_kono = 1e-6\n"
    with pytest.raises(SceneError, match=r"\[damping\] kuwabara_kono = 1e-06 is not allowed here: one damping part"):
        parse_scene(text, source="both.toml")


def toml_value(v) -> str:
    """A value as TOML writes it (inf, nan and strings included)."""
    if isinstance(v, str):
        return f'"{v}"'
    return "nan" if v != v else ("inf" if v == math.inf else repr(v))


@pytest.mark.parametrize("bad", KK.invalid)
def test_a_bad_coefficient_is_named(bad):
    text = make_scene_text() + f"[damping]\nkuwabara_kono = {toml_value(bad)}\n"
    with pytest.raises(SceneError, match=r"\[damping\] kuwabara_kono = "):
        parse_scene(text, source="bad.toml")


def test_a_scene_writes_its_damping_back():
    sc = damped_scene("hertz", False, 2e-7)
    again = parse_scene(sc.to_toml(), source="again.toml")
    assert again.damping is KK
    assert again.damping_coefficient == 2e-7
    assert again.effects == sc.effects
