"""The harmonic force load ([loading] kind = "harmonic", issue 46 item 1): both backends, an independent
DOP853 oracle, the applied force against its formula, the planner's choices and every refusal."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import quad, solve_ivp

from granchain.exceptions import GranchainError
from granchain.lammps.runner import run_lammps
from granchain.physics.estimates import contact_force_bound
from granchain.problem import ChainProblem
from granchain.scene import load_scene, parse_scene
from granchain.templates import render_deck
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_reference

from .conftest import LAW_NAMES, make_scene_text

BRASS = {"E": 115e9, "nu": 0.3, "rho": 8500.0}  # the scene's "brass" (granchain.physics.materials)
R = 4.76e-3


def drive_text(amplitude=2.0, frequency=2e4, length="cycles = 2", ramp=None) -> str:
    return f'kind = "harmonic"\namplitude = {amplitude!r}\nfrequency = {frequency!r}\n{length}\n' + (
        f"ramp = {ramp!r}\n" if ramp is not None else ""
    )


def driven(law="hertz", extra="", beads=10, end_time=1.4e-4, timestep=2e-8, outputs=None, **drive) -> str:
    outputs = outputs or f"histories = [1, {beads // 2}, {beads - 1}]\n"
    text = make_scene_text(
        beads=beads, law=law, loading=drive_text(**drive), end_time=end_time, timestep=timestep, outputs=outputs
    )
    return text + extra


def oracle_force(t, a, f, t_ramp, t_drive):
    """The drive written out here: A sin(2 pi f t) sin^2(pi t / (2 t_r)) up to t_r, A sin(2 pi f t) on to T."""
    t = np.asarray(t, dtype=float)
    ramp = np.where(t < t_ramp, np.sin(np.pi * t / (2.0 * t_ramp)) ** 2, 1.0) if t_ramp > 0 else np.ones_like(t)
    return np.where((t > 0) & (t <= t_drive), a * np.sin(2 * np.pi * f * t) * ramp, 0.0)


# ---- (a) the two backends agree, with every law and the effects a drive goes with

PRECOMPRESSED_WALL_DASHPOT = (
    '\n[precompression]\nforce = 10.0\n[boundary]\nfar_end = "wall"\n[damping]\ndashpot = 5.0\n'
)
SLOW = pytest.mark.slow  # (the fast set keeps one law with every effect but gravity, and the free chain)
CASES = [
    pytest.param(law, PRECOMPRESSED_WALL_DASHPOT, marks=() if law == "hertz" else SLOW, id=f"{law}-wall-dashpot")
    for law in LAW_NAMES
] + [
    # Kuwabara-Kono damping on a vertical chain (gravity stands it on the wall)
    pytest.param(
        "hertz",
        '\n[precompression]\nforce = 5.0\n[boundary]\nfar_end = "wall"\n[gravity]\ng = 9.81\n'
        "[damping]\nkuwabara_kono = 1e-6\n",
        marks=SLOW,
        id="hertz-gravity-kuwabara-kono",
    ),
    # a free, uncompressed chain: its momentum is the drive's impulse, as Verlet's trapezoid delivers it
    pytest.param("hertz", "", id="hertz-free"),
]


@pytest.mark.parametrize(("law", "extra"), CASES)
def test_lammps_and_reference_agree_under_a_drive(law, extra):
    sc = parse_scene(driven(law, extra), source="driven.toml")
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    scale = np.max(np.abs(ref.history_force))
    assert np.max(np.abs(lam.history_force - ref.history_force)) <= 1e-8 * scale
    assert lam.history_force.shape == ref.history_force.shape
    assert np.max(np.abs(lam.velocity - ref.velocity)) <= 1e-7 * np.max(np.abs(ref.velocity))
    # the drive's work, summed the same way on both (the reference per step, the deck per step)
    assert lam.work[-1] == pytest.approx(ref.work[-1], rel=1e-6)
    put_in = np.max(np.abs(ref.work))
    assert np.max(np.abs(ref.energy_balance_error)) < 1e-4 * put_in
    assert np.max(np.abs(lam.energy_balance_error)) < 1e-4 * put_in
    assert lam.impulse_delivered == pytest.approx(ref.impulse_delivered, rel=1e-12)
    if not extra:  # nothing else acts: the chain's momentum is the drive's impulse, as Verlet's trapezoid
        # delivers it: within its error (w h)^2 w t / 12 of A / w (the sum of h^3 f'' / 12 over the steps)
        w, h, t = 2 * math.pi * sc.loading.frequency, sc.run.timestep, sc.loading.duration
        bound = 2.0 * (w * h) ** 2 * w * t / 12.0 * sc.loading.amplitude / w
        for sol in (lam, ref):
            assert abs(sol.momentum - sol.impulse_delivered) <= bound


# ---- (b) an independent DOP853 solver of a small precompressed Hertz chain under the drive


def hertz_k() -> float:
    """Hertz's K of two equal spheres (Johnson): (4/3) E* sqrt(R*), E* = E / (2 (1 - nu^2)), R* = R / 2."""
    e_star = BRASS["E"] / (2.0 * (1.0 - BRASS["nu"] ** 2))
    return 4.0 / 3.0 * e_star * math.sqrt(R / 2.0)


