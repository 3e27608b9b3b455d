"""granchain campaign run / table / plot: the command line of granchain.campaigns (docs/campaigns.md)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from granchain.exceptions import UsageError


def cmd_campaign_run(args) -> int:
    """``granchain campaign run``: run a campaign file's points into its workspace and print its table."""
    from granchain.campaigns.run import run_campaign
    from granchain.campaigns.table import format_table

    out = args.out or f"runs/{Path(args.file).stem}-campaign"
    cluster = {
        "kind": args.cluster,
        "queue": args.queue,
        "account": args.account,
        "walltime": args.walltime,
        "jobs": args.jobs,
        "cores_per_job": args.cores_per_job,
        "memory": args.memory,
        "interface": args.interface,
        "replacements": args.replacements,
        "prologue": args.prologue,
    }
    try:
        tables, report = run_campaign(
            args.file,
            out,
            workers=args.workers,
            scheduler=args.scheduler,
            rerun=args.rerun,
            retry_failed=args.retry_failed,
            cluster=cluster,
            ranks=args.ranks,
        )
    except KeyboardInterrupt as e:
        if not getattr(e, "said", False):  # CampaignInterrupted said so already (unless quiet)
            print(
                f"granchain: interrupted; the complete points are kept in {out}: run the same command again to "
                "complete only the missing ones"
                if Path(out).exists()
                else "granchain: interrupted before the campaign's workspace was made; nothing was written",
                file=sys.stderr,
            )
        return 130
    main_table = tables.get("search", tables.get("trials", tables["table"]))
    print(format_table(main_table))
    r = report
    print(
        f"campaign   {r.points} points: {r.cached} complete before, {r.done} run now, {r.failed} failed"
        + (f", {r.failed_before} failed before" if r.failed_before else "")
        + (f", {r.lost} lost" if r.lost else "")
        + (f", {r.stale} stale run again" if r.stale else "")
    )
    extra = ", search.csv" if "search" in tables else ", trials.csv" if "trials" in tables else ""
    print(f"workspace  {out} (table.csv, table.parquet{extra})")
    if "trials" in tables:
        _print_best(out, tables)
    unfound = []
    if "search" in tables:
        unfound = [
            m for st, m in zip(tables["search"]["status"], tables["search"]["message"], strict=True) if st != "found"
        ]
        for message in unfound:
            print(f"granchain: search: {message}", file=sys.stderr)
    return 0 if not (r.failed or r.lost or r.failed_before or unfound) else 1


def cmd_campaign_table(args) -> int:
    """``granchain campaign table``: a workspace's table (or a search's transitions), also as CSV.
    Only reads the workspace to print it: --csv writes nothing there; without it table.csv and
    table.parquet are written too, and a workspace that cannot be written (read-only, someone else's,
    a full disk) is a warning, the table printed all the same."""
    import warnings

    from granchain.campaigns.table import campaign_tables, format_table, save_tables
    from granchain.campaigns.workspace import WorkspaceWriteError

    tables = campaign_tables(args.workspace)
    if not args.csv:
        try:
            save_tables(args.workspace, tables)
        except WorkspaceWriteError as e:
            warnings.warn(f"{e}; the table is printed, not saved", stacklevel=1)
    if args.best:
        return _print_best(args.workspace, tables)
    df = tables["search"] if args.search else tables.get("trials", tables["table"])
    if args.search and "search" not in tables:
        raise UsageError(f"{args.workspace}: is a grid campaign; --search is for a search campaign's transitions")
    if args.csv:
        if sys.stdout.isatty():  # on a terminal a parameter's text cannot retitle or clear it
            from granchain.campaigns.table import printable

            df = df.map(lambda v: printable(v) if isinstance(v, str) else v)
        df.to_csv(sys.stdout, index=False)
    else:
        print(format_table(df))
    return 0


def _print_best(ws, tables) -> int:
    """``campaign table --best``: an optimize campaign's best design, objective, error bar, verdict."""
    from granchain.campaigns.optimize import best_design, best_text, front_text, near_front, pareto_front
    from granchain.campaigns.table import printable, read_record

    if "trials" not in tables:
        raise UsageError(f"{ws}: is not an optimize campaign; --best is for an optimize campaign's best design")
    record = read_record(Path(ws))
    opt = record.get("optimize") or {}
    keys = tuple(opt.get("keys") or ())
    if opt.get("objective_2"):  # two objectives: the Pareto front
        rows = tables["trials"].to_dict("records")
        directions = (opt.get("direction", "minimize"), opt.get("direction_2"))
        front = pareto_front(rows, directions)
        objectives = (str(opt.get("objective")), str(opt["objective_2"]))
        for line in front_text(front, objectives, keys, near_front(rows, directions)).split("\n"):
            print(printable(line))
        return 0 if front else 1
    best = best_design(tables["trials"].to_dict("records"), opt.get("direction", "minimize"), keys)
    confirm = record.get("optimize_confirm") if isinstance(record.get("optimize_confirm"), dict) else None
    for line in best_text(best, str(opt.get("objective")), keys, confirm).split("\n"):
        print(printable(line))
    return 0 if best is not None else 1


