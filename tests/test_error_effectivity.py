"""Error bars that are printed as reliable hold within 1/3-3 of the true error on generated chains.

The true error is the distance to the same run at dt / 16. A bar marked unreliable is exempt, but
its status must say why; a "round-off" status is a bound, not an estimate (its own tests:
tests/test_precompressed_error_bars.py).
"""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, example, given, reject, settings

from granchain.invariants import InvariantError
from granchain.richardson import checked, richardson
from granchain.scene import parse_scene
from granchain.workflows.error_estimates import roundoff_floor
from granchain.workflows.run import plan_for, run_scene

from .test_varied_chains import varied_chains

#: the bar every estimate given must meet: estimated / true error within [1 / BAR, BAR]
BAR = 3.0

# Two draws of varied_chains (reference RK4, planned for rtol 1e-3) whose bars missed before the check
# at dt / 2 (richardson.checked). A 37-bead chain of random radii: contact 27's estimate was 0.21 of
# the true error (the runs at dt, 2 dt and 4 dt showed order 3.9; between dt and 2 dt the error went
# as order 2.1, a Hertzian onset's). A 34-bead precompressed one: four estimates 3.2-3.8 of the true
# error (the runs showed order 4.7-4.8 and the nominal 4 was used; below dt the error rose to order
# 5.8 and changed sign between dt and dt / 2).
MIXED_ORDER_UNDER = """
[chain]
beads = 37
radius = [
    0.0038420261307388175, 0.005456216659390767, 0.005523039806131322, 0.0025875893225723525, 0.0035299461352369978,
    0.002, 0.003348908391115033, 0.002, 0.003949794583860923, 0.0035058918543672993,
    0.0037572481192968774, 0.005259224981336776, 0.0022728619412464113, 0.002, 0.005003744904783218,
    0.005828317506800196, 0.0036519301616289197, 0.005933174650051088, 0.005283209144160455, 0.003406726907740053,
    0.003003102306966581, 0.003345948290193474, 0.002, 0.0035665275045739693, 0.004538830412243502,
    0.0032648834090207315, 0.004134329881815684, 0.002, 0.003920904542801052, 0.004117746502467174,
    0.0022846123646951154, 0.002, 0.002, 0.0024952385223600652, 0.005728058116577811,
    0.002, 0.005881292346951602,
]
material = "brass"

[contact]
law = "hertz"

[loading]
kind = "velocity"
velocity = 1.020392457530312

[run]
end_time = 0.0007528053530303202
timestep = 3.8632591278184586e-07
stop_after_contact = 27

[outputs]
peak_force = true
"""


MIXED_ORDER_OVER = """
[chain]
beads = 34
radius = [
    0.003770529949656049, 0.0024237958522583085, 0.004429920868091269, 0.00492201026466298, 0.002,
    0.003490769179431837, 0.005692983507107327, 0.002831714345570215, 0.002, 0.0034364128808278436,
    0.0045172751737088904, 0.0023170719648716383, 0.005296377356878976, 0.0029994918134513835, 0.002462677049177118,
    0.005042687769379317, 0.0021616717109148257, 0.006, 0.005287733478524563, 0.005652691933197411,
    0.002522912133110843, 0.002, 0.002016749950541204, 0.0020775469572419125, 0.004284181822308144,
    0.005659705144293734, 0.005729768601438239, 0.005003172965958667, 0.002, 0.002,
    0.005730858337870966, 0.0023156171374431483, 0.004229670043709855, 0.002259194588524955,
]
material = "brass"

[contact]
law = "hertz"

[loading]
kind = "velocity"
velocity = 1.9677207953229825

[run]
end_time = 0.0006028732883893689
timestep = 3.3949247900801587e-07
stop_after_contact = 24

[outputs]
peak_force = true

[precompression]
force = 0.5953663669167155
"""

# A draw this test found: contact 17's estimate 0.326 of the distance to dt / 16 (1.43e-10 N of 33 N),
# with that run's own round-off 5.6e-11 (roundoff_floor; the runs at dt / 2, dt / 4, dt / 8 are 8.0e-11,
# 6.7e-11, 4.8e-11 from it): the true error is known to 1.43e-10 +- 5.6e-11 only, and the estimate
# (4.65e-11) is within 1/3-3 of part of that band. A bar fails where it misses every true error the
# truth's round-off allows (_outside)
TAPER_CHECKED_TOO_LOOSELY = """
[chain]
beads = 37
radius = 4.76e-3
taper = 0.8941606373497608
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = 0.99999
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
[precompression]
force = 0.4405448307179362
"""


