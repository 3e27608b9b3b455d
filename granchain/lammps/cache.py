"""The plugin cache's trust rules: which directory may hold a plugin LAMMPS loads, and a private build.

LAMMPS loads every ``*plugin.so`` in a directory of LAMMPS_PLUGIN_PATH, and a loaded library's
constructors run as the user. So granchain loads a plugin only from a directory nobody else can
change: the cache directory, every directory above it, the plugin's own directory and the file are
owned by the user (or root) and not writable by group or others; a directory above that others may
write is allowed only when it is sticky (``/tmp``: there nobody renames or removes an entry of
another's), and then the entry below it must be the user's. A symbolic link inside the cache is
never followed. Since nobody but the user and root can change such a path, what is checked is what
LAMMPS loads (no window between the check and the load for another user to swap a file into).
A plugin is built in a fresh private directory (``mkdtemp``, mode 0700) and renamed into place whole.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
from pathlib import Path

from granchain.exceptions import GranchainError

#: the environment variable naming the cache directory
CACHE_VARIABLE = "GRANCHAIN_CACHE"


class PluginError(GranchainError, RuntimeError):
    """The plugin cannot be built or loaded; the message says what to install or do."""


class CacheError(PluginError):
    """The plugin cache cannot be used safely (or at all): a setting to fix, not a plugin's status to
    report (granchain doctor says it as an error); the message names the path and the fix."""


def _fix(where: str) -> str:
    return (
        f"{where}; granchain loads a LAMMPS plugin only from a directory nobody else can change: set "
        f"{CACHE_VARIABLE} to an absolute path of a private directory (e.g. ~/.cache/granchain), or unset it "
        "(then $XDG_CACHE_HOME/granchain or ~/.cache/granchain)"
    )


def cache_root(environ=None) -> Path:
    """The cache directory: $GRANCHAIN_CACHE (an absolute path), else by the XDG base directory rule
    $XDG_CACHE_HOME/granchain, else ~/.cache/granchain.

    An empty or relative GRANCHAIN_CACHE is refused (CacheError): it would name the current directory
    or one below it, wherever the command runs, and a plugin planted there would be loaded. An empty or
    relative XDG_CACHE_HOME is ignored, as the XDG specification says. Whichever it is, the plugin is
    loaded from it only when trusted_root finds nobody else can change it."""
    env = os.environ if environ is None else environ
    raw = env.get(CACHE_VARIABLE)
    xdg = env.get("XDG_CACHE_HOME") or ""
    if raw is None and os.path.isabs(xdg):
        return Path(xdg) / "granchain"
    if raw is None:
        home = Path.home()
        if not home.is_absolute():
            raise CacheError(_fix(f"HOME={str(home)!r} is not an absolute path, so ~/.cache/granchain is not"))
        return home / ".cache" / "granchain"
    if not raw.strip():
        raise CacheError(_fix(f"{CACHE_VARIABLE} is set but empty (it would mean the current directory)"))
    if not os.path.isabs(raw):
        raise CacheError(
            _fix(f"{CACHE_VARIABLE}={raw!r} is a relative path (it would depend on the current directory)")
        )
    return Path(raw)


def _why_unsafe(st: os.stat_result, *, parent: bool) -> str | None:
    """Why a directory (or file) with this lstat may be changed by someone else, or None."""
    if stat.S_ISLNK(st.st_mode):
        return "is a symbolic link"
    if st.st_uid not in (os.geteuid(), 0):
        return f"is owned by another user (uid {st.st_uid})"
    if st.st_mode & 0o022 and not (parent and stat.S_ISDIR(st.st_mode) and st.st_mode & stat.S_ISVTX):
        return f"is writable by {'others' if st.st_mode & 0o002 else 'its group'} (mode {stat.S_IMODE(st.st_mode):o})"
    return None


def _make_private(path: Path) -> None:
    """Make the missing directories of ``path`` with mode 0700 (os.makedirs gives the parents the umask's)."""
    missing = []
    p = path
    while not os.path.lexists(p):
        missing.append(p)
        p = p.parent
    for d in reversed(missing):
        with contextlib.suppress(FileExistsError):  # made meanwhile by a concurrent run: checked below
            os.mkdir(d, 0o700)


def trusted_root(root: Path) -> Path:
    """The cache directory, made if missing (mode 0700), as a real path that only the user or root can
    change (each directory from it up to / checked as the module says); CacheError otherwise,
    including a cache that cannot be made (read-only, not a directory)."""
    try:
        _make_private(root)
        real = Path(os.path.realpath(root))
        if not real.is_dir():
            raise CacheError(_fix(f"the plugin cache {root} is not a directory"))
        chain = [real, *real.parents]
        for i, d in enumerate(chain):
            why = _why_unsafe(os.lstat(d), parent=True)
            if why:
                named = f"{d} (above the plugin cache {root})" if i else f"the plugin cache {root}"
                raise CacheError(_fix(f"{named} {why}"))
    except OSError as e:
        raise CacheError(_fix(f"the plugin cache {root} cannot be used ({e.strerror or e})")) from None
    return real


def plugin_state(key_dir: Path, name: str) -> str:
    """What is at a plugin's directory ``key_dir`` (in a trusted cache): "ok" (the user's or root's,
    nobody else can change it or the file ``name`` in it), "missing", or "rebuild" (the user's own
    directory, but the file is missing, or another may write the file or the directory: built again).
    CacheError where something else is there (a link, another user's): it is not followed, not loaded
    and not removed."""
    try:
        st = os.lstat(key_dir)
    except FileNotFoundError:
        return "missing"
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode) or st.st_uid not in (os.geteuid(), 0):
        why = _why_unsafe(st, parent=False) or "is not a directory"
        raise CacheError(_fix(f"{key_dir} {why}, not granchain's own plugin directory (remove it)"))
    so = key_dir / name
    try:
        fst = os.lstat(so)
    except FileNotFoundError:
        fst = None
    if fst is not None and (stat.S_ISLNK(fst.st_mode) or not stat.S_ISREG(fst.st_mode)):
        what = "a symbolic link" if stat.S_ISLNK(fst.st_mode) else "not a regular file"
        raise CacheError(_fix(f"{so} is {what}, not a plugin granchain built (remove it)"))
    why = _why_unsafe(st, parent=False)
    fwhy = None if fst is None else _why_unsafe(fst, parent=False)
    if fst is not None and not why and not fwhy:
        return "ok"
    if st.st_uid == os.geteuid():  # the user's own directory: granchain builds the plugin again in its place
        return "rebuild"
    which = f"{key_dir} {why}" if why else f"{so} {fwhy or 'is missing'}"
    raise CacheError(_fix(f"{which} (root's plugin directory; ask its owner to rebuild it)"))


