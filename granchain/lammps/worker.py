"""Runs LAMMPS decks in a process of its own: one deck (under mpirun for several ranks), or many.

    python -m granchain.lammps.worker RUN_DIR
    python -m granchain.lammps.worker --serve

RUN_DIR holds deck.lmp and chain.data; LAMMPS_PLUGIN_PATH must name the plugin's directory.
Rank 0 writes worker.json: {"ok": true, "wall_time": ..., "startup_time": ..., "ranks": ...}
or {"ok": false, "error": LAMMPS's message, "kind": ...}. The results themselves are files the deck
writes (its results dump and the rest; granchain.lammps.runner.lammps_result reads them), the same
files a plain `lmp -in deck.lmp` writes. This module must not import lammps at import time (the parent
process never loads LAMMPS: a LAMMPS crash cannot take it down).

--serve (one rank; granchain.lammps.server drives it): one LAMMPS instance, made at the first deck
and kept for the next ones. It reads run directories from stdin, one JSON string a line, and for each
writes to stdout the line {"dir": ..., "started": true} when it has read it and {"dir": ..., "ok": ...}
when the run directory's worker.json is written and every file the deck wrote is closed (LAMMPS
`clear` after each deck closes its dumps and prints; every variable is deleted too, since `clear`
keeps them). What LAMMPS or a crash writes to stdout or stderr during a deck goes to RUN_DIR/worker.err.
After a LAMMPS error it answers and exits (an instance that raised is not trusted with the next deck);
it exits at the end of stdin, and when its parent process dies (even mid-run). Ctrl-C stops it at once.

A worker for one deck dies with the granchain process that started it, too (kill -9 of `granchain
run --backend lammps` must not leave LAMMPS running to the end, writing into a work directory nobody
reads): on Linux the kernel sends it SIGKILL when its parent dies (prctl PR_SET_PDEATHSIG), and a
thread watches the granchain process above it (above mpirun and its proxies, when several ranks run)
and exits when that is gone.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

#: LAMMPS's name of a deck's log, written in the run directory
LOG = "log.lammps"
#: where a served deck's stdout and stderr go (what a crash prints), in the run directory
ERR = "worker.err"


def _open_lammps(cmdargs: list[str]):
    from granchain.lammps.build import load_mpi

    load_mpi()
    import lammps

    return lammps.lammps(cmdargs=[*cmdargs, "-screen", "none", "-nocite"])


def _plugin_error(lmp) -> dict | None:
    """worker.json's report when the plugin's pair styles are unknown to this instance, else None."""
    from granchain.lammps.build import PAIR_STYLES

    missing = [s for s in PAIR_STYLES.values() if not lmp.has_style("pair", s)]
    if not missing:
        return None
    return {
        "ok": False,
        "kind": "plugin",
        "error": f"LAMMPS did not load the granchain plugin (pair styles {', '.join(missing)} unknown); "
        "run 'granchain doctor' to see the plugin's build and load status",
    }


def _write_report(d: Path, obj: dict) -> None:
    tmp = d / "worker.json.tmp"
    tmp.write_text(json.dumps(obj))
    tmp.replace(d / "worker.json")


def _run_file(lmp, d: Path) -> dict | None:
    """Run d/deck.lmp in d (its relative file names: chain.data, dumps); a failure's report, else None."""
    cwd = os.getcwd()
    try:
        os.chdir(d)
        lmp.file("deck.lmp")
    except Exception as e:  # LAMMPS raises a plain Exception carrying its error text
        return {"ok": False, "kind": "lammps", "error": str(e)}
    finally:
        os.chdir(cwd)
    return None


def _success(lmp, wall: float, startup: float, ranks: int) -> dict:
    return {
        "ok": True,
        "wall_time": wall,
        "startup_time": startup,
        "ranks": ranks,
        "lammps_version": lmp.version(),
        "time": lmp.get_thermo("time"),
        "steps": int(lmp.get_thermo("step")),
    }


#: process names between a worker and the granchain process that started it (MPI launchers)
LAUNCHERS = ("mpirun", "mpiexec", "mpiexec.hydra", "hydra_pmi_proxy", "orterun", "orted", "prterun", "prted")


