"""LAMMPS instances kept alive across runs: one child process each (granchain.lammps.worker --serve).

A fresh LAMMPS process per run pays Python's start-up, ``import lammps`` and the plugin's load
(0.1-0.3 s) every time, which dominates a campaign of small runs. Inside :func:`persistent` (or
between :func:`enable` and :func:`shutdown`), granchain.lammps.runner.run_deck runs single-rank decks
on a served child instead: the child keeps its LAMMPS instance and `clear`s it between decks.

The parent still never imports lammps: the instance lives in the child, so a crash takes only the
child. A child that dies (a crash, kill -9, a deck that exits LAMMPS) or that reported a LAMMPS error
(it exits then) is not reused: that run fails as it would in a fresh process, and the next run starts
a new child. Ctrl-C or any other exception while a deck runs kills the child (it cannot be stopped
mid-deck otherwise) before run_deck removes the work directory. Children are idle between runs;
:func:`shutdown` (also at exit) ends them, and a child exits by itself when its parent dies.

Several threads may run decks at once (a Dask worker with several threads): each run takes an idle
child or starts one, so one instance never runs two decks at once.
"""

from __future__ import annotations

import atexit
import json
import os
import select
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from granchain.lammps.build import plugin_env

#: seconds a child that reported an error, or is asked to stop, gets to exit before it is killed
EXIT_GRACE = 10.0


class ChildDied(Exception):
    """The served child ended before it had started the run (it was idle): the run can go to another."""


class LammpsServer:
    """One served LAMMPS child process (``python -m granchain.lammps.worker --serve``)."""

    def __init__(self):
        self.proc: subprocess.Popen | None = None
        self._buf = b""
        self.runs = 0
        self.plugin: Path | None = None  # the plugin file the child loaded

    @property
    def alive(self) -> bool:
        """Whether the served LAMMPS child is running."""
        return self.proc is not None and self.proc.poll() is None

    @property
    def pid(self) -> int | None:
        """The served child's process ID (None before it starts)."""
        return None if self.proc is None else self.proc.pid

    def start(self, plugin: Path | None = None) -> None:
        """Start the served child (``granchain.lammps.worker --serve``) with the plugin's environment."""
        self.plugin = plugin
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "granchain.lammps.worker", "--serve"],
            env=plugin_env(),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,  # during a deck its stderr is the run directory's worker.err
            bufsize=0,
        )
        self._buf = b""
        self.runs = 0

    def _answer(self, poll: Callable[[], None], interval: float) -> dict | None:
        """The child's next answer line, calling poll() every interval s meanwhile; None at its end."""
        fd = self.proc.stdout.fileno()
        while b"\n" not in self._buf:
            ready, _, _ = select.select([fd], [], [], interval)
            if not ready:
                poll()
                continue
            chunk = os.read(fd, 65536)
            if not chunk:
                return None
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        return json.loads(line)

    def run(
        self, work: Path, poll: Callable[[], None], interval: float, plugin: Path | None = None
    ) -> tuple[bool, int | None]:
        """Run work/deck.lmp on this child: (ok, the child's exit status if it has ended).

        plugin: the plugin file the run needs (build_plugin()); a child that loaded another (the
        plugin was rebuilt since: a process never reloads one) is replaced first.
        work/worker.json holds the child's report when it made one. Raises ChildDied if a child that had
        run decks before was gone before it started this one (a new child's end counts as the run's
        failure). Ctrl-C (any exception) meanwhile kills the child first.
        """
        if self.alive and plugin is not None and plugin != self.plugin:
            self.stop()
        fresh = not self.alive
        if fresh:
            self.stop(kill=True)  # reap a child that died while idle
            self.start(plugin)
        try:
            try:
                self.proc.stdin.write((json.dumps(str(work)) + "\n").encode())
                started = self._answer(poll, interval)
            except BrokenPipeError:
                started = None
            if started is None:  # gone before it read the run: killed while idle, or it could not start
                status = self.stop(kill=True)
                if not fresh:
                    raise ChildDied()
                return False, status
            self.runs += 1
            done = self._answer(poll, interval)
        except ChildDied:
            raise
        except BaseException:  # Ctrl-C, a bug: the deck cannot be stopped otherwise
            self.stop(kill=True)
            raise
        if done is not None and done.get("ok"):
            return True, None
        # it has crashed (no answer), or it answered an error and exits: wait for its end (its log is
        # then flushed) and let the next run start a new child
        return False, self.stop()

    def stop(self, kill: bool = False) -> int | None:
        """End the child (kill: at once; else end of stdin, then EXIT_GRACE s); its exit status."""
        proc, self.proc = self.proc, None
        if proc is None:
            return None
        try:
            if kill:
                proc.kill()
            else:
                try:
                    proc.stdin.close()
                except OSError:
                    pass
            try:
                return proc.wait(timeout=EXIT_GRACE)
            except subprocess.TimeoutExpired:
                proc.kill()
                return proc.wait()
        finally:
            for f in (proc.stdin, proc.stdout):
                try:
                    f.close()
                except OSError:
                    pass


_lock = threading.Lock()
_enabled = 0  # nesting depth of persistent() / enable()
_idle: list[LammpsServer] = []
_busy: set[LammpsServer] = set()


def enabled() -> bool:
    """Whether single-rank runs in this process go to served children."""
    return _enabled > 0


def enable() -> None:
    """From now on, single-rank runs of this process reuse served LAMMPS children (until shutdown)."""
    global _enabled
    with _lock:
        _enabled += 1


def shutdown() -> None:
    """Stop reusing children, and end the idle ones (a busy one ends when its run returns)."""
    global _enabled
    with _lock:
        _enabled = 0
        idle = list(_idle)
        _idle.clear()
    for s in idle:
        s.stop()


@contextmanager
def persistent() -> Iterator[None]:
    """Within: single-rank LAMMPS runs of this process reuse served children; after: they are ended."""
    global _enabled
    enable()
    try:
        yield
    finally:
        with _lock:
            _enabled = max(0, _enabled - 1)
            last = _enabled == 0
        if last:
            shutdown()


def acquire() -> LammpsServer:
    """An idle served child (or a new one, started at its first run) for one run."""
    with _lock:
        s = _idle.pop() if _idle else LammpsServer()
        _busy.add(s)
        return s


def release(s: LammpsServer) -> None:
    """A run is over: keep its child for the next run (if alive and reuse is still on), else end it."""
    with _lock:
        _busy.discard(s)
        keep = _enabled > 0 and s.alive
        if keep:
            _idle.append(s)
    if not keep:
        s.stop()


def children() -> list[int]:
    """Process ids of the served children alive now (for tests and diagnostics)."""
    with _lock:
        return [s.pid for s in (*_idle, *_busy) if s.alive]


def run(work: Path, poll: Callable[[], None], interval: float, plugin: Path | None = None) -> tuple[bool, int | None]:
    """Run work/deck.lmp on a served child (LammpsServer.run); a child found dead before it started
    the run (killed while idle) is replaced once."""
    s = acquire()
    try:
        try:
            return s.run(work, poll, interval, plugin)
        except ChildDied:  # a new child now: its end would be this run's failure, not ChildDied again
            return s.run(work, poll, interval, plugin)
    finally:
        release(s)


atexit.register(shutdown)
