"""Hostile scene files: extreme but finite values of every key of the schema, through the commands.

A scene file drawn here starts from a small valid scene and sets one to three keys of the schema (the
sections and keys of granchain.scene, the [contact] keys of every registered law, the sections of
every registered effect) to a hostile value: a float anywhere in the double range, the base value
scaled by a power of ten, a huge or tiny integer, a long string or one with control characters,
arrays nested hundreds deep. `granchain plan`, `predict` and `render` (and, in the slow part, a short
`granchain run`) must then either succeed or give exit 2 and one `granchain: error:` line naming a
key of the file; never a traceback, never more than a few seconds or a few hundred MB first.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import resource
import time
from decimal import Decimal

import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.physics.effects import sections
from granchain.physics.laws import LAWS

#: the schema: every section (dotted for a sub-table) and its keys
SCHEMA: dict[str, tuple[str, ...]] = {
    "chain": ("beads", "radius", "material", "taper"),
    "chain.material": ("density", "youngs_modulus", "poisson_ratio", "yield_strength"),
    "contact": ("law", *sorted({k for law in LAWS.values() for k in law.scene_keys})),
    "loading": ("kind", "amplitude", "duration", "impulse", "velocity", "radius", "mass", "material"),
    "run": ("end_time", "timestep", "stop_after_contact", "stop_after_wall"),
    "outputs": ("peak_force", "histories", "snapshots", "window", "history_interval", "dump_interval"),
    **{name: tuple(effect.scene_keys) for name, effect in sections().items()},
}
PATHS = [(section, key) for section, keys in SCHEMA.items() for key in keys] + [("", "title")]

#: small valid scenes the hostile values are put into: each law, each loading kind, each effect
BASES: list[dict] = [
    {
        "title": "hertz impulse",
        "chain": {"beads": 12, "radius": 4.76e-3, "material": "brass"},
        "contact": {"law": "hertz"},
        "loading": {"kind": "impulse", "impulse": 0.01, "duration": 1e-6},
        "run": {"end_time": 3e-5, "timestep": 1e-7},
        "outputs": {"peak_force": True, "histories": [1, 2], "snapshots": [1e-5]},
    },
    {
        "chain": {
            "beads": 10,
            "radius": 5e-3,
            "material": {"density": 7800.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3, "yield_strength": 5e8},
        },
        "contact": {"law": "bilinear", "unloading_coeff": 0.8},
        "loading": {"kind": "step", "amplitude": 40.0, "duration": 1e-5},
        "run": {"end_time": "auto", "timestep": "auto"},
        "outputs": {"peak_force": True, "histories": [1, 3], "history_interval": "auto"},
        "damping": {"dashpot": 2.0},
    },
    {
        "chain": {"beads": 10, "radius": 4.76e-3, "material": "brass", "taper": 0.97},
        "contact": {"law": "thornton", "yield_pressure": 3.25e9},
        "loading": {"kind": "velocity", "velocity": 1.0},
        "run": {"end_time": 3e-5, "timestep": "auto"},
        "outputs": {"peak_force": [2, 5], "window": [2, 5]},
    },
    {
        "chain": {"beads": 8, "radius": 4.76e-3, "material": "stainless-steel-316"},
        "contact": {"law": "hertz"},
        "loading": {"kind": "striker", "velocity": 0.5, "radius": 4e-3, "mass": 2e-3},
        "run": {"end_time": "auto", "timestep": "auto", "stop_after_contact": 5},
        "outputs": {"peak_force": True},
        "boundary": {"far_end": "wall"},
    },
    {
        "chain": {"beads": 10, "radius": 4.76e-3, "material": "chrome-steel-52100"},
        "contact": {"law": "thornton"},
        "loading": {"kind": "impulse", "impulse": 0.005, "duration": 2e-6},
        "run": {"end_time": 4e-5, "timestep": 5e-8},
        "outputs": {"peak_force": True, "histories": [2], "dump_interval": 1e-6},
        "precompression": {"force": 5.0},
        "boundary": {"far_end": "wall"},
    },
]

#: finite floats at the ends of the double range and around the scene's own limits
EDGES = [
    5e-324,
    2.2250738585072014e-308,
    1e-300,
    1e-30,
    1e-18,
    1e-15,
    1e-6,
    0.5,
    0.9999999999999999,
    1.0000000000000002,
    1e6,
    1e12,
    1e13,
    1e30,
    1e300,
    1.7976931348623157e308,
    -1e-300,
    -1e300,
    0.0,
    -0.0,
]
CONTROL = "".join(map(chr, [*range(0x20), 0x7F, 0x85, 0x9B])) + "\u202e\u2028\ufeff"

floats = st.one_of(st.sampled_from(EDGES), st.floats(allow_nan=False, allow_infinity=False))
integers = st.one_of(
    st.sampled_from([0, 1, 2, -1, 10**6, 10**6 + 1, 10**9, 2**31, 2**63 - 1, -(2**63)]),
    st.integers(-(2**63), 2**63 - 1),
)
texts = st.one_of(
    st.sampled_from(["auto", "", "hertz", "bilinear", "thornton", "striker", "wall", "brass", "x" * 100_000]),
    st.text(alphabet=st.characters(codec="utf-8") | st.sampled_from(CONTROL), max_size=40),
)


@st.composite
def nested(draw):
    """An array nested 1 to 600 deep (the TOML reader recurses once per level)."""
    return ("nested", draw(st.integers(1, 600)))


values = st.one_of(
    floats,
    integers,
    texts,
    nested(),
    st.booleans(),
    st.lists(st.one_of(floats, integers), max_size=5),
    st.builds(dict),
)


def _scaled(base, power: int):
    """The base value scaled by 10^power (a plausible value taken to an extreme), if it is a number."""
    if isinstance(base, bool) or not isinstance(base, (int, float)):
        return None
    if isinstance(base, int) and power >= 0:
        return base * 10**power  # a huge integer
    v = float(Decimal(repr(float(base))).scaleb(power))
    return v if math.isfinite(v) else None


def _toml_value(v) -> str:
    if isinstance(v, tuple) and v[0] == "nested":
        return "[" * v[1] + "]" * v[1]
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + "".join(c if c not in '"\\' and c.isprintable() else f"\\u{ord(c):04X}" for c in v) + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


def scene_text(data: dict) -> str:
    lines = [f"{k} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for section, table in data.items():
        if isinstance(table, dict):
            subs = {k: v for k, v in table.items() if isinstance(v, dict) and v}
            lines.append(f"[{section}]")
            lines += [f"{k} = {_toml_value(v)}" for k, v in table.items() if k not in subs]
            for k, sub in subs.items():
                lines.append(f"[{section}.{k}]")
                lines += [f"{kk} = {_toml_value(vv)}" for kk, vv in sub.items()]
    return "\n".join(lines) + "\n"


def _table(data: dict, section: str) -> dict:
    table = data
    for part in filter(None, section.split(".")):
        table = table.get(part) if isinstance(table.get(part), dict) else {}
    return table


@st.composite
def hostile_scenes(draw) -> tuple[dict, list]:
    """(scene data, [(section, key), ...] set): a base scene with one to three keys made hostile."""
    import copy

    data = copy.deepcopy(draw(st.sampled_from(BASES)))
    changed = []
    for _ in range(draw(st.sampled_from([1, 1, 1, 2, 3]))):
        # half the time a key the scene has (its value goes deep), else any key of the schema
        present = [(sec, k) for sec, k in PATHS if k in _table(data, sec)]
        section, key = draw(st.one_of(st.sampled_from(present), st.sampled_from(PATHS)))
        if section == "":
            table = data
        elif "." in section:
            outer, inner = section.split(".")
            table = data.setdefault(outer, {})
            if not isinstance(table.get(inner), dict):
                table[inner] = {"density": 8500.0, "youngs_modulus": 1.15e11, "poisson_ratio": 0.3}
            table = table[inner]
        else:
            table = data.setdefault(section, {})
        base = table.get(key)
        # mostly the base value taken a few decades (inside the scene's ranges: deep into the planner and the
        # deck) or hundreds of decades (refused) away; else any hostile value
        power = draw(st.one_of(st.integers(-2, 2), st.integers(-6, 6), st.integers(-320, 320)))
        scaled = _scaled(base, power)
        value = scaled if scaled is not None and draw(st.integers(0, 5)) else draw(values)
        table[key] = value
        changed.append((section, key))
    return data, changed


@contextlib.contextmanager
def memory_limit(extra_bytes: int):
    """The process's address space limited to its size now plus extra_bytes (restored after): an
    allocation beyond it raises MemoryError, which the commands must never reach."""
    with open("/proc/self/status") as f:
        vm = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = vm + extra_bytes
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


#: a command refuses or finishes within this (a few seconds on a quiet machine; generous for a shared one)
SECONDS = 20.0
#: and within this much memory above what the test process has
EXTRA_BYTES = 1_500_000_000


def run_cli(argv: list[str]) -> tuple[int, str, float]:
    err, out = io.StringIO(), io.StringIO()
    started = time.monotonic()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out), memory_limit(EXTRA_BYTES):
        rc = main(argv)  # an exception escaping main is a traceback: the test fails with it
    return rc, err.getvalue(), time.monotonic() - started


def check_outcome(rc: int, err: str, seconds: float, text: str, argv: list[str]) -> None:
    assert "Traceback" not in err, err
    assert seconds < SECONDS, f"{argv[0]} took {seconds:.1f} s"
    # run exits 1 when it ended before measuring what the scene asked for (it says what, on stderr)
    assert rc in (0, 2) or (rc == 1 and argv[0] == "run" and "not measured" in err), (rc, err)
    errors = [line for line in err.splitlines() if line.startswith("granchain: error:")]
    if rc in (0, 1):
        assert not errors, err
        return
    assert len(errors) == 1, err
    tail = err[err.index("granchain: error:") :]
    assert tail.count("\n") <= 1, err  # the error is the last line, one line
    message = errors[0]
    named = [k for keys in SCHEMA.values() for k in keys] + [s.split(".")[-1] for s in SCHEMA] + ["title", "TOML"]
    named += ["nests", "section", "[run] timestep", "MPI", "LAMMPS"]
    assert any(k in message for k in named), message


def _event(text: str) -> None:
    """A hypothesis event (statistics), if inside a hypothesis test."""
    from hypothesis.errors import InvalidArgument

    with contextlib.suppress(InvalidArgument):
        event(text)


def _commands(data: dict, tmp_path, commands=("plan", "predict", "render")) -> list[int]:
    text = scene_text(data)
    path = tmp_path / "hostile.toml"
    path.write_text(text, encoding="utf-8")
    codes = []
    for cmd in commands:
        argv = [cmd, str(path)]
        rc, err, seconds = run_cli(argv)
        check_outcome(rc, err, seconds, text, argv)
        _event(f"{cmd}: {'refused' if rc else 'done'}")
        codes.append(rc)
    return codes


def _data(changes: dict, base: int = 0) -> dict:
    import copy

    data = copy.deepcopy(BASES[base])
    for (section, key), value in changes.items():
        table = data
        for part in filter(None, section.split(".")):
            table = table.setdefault(part, {})
        table[key] = value
    return data


#: the inputs that crashed or misled before (each its own test, fast)
KNOWN = {
    "youngs_modulus 1e-300": (
        _data({("chain", "material"): {"density": 8500.0, "youngs_modulus": 1e-300, "poisson_ratio": 0.3}}),
        "youngs_modulus",
    ),
    "taper 1e300": (_data({("chain", "taper"): 1e300}), "taper"),
    "yield_pressure 1e300": (_data({("contact", "yield_pressure"): 1e300}, base=2), "yield_pressure"),
    "yield_pressure 1e-300": (_data({("contact", "yield_pressure"): 1e-300}, base=2), "yield_pressure"),
    "striker mass 1e300": (_data({("loading", "mass"): 1e300}, base=3), "mass"),
    "striker radius 1e-300": (_data({("loading", "radius"): 1e-300}, base=3), "radius"),
    "beads 2^63-1": (_data({("chain", "beads"): 2**63 - 1, ("outputs", "histories"): []}), "beads"),
    "beads 1e9": (_data({("chain", "beads"): 10**9}), "beads"),
    "taper on 1e7 beads": (_data({("chain", "beads"): 10**7, ("chain", "taper"): 0.9999999}), "beads"),
    "taper on 2e5 beads": (_data({("chain", "beads"): 200_000, ("chain", "taper"): 0.999999}), "beads"),
    "end_time 1e300": (_data({("run", "end_time"): 1e300, ("run", "timestep"): "auto"}), "end_time"),
    "title nested 500 deep": (_data({("", "title"): ("nested", 500)}), "nests"),
    "dashpot 1e308": (_data({("damping", "dashpot"): 1e308}), "dashpot"),
    "precompression 1e300": (_data({("precompression", "force"): 1e300}, base=4), "force"),
    "timestep 5e-324": (_data({("run", "timestep"): 5e-324}), "timestep"),
    "duration 1e300": (_data({("loading", "duration"): 1e300}), "duration"),
    "poisson_ratio near -1": (
        _data(
            {
                ("chain", "material"): {
                    "density": 1000.0,
                    "youngs_modulus": 1e12,
                    "poisson_ratio": -0.9999999999999999,
                },
                ("chain", "radius"): 1e-6,
            }
        ),
        "poisson_ratio",
    ),
}


@pytest.mark.parametrize("name", list(KNOWN))
def test_known_hostile_values_are_refused_naming_the_key(tmp_path, name):
    data, key = KNOWN[name]
    codes = _commands(data, tmp_path)
    assert codes == [2, 2, 2]
    rc, err, _ = run_cli(["plan", str(tmp_path / "hostile.toml")])
    assert key in err, err


def test_a_long_title_with_control_characters_is_shown_escaped_or_refused(tmp_path):
    data = _data({("", "title"): "\x1b]0;owned\x07\x1b[2J" + "t" * 100_000})
    _commands(data, tmp_path)


@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.data_too_large],
)
@given(hostile_scenes())
@example((_data({("loading", "duration"): 1e-18, ("run", "end_time"): "auto"}, base=1), []))
def test_hostile_scene_files_are_planned_predicted_rendered_or_refused(tmp_path, drawn):
    data, _ = drawn
    _commands(data, tmp_path)


@pytest.mark.slow
@settings(
    max_examples=100,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.data_too_large],
)
@given(hostile_scenes())
def test_hostile_scene_files_run_briefly_or_are_refused(tmp_path_factory, drawn):
    """The slow part: more scenes, and those the planner takes run (reference backend) under a step
    limit small enough that a run is short; a longer one must be refused by the step limit."""
    data, _ = drawn
    tmp_path = tmp_path_factory.mktemp("hostile")
    if _commands(data, tmp_path, ("plan",)) != [0]:
        return
    _commands(data, tmp_path, ("predict", "render"))
    from granchain.scene import load_scene
    from granchain.workflows.guards import estimate
    from granchain.workflows.run import plan_for

    est = estimate(plan_for(load_scene(tmp_path / "hostile.toml"))[0])
    if est.steps * est.beads > 2e6:  # valid, and long: the step limit's own tests are test_resource_guards'
        _event("run: skipped (over 2e6 bead-steps)")
        return
    os.environ["GRANCHAIN_MAX_STEPS"] = "20000"
    try:
        argv = ["run", str(tmp_path / "hostile.toml"), "--out", str(tmp_path / "out"), "--quiet"]
        rc, err, seconds = run_cli(argv)
    finally:
        del os.environ["GRANCHAIN_MAX_STEPS"]
    check_outcome(rc, err, max(seconds - 60.0, 0.0), "", argv)  # a run and its error estimate may take a while
    _event("run: " + ("ran" if rc == 0 else "steps over the limit" if "GRANCHAIN_MAX_STEPS" in err else "refused"))
    assert rc == 2 or (tmp_path / "out" / "summary.json").exists()


def test_a_huge_or_sparse_scene_file_is_refused_before_it_is_read(tmp_path):
    sparse = tmp_path / "sparse.toml"
    with open(sparse, "wb") as f:
        f.truncate(6 * 1024**3)  # 6 GB of holes: read whole, it took the memory first
    rc, err, seconds = run_cli(["plan", str(sparse)])
    check_outcome(rc, err, seconds, "", ["plan"])
    assert rc == 2
    assert "at most 16,777,216 bytes" in err
    assert seconds < 5
    long = tmp_path / "long.toml"
    long.write_text(scene_text(_data({("", "title"): "x" * 17_000_000})))
    rc, err, _ = run_cli(["render", str(long)])
    assert rc == 2
    assert "long.toml: is 17,0" in err
