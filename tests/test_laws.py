"""Every registered contact law (granchain.physics.laws.LAWS) keeps the rules of laws/base.py, for
every parameter set in its ranges and every overlap and history (hypothesis)."""

import dataclasses
import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.physics.laws import LAWS, LawCoefficients, ThorntonLaw, contact_keys
from granchain.physics.laws.base import ContactLaw
from granchain.physics.laws.bilinear import bilinear_dissipated, bilinear_energy, bilinear_force, unloading_stiffness
from granchain.physics.laws.hertz import hertz_energy, hertz_force
from granchain.physics.models import dissipation_per_cycle

LAW_NAMES = sorted(LAWS)


def law_strategy(name):
    cls = LAWS[name]
    fields = [f.name for f in dataclasses.fields(cls)]
    lo_hi = cls.parameter_ranges
    assert set(lo_hi) == set(fields), f"{name}: parameter_ranges must cover {fields}"
    parts = {}
    for f in fields:
        lo, hi = lo_hi[f]
        if lo > 0:  # log-uniform over decades
            parts[f] = st.floats(math.log10(lo), math.log10(hi)).map(lambda x: 10.0**x)
        else:
            parts[f] = st.floats(lo, hi)
    return st.fixed_dictionaries(parts).map(lambda kw: cls(**kw))


def overlap_scale(law):
    """An overlap where the law is doing something: its yield overlap, else a typical 1e-6 m."""
    return float(getattr(law, "yield_overlap", 1e-6))


@st.composite
def law_and_state(draw, name):
    law = draw(law_strategy(name))
    s = overlap_scale(law)
    amax = s * draw(st.one_of(st.just(0.0), st.floats(1e-6, 20.0)))  # no subnormal overlaps
    frac = draw(st.floats(0.0, 1.0))
    return law, amax, frac