def _true_and_estimated(sc):
    """(the run, its distance to dt / 16, that run's round-off, which peaks the distance is known for)
    of a scene run with reference RK4 and its error bars."""
    try:
        got = run_scene(sc, backend="reference", method="rk4", error_estimate="checked")
    except InvariantError as e:
        # a draw the run watch stops has no bars to check (a steep taper under a fast kick was, before
        # the watch held each contact to its own radii: test_varied_chains)
        if "overlap far below the radius" not in str(e):
            raise
        reject()
    finer = replace(sc, run=replace(sc.run, timestep=sc.run.timestep / 16))
    fine = run_scene(finer, backend="reference", method="rk4")
    a, b = got.solution, fine.solution
    true = np.abs(a.peak_force - b.peak_force)
    # known above the finer run's own round-off (1e3 ulps, and its floor: roundoff_floor)
    floor = roundoff_floor(fine.scene, b)
    floor = np.zeros_like(true) if floor is None else np.nan_to_num(floor)
    known = a.complete & b.complete & (true > np.maximum(1e3 * np.spacing(np.abs(a.peak_force)), floor))
    return got, true, floor, known


def _outside(estimate: float, true: float, floor: float) -> bool:
    """Whether an estimate misses 1/3-3 of every true error within the truth's round-off (true +- floor)."""
    return estimate > BAR * (true + floor) or estimate < (true - floor) / BAR


@pytest.mark.slow
# (no shrinking: a draw costs the run 19.75 times over, and a failing one is printed as drawn; CI's
# profile fixes the draws, conftest.py)
@settings(
    max_examples=1,  # (and the three explicit examples: each draw costs about 20 runs; CI's time budget)
    deadline=None,
    suppress_health_check=list(HealthCheck),
    phases=(Phase.explicit, Phase.reuse, Phase.generate),
)
@given(sc=varied_chains())
@example(sc=parse_scene(MIXED_ORDER_UNDER, source="mixed-under.toml"))
@example(sc=parse_scene(MIXED_ORDER_OVER, source="mixed-over.toml"))
@example(sc=parse_scene(TAPER_CHECKED_TOO_LOOSELY, source="taper.toml"))
def test_every_reliable_rk4_bar_holds_on_varied_chains(sc):
    planned, _ = plan_for(sc, "reference", "rk4", 1e-3)
    planned = replace(
        planned,
        outputs=replace(planned.outputs, histories=(), snapshots=(), history_interval=None, dump_interval=None),
    )
    got, true, floor, known = _true_and_estimated(planned)
    est = got.errors.peak_force
    assert est is not None, got.errors.why_none
    measured = got.solution.complete
    for i in np.flatnonzero(measured & ~est.reliable):  # marked: it must say why
        status = str(est.status[i])
        assert status.startswith(("unreliable: ", "not measured: ")), f"contact {i + 1}: {status}"
        assert len(status.split(": ", 1)[1]) > 10, f"contact {i + 1}: {status}"
    given_ = known & est.reliable & (est.status != "round-off")
    ratio = est.error[given_] / true[given_]
    outside = [
        f"contact {i + 1}: {est.error[i] / true[i]:.3g} ({est.status[i]}; true {true[i]:.3g} +- {floor[i]:.2g})"
        for i in np.flatnonzero(given_)
        if _outside(est.error[i], true[i], floor[i])
    ]
    assert not outside, f"{ratio.size} bars given, outside 1/3-3: {outside}"


def _sequence(errors, exact=100.0):
    """Peak forces at dt / 2, dt, 2 dt, 4 dt with these errors (one item each)."""
    return [np.array([exact + e]) for e in errors]


def test_a_check_at_half_the_step_marks_an_order_that_drops_below_dt():
    """Errors of one RK4 peak as measured on a varied chain (contact 9 of a walled 39-bead chain of
    random materials): order 4.75 over dt, 2 dt, 4 dt, 2.2 below dt. Richardson's estimate from the
    three runs is 0.25 of the true error; the run at dt / 2 shows the drop and the bar is withheld."""
    h, f, c, cc = _sequence([-3.72e-6, -1.91e-5, -9.08e-5, -2.04e-3])
    bars = richardson(f, c, cc, 4, orders=(2.5, 4.0))
    assert bars.error[0] / 1.91e-5 < 1 / BAR  # the three runs alone miss
    out = checked(bars, h, f, c, 4, orders=(2.5, 4.0))
    assert not out.reliable[0]
    assert out.status[0].startswith("unreliable: ")
    assert "dt / 2" in out.status[0]


