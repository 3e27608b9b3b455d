"""Shared temporary directories: a granchain run in another PID namespace (a container) or on another
host sharing $TMPDIR, or beside the same --out, must not delete a live run's work or partial
directory, whose pid it cannot see; a dead run's (its lock released) is still removed."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from granchain import safe_files
from granchain.lammps import runner

from .conftest import make_scene_text

#: a run long enough to be caught while LAMMPS runs
SCENE = make_scene_text(beads=400, end_time=1e-3, timestep=2e-8)
SHORT = make_scene_text(beads=20, end_time=5e-5, timestep=5e-8)
OLD = 1e9  # a modification time long past: only the lock (or its absence) decides


def _other_namespace() -> list[str]:
    """The command prefix running a child in a PID namespace of its own (root only)."""
    if os.geteuid() != 0 or not shutil.which("unshare"):
        pytest.skip("a second PID namespace needs root and unshare (util-linux); CI runs as root")
    probe = subprocess.run(["unshare", "--pid", "--fork", "--mount-proc", "true"], capture_output=True, text=True)
    assert probe.returncode == 0, f"unshare --pid failed as root: {probe.stderr}"
    return ["unshare", "--pid", "--fork", "--mount-proc"]


def _in_namespace(ns, code: str, env: dict) -> subprocess.CompletedProcess:
    """Python ``code`` in the other namespace."""
    return subprocess.run([*ns, sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)


def _dead_dir(tmp: Path) -> Path:
    """A work directory as a killed run of this host leaves it: its lock released with its process."""
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    dead = tmp / f"{runner.WORK_PREFIX}{p.pid}-{safe_files.host_tag()}-deadbeef"
    dead.mkdir()
    (dead / "log.lammps").write_text("x")
    for f in (dead / "log.lammps", dead):
        os.utime(f, (OLD, OLD))
    return dead


def test_a_run_in_another_pid_namespace_leaves_a_live_run_alone(tmp_path):
    ns = _other_namespace()
    tmp = tmp_path / "shared-tmp"
    tmp.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp), "GRANCHAIN_QUIET": "1"}
    for name, text in (("long.toml", SCENE), ("short.toml", SHORT)):
        (tmp_path / name).write_text(text)
    dead = _dead_dir(tmp)
    live = subprocess.Popen(
        [sys.executable, "-m", "granchain", "run", str(tmp_path / "long.toml"), "--backend", "lammps"]
        + ["--out", str(tmp_path / "live-out")],
        env=env,
        start_new_session=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not [d for d in tmp.glob(f"{runner.WORK_PREFIX}*") if d != dead] and live.poll() is None:
        assert time.monotonic() < deadline, "the live run made no work directory"
        time.sleep(0.02)
    os.killpg(live.pid, signal.SIGSTOP)  # caught while LAMMPS runs: held there, as long as the test needs
    try:
        work = [d for d in tmp.glob(f"{runner.WORK_PREFIX}*") if d != dead]
        assert work, "the live run ended before it was caught"
        other = _in_namespace(
            ns,
            "from granchain.cli import main\n"
            f"raise SystemExit(main(['run', {str(tmp_path / 'short.toml')!r}, '--backend', 'lammps', "
            f"'--out', {str(tmp_path / 'other-out')!r}]))",
            env,
        )
        assert other.returncode == 0, other.stderr
        assert all(d.is_dir() for d in work), "the other namespace's run deleted the live run's work directory"
        assert not dead.exists(), "a dead run's work directory (its lock released) is still swept"
    finally:
        os.killpg(live.pid, signal.SIGCONT)
    out, err = live.communicate(timeout=300)
    assert live.returncode == 0, err
    assert (tmp_path / "live-out" / "summary.json").exists()


HOLD = """
import sys, time
from granchain import safe_files
with safe_files.atomic_directory(sys.argv[1], "run") as tmp:
    print(tmp, flush=True)
    sys.stdin.read()
