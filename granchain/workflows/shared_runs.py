"""Runs made once and shared: inside one block, a run of a (scene, method) key is not made again.

granchain compare needs the same reference RK4 runs twice (the reference's error-bar companions and
LAMMPS's, workflows.run.shared_reference_runs). :class:`SharedRuns` holds the runs made inside the
block, by key, for every thread of the process; :func:`sharing` opens the block and may start the
runs it will be asked for at once in one worker process.
"""

from __future__ import annotations

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

            pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("fork"))
            for key in todo:
                _current.runs[key] = pool.submit(prefetched, *key)
        yield _current
    finally:
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        _current = outer


__all__ = ["Abandoned", "SharedRuns", "current", "sharing"]
