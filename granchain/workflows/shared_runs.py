"""Runs made once and shared: inside one block, a run of a (scene, method) key is not made again.

granchain compare needs the same reference RK4 runs twice (the reference's error-bar companions and
LAMMPS's, workflows.run.shared_reference_runs). :class:`SharedRuns` holds the runs made inside the
block, by key, for every thread of the process; :func:`sharing` opens the block and may start the
runs it will be asked for at once in one worker process.

The worker dies with the process that started it, however that one ends (SIGTERM, SIGHUP, kill -9):
on Linux the kernel kills it (``PR_SET_PDEATHSIG``), a SIGTERM or SIGHUP to the parent first ends the
worker (:func:`_ending_pool_on`), and the worker holds none of the caller's output (its stdout and
stderr are /dev/null), so ``granchain compare | tee log`` ends when compare does.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, wait
from contextlib import contextmanager
from dataclasses import replace

from granchain.results import RunResult


class Abandoned(Exception):
    """A run or a wait for a shared run given up: the sharing block is being left after another run
    failed (granchain compare's LAMMPS run in a thread, when the reference's failed)."""


class SharedRuns:
    """The runs made inside one :func:`sharing` block, shared by threads.

    Attributes
    ----------
    runs : dict
        key -> the RunResult, or a Future of it: a prefetch in the worker process or a run being
        made by another thread (waited for; made again by the caller if it failed, as serially).
    lock : threading.Lock
        Held while ``runs`` is read or changed.
    """

    def __init__(self):
        self.runs: dict = {}
        self.lock = threading.Lock()
        self._stop = Future()

    def abandon(self) -> None:
        """Give up: runs not yet started and waits for shared runs raise Abandoned from now on."""
        if not self._stop.done():
            self._stop.set_result(None)

    @property
    def abandoned(self) -> bool:
        """Whether :meth:`abandon` was called."""
        return self._stop.done()

    def wait(self, future):
        """The future's result (None if it failed with an Exception); Abandoned if given up first."""
        done, _ = wait([future, self._stop], return_when=FIRST_COMPLETED)
        if future not in done:
            raise Abandoned("the shared run is no longer waited for")
        try:
            return future.result()
        except Exception:  # failed in the worker, the worker died, or another thread's run failed
            return None

    def get(self, key, make: Callable[..., RunResult]) -> RunResult:
        """The shared run of ``key``: ``make(*key)`` here, or waited for if prefetched or being made by
        another thread; each caller gets its own RunResult (a shallow copy) around the shared solution.

        A prefetch not started yet is made here at once rather than after the worker's queue; one
        that failed (or whose worker died), and another thread's run that raised, are made again
        here, so that this caller gets the run's own error as it would serially.
        """
        while True:
            with self.lock:
                got = self.runs.get(key)
                if got is None or (isinstance(got, Future) and got.cancel()):
                    mine = Future()  # made here: another thread asking meanwhile waits for it
                    mine.set_running_or_notify_cancel()
                    self.runs[key] = mine
                    break
            if isinstance(got, RunResult):
                return replace(got, extra=dict(got.extra))
            result = self.wait(got)
            with self.lock:
                if self.runs.get(key) is got:
                    if result is None:
                        del self.runs[key]
                    else:
                        self.runs[key] = result
        try:
            if self.abandoned:
                raise Abandoned("not started: the block is being left")
            result = make(*key)
        except BaseException as e:
            with self.lock:
                if self.runs.get(key) is mine:
                    del self.runs[key]
            mine.set_exception(e)
            raise
        with self.lock:
            self.runs[key] = result
        mine.set_result(result)
        return replace(result, extra=dict(result.extra))


#: the SharedRuns of the sharing() block this process is in, else None
_current: SharedRuns | None = None


def current() -> SharedRuns | None:
    """The SharedRuns of the :func:`sharing` block this process is in, None outside one."""
    return _current


def _worker_start(parent: int) -> None:
    """The prefetch worker's first act (its pool's initializer): die with ``parent``, and let go of
    the caller's stdout and stderr (a pipe it held open would outlive the caller).

    PR_SET_PDEATHSIG fires when the thread that forked the worker ends: the pool is made and its
    first task submitted (which forks) by the thread that holds the :func:`sharing` block, and the
    block outlives the pool."""
    if sys.platform.startswith("linux"):
        import ctypes

        pr_set_pdeathsig = 1
        try:
            ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # no prctl: the check below and the parent's handler remain
            pass
    if os.getppid() != parent:  # the parent died before the line above took effect
        os._exit(70)
    for sig in (signal.SIGTERM, signal.SIGHUP):  # the parent's handler (_ending_pool_on) is not ours
        signal.signal(sig, signal.SIG_DFL)
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(null, fd)
    os.close(null)


def _kill_workers(pool) -> None:
    """End a pool's worker processes now (not after their run, as shutdown would)."""
    if hasattr(pool, "kill_workers"):  # Python 3.14
        pool.kill_workers()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.kill()


@contextmanager
def _ending_pool_on(pool, signals=(signal.SIGTERM, signal.SIGHUP)) -> Iterator[None]:
    """Inside this block, ``signals`` end the pool's worker before they act as they did before
    (the default: this process ends too). Only the main thread may set handlers: elsewhere the
    worker's PR_SET_PDEATHSIG alone ends it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {sig: signal.getsignal(sig) for sig in signals}

    def handler(sig, frame):
        _kill_workers(pool)
        previous = before[sig]
        if callable(previous):
            previous(sig, frame)
            return
        signal.signal(sig, previous if previous is not None else signal.SIG_DFL)
        signal.raise_signal(sig)

    for sig in signals:
        signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, previous in before.items():
            signal.signal(sig, previous if previous is not None else signal.SIG_DFL)


@contextmanager
def sharing(prefetch: Iterable = (), prefetched: Callable | None = None) -> Iterator[SharedRuns]:
    """A block inside which runs are shared (:meth:`SharedRuns.get`); yields its SharedRuns.

    A block inside another shares the outer one's runs. Threads may run inside the block; a thread
    still running must be joined before the block is left (:meth:`SharedRuns.abandon` makes its
    waits give up).

    Parameters
    ----------
    prefetch : iterable of keys
        Keys that will be asked for, started at once in one worker process (forked) when
        ``prefetched`` is given.
    prefetched : callable or None
        A module-level function ``prefetched(*key)`` that makes a key's run in the worker and returns
        it, or None if it failed there (it is then made again by the caller that asks for it).
    """
    global _current
    outer = _current
    _current = SharedRuns() if outer is None else outer
    pool = None
    try:
        todo = [k for k in dict.fromkeys(prefetch) if k not in _current.runs]
        if todo and prefetched is not None:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            pool = ProcessPoolExecutor(
                max_workers=1,
                mp_context=multiprocessing.get_context("fork"),
                initializer=_worker_start,
                initargs=(os.getpid(),),
            )
            with _ending_pool_on(pool):
                for key in todo:
                    _current.runs[key] = pool.submit(prefetched, *key)
                yield _current
        else:
            yield _current
    finally:
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        _current = outer


__all__ = ["Abandoned", "SharedRuns", "current", "sharing"]