def _proc_stat(pid: int) -> tuple[str, int, int] | None:
    """(name, parent pid, start time in clock ticks) of a process, from /proc; None if gone, a zombie
    (or no /proc)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            data = f.read().decode("utf-8", "replace")
    except OSError:
        return None
    name = data[data.index("(") + 1 : data.rindex(")")]
    fields = data[data.rindex(")") + 2 :].split()
    if fields[0] in ("Z", "X"):  # dead, not yet reaped
        return None
    return name, int(fields[1]), int(fields[19])


def _starter() -> tuple[int, int | None]:
    """(pid, start time) of the granchain process that started this worker: the parent, or the first
    process above it that is not an MPI launcher (LAUNCHERS)."""
    pid = os.getppid()
    for _ in range(8):
        st = _proc_stat(pid)
        if st is None:
            return pid, None
        name, ppid, _start = st
        if name not in LAUNCHERS or ppid <= 1:
            return pid, _start
        pid = ppid
    st = _proc_stat(pid)
    return pid, (st[2] if st else None)


def _die_with_parent() -> None:
    """Exit when the process that started this worker dies (see the module's docstring)."""
    import signal
    import threading

    parent = os.getppid()
    if sys.platform.startswith("linux"):
        import ctypes

        PR_SET_PDEATHSIG = 1
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # no prctl: the watch below still ends it
            pass
        if os.getppid() != parent:  # the parent died before prctl took effect
            os._exit(70)
    starter, started = _starter()

    def gone() -> bool:
        st = _proc_stat(starter)
        if st is not None:
            return started is not None and st[2] != started  # the pid reused by another process
        if os.path.isdir("/proc"):
            return True
        try:
            os.kill(starter, 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            return False
        return False

    def watch() -> None:
        while True:
            time.sleep(0.25)
            if gone():
                os._exit(70)

    if gone():
        os._exit(70)
    threading.Thread(target=watch, name="granchain-starter-watch", daemon=True).start()


def main(run_dir: str) -> int:
    """Run the deck in run_dir in this process's LAMMPS and write worker.json (the worker's entry point)."""
    _die_with_parent()
    t0 = time.perf_counter()
    d = Path(run_dir)
    lmp = _open_lammps(["-log", str(d / LOG)])
    rank = lmp.extract_setting("world_rank")
    nprocs = lmp.extract_setting("world_size")

    def report(obj: dict) -> None:
        if rank == 0:
            _write_report(d, obj)

    bad = _plugin_error(lmp)
    if bad:
        report(bad)
        lmp.close()
        return 3
    t1 = time.perf_counter()
    bad = _run_file(lmp, d)
    if bad:
        report(bad)
        return 4
    t2 = time.perf_counter()
    report(_success(lmp, t2 - t1, t1 - t0, nprocs))
    lmp.close()
    return 0


# ------------------------------------------------------------------------------ --serve


def _watch_parent() -> None:
    """Exit when the parent process is gone (it was killed; a run in progress is nobody's any more).

    A thread: LAMMPS's Python module calls the library through ctypes, which releases the GIL, so
    this runs during a deck too. The end of stdin says the same, but only once a deck has ended.
    """
    import threading

    parent = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os._exit(70)

    threading.Thread(target=watch, name="granchain-parent-watch", daemon=True).start()


def _hms(seconds: float) -> str:
    s = int(seconds)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class _Served:
    """The --serve loop's state: the LAMMPS instance (made at the first deck) and its log header."""

    def __init__(self):
        self.lmp = None
        self.header = ""  # what LAMMPS wrote to its log before the first command (version, threads, plugins)
        self.runs = 0

    def clear(self) -> None:
        """Back to a fresh instance's state: `clear` (it destroys the fixes and dumps, which closes their
        files) and every variable deleted (`clear` keeps them, and an index-style variable, once
        defined, ignores a later definition)."""
        self.lmp.command("clear")
        for name in self.lmp.available_ids("variable"):
            self.lmp.command(f"variable {name} delete")

    def run(self, d: Path) -> dict:
        t0 = time.perf_counter()
        log = d / LOG
        if self.lmp is None:  # the first deck: its log gets LAMMPS's own start-up lines, as in a fresh process
            self.lmp = _open_lammps(["-log", str(log)])
            self.lmp.flush_buffers()
            self.header = log.read_text(errors="replace")
        else:  # the same start-up lines, then LAMMPS appends the deck's log
            log.write_text(self.header)
            self.lmp.command(f'log "{log}" append')
        self.runs += 1
        bad = _plugin_error(self.lmp)  # checked for every deck: plugins are process-wide, `clear` keeps them
        if bad:
            return bad
        t1 = time.perf_counter()
        bad = _run_file(self.lmp, d)
        if bad:
            return bad
        t2 = time.perf_counter()
        report = _success(self.lmp, t2 - t1, t1 - t0, 1)
        self.lmp.command("log none")  # closes log.lammps (the command itself is echoed into it: taken out)
        with open(log, "rb+") as f:
            f.seek(0, os.SEEK_END)
            n = f.tell()
            tail = b"log none\n"
            f.seek(max(0, n - len(tail)))
            if f.read() == tail:
                f.truncate(n - len(tail))
            f.seek(0, os.SEEK_END)
            f.write(f"Total wall time: {_hms(time.perf_counter() - t0)}\n".encode())
        self.clear()
        report["instance_runs"] = self.runs
        return report


def serve() -> int:
    """The --serve loop (see the module's docstring)."""
    import signal

    # Ctrl-C (to the terminal's process group) ends a served instance at once, mid-deck too: a Dask
    # worker that started it ignores SIGINT (the driver stops the cluster), which a child would inherit.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    _watch_parent()
    # the protocol keeps stdout's file descriptor; fd 1 and 2 go to each deck's worker.err (LAMMPS or
    # a plugin printing to stdout cannot break the protocol; what a crash prints is kept with its run)
    answers = os.fdopen(os.dup(1), "w", buffering=1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    served = _Served()

    def answer(obj: dict) -> None:
        answers.write(json.dumps(obj) + "\n")
        answers.flush()

    for line in sys.stdin:
        if not line.strip():
            continue
        d = Path(json.loads(line))
        answer({"dir": str(d), "started": True})
        err = os.open(d / ERR, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(err, 1)
        os.dup2(err, 2)
        os.close(err)
        try:
            report = served.run(d)
        except Exception as e:  # noqa: BLE001 - granchain's own failure around the deck (a full disk): reported
            report = {"ok": False, "kind": "worker", "error": f"{type(e).__name__}: {e}"}
        finally:
            sys.stderr.flush()
            os.dup2(null, 1)
            os.dup2(null, 2)
        _write_report(d, report)
        answer({"dir": str(d), "ok": bool(report.get("ok"))})
        if not report.get("ok"):
            return 4  # a LAMMPS that raised is not trusted with the next deck: the parent starts a new one
    if served.lmp is not None:
        served.lmp.close()
    return 0


if __name__ == "__main__":
    if sys.argv[1:] == ["--serve"]:
        sys.exit(serve())
    sys.exit(main(sys.argv[1]))
