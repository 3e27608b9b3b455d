"""The plugin cache is shared ground: a library another user plants where granchain looks for its
LAMMPS plugin (a shared cache, the current directory, a link) must never be loaded, since its
constructor would run as the user. An unusable cache is one clear error, not a traceback."""

import os
import pwd
import secrets
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from granchain.lammps import build, cache

from .conftest import make_scene_text

SCENE = make_scene_text(beads=20, end_time=5e-5, timestep=5e-8)

#: a planted "plugin": its constructor runs on load and leaves the file $PLANTED_MARKER behind
PLANTED_C = r"""
#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>
__attribute__((constructor)) static void planted(void) {
    const char *m = getenv("PLANTED_MARKER");
    if (m) { int fd = open(m, O_WRONLY | O_CREAT, 0644); if (fd >= 0) close(fd); }
}
"""


@pytest.fixture
def shared():
    """A directory below /tmp that a second user can read (the attacker's staging ground), with the
    planted library compiled in it."""
    base = Path(tempfile.mkdtemp(prefix="granchain-hostile-cache-"))
    os.chmod(base, 0o755)
    src = base / "planted.c"
    src.write_text(PLANTED_C)
    r = subprocess.run(["gcc", "-shared", "-fPIC", "-o", str(base / "planted.so"), str(src)], capture_output=True)
    assert r.returncode == 0, r.stderr
    os.chmod(base / "planted.so", 0o755)
    (base / "pub").mkdir()
    os.chmod(base / "pub", 0o1777)  # where the second user makes their directories
    yield base
    subprocess.run(["rm", "-rf", str(base)], check=False)


@pytest.fixture
def other_user():
    """A second local user, made for the test (root only) and removed after it."""
    if os.geteuid() != 0:
        pytest.skip("planting a plugin as a second local user needs root to create one (useradd); CI runs as root")
    name = "gcatk" + secrets.token_hex(4)
    r = subprocess.run(
        ["useradd", "--no-create-home", "--shell", "/usr/sbin/nologin", name], capture_output=True, text=True
    )
    assert r.returncode == 0, f"useradd {name} failed as root: {r.stderr}"
    try:
        yield pwd.getpwnam(name)
    finally:
        subprocess.run(["userdel", name], capture_output=True, check=False)


def as_user(user, script: str, *args: str) -> None:
    """Run a shell script as ``user`` (the planting)."""
    subprocess.run(["sh", "-c", script, "sh", *args], user=user.pw_uid, group=user.pw_gid, extra_groups=[], check=True)


PLANT = 'mkdir -p "$1/$2" && cp "$3" "$1/$2/granchainplugin.so"'


def key_name() -> str:
    """The plugin's directory name in the cache (what build_plugin looks for)."""
    return f"plugin-{build.lammps_version()}-{build.plugin_key()}"


def granchain(args, cwd, cache_value, marker, **env):
    """The granchain command line in a child, with GRANCHAIN_CACHE = cache_value (None: unset)."""
    e = {**os.environ, "PLANTED_MARKER": str(marker), **env}
    e.pop("GRANCHAIN_CACHE", None)
    if cache_value is not None:
        e["GRANCHAIN_CACHE"] = cache_value
    return subprocess.run(
        [sys.executable, "-m", "granchain", *args], cwd=cwd, env=e, capture_output=True, text=True, timeout=300
    )


def assert_refused(r, marker, *words):
    """Not loaded (no marker), and said in one `granchain: error:` line naming ``words``, exit 2."""
    assert not marker.exists(), "the planted library was loaded: its constructor ran as the user"
    assert r.returncode == 2, r.stdout + r.stderr
    errors = [line for line in r.stderr.splitlines() if line.startswith("granchain: error:")]
    assert len(errors) == 1, r.stderr
    assert "Traceback" not in r.stderr, r.stderr
    for w in words:
        assert w in errors[0]


