"""Reference solver (RK4, velocity Verlet): exact loading, conservation, convergence, the paper's constants."""

import math

import numpy as np
import pytest

from granchain.physics import models
from granchain.reference.solver import ChainProblem, solve_chain

from .conftest import BILINEAR, make_scene

HERTZ = make_scene()
PLASTIC = make_scene(law="bilinear", contact_extra=BILINEAR)


def fitted_order(dts, errors) -> float:
    """Least-squares slope of log(error) against log(dt)."""
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])


@pytest.mark.parametrize("method", ["rk4", "verlet"])
@pytest.mark.parametrize("scene", [HERTZ, PLASTIC], ids=["hertz", "bilinear"])
def test_momentum_after_loading_equals_impulse(scene, method):
    # dt = 3e-8 does not divide T = 1e-6: the step before T is shortened to land on it
    p = ChainProblem.from_scene(scene)
    sol = solve_chain(p, 5e-5, 3e-8, method)
    assert sol.impulse_delivered == pytest.approx(0.1, rel=1e-15)
    assert abs(sol.momentum - 0.1) < 64 * np.finfo(float).eps * 0.1 * scene.chain.beads


def test_step_load_ends_exactly_at_T():
    # bead 1's velocity history: the load's impulse A*T enters in exactly the steps inside (0, T]
    sc = make_scene(
        beads=3, loading='kind = "step"\namplitude = 10.0\nduration = 1.05e-6', end_time=2e-6, timestep=1e-7
    )
    p = ChainProblem.from_scene(sc)
    s1 = solve_chain(p, 1.05e-6, 1e-7, "verlet")
    s2 = solve_chain(p, 2e-6, 1e-7, "verlet")
    assert s1.momentum == pytest.approx(10.0 * 1.05e-6, rel=1e-13)
    assert s2.momentum == pytest.approx(10.0 * 1.05e-6, rel=1e-13)


@pytest.mark.parametrize(("method", "bound"), [("rk4", 1e-9), ("verlet", 2e-6)])
def test_elastic_energy_conserved_after_loading(method, bound):
    """Stated drift bounds at dt = 2.5e-8 s (tau/31) on the 30-bead Hertz scene over 200 us."""
    sol = solve_chain(ChainProblem.from_scene(HERTZ), 2e-4, 2.5e-8, method)
    after = sol.energy_time > 1e-6
    total = sol.kinetic + sol.potential
    drift = np.max(np.abs(total[after] - sol.work[-1])) / sol.work[-1]
    print(f"{method}: max relative energy error after loading = {drift:.2e}")
    assert drift < bound
    # the work of f(t) is constant once the load is off
    assert np.ptp(sol.work[after]) == 0.0


@pytest.mark.parametrize("method", ["rk4", "verlet"])
def test_bilinear_energy_balance(method):
    sol = solve_chain(ChainProblem.from_scene(PLASTIC), 2e-4, 1e-8, method)
    err = np.max(np.abs(sol.energy_balance_error)) / sol.work[-1]
    print(f"{method}: kinetic + stored + dissipated - work, max over the run = {err:.2e} of the work")
    assert err < 1e-6
    assert sol.dissipated[-1] > 0.5 * sol.work[-1]  # beta = 0.8 dissipates most of the input


@pytest.mark.parametrize("scene", [HERTZ, PLASTIC], ids=["hertz", "bilinear"])
def test_convergence_orders(scene):
    """Measured orders (peak force of every contact, and final displacements) against a fine run.

    Expected: Verlet 2 on both laws. RK4 4, because the solver splits steps where a contact
    crosses a kink of its force law (first touch and separation, loading <-> unloading); without
    that event location the measured RK4 order drops to about 2.8 (Hertz) and 1.5 (bilinear).
    """
    p = ChainProblem.from_scene(scene)
    dts = np.array([2e-7, 1e-7, 5e-8, 2.5e-8])
    report = {}
    for method, fine in (("rk4", 2.5e-9), ("verlet", 1e-9)):
        ref = solve_chain(p, 2e-4, fine, method)
        e_pk, e_u = [], []
        for dt in dts:
            s = solve_chain(p, 2e-4, dt, method)
            e_pk.append(np.max(np.abs(s.peak_force - ref.peak_force)) / np.max(ref.peak_force))
            e_u.append(np.max(np.abs(s.displacement - ref.displacement)) / np.max(np.abs(ref.displacement)))
        report[method] = (fitted_order(dts, e_pk), fitted_order(dts, e_u), e_pk[-1])
    print(
        scene.contact.law,
        {m: tuple(round(x, 2) if i < 2 else float(f"{x:.2e}") for i, x in enumerate(v)) for m, v in report.items()},
    )
    pk_v, u_v, _ = report["verlet"]
    assert 1.8 < pk_v < 2.6
    assert 1.8 < u_v < 2.6
    pk_r, u_r, finest = report["rk4"]
    assert pk_r > 3.5
    assert u_r > 3.0
    assert finest < 1e-9