@pytest.mark.parametrize("name", LAW_NAMES)
def test_registry_entry_is_complete(name):
    cls = LAWS[name]
    assert cls.name == name
    assert cls.pair_style == f"chain/{name}"
    assert dataclasses.fields(cls)[0].name == "k"
    # the [contact] values: a frozen dataclass whose fields are the scene keys, each with its range
    assert issubclass(cls.Coefficients, LawCoefficients)
    assert cls.Coefficients.__dataclass_params__.frozen
    assert cls.scene_keys == tuple(f.name for f in dataclasses.fields(cls.Coefficients))
    assert set(cls.scene_key_ranges) == set(cls.scene_keys)
    assert set(cls.example_contact) <= set(cls.scene_keys)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_a_scene_holds_its_laws_coefficients(name):
    from granchain.scene import parse_scene, scene_from_dict, scene_to_dict

    from .conftest import make_scene_text

    cls = LAWS[name]
    sc = parse_scene(make_scene_text(law=name), source="t.toml")
    assert type(sc.contact.coefficients) is cls.Coefficients
    assert {k: getattr(sc.contact.coefficients, k) for k in cls.example_contact} == cls.example_contact
    # each key reads on the contact too; another law's key reads None
    for key in contact_keys():
        assert getattr(sc.contact, key) == (getattr(sc.contact.coefficients, key) if key in cls.scene_keys else None)
    with pytest.raises(AttributeError):
        sc.contact.no_such_key  # noqa: B018
    back = scene_from_dict(scene_to_dict(sc), source="t.toml")
    assert back.contact == sc.contact
    assert pickle.loads(pickle.dumps(sc.contact)) == sc.contact


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_force_never_negative_and_zero_when_apart(name, data):
    law, amax, frac = data.draw(law_and_state(name))
    a = np.array([-1e-3, -1e-12, 0.0, frac * amax, amax, 1.5 * amax + 1e-9])
    f = law.force(a, amax)
    assert np.all(f >= 0.0)
    assert np.all(np.isfinite(f))
    assert f[0] == f[1] == f[2] == 0.0
    assert np.all(law.energy(a[:3], amax) == 0.0)


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_loading_and_history(name, data):
    """At alpha >= alpha_max the force is the virgin curve (a stale history gives the loading force);
    static_overlap inverts it; the force is continuous at alpha_max."""
    law, amax, _ = data.draw(law_and_state(name))
    a = amax * 1.3 + 1e-9
    assert np.isclose(law.force(a, amax), law.loading_force(a), rtol=1e-12)
    assert np.isclose(law.force(amax, amax), law.loading_force(amax), rtol=1e-12, atol=0)
    f = float(law.loading_force(a))
    assert np.isclose(law.static_overlap(f), a, rtol=1e-9)
    eps = 1e-9 * amax
    left, right = float(law.force(amax - eps, amax)), float(law.force(amax + eps, amax))
    assert abs(right - left) <= 1e-6 * max(f, 1e-300) + float(law.tangent_stiffness(f)) * 2 * eps


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_energy_balance_of_a_load_unload_path(name, data):
    """Load on the virgin curve to alpha_max, unload to alpha: the work done equals the stored energy
    at alpha plus what the contact dissipated (rule 2), to quadrature accuracy."""
    law, amax, frac = data.draw(law_and_state(name))
    if amax <= 0.0:
        return
    alpha = frac * amax
    x_in = np.linspace(0.0, amax, 20001)
    w_in = np.trapezoid(law.loading_force(x_in), x_in)
    x_out = np.linspace(alpha, amax, 20001)
    w_out = np.trapezoid(law.force(x_out, amax), x_out)
    stored = float(law.energy(alpha, amax))
    lost = float(law.dissipated(amax))
    assert lost >= -1e-12 * w_in
    # trapezoid error ~ F'' h^2 (and the sqrt at zero force): 1e-6 of the work is far above it
    assert math.isclose(w_in - w_out, stored + lost, rel_tol=1e-6, abs_tol=1e-9 * w_in)


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_energy_is_the_integral_of_the_unloading_force(name, data):
    law, amax, frac = data.draw(law_and_state(name))
    if amax <= 0.0:
        return
    a = min(max(frac, 0.05), 0.95) * amax  # away from the kink at alpha_max
    h = 1e-6 * amax
    levels = [float(np.broadcast_to(k.level, (1,))[0]) for k in law.kinks(np.array([amax]))]
    if any(abs(a - lv) < 2 * h for lv in levels):
        return  # a central difference across a kink of the law is not its derivative
    de = (float(law.energy(a + h, amax)) - float(law.energy(a - h, amax))) / (2 * h)
    f = float(law.force(a, amax))
    assert math.isclose(de, f, rel_tol=1e-4, abs_tol=1e-6 * float(law.loading_force(amax)))


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_tangent_stiffness_bounds_every_slope(name, data):
    """The planner's stiffest tangent at force F bounds the slope of the virgin curve up to F and of
    the unloading curve from F (finite differences)."""
    law, amax, _ = data.draw(law_and_state(name))
    if amax <= 0.0:
        return
    f = float(law.loading_force(amax))
    kt = float(law.tangent_stiffness(f))
    x = np.linspace(0.0, amax, 401)
    slopes = np.diff(law.force(x, amax)) / np.diff(x)
    virgin = np.diff(law.loading_force(x)) / np.diff(x)
    assert np.all(slopes <= kt * (1 + 1e-6))
    assert np.all(virgin <= kt * (1 + 1e-6))


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_loading_stiffness_is_the_slope_a_further_compression_meets(name, data):
    """loading_stiffness(F) (the precompressed chain's linearised contact, estimates.linearised_stiffnesses)
    is the forward slope of the virgin curve where it carries F: on Thornton's plastic line beyond F_y,
    not Hertz's tangent at F (the planner took that, 2-100x too stiff, and planned a precompressed
    Thornton chain's fronts too fast)."""
    law, amax, _ = data.draw(law_and_state(name))
    if amax <= 0.0:
        return
    h = 1e-7 * amax
    levels = [float(np.broadcast_to(k.level, (1,))[0]) for k in law.kinks(np.array([amax]))]
    if any(amax <= lv < amax + 2 * h for lv in levels if lv != amax):
        return  # a forward difference across the yield kink is neither slope
    f = float(law.loading_force(amax))
    forward = (float(law.loading_force(amax + h)) - f) / h
    assert math.isclose(float(law.loading_stiffness(f)), forward, rel_tol=1e-5)


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_zero_force_kink_is_where_the_force_vanishes(name, data):
    """The first kink of every law is where the force reaches zero (RK4 event location)."""
    law, amax, _ = data.draw(law_and_state(name))
    level = float(np.broadcast_to(law.kinks(np.array([amax]))[0].level, (1,))[0])
    assert float(law.force(level, amax)) <= 1e-9 * max(float(law.loading_force(amax)), 1e-300)
    above = level + 0.01 * max(amax - level, 1e-12)
    if amax > 0:
        assert float(law.force(above, amax)) > 0.0


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=10, deadline=None)
@given(data=st.data())
def test_join_keeps_each_group(name, data):
    cls = LAWS[name]
    a = data.draw(law_strategy(name), label="a")
    b = data.draw(law_strategy(name), label="b")
    j = cls.join([(a, 2), (b, 3)])
    alpha = np.full(5, overlap_scale(a))
    f = j.force(alpha, np.zeros(5))
    assert np.allclose(f[:2], a.force(alpha[:2], 0.0))
    assert np.allclose(f[2:], b.force(alpha[2:], 0.0))