def test_a_check_at_half_the_step_keeps_a_clean_sequence():
    """A clean order-4 error (and one of order 2.5, RK4's onsets): the run at dt / 2 confirms the bar,
    which stays as it was."""
    for q in (4.0, 2.5):
        h, f, c, cc = _sequence([1e-6 * 2.0 ** (q * k) for k in (-1, 0, 1, 2)])
        bars = richardson(f, c, cc, 4, orders=(2.5, 4.0))
        out = checked(bars, h, f, c, 4, orders=(2.5, 4.0))
        assert out.reliable[0]
        assert out.error[0] == bars.error[0]
        assert out.error[0] / 1e-6 == pytest.approx(1.0, rel=1e-6)


def test_a_check_at_half_the_step_marks_a_sign_change_below_dt():
    """The error changes sign between dt and dt / 2 (the 34-bead draw above, contact 13): with the
    three runs' order 4.8 the estimate was 3.8 times the true error; the check withholds it."""
    h, f, c, cc = _sequence([4.64e-7, -1.95e-6, -1.12e-4, -3.13e-3])
    bars = richardson(f, c, cc, 4, orders=(2.5, 4.0))
    assert bars.error[0] / 1.95e-6 > BAR
    out = checked(bars, h, f, c, 4, orders=(2.5, 4.0))
    assert not out.reliable[0]
    assert "dt / 2" in out.status[0]


SMALL_CHAIN = """
[chain]
beads = 8
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.05
duration = 2e-6
[run]
end_time = 4e-5
timestep = "auto"
[outputs]
peak_force = true
"""


def test_the_check_at_half_the_step_is_run_only_when_asked_for():
    """By default RK4's bars cost their two companions (2 dt, 4 dt: 3/4 of the run); "checked" adds
    the run at dt / 2; any other value is refused before a run."""
    from granchain.exceptions import GranchainError
    from granchain.scene import parse_scene

    sc = parse_scene(SMALL_CHAIN, source="small.toml")
    plain = run_scene(sc, backend="reference", method="rk4", error_estimate=True).errors
    assert plain.check_timestep is None
    assert len(plain.timesteps) == 2
    assert "--error-estimate checked" in plain.why_unchecked  # unchecked bars say so, and how to check them
    got = run_scene(sc, backend="reference", method="rk4", error_estimate="checked")
    assert got.errors.check_timestep == pytest.approx(0.5 * got.scene.run.timestep, rel=1e-12)
    assert got.errors.why_unchecked is None
    with pytest.raises(GranchainError, match="error_estimate"):
        run_scene(sc, backend="reference", method="rk4", error_estimate="yes")


def test_a_check_asked_of_verlet_says_why_it_is_not_made():
    """The check at dt / 2 is RK4's: asked of a Verlet run (Richardson on a Hertz chain) it makes no run at
    dt / 2, and the report says why rather than passing for checked. (On a kinked law "checked" measures
    Verlet's error against RK4 runs: test_kinked_error_bars.)"""
    from granchain.scene import parse_scene

    sc = parse_scene(SMALL_CHAIN, source="small-hertz.toml")
    plain = run_scene(sc, backend="reference", method="verlet", error_estimate=True).errors
    got = run_scene(sc, backend="reference", method="verlet", error_estimate="checked").errors
    assert plain.why_unchecked is None
    assert got.check_timestep is None
    assert got.timesteps == plain.timesteps
    assert "RK4" in got.why_unchecked
    assert got.summary(1.0)["why_unchecked"] == got.why_unchecked


def test_compare_refuses_a_bad_error_estimate_before_any_run(monkeypatch):
    """compare checks error_estimate before it plans, builds or runs anything."""
    from granchain.exceptions import GranchainError
    from granchain.workflows import compare_backends

    def no_run(*a, **k):
        raise AssertionError("a run started")

    monkeypatch.setattr(compare_backends, "plan_for", no_run)
    with pytest.raises(GranchainError, match="error_estimate"):
        compare_backends.compare_scene(parse_scene(SMALL_CHAIN, source="small.toml"), error_estimate="on")