def dop853_histories(n, f0, a, f, t_ramp, t_drive, times):
    """Contact forces of n beads, bead 1 pushed by F0 + the drive, bead n by F0 back (a free far end)."""
    k, m = hertz_k(), BRASS["rho"] * 4.0 / 3.0 * math.pi * R**3
    delta0 = (f0 / k) ** (2.0 / 3.0)
    u0 = delta0 * np.arange(n - 1, -1, -1, dtype=float)  # bead n at 0, each contact at F0

    def rhs(t, y):
        u, v = y[:n], y[n:]
        d = np.maximum(u[:-1] - u[1:], 0.0)
        fc = k * d**1.5
        acc = np.zeros(n)
        acc[:-1] -= fc
        acc[1:] += fc
        acc[0] += f0 + float(oracle_force(t, a, f, t_ramp, t_drive))
        acc[-1] -= f0
        return np.concatenate((v, acc / m))

    out, sol = [], None
    for lo, hi in ((0.0, t_drive), (t_drive, times[-1])):  # the drive stops at T: a breakpoint
        sel = times[(times >= lo) & (times <= hi)] if lo == 0.0 else times[times > lo]
        y0 = np.concatenate((u0, np.zeros(n))) if lo == 0.0 else sol.y[:, -1]
        span = np.append(sel, hi) if (sel.size == 0 or sel[-1] < hi) else sel
        sol = solve_ivp(rhs, (lo, hi), y0, method="DOP853", rtol=1e-12, atol=1e-18, t_eval=span)
        keep = np.isin(sol.t, sel)
        d = sol.y[: n - 1, keep] - sol.y[1:n, keep]
        out.append((k * np.maximum(d, 0.0) ** 1.5).T)
    return np.vstack(out)


def test_reference_agrees_with_an_independent_dop853_chain():
    rtol = 1e-6
    n, f0, a, f = 6, 10.0, 1.0, 8e3
    text = make_scene_text(
        beads=n,
        law="hertz",
        loading=drive_text(amplitude=a, frequency=f, length="cycles = 2", ramp=1.5),
        end_time=3.5e-4,
        timestep=1e-8,
        outputs=f"histories = [{', '.join(str(i) for i in range(1, n))}]\n",
    )
    sc = parse_scene(text + "\n[precompression]\nforce = 10.0\n", source="dop853.toml")
    planned = plan_scene(sc, rtol=rtol, method="rk4").scene
    sol = run_reference(planned, "rk4").solution
    t_drive, t_ramp = 2 / f, 1.5 / f
    oracle = dop853_histories(n, f0, a, f, t_ramp, t_drive, np.asarray(sol.history_time))
    # the run's rtol bounds its peaks against the dynamic force scale (the rise above F0): its histories
    # (the same integration, sampled) within a few times that
    scale = np.max(np.abs(oracle - f0))
    err = np.max(np.abs(np.asarray(sol.history_force) - oracle))
    print(f"max |F_ref - F_dop853| = {err:.3g} N on a dynamic scale of {scale:.3g} N")
    assert err <= 5.0 * rtol * scale
    assert scale > 0.5 * a  # the drive moved the chain


# ---- (c) the force the deck and the reference apply is the formula; the ramp starts smoothly


