"""Scene files: the documented shape parses; every invalid input gets one clear error."""

import math
import re
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.cli import bundled_scenes
from granchain.physics import materials as mat
from granchain.scene import SceneError, load_scene, parse_scene, scene_from_dict

from .conftest import ISSUE_SCENE


def test_issue_scene_shape_parses():
    sc = parse_scene(ISSUE_SCENE, source="issue.toml")
    assert sc.chain.beads == 200
    assert sc.chain.radius == 4.76e-3
    assert sc.chain.material == mat.MATERIALS["brass"]
    assert sc.loading.amplitude == 40.0
    assert sc.loading.duration == 1e-2
    assert sc.outputs.histories == (1, 2, 3)
    assert sc.outputs.snapshots == (2e-3,)
    assert sc.peak_contacts == tuple(range(1, 200))


def test_bundled_scenes_parse_and_roundtrip():
    scenes = bundled_scenes()
    assert "default" in scenes
    assert len(scenes) >= 6
    for name, text in scenes.items():
        sc = parse_scene(text, source=name)
        back = parse_scene(sc.to_toml(), source=name)
        assert back.chain == sc.chain
        assert back.contact == sc.contact
        assert back.loading == sc.loading
        assert back.run == sc.run
        assert back.outputs == sc.outputs


def test_impulse_kind_is_a_step_with_amplitude_impulse_over_duration():
    data = tomllib.loads(ISSUE_SCENE)
    data["loading"] = {"kind": "impulse", "impulse": 0.4, "duration": 1e-3}
    sc = scene_from_dict(data, source="x")
    assert sc.loading.amplitude == pytest.approx(0.4 / 1e-3)
    assert sc.loading.impulse == pytest.approx(0.4)


@pytest.mark.parametrize("kind", ["step", "impulse"])
@pytest.mark.parametrize("duration", [0.0, 5e-19, 2.2250738585072014e-308])
def test_a_loading_time_below_an_attosecond_is_refused(kind, duration):
    data = tomllib.loads(ISSUE_SCENE)
    size = {"step": ("amplitude", 10.0), "impulse": ("impulse", 0.01)}[kind]
    data["loading"] = {"kind": kind, size[0]: size[1], "duration": duration}
    with pytest.raises(
        SceneError, match=r"\[loading\] duration = .* a finite number >= 1e-18 and <= 10000 \(loading time"
    ):
        scene_from_dict(data, source="x")
    data["loading"]["duration"] = 1e-18  # the floor itself is a loading time
    assert scene_from_dict(data, source="x").loading.duration == 1e-18


def test_bilinear_stiffness_from_yield_strength():
    data = tomllib.loads(ISSUE_SCENE)
    data["chain"]["material"] = {
        "density": 8500.0,
        "youngs_modulus": 115e9,
        "poisson_ratio": 0.3,
        "yield_strength": 5.52e8,
    }
    data["contact"] = {"law": "bilinear", "unloading_coeff": 0.8}
    sc = scene_from_dict(data, source="x")
    assert sc.stiffness == pytest.approx(18.5 * 5.52e8 * 4.76e-3 / 2)


# ---- one test per rule: (mutation of the issue scene, key named in the message, words of the fix)


def mutate(path, value):
    data = tomllib.loads(ISSUE_SCENE)
    d = data
    for k in path[:-1]:
        d = d.setdefault(k, {})
    if value is DELETE:
        del d[path[-1]]
    else:
        d[path[-1]] = value
    return data


DELETE = object()

