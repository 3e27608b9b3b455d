"""`granchain reproduce`: the paper's figures and printed numbers regenerated from campaigns shipped
in this package, each number beside the paper's, with its error bar, the model's value and a verdict.

    granchain reproduce [--quick | --full] --out DIR [--workers N | --scheduler ADDRESS]

Every run is a point of a campaign in DIR/ws/ (cached: a second call runs nothing and redraws);
the figures go to DIR/figures/, the report to DIR/report.md and DIR/report.html (self-contained),
the rows to DIR/rows.json. docs/reproduce.md says what each section computes and how.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
import time
import traceback
from dataclasses import asdict
from datetime import UTC, datetime
from pathlib import Path

from granchain import safe_files
from granchain.exceptions import GranchainError, UsageError
from granchain.reproduce.sections import Context, SectionResult, not_yet, output_dir, output_file

#: the sections, in the report's order: (module under granchain.reproduce, title)
SECTIONS = (
    ("constants", "Eq. 8 and the Appendix constants A1-A4"),
    ("elastic", "Sec. II C numbers and Fig. 2: a long step load on an elastic chain"),
    ("table1", "Table I and Fig. 9: a long load on a bilinear chain"),
    ("fig1", "Fig. 1: single solitary wave -> wave train"),
    ("fig3", "Fig. 3: peak force over amplitude at fixed impulses, and the master curve"),
    ("plastic", "Figs. 5-8: bilinear chains under a short impulse"),
    ("laws", "Thornton vs bilinear: does the bilinear law capture the nonlinear law's phenomena?"),
)


def campaign_specs(quick: bool) -> dict[str, dict]:
    """Every campaign `reproduce` runs in a mode, by workspace name (DIR/ws/<mode>-<name>)."""
    mode = "quick" if quick else "full"
    out = {}
    for name, _ in SECTIONS:
        mod = importlib.import_module(f"granchain.reproduce.{name}")
        out.update({f"{mode}-{k}": v for k, v in mod.campaign_specs(quick).items()})
    return out


def run_section(ctx: Context, name: str, title: str) -> SectionResult:
    """One section of the report: its module's ``run(ctx)``. A section whose module is missing or
    raises is reported as not reproduced (with the traceback in its notes), and the others still run."""
    try:
        mod = importlib.import_module(f"granchain.reproduce.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"granchain.reproduce.{name}":
            raise
        return not_yet(name, title, "this section's module is not written yet")
    try:
        return mod.run(ctx)
    except Exception as exc:  # a failed section is reported, and the others still run
        res = not_yet(name, title, f"the section failed: {type(exc).__name__}: {exc}")
        res.notes.append("```\n" + traceback.format_exc(limit=4) + "```")
        res.failed = True
        return res


def reproduce(
    out, quick: bool = True, workers: int | None = None, scheduler: str | None = None, sections=None, stream=None
) -> dict:
    """Run every section (or those named in `sections`) into `out`; returns the report's metadata
    with 'sections' (SectionResult list), 'ran' and 'cached' (campaign points) and the paths."""
    from granchain._version import __version__
    from granchain.reproduce import report

    if workers is not None and scheduler is not None:
        raise UsageError("--workers and --scheduler: give one (a scheduler brings its own workers)")
    names = [n for n, _ in SECTIONS]
    for s in sections or ():
        if s not in names:
            raise UsageError(f"--section {s!r}: choose from {', '.join(names)}")
    t0 = time.monotonic()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    output_dir(out / "ws", "its campaign workspaces")  # before any section: one error, not one per section
    ctx = Context(out, quick=quick, workers=workers, scheduler=scheduler, stream=stream)
    results = [run_section(ctx, n, t) for n, t in SECTIONS if not sections or n in sections]
    meta = {
        "mode": ctx.mode,
        "version": __version__,
        "when": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "ran": sum(r.ran for r in ctx.reports.values()),
        "cached": sum(r.cached for r in ctx.reports.values()),
        "failed_points": sum(r.failed + r.failed_before + r.lost for r in ctx.reports.values()),
        "campaigns": {k: {"ran": r.ran, "cached": r.cached, "points": r.points} for k, r in ctx.reports.items()},
    }
    meta["elapsed"] = time.monotonic() - t0
    for r in results:
        for row in r.rows:
            row.judge()
    safe_files.write_text(
        output_file(out / "rows.json"),
        json.dumps(
            {
                **meta,
                "rows": [asdict(row) for s in results for row in s.rows],
                "sections": [
                    {
                        "key": s.key,
                        "title": s.title,
                        "reproduced": s.reproduced,
                        "figures": [f.name for f in s.figures],
                        "cost": s.cost,
                    }
                    for s in results
                ],
            },
            indent=1,
            default=float,
        ),
    )
    md = report.write_markdown(out, results, meta)
    page = report.write_html(out, results, meta)
    return {**meta, "sections": results, "report_md": md, "report_html": page}


def build_parser() -> argparse.ArgumentParser:
    """The ``granchain reproduce`` command line: the mode (--quick, the default, or --full), --out,
    where campaign points run (--workers or --scheduler), --section and --quiet."""
    p = argparse.ArgumentParser(
        prog="granchain reproduce",
        description="Regenerate the paper's figures and printed numbers, with verdicts (docs/reproduce.md).",
    )
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="coarser grids and shorter chains (default)")
    mode.add_argument("--full", action="store_true", help="the paper's resolution (slow)")
    p.add_argument("--out", required=True, help="output directory (its ws/ caches every run)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, help="local Dask workers (default: the cores)")
    where.add_argument("--scheduler", default=None, help="address of a running Dask scheduler")
    p.add_argument("--section", action="append", default=None, help="only this section (repeatable)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    return p


def main(argv: list[str] | None = None) -> int:
    """Exit status: 0 every section ran, 1 a section or campaign point failed, 2 a user error."""
    for out in (sys.stdout, sys.stderr):  # as granchain.cli.terminal.tolerant_output (a layer above this one)
        if hasattr(out, "reconfigure"):
            out.reconfigure(errors="backslashreplace")
    args = build_parser().parse_args(argv)
    if args.workers is not None and args.workers < 1:
        print(f"granchain: error: --workers {args.workers}: give 1 or more", file=sys.stderr)
        return 2
    stream = open(os.devnull, "w") if args.quiet else None  # noqa: SIM115
    try:
        meta = reproduce(
            args.out,
            quick=not args.full,
            workers=args.workers,
            scheduler=args.scheduler,
            sections=args.section,
            stream=stream,
        )
    except GranchainError as exc:
        print(f"granchain: error: {exc}", file=sys.stderr)
        return 2
    finally:
        if stream is not None:
            stream.close()
    counts: dict[str, int] = {}
    for s in meta["sections"]:
        for r in s.rows:
            counts[r.verdict] = counts.get(r.verdict, 0) + 1
    print(f"report: {meta['report_md']} and {meta['report_html']}")
    print(", ".join(f"{v}: {n}" for v, n in sorted(counts.items())) + f"; runs {meta['ran']}, cached {meta['cached']}")
    bad = any(getattr(s, "failed", False) for s in meta["sections"]) or meta["failed_points"]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