def lammps_values(formulas: list[tuple[str, float]], tmp: Path) -> list[float]:
    """Each (formula of v_t, t) evaluated by LAMMPS itself: one plain `lmp` run of print commands."""
    lines = []
    for k, (formula, t) in enumerate(formulas):
        lines += [f"variable t equal {t!r}", f'variable f equal "{formula}"', f'print "VALUE {k} $(v_f:%.17g)"']
    deck = tmp / "formulas.in"
    deck.write_text("\n".join(lines) + "\n")
    lmp = Path(sys.executable).with_name("lmp")
    out = subprocess.run([str(lmp), "-in", str(deck), "-log", "none", "-nocite"], capture_output=True, text=True)
    found = dict(re.findall(r"^VALUE (\d+) (\S+)$", out.stdout, re.M))
    assert len(found) == len(formulas), out.stdout[-2000:] + out.stderr[-2000:]
    return [float(found[str(k)]) for k in range(len(formulas))]


def deck_formula(deck: str, name: str) -> str:
    return re.search(rf'^variable\s+{name}\s+equal\s+"(.*)"$', deck, re.M).group(1)


drives = st.tuples(
    st.floats(1e-3, 1e3),  # amplitude, N
    st.floats(1e2, 1e5),  # frequency, Hz
    st.floats(0.5, 20.0),  # cycles
    st.one_of(st.just(0.0), st.floats(2e-3, 1.0)),  # ramp, as a fraction of the cycles (>= 1e-3 periods)
    # the time, as a fraction of T (t = 0, or at least 1e-9 T: LAMMPS's number parser refuses subnormal
    # numbers, std::stod, which a run's time never is)
    st.one_of(st.just(0.0), st.floats(1e-9, 1.2)),
)


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(drives, min_size=5, max_size=20))
def test_applied_force_equals_the_formula(tmp_path, cases):
    checks = []
    for a, f, cycles, ramp_part, when in cases:
        ramp = ramp_part * cycles
        t_drive, t_ramp = cycles / f, ramp / f
        text = driven(
            amplitude=a,
            frequency=f,
            length=f"cycles = {cycles!r}",
            ramp=ramp,
            end_time=1.5 * t_drive,
            timestep=t_drive / 100,
        )
        sc = parse_scene(text + "\n[precompression]\nforce = 10.0\n", source="p.toml")
        t = when * t_drive
        want = float(oracle_force(t, a, f, t_ramp, t_drive))
        # the reference's load (ChainProblem.load_force inside (0, T], 0 outside: the solver's loaded segments)
        p = ChainProblem.from_scene(sc)
        got = float(p.load_force(t)) if 0 < t <= t_drive else 0.0
        assert got == pytest.approx(want, abs=1e-9 * a)
        if 0 < t <= t_drive:  # the deck's fix addforce formula, for LAMMPS to evaluate at t
            checks.append((deck_formula(render_deck(sc).deck, "drive").replace("time", "v_t"), t, want, a))
        # the delivered impulse the results report: the integral of the formula up to min(t, T)
        upto = min(t, t_drive)
        pts = [t_ramp] if 0 < t_ramp < upto else None  # (the ramp's end: where the integrand's form changes)
        args = (a, f, t_ramp, t_drive)
        impulse = quad(oracle_force, 0, upto, args=args, points=pts, limit=500, epsabs=1e-16)[0]
        assert float(p.load_impulse(t)) == pytest.approx(impulse, abs=1e-7 * a / f)
    if checks:
        values = lammps_values([(formula, t) for formula, t, _, _ in checks], tmp_path)
        for (_, _, want, a), value in zip(checks, values, strict=True):
            assert value == pytest.approx(want, abs=1e-9 * a)


