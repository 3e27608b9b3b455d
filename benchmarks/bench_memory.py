"""What this machine's memory gives one core and two: the ceiling under issue 18's items 3 and 6.

A streaming kernel (numpy c = a + b: 24 bytes per element, reads of a and b and the write of c; the
write-allocate read of c is not counted) over arrays of a given working set, run by one process alone
and by two processes at once (started together at a barrier, as two MPI ranks are). For each working
set it prints the rate of one process, each of two, and the aggregate of two over one: the largest
speed-up np 2 can give a code that streams that many bytes per step, whatever the code.

    python benchmarks/bench_memory.py --reps 5
    python benchmarks/bench_memory.py --sizes-mib 1,16,64,512 --reps 3

Read with `bench_pair.py scaling` (ns per bead-step against N) and `bench_pair.py mpi` (np1/np2):
the chain's per-step working set is about (bytes per bead) x N, against the 32 MiB L3 of this machine.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import time

import numpy as np


def _stream(mib: float, sweeps: int, barrier, out) -> None:
    """One process: (a, b, c) of mib MiB together; c = a + b, sweeps times after one warm-up sweep;
    puts the GB/s (24 bytes per element) of the timed sweeps on out."""
    n = max(int(mib * 2**20 / 24), 1024)
    a, b, c = np.ones(n), np.ones(n), np.empty(n)
    np.add(a, b, out=c)  # touch every page before the clock starts
    if barrier is not None:
        barrier.wait()
    t0 = time.perf_counter()
    for _ in range(sweeps):
        np.add(a, b, out=c)
    dt = time.perf_counter() - t0
    out.put(24.0 * n * sweeps / dt / 1e9)


def rate(mib: float, procs: int) -> list[float]:
    """GB/s of each of procs processes streaming mib MiB each at once (about 0.5 s of sweeps)."""
    sweeps = max(int(0.5 * 2**30 * 10 / (mib * 2**20)), 5)  # ~5 GB streamed per process
    ctx = mp.get_context("fork")
    out = ctx.Queue()
    barrier = ctx.Barrier(procs) if procs > 1 else None
    ps = [ctx.Process(target=_stream, args=(mib, sweeps, barrier, out)) for _ in range(procs)]
    for p in ps:
        p.start()
    got = [out.get() for _ in ps]
    for p in ps:
        p.join()
    return got


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes-mib", default="0.5,4,16,32,64,256,768", help="working sets per process, MiB")
    ap.add_argument("--reps", type=int, default=3, help="alternated one-process and two-process runs")
    args = ap.parse_args()
    sizes = [float(s) for s in args.sizes_mib.split(",")]
    print(f"cores {os.cpu_count()}, load {os.getloadavg()[0]:.2f} at start")
    print("| working set per process (MiB) | one process (GB/s) | each of two (GB/s) | two / one (aggregate) |")
    print("|---|---|---|---|")
    for mib in sizes:
        one, two, ratios = [], [], []
        for _ in range(args.reps):  # alternated, paired: the ratio of each pair, then the median
            r1 = rate(mib, 1)[0]
            r2 = rate(mib, 2)
            one.append(r1)
            two.extend(r2)
            ratios.append(sum(r2) / r1)
        print(
            f"| {mib:g} | {statistics.median(one):.1f} | {statistics.median(two):.1f} | "
            f"{statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f}) |"
        )
    print(f"load {os.getloadavg()[0]:.2f} at end")


if __name__ == "__main__":
    main()
