"""Every registered damping part (granchain.physics.damping.DAMPING) keeps the rules of damping/base.py,
and every law's tangent of the branch in force (ContactLaw.overlap_tangent, which Kuwabara-Kono reads) is
the slope of that branch (hypothesis over the laws' parameter ranges, overlaps and histories)."""

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import granchain.lammps
from granchain.lammps import build
from granchain.physics.damping import DAMPING, damping_keys
from granchain.scene import SceneError, parse_scene

from .conftest import make_scene_text
from .test_laws import LAW_NAMES, law_and_state

PARTS = sorted(DAMPING)


def test_the_registry_is_the_only_list():
    assert list(DAMPING)[0] == "none"
    assert not DAMPING["none"].velocity_dependent
    for name, part in DAMPING.items():
        assert part.name == name
        header = Path(granchain.lammps.__file__).parent / build.damping_header(name)
        assert header.is_file(), header
        assert f"struct {build.damping_kernel(name)} " in header.read_text()
        assert build.damping_header(name) in build.SOURCES
        if part.key:
            assert part.velocity_dependent, name  # (a part without a rate would be a law)
            assert part.dissipated_vectors, name
            assert part.label == f"[damping] {part.key}"
            assert part.pair_style_args(part.example).split()[0] in header.read_text()


@pytest.mark.parametrize("key", sorted(damping_keys()))
def test_each_part_is_read_and_written_back(key):
    part = damping_keys()[key]
    sc = parse_scene(make_scene_text() + f"[damping]\n{key} = {part.example!r}\n", source="d.toml")
    assert sc.damping is part
    assert sc.damping_coefficient == part.example
    assert parse_scene(sc.to_toml(), source="again.toml").effects == sc.effects
    for other in damping_keys():
        if other != key:
            text = make_scene_text() + f"[damping]\n{key} = {part.example!r}\n{other} = 1.0\n"
            with pytest.raises(SceneError, match=r"\[damping\] .* is not allowed here: one damping part per scene"):
                parse_scene(text, source="both.toml")


@settings(max_examples=60, deadline=None)
@given(
    part=st.sampled_from(PARTS),
    data=st.data(),
)
def test_the_damped_force_never_pulls_and_is_the_law_at_rest(part, data):
    cls = DAMPING[part]
    law, amax, frac = data.draw(law_and_state(data.draw(st.sampled_from(LAW_NAMES))))
    alpha = np.array([max(frac * amax, 1e-9), amax if amax > 0 else 2e-9])
    elastic = law.force(alpha, np.array([amax, amax]))
    rate = np.array(data.draw(st.lists(st.floats(-10.0, 10.0), min_size=2, max_size=2)))
    coefficient = cls.example
    total = cls.damped_force(coefficient, law, alpha, np.array([amax, amax]), rate, elastic)
    assert np.all(total >= 0.0)
    assert np.array_equal(
        cls.damped_force(coefficient, law, alpha, np.array([amax, amax]), 0.0 * rate, elastic), elastic
    )
    # closing adds force, opening takes it away (until the clip)
    assert np.all((total >= elastic) == (rate >= 0.0) | (total == elastic))


@settings(max_examples=80, deadline=None)
@given(name=st.sampled_from(LAW_NAMES), data=st.data())
def test_the_overlap_tangent_is_the_slope_of_the_branch_in_force(name, data):
    """Loading (alpha at the history): the virgin curve's slope; un/reloading (alpha below it, history
    fixed): the slope of force(., alpha_max); by central differences, to 1e-4."""
    law, amax, frac = data.draw(law_and_state(name))
    if amax <= 0.0:
        amax = 1e-6
    h = 1e-7 * amax
    loading = float(law.overlap_tangent(np.array([amax]), np.array([amax]))[0])
    slope = (float(law.loading_force(amax + h)) - float(law.loading_force(amax - h))) / (2 * h)
    assert loading == pytest.approx(slope, rel=1e-4, abs=1e-12 * abs(slope) + 1e-300)
    a = max(frac, 0.05) * amax * 0.99
    hist = np.array([amax])
    unload = float(law.overlap_tangent(np.array([a]), hist)[0])
    f_hi, f_lo = (float(law.force(np.array([a + s * h]), hist)[0]) for s in (1.0, -1.0))
    if f_hi > 0.0 and f_lo > 0.0:  # (not at the unloading curve's zero, its kink)
        assert unload == pytest.approx((f_hi - f_lo) / (2 * h), rel=1e-4)
    assert float(law.overlap_tangent(np.array([0.0]), hist)[0]) >= 0.0
    assert math.isfinite(unload)