RULES = [
    ("unknown key", ("chain", "bead_count"), 5, "bead_count", "allowed keys"),
    ("unknown section", ("solver",), {"x": 1}, "solver", "allowed"),
    ("missing section", ("run",), DELETE, "[run]", "needs"),
    ("beads wrong type", ("chain", "beads"), "200", "beads", "integer"),
    ("beads float", ("chain", "beads"), 200.0, "beads", "integer"),
    ("beads too few", ("chain", "beads"), 0, "beads", ">= 1"),
    ("beads too many", ("chain", "beads"), 2**63 - 1, "beads", "<= 1,000,000"),
    ("negative radius", ("chain", "radius"), -4.76e-3, "radius", ">= 1e-06"),
    ("zero radius", ("chain", "radius"), 0.0, "radius", ">= 1e-06"),
    ("radius bool", ("chain", "radius"), True, "radius", "number"),
    ("unknown material", ("chain", "material"), "unobtainium", "material", "brass"),
    (
        "bad poisson",
        ("chain", "material"),
        {"density": 1000.0, "youngs_modulus": 1e9, "poisson_ratio": 0.5},
        "poisson_ratio",
        "< 0.5",
    ),
    (
        "material unknown key",
        ("chain", "material"),
        {"density": 1000.0, "youngs_modulus": 1e9, "poisson_ratio": 0.3, "colour": "gold"},
        "colour",
        "allowed keys",
    ),
    ("unknown law", ("contact", "law"), "hooke", "law", "'hertz', 'bilinear'"),
    ("hertz with beta", ("contact", "unloading_coeff"), 0.5, "unloading_coeff", "only the bilinear"),
    ("negative time", ("run", "end_time"), -1.0, "end_time", "> 0"),
    ("zero timestep", ("run", "timestep"), 0.0, "timestep", ">= 1e-24"),
    ("timestep over end", ("run", "timestep"), 1.0, "timestep", "no longer than end_time"),
    ("nan amplitude", ("loading", "amplitude"), float("nan"), "amplitude", "finite"),
    ("loading key of other kind", ("loading", "velocity"), 3.0, "velocity", "amplitude (N) and duration"),
    ("unknown loading kind", ("loading", "kind"), "ramp", "kind", "'step', 'impulse', 'harmonic', 'velocity'"),
    ("missing amplitude", ("loading", "amplitude"), DELETE, "amplitude", "force A"),
    ("history out of range", ("outputs", "histories"), [0, 3], "histories", "contacts 1..199"),
    ("history beyond chain", ("outputs", "histories"), [200], "histories", "out of range"),
    ("peak list wrong type", ("outputs", "peak_force"), "all", "peak_force", "true, false, or a list"),
    ("snapshot after end", ("outputs", "snapshots"), [6e-3], "snapshots", "end_time"),
    ("window reversed", ("outputs", "window"), [50, 10], "window", "first < last"),
    ("history interval below dt", ("outputs", "history_interval"), 1e-9, "history_interval", "time step"),
]


@pytest.mark.parametrize(("what", "path", "value", "key", "fix"), RULES, ids=[r[0] for r in RULES])
def test_invalid_scene_rule(what, path, value, key, fix):
    with pytest.raises(SceneError) as e:
        scene_from_dict(mutate(path, value), source="bad.toml")
    msg = str(e.value)
    assert msg.startswith("bad.toml:"), msg
    assert key in msg, msg
    assert fix in msg, msg
    if value is not DELETE and not isinstance(value, dict) and key not in ("solver",):
        assert (
            repr(value) in msg
            or repr(float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else value) in msg
            or str(value) in msg
        ), msg


BETA_CASES = [(-0.1, ">= 0"), (1.0, "< 1"), (1.5, "< 1")]


@pytest.mark.parametrize(("beta", "fix"), BETA_CASES)
def test_beta_outside_unit_interval(beta, fix):
    data = mutate(("contact", "law"), "bilinear")
    data["contact"].update(unloading_coeff=beta, plastic_stiffness=2.43e7)
    with pytest.raises(SceneError, match=re.escape("unloading_coeff")) as e:
        scene_from_dict(data, source="b.toml")
    assert fix in str(e.value)
    assert repr(float(beta)) in str(e.value)


def test_bilinear_without_stiffness():
    data = mutate(("contact", "law"), "bilinear")
    data["contact"]["unloading_coeff"] = 0.8
    with pytest.raises(SceneError, match="plastic_stiffness .* yield_strength"):
        scene_from_dict(data, source="b.toml")