def cmd_campaign_plot(args) -> int:
    """``granchain campaign plot``: an observable against a varied key, with its error bars."""
    from granchain.campaigns.plot import plot_campaign, plot_convergence

    formats = tuple(f.strip() for f in args.format.split(",") if f.strip())
    if args.convergence:
        for path in plot_convergence(args.workspace, out=args.out, formats=formats):
            print(path)
        return 0
    if args.x is None or args.y is None:
        raise UsageError("campaign plot: give --x and --y (or --convergence for an optimize campaign)")
    paths = plot_campaign(
        args.workspace,
        x=args.x,
        y=args.y,
        hue=args.hue,
        map_key=args.map,
        out=args.out,
        formats=formats,
    )
    for path in paths:
        print(path)
    return 0


def ranks_arg(text: str) -> int | str:
    """--ranks: a whole number of MPI ranks per point, or "auto"."""
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of MPI ranks or 'auto', got {text!r}") from None


def add_campaign_parser(sub) -> None:
    """granchain campaign run / table / plot (docs/campaigns.md)."""
    cp = sub.add_parser("campaign", help="sweeps and searches over scenes, cached and resumable, on Dask")
    csub = cp.add_subparsers(dest="campaign_command", required=True)
    cr = csub.add_parser("run", help="run a campaign file's points into a workspace (only what is missing)")
    cr.add_argument("file", help="campaign file (.toml; docs/campaigns.md)")
    cr.add_argument("--out", help="workspace directory (default runs/<file>-campaign)")
    cr.add_argument("--workers", type=int, default=None, help="local Dask worker processes (default: the cores)")
    cr.add_argument("--scheduler", default=None, help="address of a running Dask scheduler (tcp://host:8786)")
    cr.add_argument(
        "--ranks", type=ranks_arg, default=None, help="MPI ranks per LAMMPS point, or auto (default: [campaign] ranks)"
    )
    cl = cr.add_argument_group("worker jobs on a batch queue (docs/clusters.md; flags win over the file's [cluster])")
    cl.add_argument("--cluster", choices=["local", "slurm", "pbs"], default=None, help="where the workers run")
    cl.add_argument("--queue", default=None, help="partition / queue of the worker jobs (#SBATCH -p)")
    cl.add_argument("--account", default=None, help="account charged for the jobs (#SBATCH -A)")
    cl.add_argument("--walltime", default=None, help="each worker job's time limit, HH:MM:SS (default 01:00:00)")
    cl.add_argument("--jobs", type=int, default=None, help="worker jobs kept in the queue (default 1)")
    cl.add_argument("--cores-per-job", type=int, default=None, help="cores per job (default: the ranks of a point)")
    cl.add_argument("--memory", default=None, help="memory per job, e.g. 4GB (default: the queue's)")
    cl.add_argument("--interface", default=None, help="network interface of the scheduler and workers (ib0, lo)")
    cl.add_argument("--replacements", type=int, default=None, help="ended jobs replaced (default 2 per job)")
    cl.add_argument(
        "--prologue",
        action="append",
        default=None,
        help="a shell line each job runs before its worker (repeatable), e.g. 'source /shared/venv/bin/activate'",
    )
    cr.add_argument("--rerun", action="store_true", help="run every point again, complete or not")
    cr.add_argument("--retry-failed", action="store_true", help="run the points that failed before again")
    cr.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    cr.set_defaults(func=cmd_campaign_run)
    ct = csub.add_parser("table", help="the table of a workspace (also written as table.csv and table.parquet)")
    ct.add_argument("workspace", help="a campaign workspace (granchain campaign run --out)")
    ct.add_argument("--csv", action="store_true", help="print the whole table as CSV")
    ct.add_argument("--search", action="store_true", help="a search campaign's transitions (one row per outer point)")
    ct.add_argument(
        "--best", action="store_true", help="an optimize campaign's best design and whether it is distinguished"
    )
    ct.set_defaults(func=cmd_campaign_table)
    cpl = csub.add_parser("plot", help="an observable against a key, with error bars (or a 2D map)")
    cpl.add_argument("workspace", help="a campaign workspace")
    cpl.add_argument("--x", default=None, help="the key on the x axis (a column of the table)")
    cpl.add_argument("--y", default=None, help="the observable (a column: leading_peak_force, wave_speed, ...)")
    cpl.add_argument(
        "--convergence", action="store_true", help="an optimize campaign: objective and best so far per trial"
    )
    cpl.add_argument("--hue", default=None, help="one line per value of this key (the other varied keys follow)")
    cpl.add_argument("--map", default=None, help="a 2D map of --y over --x and this key instead of lines")
    cpl.add_argument("--out", default=None, help="figure path without suffix (default WS/plots/<y>-vs-<x>...)")
    cpl.add_argument("--format", default="png", help="png, pdf, svg (comma-separated; default png)")
    cpl.set_defaults(func=cmd_campaign_plot)