"""


def test_a_writer_in_another_pid_namespace_leaves_a_live_partial_directory_alone(tmp_path):
    ns = _other_namespace()
    out = tmp_path / "run"
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(out)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        partial = Path(holder.stdout.readline().strip())
        assert partial.is_dir()
        os.utime(partial, (OLD, OLD))
        # an earlier writer's, killed: named by the older rule (its pid only) and old
        legacy = tmp_path / f".{out.name}.partial-999999"
        legacy.mkdir()
        os.utime(legacy, (OLD, OLD))
        other = _in_namespace(
            ns,
            "import sys\nfrom granchain import safe_files\n"
            f"with safe_files.atomic_directory({str(out)!r}, 'run') as tmp:\n    (tmp / 'x').write_text('x')\n",
            dict(os.environ),
        )
        assert other.returncode == 0, other.stderr
        assert partial.is_dir(), "the other namespace's writer deleted a live writer's partial directory"
        assert not legacy.exists()
    finally:
        holder.stdin.close()
        holder.wait(timeout=60)
        holder.stdout.close()


def test_another_hosts_directory_is_kept_until_it_is_old(tmp_path):
    d = tmp_path / "foreign"
    d.mkdir()
    (d / "progress.txt").write_text("1")
    other_tag = "0" * 12
    assert other_tag != safe_files.host_tag()
    for age, gone in ((3600, False), (safe_files.FOREIGN_AGE - 60, False), (safe_files.FOREIGN_AGE + 60, True)):
        t = time.time() - age
        for p in (d / "progress.txt", d):
            os.utime(p, (t, t))
        assert safe_files.owner_gone(d, other_tag) is gone
        assert safe_files.owner_gone(d, None) is gone  # a name without a host tag: judged by age too
    os.utime(d / "progress.txt")  # a file written now: its directory is in use
    assert safe_files.owner_gone(d, other_tag) is False


def test_only_the_users_own_real_directories_are_swept(tmp_path):
    tag = safe_files.host_tag()
    target = tmp_path / "target"
    target.mkdir()
    link = tmp_path / "link"
    link.symlink_to(target)
    assert safe_files.owner_gone(link, tag) is False  # a link is never followed
    plain = tmp_path / "plain"
    plain.mkdir()
    os.utime(plain, (OLD, OLD))
    assert safe_files.owner_gone(plain, tag) is True
    held = safe_files.hold_lock(plain)
    try:
        assert safe_files.owner_gone(plain, tag) is False  # this process holds it: alive
    finally:
        os.close(held)
    if os.geteuid() == 0:
        os.chown(plain, 65534, 65534)  # another user's (nobody's)
        assert safe_files.owner_gone(plain, tag) is False


def test_a_long_out_name_has_a_bounded_partial_name(tmp_path):
    out = tmp_path / ("r" * 245)
    with safe_files.atomic_directory(out, "run") as tmp:
        assert len(os.fsencode(tmp.name)) < 255
        (tmp / "x").write_text("x")
    assert (out / "x").read_text() == "x"
    with safe_files.atomic_directory(out, "run", overwrite=True) as tmp:  # the replaced one's .old- name too
        (tmp / "x").write_text("y")
    assert (out / "x").read_text() == "y"
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]
    # two long names alike in their first bytes keep different partial names
    a, b = "é" * 120 + "a", "é" * 120 + "b"
    assert safe_files.sibling_stem(a) != safe_files.sibling_stem(b)


def _fit(piece: str, size: int) -> str:
    """``piece`` repeated to at most ``size`` UTF-8 bytes (whole characters)."""
    name = ""
    while len((name + (c := piece[len(name) % len(piece)])).encode()) <= size:
        name += c
    return name


#: valid file names of every length up to the 255-byte limit
NAMES = st.builds(
    _fit,
    st.text(st.characters(blacklist_characters="/\x00", blacklist_categories=("Cs",)), min_size=1, max_size=6),
    st.integers(4, 255),
).filter(lambda n: n.strip(".") != "")


@given(name=NAMES)
def test_every_valid_out_name_is_written(tmp_path_factory, name):
    """Whatever a valid --out name (up to the file system's 255 bytes), its directory is written: the
    hidden partial and old names beside it stay within the limit."""
    parent = tmp_path_factory.mktemp("out")
    for overwrite in (False, True):
        with safe_files.atomic_directory(parent / name, "run", overwrite=overwrite) as tmp:
            (tmp / "x").write_text(str(overwrite))
    assert (parent / name / "x").read_text() == "True"
    assert [p.name for p in parent.iterdir()] == [name]


def test_run_with_a_245_character_out_name(tmp_path):
    from granchain.cli import main

    (tmp_path / "s.toml").write_text(SHORT)
    out = tmp_path / ("o" * 245)
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(out)]) == 0
    assert (out / "summary.json").exists()
