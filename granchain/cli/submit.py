"""granchain submit: one big run on a batch queue (docs/clusters.md)."""

from __future__ import annotations

import sys


def cmd_submit(args) -> int:
    """``granchain submit``: a scene's deck run on a batch queue, awaited and collected with --wait."""
    from granchain.cli.terminal import print_result, resolve_scene
    from granchain.workflows.collect import collect
    from granchain.workflows.submit import cancel, submit, wait

    scene = resolve_scene(args.scene)
    sub = submit(
        scene,
        args.out,
        ranks=args.ranks,
        queue=args.queue,
        account=args.account,
        walltime=args.walltime,
        memory=args.memory,
    )
    print(f"submitted job {sub.job_id}: {sub.script}", flush=True)
    if not args.wait:
        print(f"when it ends: granchain collect {sub.directory}   (its state: scontrol show job {sub.job_id})")
        return 0

    def on_state(state: str) -> None:
        print(f"granchain: job {sub.job_id} {state.lower()}", file=sys.stderr, flush=True)

    try:
        wait(sub, on_state=on_state)
    except KeyboardInterrupt:
        cancel(sub)
        print(f"granchain: interrupted; job {sub.job_id} (this submission's) was cancelled", file=sys.stderr)
        return 130
    print_result(collect(sub.directory), sub.directory)
    return 0


def add_submit_parser(sub) -> None:
    """granchain submit SCENE --out DIR [--ranks N] [--queue Q] [--account A] [--walltime T] [--memory M] [--wait]."""
    s = sub.add_parser(
        "submit",
        help="render a scene's deck, submit it to SLURM (plain LAMMPS under mpirun), and collect it (--wait)",
    )
    s.add_argument("scene", nargs="?", help="scene file or bundled scene name (default: default)")
    s.add_argument("--out", required=True, help="a new directory: the deck, job.sh, then the run directory")
    s.add_argument("--ranks", type=int, default=1, help="MPI ranks of the job (#SBATCH -n; default 1)")
    s.add_argument("--queue", default=None, help="partition (#SBATCH -p)")
    s.add_argument("--account", default=None, help="account (#SBATCH -A)")
    s.add_argument("--walltime", default="01:00:00", help="time limit HH:MM:SS (#SBATCH -t; default 01:00:00)")
    s.add_argument("--memory", default=None, help="memory of the job, e.g. 4GB (#SBATCH --mem)")
    s.add_argument("--wait", action="store_true", help="wait for the job and collect its run directory")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    s.set_defaults(func=cmd_submit)
