"""RK4 references take their own error at the scene's onset order, 1 + n of its law, not Hertz's 2.5.

A Verlet run measured against RK4 runs at h and 2 h adds the references' own error |r - r_c| /
(2^q - 1), q RK4's lowest order on the chain: where a contact closes under F = K alpha^n its error
goes as dt^(1 + n) (ContactLaw.onset_order). A fixed 2.5 held that for Hertzian
onsets only; a law of another exponent gets its own (workflows.errorbars.facts.reference_order).
"""

import numpy as np
import pytest

from granchain.integrators import RK4
from granchain.scene import scene_from_dict
from granchain.workflows.errorbars.bars import against_rk4_bars, per_contact
from granchain.workflows.errorbars.facts import companion_scene, reference_order
from granchain.workflows.errorbars.report import ErrorReport
from granchain.workflows.run import run_scene

from .conftest import LAW_NAMES, make_scene

RADIUS = 4.76e-3


def power_chain(n: float, beads: int = 8):
    """A brass chain on F = K alpha^n, K the Hertz force at an overlap of 1e-5 R (brass-like), kicked."""
    a = 1e-5 * RADIUS
    k = 1.3e10 * np.sqrt(RADIUS / 2) * a**1.5 / a**n
    return scene_from_dict(
        {
            "chain": {"beads": beads, "radius": RADIUS, "material": "brass"},
            "contact": {"law": "power", "exponent": n, "stiffness": k},
            "loading": {"kind": "velocity", "velocity": 0.3},
            "run": {"end_time": "auto", "timestep": "auto"},
            "outputs": {"peak_force": True},
        },
        source="power.toml",
    )


@pytest.mark.parametrize("n", [1.2, 2.5, 3.0])
def test_the_reference_order_is_the_laws_onset_order_at_most_rk4s(n):
    """1 + n of the power law's exponent, at most RK4's order 4."""
    assert reference_order(power_chain(n)) == pytest.approx(min(1.0 + n, RK4.order), rel=1e-15)


@pytest.mark.parametrize("law", LAW_NAMES)
def test_every_law_has_a_reference_order_between_its_onset_and_rk4s(law):
    """The registered laws' (2.5 for the Hertzian onsets and the bilinear loading line)."""
    sc = make_scene(law=law)
    assert reference_order(sc) == min(sc.law.onset_order(), RK4.order)
    assert 2.0 <= reference_order(sc) <= RK4.order


@pytest.mark.parametrize("n", [1.2, 2.5])
def test_a_power_chains_rk4_references_take_their_own_error_at_its_onset_order(n):
    """The bars against RK4 runs at 2 dt and 4 dt on a power chain: |v - r| + |r - r_c| / (2^(1 + n) - 1)
    for every contact that has one (before: 2^2.5 - 1 whatever n)."""
    sc = power_chain(n)
    result = run_scene(sc, method="verlet")
    runs = [run_scene(companion_scene(result.scene, f), method="rk4").solution for f in (2.0, 4.0)]
    report = ErrorReport(order=2, timesteps=[], wall_times=[], against="rk4")
    against_rk4_bars(report, result, runs)
    v, r, rc = per_contact((result.solution, *runs), "peak_force", len(result.solution.peak_force), True)
    expected = np.abs(v - r) + np.abs(r - rc) / (2.0 ** (1.0 + n) - 1.0)
    ok = report.peak_force.reliable
    assert ok.sum() >= 3
    np.testing.assert_allclose(report.peak_force.error[ok], expected[ok], rtol=1e-12)
    # the references' own error matters here: at Hertz's 2.5 the bars would differ
    hertz = np.abs(v - r) + np.abs(r - rc) / (2.0**2.5 - 1.0)
    assert np.max(np.abs(hertz[ok] / expected[ok] - 1.0)) > 1e-6


def test_against_reference_has_no_default_order():
    """A caller must pass its scene's onset order: a default would be Hertz's 2.5 for every law."""
    from granchain.richardson import against_reference

    with pytest.raises(TypeError, match="order"):
        against_reference([1.0], [1.0], [1.0])