def test_bilinear_with_two_stiffnesses():
    data = mutate(("contact", "law"), "bilinear")
    data["contact"].update(unloading_coeff=0.8, plastic_stiffness=2.43e7)
    data["chain"]["material"] = {
        "density": 8500.0,
        "youngs_modulus": 115e9,
        "poisson_ratio": 0.3,
        "yield_strength": 5e8,
    }
    with pytest.raises(SceneError, match="only one"):
        scene_from_dict(data, source="b.toml")


def test_impulse_needs_end_time_after_duration():
    data = tomllib.loads(ISSUE_SCENE)
    data["loading"] = {"kind": "impulse", "impulse": 0.4, "duration": 1e-2}
    with pytest.raises(SceneError, match="end_time.*never fully delivered"):
        scene_from_dict(data, source="b.toml")


def test_step_may_outlast_the_run():
    # a step load longer than the run is a valid request: the loading phase itself (Fig. 2, Fig. 9)
    assert parse_scene(ISSUE_SCENE).loading.duration > parse_scene(ISSUE_SCENE).run.end_time


def test_malformed_toml(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[chain\nbeads = 3\n")
    with pytest.raises(SceneError, match="bad.toml: is not valid TOML"):
        load_scene(p)


def test_not_a_file(tmp_path):
    with pytest.raises(SceneError, match="is not a file"):
        load_scene(tmp_path)
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene(tmp_path / "missing.toml")


# ---- property-based: any mutation of a valid scene is either valid or refused with a SceneError

scalars = st.one_of(
    st.integers(-5, 300),
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.booleans(),
    st.text(max_size=5),
    st.lists(st.integers(-2, 250), max_size=4),
)
paths = st.sampled_from(
    [
        ("chain", "beads"),
        ("chain", "radius"),
        ("chain", "material"),
        ("contact", "law"),
        ("contact", "unloading_coeff"),
        ("contact", "plastic_stiffness"),
        ("loading", "kind"),
        ("loading", "amplitude"),
        ("loading", "duration"),
        ("loading", "impulse"),
        ("run", "end_time"),
        ("run", "timestep"),
        ("outputs", "peak_force"),
        ("outputs", "histories"),
        ("outputs", "snapshots"),
        ("outputs", "window"),
        ("outputs", "history_interval"),
        ("outputs", "extra"),
        ("chain", "colour"),
    ]
)


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.lists(st.tuples(paths, scalars), min_size=1, max_size=3))
def test_mutated_scenes_are_valid_or_refused_clearly(mutations):
    data = tomllib.loads(ISSUE_SCENE)
    for path, value in mutations:
        data.setdefault(path[0], {})[path[1]] = value
    try:
        sc, refused = scene_from_dict(data, source="gen.toml"), None
    except SceneError as e:
        sc, refused = None, str(e)
    if refused is not None:
        assert refused.startswith("gen.toml:")
        return
    # a scene accepted is physically sensible
    assert sc.chain.beads is None or sc.chain.beads >= 2
    assert sc.chain.radius > 0
    if sc.run.timestep is not None and sc.run.end_time is not None:
        assert 0 < sc.run.timestep <= sc.run.end_time
    if sc.contact.law == "bilinear":
        assert 0 <= sc.contact.unloading_coeff < 1
        assert sc.stiffness > 0


def test_bundled_scene_files_exist_on_disk():
    root = Path(__file__).parents[1] / "granchain" / "scenes"
    assert {p.stem for p in root.glob("*.toml")} == set(bundled_scenes())


# ---- property-based, end to end: generated scene files through `granchain run` -- valid ones run,
# invalid ones are refused with one message naming the file; never a traceback

SMALL_SCENE = """
[chain]
beads = 8
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.01
duration = 1e-6
[run]
end_time = 2e-5
timestep = 1e-7
[outputs]
peak_force = true
histories = [1, 2]
"""
file_paths = st.sampled_from(
    [
        ("chain", "beads"),
        ("chain", "radius"),
        ("chain", "material"),
        ("chain", "radii"),
        ("contact", "law"),
        ("contact", "unloading_coeff"),
        ("contact", "plastic_stiffness"),
        ("loading", "kind"),
        ("loading", "velocity"),
        ("loading", "impulse"),
        ("loading", "duration"),
        ("run", "timestep"),
        ("run", "end_time"),
        ("outputs", "histories"),
        ("outputs", "snapshots"),
        ("boundary", "far_end"),
        ("damping", "dashpot"),
        ("precompression", "force"),
        ("loading", "mass"),
        ("loading", "amplitude"),
    ]
)
file_values = st.one_of(
    st.sampled_from([0, 1, 2, 5, 12, -1, 0.5, 0.99, 1.0, 1e-7, 1e-6, 5e-6, 1e-5, 3e-5, 2.43e7, -4.76e-3, 4.76e-3]),
    st.sampled_from(["hertz", "bilinear", "wall", "free", "velocity", "striker", "step", "brass", "auto", ""]),
    st.lists(st.sampled_from([1, 2, 3, 7, 9, 4.76e-3, 3e-3]), max_size=3),
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.booleans(),
)

#: run lengths stay small (a valid 1e7 s run is valid, and would run for a day)
run_values = st.sampled_from([1e-7, 1e-6, 5e-6, 2e-5, 3e-5, 0, -1e-6, "auto", "x", float("nan"), float("inf"), True])


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v + '"'
    if isinstance(v, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(v), repr(v))
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


@settings(
    max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(
    st.lists(
        file_paths.flatmap(lambda p: st.tuples(st.just(p), run_values if p[0] == "run" else file_values)), max_size=2
    ),
    st.sampled_from([""] * 12 + ["[chain\n", "beads = = 3\n", "\x00", "[run]\nend_time = 1e-5\n"]),
)
# (an impulse over the smallest normal double's seconds overflowed the peak-force models: a crash)
@example(mutations=[(("loading", "duration"), 2.2250738585072014e-308)], garbage="")
def test_generated_scene_files_run_or_are_refused_clearly(tmp_path_factory, mutations, garbage):
    import contextlib
    import io

    from granchain.cli import main

    data = tomllib.loads(SMALL_SCENE)
    for (section, key), value in mutations:
        data.setdefault(section, {})[key] = value
    text = "\n".join(
        f"[{section}]\n" + "".join(f"{k} = {_toml_value(v)}\n" for k, v in table.items())
        for section, table in data.items()
    )
    d = tmp_path_factory.mktemp("gen")
    path = d / "gen.toml"
    path.write_text(text + garbage)
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(["run", str(path), "--out", str(d / "out")])  # an uncaught exception fails the test
    # the planner's notes and warnings come first on stderr ("plan (rk4): ...", "granchain: warning: ...",
    # and the integrator a scene chose: "granchain: the reference backend runs verlet, ..." for a dashpot)
    notes = ("plan (", "granchain: warning: ", "granchain: the reference backend runs ")
    message = "".join(line for line in err.getvalue().splitlines(True) if not line.startswith(notes))
    from hypothesis import event

    event("ran" if rc == 0 else message.replace(str(path), "FILE")[:70])
    if rc == 0:
        assert (d / "out" / "summary.json").exists()
        return
    assert rc == 2, message
    assert message.startswith("granchain: error: "), message
    assert message.count("\n") <= 3, message
    assert not (d / "out").exists()
    if "invariant" not in message and "stability limit" not in message:
        assert str(path) in message or "gen.toml" in message  # a scene error names the file


# ---- material values outside any real solid's range: the unit slip is named with its fix


def _material_scene(material: dict, contact: dict | None = None) -> dict:
    data = tomllib.loads(ISSUE_SCENE)
    data["chain"]["material"] = {"density": 8500.0, "youngs_modulus": 115e9, "poisson_ratio": 0.3, **material}
    if contact is not None:
        data["contact"] = contact
    return data


@pytest.mark.parametrize(
    ("key", "slips"),
    [
        ("density", ((1e3, "g/cm^3"),)),
        ("youngs_modulus", ((1e9, "GPa"),)),
        ("yield_strength", ((1e6, "MPa"), (1e9, "GPa"))),
    ],
)
@settings(max_examples=60, deadline=None)
@given(where=st.floats(0.0, 1.0))
def test_a_material_value_in_another_unit_is_refused_naming_the_slip(key, slips, where):
    """Any real solid's value (within the range, log-uniform) typed in g/cm^3, GPa or MPa is refused
    naming the key, the value and the SI number to write; the SI value itself is accepted."""
    rng = {"density": mat.DENSITY_RANGE, "youngs_modulus": mat.YOUNGS_MODULUS_RANGE}.get(key, mat.YIELD_STRENGTH_RANGE)
    for factor, unit in slips:
        high = rng.high if key != "yield_strength" else 0.1 * 115e9  # a yield strain of at most 10 %
        si = float(f"{10 ** (math.log10(rng.low) + where * math.log10(high / rng.low)):.4g}")
        typed = si / factor
        with pytest.raises(SceneError) as err:
            scene_from_dict(_material_scene({key: typed}), source="x.toml")
        msg = str(err.value)
        assert f"[chain.material] {key} = {typed:g}" in msg, msg
        assert f"in {unit}? write {si:.6g}" in msg, msg
        assert getattr(scene_from_dict(_material_scene({key: si}), source="x.toml").chain.material, key) == si


@example(325.0)
@settings(max_examples=40, deadline=None)
@given(mpa=st.floats(0.2, 5e4))
def test_a_thornton_yield_pressure_in_mpa_is_refused(mpa):
    data = tomllib.loads(ISSUE_SCENE)
    data["contact"] = {"law": "thornton", "yield_pressure": mpa}
    with pytest.raises(SceneError, match=rf"\[contact\] yield_pressure = {mpa:g} Pa is below .* in MPa\? write"):
        scene_from_dict(data, source="x.toml")
    data["contact"]["yield_pressure"] = mpa * 1e6
    if mpa * 1e6 <= mat.YIELD_PRESSURE_RANGE.high:
        assert scene_from_dict(data, source="x.toml").contact.coefficients.yield_pressure == mpa * 1e6


def test_soft_and_dense_real_solids_are_accepted():
    """PTFE (E 1.46 GPa), a PDMS elastomer (E 1 MPa), a hydrogel (E 20 kPa, 1000 kg/m^3), cork
    (200 kg/m^3), osmium (22,590 kg/m^3), lead (yield 5 MPa) are all real beads."""
    for material in (
        {"density": 2200.0, "youngs_modulus": 1.46e9, "poisson_ratio": 0.46},
        {"density": 965.0, "youngs_modulus": 1e6, "poisson_ratio": 0.49},
        {"density": 1000.0, "youngs_modulus": 2e4, "poisson_ratio": 0.45},
        {"density": 200.0, "youngs_modulus": 2e7, "poisson_ratio": 0.0},
        {"density": 22590.0, "youngs_modulus": 5.6e11, "poisson_ratio": 0.25},
        {"density": 11340.0, "youngs_modulus": 1.6e10, "poisson_ratio": 0.44, "yield_strength": 5e6},
    ):
        scene_from_dict(_material_scene(material), source="x.toml")


def test_a_metals_modulus_in_mpa_is_refused_by_its_yield_strain():
    """Steel's E typed in MPa (2e5) is a hydrogel's modulus in Pa; with a yield strength of 290 MPa it
    makes a yield strain of 1450, which no solid has."""
    data = _material_scene({"youngs_modulus": 2e5, "yield_strength": 2.9e8})
    with pytest.raises(SceneError, match=r"yield strain .* youngs_modulus in MPa\? write 2e\+11"):
        scene_from_dict(data, source="x.toml")


@pytest.mark.parametrize("name", list(mat.MATERIALS))
def test_the_built_in_materials_are_inside_the_plausible_ranges(name):
    m = mat.MATERIALS[name]
    assert mat.DENSITY_RANGE.refusal(m.density) is None
    assert mat.YOUNGS_MODULUS_RANGE.refusal(m.youngs_modulus) is None
    if m.yield_strength is not None:
        assert mat.YIELD_STRENGTH_RANGE.refusal(m.yield_strength) is None
        assert mat.YIELD_PRESSURE_RANGE.refusal(mat.YIELD_PRESSURE_FACTOR * m.yield_strength) is None
    assert mat.yield_strain_refusal(m) is None