def private_build_dir(root: Path) -> Path:
    """A fresh directory to build a plugin in, private to the user (mode 0700), in the cache ``root``."""
    try:
        return Path(tempfile.mkdtemp(prefix=".build-", dir=root))
    except OSError as e:
        raise CacheError(_fix(f"the plugin cache {root} is not writable ({e.strerror or e})")) from None


def install(built: Path, key_dir: Path, name: str, replace: bool = False) -> None:
    """Move a build directory holding only the plugin file ``name`` to ``key_dir`` whole (rename):
    a concurrent build's complete directory already there is kept (replace: replaced, if the
    user's); the user's own unsafe one is replaced."""
    os.chmod(built / name, 0o755)  # whatever the umask: nobody else may write what LAMMPS loads
    os.chmod(built, 0o755)
    state = plugin_state(key_dir, name)
    if state == "rebuild" or (replace and state == "ok" and os.lstat(key_dir).st_uid == os.geteuid()):
        old = Path(tempfile.mkdtemp(prefix=".old-", dir=key_dir.parent))
        os.replace(key_dir, old / "plugin")
        shutil.rmtree(old, ignore_errors=True)
    try:
        os.rename(built, key_dir)
    except OSError:  # another build won the race: its directory is checked like any other
        shutil.rmtree(built, ignore_errors=True)
        if plugin_state(key_dir, name) != "ok":
            raise


def check_plugin_path_entry(entry: str) -> None:
    """Refuse (CacheError) a LAMMPS_PLUGIN_PATH entry that would let another user's library be loaded:
    relative (the current directory of LAMMPS), or a directory (or, where it does not exist, the
    directory it would be made in) that another user owns or may add a file to (a sticky directory
    too: anyone may add a ``*plugin.so`` to it), or one below such a directory. An empty entry names
    no directory (LAMMPS skips it)."""
    if not entry:
        return
    if not os.path.isabs(entry):
        raise CacheError(
            f"LAMMPS_PLUGIN_PATH holds {entry!r}, a relative path: LAMMPS would load every *plugin.so in that "
            "directory below wherever it runs; name plugin directories by absolute paths, or unset LAMMPS_PLUGIN_PATH"
        )
    real = Path(os.path.realpath(entry))
    first = next(d for d in [real, *real.parents] if os.path.lexists(d))
    for d in [first, *first.parents]:
        why = _why_unsafe(os.lstat(d), parent=d != first)
        if why:
            raise CacheError(
                f"LAMMPS_PLUGIN_PATH holds {entry}: {d} {why}, so another user could put a *plugin.so there that "
                "LAMMPS loads and runs as you; remove that entry from LAMMPS_PLUGIN_PATH"
            )