def test_rk4_beats_verlet_at_equal_step():
    p = ChainProblem.from_scene(PLASTIC)
    ref = solve_chain(p, 2e-4, 2.5e-9, "rk4")
    err = {m: np.max(np.abs(solve_chain(p, 2e-4, 5e-8, m).peak_force - ref.peak_force)) for m in ("rk4", "verlet")}
    assert err["rk4"] < err["verlet"]


def test_peak_refinement_beats_raw_samples():
    """The in-run Hermite refinement is closer to the converged peak than the largest sample."""
    sc = make_scene(outputs="histories = [5, 10, 15]")
    p = ChainProblem.from_scene(sc)
    ref = solve_chain(p, 2e-4, 2.5e-9, "rk4")
    coarse = solve_chain(p, 2e-4, 2e-7, "rk4", histories=(4, 9, 14))
    raw = coarse.history_force.max(axis=0)
    refined = coarse.peak_force[[4, 9, 14]]
    exact = ref.peak_force[[4, 9, 14]]
    assert np.all(np.abs(refined - exact) < 0.05 * np.abs(raw - exact))


def test_snapshots_at_exact_times_and_history_stride():
    p = ChainProblem.from_scene(HERTZ)
    s = solve_chain(p, 1e-4, 3e-8, "rk4", snapshots=(1.7e-5, 5.00001e-5), histories=(0, 3), history_stride=10)
    assert list(s.snapshot_time) == [1.7e-5, 5.00001e-5]
    assert s.snapshot_velocity.shape == (2, 30)
    assert s.snapshot_force.shape == (2, 29)
    # every 10th step from t = 0, as LAMMPS's dump: the last row is the last such step, not the end
    assert s.history_time[0] == 0.0
    assert 1e-4 - 10 * 3e-8 < s.history_time[-1] <= 1e-4
    assert np.all(np.diff(s.history_time) > 0)
    assert s.history_force.shape[1] == 2
    # the snapshot is the same state a run ending there reaches
    s2 = solve_chain(p, 1.7e-5, 3e-8, "rk4")
    assert np.array_equal(s2.velocity, s.snapshot_velocity[0])


@pytest.mark.parametrize("loading", ["velocity", "impulse"])
def test_short_pulse_solitary_wave_matches_eq8(loading):
    """Eq. 8 within 1% far down a long elastic chain; prints the constant our solver implies."""
    m = HERTZ.mass
    text = (
        ('kind = "velocity"\nvelocity = ' + repr(0.4 / m))
        if loading == "velocity"
        else 'kind = "impulse"\nimpulse = 0.4\nduration = 1e-6'
    )
    sc = make_scene(beads=120, loading=text, end_time=7e-4, timestep=2.5e-8)
    sol = solve_chain(ChainProblem.from_scene(sc), 7e-4, 2.5e-8, "rk4")
    measured = sol.peak_force[59:90]  # contacts 60..90: formed, far from both ends
    assert np.all(np.isfinite(sol.time_of_peak[59:90]))
    eq8 = models.short_load_peak_force(0.4, m, sc.e_star, sc.r_star)
    constant = models.EQ8_CONSTANT * measured.mean() / eq8
    print(
        f"{loading}: leading peak {measured.mean():.1f} N (spread {np.ptp(measured) / measured.mean():.1e}), "
        f"Eq. 8 {eq8:.1f} N, implied constant {constant:.4f}"
    )
    assert abs(measured.mean() / eq8 - 1) < 0.01
    assert np.ptp(measured) / measured.mean() < 1e-3  # a steady solitary wave


def test_linear_chain_appendix_constants():
    """beta = 0 bilinear (a linear spring that cannot pull) hit by an impulse: A2 within 1%.

    A1 (v_m) is measured as the velocity of bead 1 when contact 1 peaks; A3 (F_2) as the force of
    contact 2 at that instant (the relative velocity of beads 1 and 2 is zero there, so beads 1
    and 2 share v_m). Printed, with the paper's values, for the note.
    """
    k, impulse = 2.43e7, 0.1
    sc = make_scene(
        beads=40,
        law="bilinear",
        contact_extra=f"unloading_coeff = 0.0\nplastic_stiffness = {k!r}\n",
        loading=f'kind = "velocity"\nvelocity = {impulse / HERTZ.mass!r}',
        end_time=2e-4,
        timestep=5e-9,
    )
    m = sc.mass
    sol = solve_chain(ChainProblem.from_scene(sc), 2e-4, 5e-9, "rk4", histories=(0, 1))
    s = math.sqrt(k / m) * impulse
    a2 = sol.peak_force[0] / s
    i = int(np.argmax(sol.history_force[:, 0]))
    a1 = sol.history_velocity[i, 0] * m / impulse
    v2 = sol.history_velocity[i, 1] * m / impulse
    a3 = sol.history_force[i, 1] / s
    print(
        f"A1 measured {a1:.4f} (bead 2: {v2:.4f}) paper 0.482; A2 measured {a2:.4f} paper 0.721; "
        f"A3 measured {a3:.4f} paper 0.199"
    )
    assert abs(a2 / models.APPENDIX_A2 - 1) < 0.01
