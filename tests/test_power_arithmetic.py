"""The power law's numpy twin takes the C++ kernel's arithmetic (granchain/lammps/law_power.h), through LAMMPS.

chain/power computes alpha^n without pow where n is whole or half-whole (sqrt(alpha) or 1, times 1,
alpha, alpha^2 or alpha^2 alpha) and its tangent as n F / alpha from the force (no second pow: the
Kuwabara-Kono part's). The twin (PowerLaw.power, PowerLaw.damping_tangent) takes the same operations
in the same order, so on the overlaps LAMMPS works with (d0 - |x_i - x_j|, read back from its positions)
both give the same doubles: the force of every contact (d_fc after ``run 0``) and its Kuwabara-Kono
total, with velocities set on the beads and the overlap rate formed as the pair loop forms it. For an
exponent that is neither, both call pow: equal up to the libm's, asserted to 4 ulp (1e-15).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.physics.damping import DAMPING
from granchain.physics.laws.power import PowerLaw

from .test_kernels import new_lammps, num

#: (1,1), (2,2), (1,2) type pairs' exponents in each run: whole, half-whole and neither
EXPONENT_SETS = ((1.0, 1.5, 2.0), (2.5, 3.0, 1.3), (1.7, 2.2, 2.9))
PAIRS = ((1, 1), (2, 2), (1, 2))
D0 = {(1, 1): 0.0095, (2, 2): 0.0105, (1, 2): 0.01}
A_KK = 1e-6  # s, the Kuwabara-Kono constant
K_AT = 1e3  # N: each pair's K makes its force 1e3 N at the overlap 1e-5 m
ALPHA0 = 1e-5


def products_only(n: float) -> bool:
    """Whether the kernel computes alpha^n without pow (n whole or half-whole)."""
    return 2.0 * n == math.floor(2.0 * n)


def run_chain(exponents, velocities: bool):
    """A chain of the three type pairs' contacts at a grid of overlaps around ALPHA0, with random bead
    velocities and Kuwabara-Kono damping where `velocities`; ``run 0``. Returns each contact's type-pair
    index, the overlap LAMMPS works with, the overlap rate as its pair loop forms it, and d_fc."""
    grid = ALPHA0 * np.geomspace(1e-3, 3.0, 14)
    pair_index = np.repeat([0, 2, 1], [grid.size, grid.size + 1, grid.size])  # 1-1, then 1-2 / 2-1, then 2-2
    alpha_target = np.concatenate([grid, np.append(grid, grid[-1]), grid])
    types = [1] * (grid.size + 1) + [2 if i % 2 == 0 else 1 for i in range(grid.size + 1)] + [2] * grid.size
    d0 = np.array([D0[PAIRS[p]] for p in pair_index])
    x = np.concatenate([[0.0], np.cumsum(d0 - alpha_target)])
    x -= 0.5 * x[-1]
    rng = np.random.default_rng(41)
    v = rng.uniform(-3.0, 3.0, x.size) if velocities else np.zeros(x.size)
    style = f"chain/power kuwabara_kono {num(A_KK)}" if velocities else "chain/power"
    lmp = new_lammps()
    try:
        cmds = [
            "units si",
            "atom_style sphere",
            "atom_modify map array",
            "boundary f p p",
            "newton off",
            "comm_modify vel yes",
            f"region box block {num(x[0] - 0.05)} {num(x[-1] + 0.05)} -0.05 0.05 -0.05 0.05 units box",
            "create_box 2 box",
            *(f"create_atoms {t} single {num(xi)} 0.0 0.0 units box" for t, xi in zip(types, x, strict=True)),
            *(f"set atom {i + 1} vx {num(vi)}" for i, vi in enumerate(v)),
            "fix contact all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak d_fmin d_edash ghost yes",
            f"pair_style {style}",
            *(
                f"pair_coeff {i} {j} {num(K_AT / ALPHA0**n)} {num(D0[(i, j)])} {num(n)}"
                for (i, j), n in zip(PAIRS, exponents, strict=True)
            ),
            "neighbor 0.001 bin",
            "run 0",
        ]
        lmp.commands_list(cmds)
        order = np.argsort(lmp.numpy.extract_atom("id").astype(int))
        xs = np.array(lmp.numpy.extract_atom("x"), dtype=float)[order, 0]
        vs = np.array(lmp.numpy.extract_atom("v"), dtype=float)[order, 0]
        fc = np.array(lmp.numpy.extract_atom("d_fc"), dtype=float)[order][: pair_index.size]
    finally:
        lmp.close()
    delx = xs[:-1] - xs[1:]
    r = np.abs(delx)
    alpha = d0 - r
    assert np.allclose(alpha, alpha_target, rtol=1e-6)
    rate = -(delx * (vs[:-1] - vs[1:])) / r  # the pair loop's; the same for either order of the pair
    return pair_index, alpha, rate, fc


def twin(exponents, pair_index) -> PowerLaw:
    """The twin with each contact's type pair's K and n."""
    n = np.array([exponents[p] for p in pair_index])
    return PowerLaw(k=K_AT / ALPHA0**n, exponent=n)


def assert_same(cpp, numpy_, n):
    """Bit for bit where the exponent takes products only; within 4 ulp where both call pow."""
    exact = np.array([products_only(e) for e in n])
    assert np.array_equal(cpp[exact], numpy_[exact])
    assert np.all(np.abs(cpp - numpy_) <= 1e-15 * np.abs(numpy_))


@pytest.mark.parametrize("exponents", EXPONENT_SETS)
def test_the_twin_force_is_the_kernels(exponents):
    pair_index, alpha, _, fc = run_chain(exponents, velocities=False)
    law = twin(exponents, pair_index)
    assert np.all(fc > 0.0)
    assert_same(fc, law.force(alpha), np.asarray(law.exponent))
    # and one exponent for every contact (the scalar path) takes the same products
    for p, n in enumerate(exponents):
        mine = pair_index == p
        one = PowerLaw(k=K_AT / ALPHA0**n, exponent=n)
        out, tmp = np.empty(mine.sum()), np.empty(mine.sum())
        one.force_into(alpha[mine], None, out, tmp)
        assert_same(fc[mine], one.force(alpha[mine]), np.full(mine.sum(), n))
        assert_same(fc[mine], out, np.full(mine.sum(), n))


@pytest.mark.parametrize("exponents", EXPONENT_SETS)
def test_the_twin_kuwabara_kono_total_is_the_kernels(exponents):
    pair_index, alpha, rate, fc = run_chain(exponents, velocities=True)
    law = twin(exponents, pair_index)
    elastic = law.force(alpha)
    total = DAMPING["kuwabara_kono"].damped_force(A_KK, law, alpha, None, rate, elastic)
    assert np.any(total == 0.0)  # clipped contacts
    assert np.any(total > 1.5 * elastic)  # and strongly damped ones
    # the same doubles wherever the elastic force is (n F / alpha on both sides: no pow of its own)
    exact = np.array([products_only(e) for e in np.asarray(law.exponent)])
    assert np.array_equal(fc[exact], total[exact])
    assert np.all(np.abs(fc - total) <= 1e-14 * (np.abs(total) + elastic))


@settings(max_examples=200, deadline=None)
@given(
    n=st.one_of(st.sampled_from([1.0, 1.5, 2.0, 2.5, 3.0]), st.floats(1.0, 3.0)),
    alpha=st.lists(st.floats(1e-12, 1e-2), min_size=1, max_size=8),
)
def test_the_twins_products_and_tangent_are_the_power_law(n, alpha):
    """power(alpha) is alpha^n and damping_tangent n k alpha^(n-1) (overlap_tangent), to rounding; apart 0.

    Rounding: the products round up to three times (sqrt, alpha^2, the last product: 1.5 ulp) against
    pow's half ulp, so 1e-15 (4.5 ulp); n F / alpha rounds four times and F's power up to 3 ulp, n k
    alpha^(n-1) three times (5 ulp in all), so 2e-15 (9 ulp)."""
    a = np.array(alpha)
    law = PowerLaw(k=1e9, exponent=n)
    assert np.allclose(law.power(a), a**n, rtol=1e-15, atol=0.0)
    f = law.force(a)
    assert np.allclose(law.damping_tangent(a, None, f), law.overlap_tangent(a), rtol=2e-15, atol=0.0)
    zero = np.array([0.0, -1e-9])
    assert np.array_equal(law.damping_tangent(zero, None, law.force(zero)), [0.0, 0.0])