@settings(max_examples=30, deadline=None)
@given(st.floats(1e2, 1e5), st.floats(0.25, 5.0))
def test_the_ramp_is_continuous_with_zero_slope_at_both_ends(f, ramp):
    text = driven(frequency=f, length=f"cycles = {ramp + 2.0!r}", ramp=ramp, end_time=(ramp + 2) / f)
    p = ChainProblem.from_scene(parse_scene(text, source="r.toml"))
    a, tr = p.amplitude, ramp / f
    env = lambda t: float(p.load_force(t)) / (a * math.sin(2 * math.pi * f * t))  # noqa: E731 - r(t)
    for h in (1e-3 * tr, 1e-4 * tr):
        assert abs(env(h)) <= 3.0 * (h / tr) ** 2  # r(h) = (pi h / 2 t_r)^2 + ...: zero value, zero slope
        assert abs(env(tr - h) - 1.0) <= 3.0 * (h / tr) ** 2  # and it meets 1 with zero slope at t_r
        assert abs(float(p.load_force(h))) <= 20.0 * a * f * h * (h / tr) ** 2  # as A 2 pi f t (pi t / 2 t_r)^2


# ---- the planner: the drive's length and the chain's transit; F0 + 3 A


def test_bundled_scene_plan_ends_after_the_drive_and_its_transit():
    sc = load_scene("harmonic-precompressed-chain")
    plan = plan_scene(sc, rtol=1e-3, method="rk4")
    ld, f0 = sc.loading, sc.effects.precompression
    k = hertz_k()
    k_lin = 1.5 * k ** (2 / 3) * f0 ** (1 / 3)  # field-physics: the linearised Hertz stiffness at F0
    m = BRASS["rho"] * 4 / 3 * math.pi * R**3
    f_c = math.sqrt(k_lin / m) / math.pi
    assert ld.frequency < f_c  # the scene drives below its cutoff
    sonic = sc.n_contacts * math.sqrt(m / k_lin)  # the fastest signal's transit (c0 = D sqrt(k_lin / m))
    transit = plan.scene.run.end_time - ld.duration
    assert sonic <= transit <= 3.0 * sonic
    assert plan.scene.run.stop_after_contact is None  # no stop check under a drive
    assert contact_force_bound(sc) == pytest.approx(f0 + 3.0 * ld.amplitude)


# ---- (d) every refusal names its field and the fix


@pytest.mark.parametrize(
    ("drive", "words"),
    [
        (drive_text(frequency=0.0), ("frequency", "> 0")),
        (drive_text(frequency=-5.0), ("frequency", "> 0")),
        (drive_text(amplitude=0.0), ("amplitude", "> 0")),
        (drive_text(amplitude=-1.0), ("amplitude", "> 0")),
        (drive_text(length="cycles = 3\nduration = 1e-3"), ("cycles", "duration", "remove one")),
        (drive_text(length=""), ("cycles", "duration", "add one")),
        (drive_text(length="cycles = 0"), ("cycles", "> 0")),
        (drive_text(length="duration = -1e-3"), ("duration", "> 0")),
        (drive_text(length="cycles = 3", ramp=4.0), ("ramp", "at most the drive's length", "shorten the ramp")),
        (drive_text(ramp=-1.0), ("ramp", ">= 0")),
        (drive_text(ramp=1e-300), ("ramp", "write 0")),
        (drive_text() + "velocity = 1.0\n", ("velocity", "not allowed", "frequency")),
    ],
)
def test_bad_drives_are_refused_with_one_clear_message(drive, words):
    text = make_scene_text(beads=12, loading=drive, end_time=2e-4, timestep=2e-8)
    with pytest.raises(GranchainError) as info:
        parse_scene(text, source="bad.toml")
    msg = str(info.value)
    assert "\n" not in msg
    assert "bad.toml" in msg
    assert "[loading]" in msg
    for w in words:
        assert w in msg, (w, msg)


def test_a_stop_check_is_refused_under_a_drive():
    text = driven().replace("[outputs]", "stop_after_contact = 3\n[outputs]")
    with pytest.raises(GranchainError, match=r"stop_after_contact.*harmonic.*remove it"):
        parse_scene(text, source="stop.toml")


def test_leading_pulse_observables_are_not_applicable_with_a_reason():
    sc = load_scene("harmonic-precompressed-chain")
    res = run_reference(plan_scene(sc, rtol=1e-2, method="rk4").scene, "rk4")
    obs = res.observables()
    for name in ("leading_peak_force", "wave_speed", "leading_pulse_decay_length"):
        assert obs[name] is None
    assert res.observables_missing()["leading_peak_force"].startswith("a harmonic drive")
    assert obs["max_peak_force"] > 0