def run_args(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    return ["run", str(scene), "--backend", "lammps", "--out", str(tmp_path / "out")]


def _shared_of_other(base, user):
    d = base / "pub" / "shared"
    as_user(user, 'mkdir "$1" && chmod 1777 "$1"', str(d))
    return d, str(d), d


def _shared_of_root(base, user):
    d = base / "shared"
    d.mkdir()
    os.chmod(d, 0o1777)  # as /tmp is
    return d, str(d), d


def _cwd_empty(base, user):
    d = base / "pub" / "cwd"
    as_user(user, 'mkdir "$1" && chmod 1777 "$1"', str(d))
    return d, "", d


def _cwd_relative(base, user):
    d = base / "pub" / "cwd"
    as_user(user, 'mkdir "$1" && chmod 1777 "$1"', str(d))
    return d / "cache", "cache", d


def _linked_cache(base, user):
    """GRANCHAIN_CACHE names a link the other user planted in a sticky directory, to their own directory."""
    d = base / "sticky"
    d.mkdir()
    os.chmod(d, 0o1777)
    theirs = base / "pub" / "theirs"
    as_user(user, 'mkdir "$1" && ln -s "$1" "$2"', str(theirs), str(d / "cache"))
    return theirs, str(d / "cache"), base


PLANTS = {
    "shared 1777 cache of the other user": (_shared_of_other, "another user"),
    "shared 1777 cache of root, the other user's plugin directory in it": (_shared_of_root, "another user"),
    "GRANCHAIN_CACHE empty, plugin in the current directory": (_cwd_empty, "empty"),
    "GRANCHAIN_CACHE relative, plugin below the current directory": (_cwd_relative, "relative"),
    "GRANCHAIN_CACHE a link the other user planted": (_linked_cache, "another user"),
}


@pytest.mark.parametrize("case", list(PLANTS))
def test_a_plugin_planted_by_another_user_is_not_loaded(case, shared, other_user, tmp_path):
    make, why = PLANTS[case]
    where, value, cwd = make(shared, other_user)
    as_user(other_user, PLANT, str(where), key_name(), str(shared / "planted.so"))
    marker = tmp_path / "planted-ran"
    r = granchain(run_args(tmp_path), cwd, value, marker)
    assert_refused(r, marker, "GRANCHAIN_CACHE", why)
    assert not (tmp_path / "out").exists()


def _link_at_plugin_dir(root: Path, planted: Path) -> None:
    elsewhere = planted.parent / "elsewhere"
    elsewhere.mkdir()
    shutil.copy(planted, elsewhere / build.PLUGIN_NAME)
    (root / key_name()).symlink_to(elsewhere)


def _link_at_plugin_file(root: Path, planted: Path) -> None:
    (root / key_name()).mkdir()
    (root / key_name() / build.PLUGIN_NAME).symlink_to(planted)


@pytest.mark.parametrize("plant", [_link_at_plugin_dir, _link_at_plugin_file], ids=["plugin dir", "plugin file"])
@pytest.mark.parametrize("command", ["doctor", "run"])
def test_a_link_in_the_cache_is_not_followed(plant, command, shared, tmp_path):
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    plant(root, shared / "planted.so")
    marker = tmp_path / "planted-ran"
    r = granchain(["doctor"] if command == "doctor" else run_args(tmp_path), tmp_path, str(root), marker)
    assert_refused(r, marker, "GRANCHAIN_CACHE", "symbolic link")
    assert (shared / "planted.so").exists()  # what the link points to is not removed either


def _under_a_file(tmp_path: Path) -> Path:
    (tmp_path / "file").write_text("not a directory")
    return tmp_path / "file" / "cache"


def _read_only(tmp_path: Path) -> Path:
    if os.geteuid() == 0:
        pytest.skip("root writes a mode 0500 directory; the cache below a file covers root")
    d = tmp_path / "ro"
    d.mkdir(mode=0o500)
    return d / "cache"


@pytest.mark.parametrize("where", [_under_a_file, _read_only], ids=["below a file", "read-only"])
@pytest.mark.parametrize("command", ["doctor", "run"])
def test_an_unwritable_cache_is_one_clear_error(where, command, tmp_path):
    value = str(where(tmp_path))
    marker = tmp_path / "unused"
    r = granchain(["doctor"] if command == "doctor" else run_args(tmp_path), tmp_path, value, marker)
    assert_refused(r, marker, "GRANCHAIN_CACHE", value)


FAKE_CXX = '#!/bin/sh\nwhile [ $# -gt 0 ]; do if [ "$1" = -o ]; then shift; printf built > "$1"; fi; shift; done\n'


@pytest.fixture
def fake_compiler(tmp_path, monkeypatch):
    """A compiler that writes a stand-in plugin (the build's directories and modes are what is tested)."""
    cxx = tmp_path / "bin" / "g++"
    cxx.parent.mkdir()
    cxx.write_text(FAKE_CXX)
    cxx.chmod(0o755)
    monkeypatch.setenv("CXX", str(cxx))
    old = os.umask(0o002)  # a umask that leaves group-writable files: the build must not
    yield
    os.umask(old)


def _writable_by_others(p: Path) -> bool:
    return bool(os.lstat(p).st_mode & 0o022)


def test_the_build_is_private_and_whole(tmp_path, monkeypatch, fake_compiler):
    root = tmp_path / "new" / "cache"
    monkeypatch.setenv("GRANCHAIN_CACHE", str(root))
    so = build.build_plugin()
    assert so.read_text() == "built"
    assert sorted(p.name for p in root.iterdir()) == [key_name()]  # no build directory left behind
    assert sorted(p.name for p in so.parent.iterdir()) == [build.PLUGIN_NAME]  # no sources: LAMMPS loads *plugin.so
    for p in (so, so.parent, root, root.parent):
        assert not _writable_by_others(p), p
    # the user's own plugin directory that others could write is built again, not loaded
    os.chmod(so.parent, 0o777)
    so.write_text("tampered")
    assert build.build_plugin().read_text() == "built"
    assert not _writable_by_others(so.parent)


@given(key_mode=st.integers(0o500, 0o777) | st.just(0o1777), file_mode=st.integers(0o400, 0o777))
def test_a_plugin_is_loaded_only_when_nobody_else_can_change_it(tmp_path_factory, key_mode, file_mode):
    """For every mode of the plugin's directory and file: "ok" (loaded) exactly when neither is
    writable by group or others; the user's own otherwise built again ("rebuild"), never loaded."""
    root = tmp_path_factory.mktemp("cache")
    key = root / "plugin-x"
    key.mkdir()
    (key / build.PLUGIN_NAME).write_text("x")
    os.chmod(key / build.PLUGIN_NAME, file_mode)
    os.chmod(key, key_mode)
    expected = "rebuild" if (key_mode | file_mode) & 0o022 else "ok"
    assert cache.plugin_state(key, build.PLUGIN_NAME) == expected
    os.chmod(key, 0o700)


def test_lammps_plugin_path_open_to_others_is_refused(tmp_path, monkeypatch):
    private = tmp_path / "p"
    private.mkdir(mode=0o700)
    monkeypatch.setattr(build, "build_plugin", lambda: private / build.PLUGIN_NAME)
    open_dir = tmp_path / "open"
    open_dir.mkdir()
    os.chmod(open_dir, 0o1777)
    for entry, why in [
        (str(open_dir), "writable by others"),
        ("plugins", "relative"),
        (str(open_dir / "not-yet"), "writable by others"),  # anyone may make it
    ]:
        with pytest.raises(cache.CacheError, match=why):
            build.plugin_env({"LAMMPS_PLUGIN_PATH": entry})
    env = build.plugin_env({"LAMMPS_PLUGIN_PATH": str(private)})
    assert env["LAMMPS_PLUGIN_PATH"].split(os.pathsep) == [str(private), str(private)]


def test_the_lmp_entry_point_never_names_an_unchecked_directory(tmp_path, monkeypatch):
    open_cache = tmp_path / "open"
    open_cache.mkdir()
    os.chmod(open_cache, 0o777)
    monkeypatch.setenv("GRANCHAIN_CACHE", str(open_cache))
    d = build.entry_point_plugin_dir()
    assert not Path(d).is_dir()  # LAMMPS loads nothing from it
    assert str(open_cache) not in d
    assert stat.S_ISCHR(os.stat(d).st_mode)