# ---- the law's models (rule 8): declared in model_domains, and every model it gives or draws is declared

#: a scene of every kind a law's models are for: the paper's chain under a short and a long load, a
#: two-body impact, one bead struck or on the wall, a precompressed chain ([section] lines besides
#: [contact]; the law's example contact is added)
MODEL_SCENES = {
    "short impulse": (30, 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6', ""),
    "long step": (200, 'kind = "step"\namplitude = 40.0\nduration = 1e-2', ""),
    "two-bead impact": (2, 'kind = "velocity"\nvelocity = 1.0', ""),
    "struck bead": (1, 'kind = "striker"\nvelocity = 1.0', ""),
    "bead on the wall": (1, 'kind = "velocity"\nvelocity = 1.0', '[boundary]\nfar_end = "wall"\n'),
    "precompressed chain": (30, 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6', "[precompression]\nforce = 10.0\n"),
}


def model_scenes(name):
    """The scenes of MODEL_SCENES the law accepts."""
    from granchain.scene import SceneError, parse_scene

    from .conftest import make_scene_text

    out = {}
    for kind, (beads, loading, extra) in MODEL_SCENES.items():
        try:
            out[kind] = parse_scene(
                make_scene_text(beads=beads, law=name, loading=loading) + extra, source=f"{kind}.toml"
            )
        except SceneError:
            continue
    return out


@pytest.mark.parametrize("name", LAW_NAMES)
def test_model_tables_name_declared_models(name):
    from granchain.physics.laws.base import MODEL_NEEDS

    cls = LAWS[name]
    assert set(cls.model_domains.values()) <= set(MODEL_NEEDS), cls.model_domains
    for quantity, candidates in cls.compare_models.items():
        assert candidates, quantity
        for model, label in candidates:
            assert model in cls.model_domains, (quantity, model)
            assert label, (quantity, model)
    # a model name is one law's: the predictions' table of domains (name -> law) keeps one owner
    for other, c in LAWS.items():
        if other != name:
            assert not set(cls.model_domains) & set(c.model_domains), (name, other)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_every_model_a_law_gives_or_draws_is_declared(name):
    from granchain.physics.predictions import applicability

    cls = LAWS[name]
    scenes = model_scenes(name)
    assert {"short impulse", "long step", "two-bead impact"} <= set(scenes)
    given: set[str] = set()
    for kind, sc in scenes.items():
        fields = cls.predictions(sc)
        names = [f["name"] for f in fields]
        assert len(names) == len(set(names)), (kind, names)
        assert set(names) <= set(cls.model_domains), (kind, names)
        values = {f["name"]: f["value"] for f in fields}
        for obs in ({}, {"leading_peak_force": 100.0}):
            measured = cls.measured_models(sc, values, obs)
            assert set(measured) <= set(cls.model_domains) - set(names), (kind, measured)
            given |= set(measured)
        given |= set(names)
        asked = []

        def applies(model, label, sc=sc, asked=asked):
            asked.append(model)
            return applicability(model, sc).applies

        contacts = np.arange(1.0, max(sc.chain.beads, 2))
        curves = cls.model_curves(sc, contacts, applies)
        assert set(asked) <= set(cls.model_domains), (kind, asked)
        assert len(curves) <= len(asked)
        assert all(np.shape(y) == contacts.shape for y in curves.values())
    # every declared model is given on some scene it is for
    assert given == set(cls.model_domains), sorted(set(cls.model_domains) - given)


# ---- Thornton (1997): the law as written in issue 14


@settings(max_examples=60, deadline=None)
@given(law=law_strategy("thornton"), x=st.floats(0.0, 1.0), m=st.floats(1.0, 50.0))
def test_thornton_is_hertz_below_yield_and_its_enlarged_radius(law, x, m):
    dy = float(law.yield_overlap)
    a = x * dy
    assert math.isclose(float(law.force(a, dy)), float(hertz_force(a, law.k)), rel_tol=1e-12, abs_tol=0)
    # the plastic line continues Hertz with the same slope at d_y (S = 3/2 k d_y^(1/2) = pi p_y R*)
    assert math.isclose(float(law.plastic_slope), 1.5 * float(law.k) * math.sqrt(dy), rel_tol=1e-14)
    # unloading from d_max = m d_y: R_p = 4 E* a_p^3 / (3 F_max), a_p^2 = R* d_max, and k = 4/3 E* sqrt(R*)
    # give k_p / k = sqrt(R_p / R*) = sqrt(k d_max^(3/2) / F_max) (E* and R* cancel)
    dmax = m * dy
    _, fmax, kp, dp = law.unloading(np.array([dmax]))
    assert math.isclose(float(fmax[0]), float(law.yield_force) + float(law.plastic_slope) * (dmax - dy), rel_tol=1e-12)
    assert math.isclose(float(kp[0]), float(law.k) * math.sqrt(float(law.k) * dmax**1.5 / float(fmax[0])), rel_tol=1e-9)
    assert 0.0 <= float(dp[0]) < dmax


@st.composite
def thornton_history(draw):
    """A Thornton law over n contacts (two drawn laws joined: per-contact k and d_y), and overlaps in units of d_y."""
    n = draw(st.integers(1, 40))
    first, second = draw(law_strategy("thornton")), draw(law_strategy("thornton"))
    m = draw(st.integers(0, n))
    law = ThorntonLaw.join([(first, m), (second, n - m)]) if 0 < m < n else first
    scale = np.broadcast_to(np.asarray(law.yield_overlap, dtype=float), (n,))
    levels = st.one_of(st.just(0.0), st.just(1.0), st.floats(-1.0, 6.0))  # at rest, at yield, anywhere
    rounds = [draw(st.lists(levels, min_size=n, max_size=n)) for _ in range(5)]
    return law, scale, [scale * np.array(r) for r in rounds]


@settings(max_examples=60, deadline=None)
@given(case=thornton_history())
def test_thornton_kept_history_constants_give_force_and_kinks_to_the_bit(case):
    """force_into, force, energy and kink_screens from the kept per-history constants
    (history_constants) give what unloading and the base's kink_screens over kinks give, bit for bit,
    while the history array grows in place (a few contacts or all, as the solver's steps raise it),
    and the law still pickles."""
    law, scale, rounds = case
    n = scale.size
    amax = rounds[0].copy()
    out, tmp = np.empty(n), np.empty(n)
    for i, alpha in enumerate(rounds[1:]):
        a = alpha.copy()
        a[::3] = amax[::3]  # some overlaps exactly at alpha_max
        law.force_into(a, amax, out, tmp)
        plain = dataclasses.replace(law)  # (a new instance: no kept constants, unloading every call)
        want = plain.force(a, amax)
        assert out.tobytes() == want.tobytes(), np.flatnonzero(out != want)
        assert law.force(a, amax).tobytes() == want.tobytes()  # (from the kept constants too)
        assert law.energy(a, amax).tobytes() == plain.energy(a, amax).tobytes()
        a1 = rounds[(i + 2) % len(rounds)]
        got = law.kink_screens(amax, a, a1)
        ref = ContactLaw.kink_screens(law, amax, a, a1)
        assert [(k.kind, k.from_below, idx.tolist()) for k, _, idx in got] == [
            (k.kind, k.from_below, idx.tolist()) for k, _, idx in ref
        ]
        for (k, level, _), (kr, level_r, _) in zip(got, ref, strict=True):
            assert np.array_equal(np.broadcast_to(level, (n,)), np.broadcast_to(level_r, (n,)))
            assert (k.where is None) == (kr.where is None)
            assert k.where is None or np.array_equal(k.where, kr.where)
        np.maximum(amax, a if i % 2 else np.where(np.arange(n) % 5 == 0, a, 0.0), out=amax)  # in place
    restored = pickle.loads(pickle.dumps(law))  # (the kept constants stay behind)
    assert "_histories" not in vars(restored)
    assert restored.force(rounds[1], amax).tobytes() == law.force(rounds[1], amax).tobytes()


def test_thornton_scene_needs_the_limiting_pressure():
    from granchain.scene import SceneError, scene_from_dict

    d = {
        "chain": {"beads": 10, "radius": 0.00476, "material": "brass"},
        "contact": {"law": "thornton"},
        "loading": {"kind": "velocity", "velocity": 1.0},
        "run": {"end_time": 1e-4, "timestep": 1e-8},
    }
    with pytest.raises(SceneError, match="not the tensile yield") as e:
        scene_from_dict(d, source="t.toml")
    assert "yield_pressure" in str(e.value)
    d["contact"]["yield_pressure"] = 1e9
    sc = scene_from_dict(d, source="t.toml")
    assert isinstance(sc.law, ThorntonLaw)
    d["contact"]["unloading_coeff"] = 0.5
    with pytest.raises(SceneError, match="only the bilinear law"):
        scene_from_dict(d, source="t.toml")


# ---- the law kernels, overlap by overlap (hypothesis): properties for every overlap and history
overlap = st.floats(-1e-3, 1e-3, allow_nan=False)
positive_overlap = st.floats(1e-9, 1e-3)
stiffness = st.floats(1e3, 1e10)
beta = st.floats(0.0, 0.99)


@given(overlap, st.floats(0, 1e-3), stiffness, beta)
def test_forces_nonnegative(a, amax, k, b):
    assert hertz_force(a, k) >= 0
    assert bilinear_force(a, amax, k, b) >= 0


@given(st.floats(-1e-3, 0.0), st.floats(0, 1e-3), stiffness, beta)
def test_no_force_without_overlap(a, amax, k, b):
    assert hertz_force(a, k) == 0
    assert bilinear_force(a, amax, k, b) == 0
    assert hertz_energy(a, k) == 0
    assert bilinear_energy(a, amax, k, b) == 0


@given(positive_overlap, stiffness, beta, st.floats(0.0, 1.0))
def test_bilinear_continuity(amax, k, b, frac):
    # at alpha_max the unloading line meets the loading line; at beta alpha_max it reaches zero
    eps = amax * 1e-9
    left = bilinear_force(amax - eps, amax, k, b)
    right = bilinear_force(amax + eps, amax, k, b)
    assert abs(right - left) <= 1e-6 * k * amax + unloading_stiffness(k, b) * 2 * eps
    assert bilinear_force(b * amax, amax, k, b) <= unloading_stiffness(k, b) * 1e-12 * amax + 1e-300
    # never above the loading line, never below zero
    a = frac * amax
    assert 0 <= bilinear_force(a, amax, k, b) <= k * amax * (1 + 1e-12)


@given(positive_overlap, stiffness, beta)
def test_load_unload_cycle_dissipates_eq20(amax, k, b):
    # load 0 -> alpha_max on F = k alpha, unload to zero force: the loop's area is Eq. 20
    a_load = np.linspace(0, amax, 2001)
    w_in = np.trapezoid(bilinear_force(a_load, 0.0, k, b), a_load)
    # the law is piecewise linear: with its kink (beta alpha_max) as a node the trapezoid is exact
    a_unload = np.unique(np.append(np.linspace(0, amax, 2001), b * amax))[::-1]
    w_out = -np.trapezoid(bilinear_force(a_unload, amax, k, b), a_unload)
    eq20 = dissipation_per_cycle(k * amax, k, b)
    assert np.isclose(w_in - w_out, eq20, rtol=1e-9, atol=1e-12 * w_in)  # atol: round-off at beta = 0
    assert np.isclose(bilinear_dissipated(amax, k, b), eq20, rtol=1e-12)
    # stored + dissipated = work done, at the top of the cycle
    assert np.isclose(bilinear_energy(amax, amax, k, b) + bilinear_dissipated(amax, k, b), w_in, rtol=1e-5)


@given(positive_overlap, stiffness, beta, st.floats(0.0, 1.0))
def test_energies_are_integrals_of_force(amax, k, b, frac):
    a = max(frac * amax, 1e-12)
    h = a * 1e-6
    dh = (hertz_energy(a + h, k) - hertz_energy(a - h, k)) / (2 * h)
    assert np.isclose(dh, hertz_force(a, k), rtol=1e-5)
    if a < amax * (1 - 1e-5) and abs(a - b * amax) > 2 * h:  # not across a kink of the law
        db = (bilinear_energy(a + h, amax, k, b) - bilinear_energy(a - h, amax, k, b)) / (2 * h)
        assert np.isclose(db, bilinear_force(a, amax, k, b), rtol=1e-4, atol=1e-9 * k * amax)


@given(overlap, st.floats(0, 1e-3), stiffness)
def test_beta_zero_is_a_linear_elastic_spring(a, amax, k):
    assert bilinear_force(a, amax, k, 0.0) == k * max(a, 0.0)
    assert bilinear_dissipated(amax, k, 0.0) == 0.0
    assert np.isclose(bilinear_energy(a, max(a, amax), k, 0.0), 0.5 * k * max(a, 0.0) ** 2)


def test_vectorized_per_contact_stiffness():
    a = np.array([1e-6, -1e-6, 2e-6])
    k = np.array([1e9, 2e9, 3e9])
    assert np.allclose(hertz_force(a, k), [k[0] * 1e-9, 0.0, k[2] * 2e-6**1.5])
    am = np.array([2e-6, 0.0, 2e-6])
    f = bilinear_force(a, am, k, 0.5)
    assert np.allclose(f, [k[0] * 2 * (1e-6 - 1e-6), 0.0, k[2] * 2e-6])
