"""A work-precision study's files: accuracy.csv, accuracy.png and accuracy.md, written aside and renamed
into place, and the Markdown summary."""

from __future__ import annotations

import csv
import os
from pathlib import Path

from granchain import safe_files
from granchain.integrators import INTEGRATORS
from granchain.rundir import RunDirError, check_output_dir, owned_by_granchain
from granchain.workflows.accuracy_model import PLAN_RTOL, STUDY_METHODS, TARGETS, AccuracyStudy


def check_study_dir(out: str | Path, overwrite: bool = False) -> Path:
    """Fail early (before the study runs) if out cannot take the study: it exists and is not empty
    (without overwrite), it is not a directory granchain wrote (with overwrite), it is a link, or its
    parent is not writable (a RunDirError naming it and the fix). An empty directory is taken."""
    out = Path(out)
    if _empty_dir(out):
        return out
    return check_output_dir(out, overwrite)


def _empty_dir(d: Path) -> bool:
    if os.path.islink(d) or not d.is_dir():
        return False
    try:
        with os.scandir(d) as it:
            return next(it, None) is None
    except OSError:
        return False


def write_study(study: AccuracyStudy, out: str | Path, overwrite: bool = False) -> list[Path]:
    """accuracy.csv, accuracy.png and accuracy.md in the directory out, written aside and renamed into
    place (granchain's marker in it): out must be new or empty, or, with overwrite, a directory
    granchain wrote (check_study_dir). Returns the three paths."""
    out = check_study_dir(out, overwrite)
    if _empty_dir(out):
        os.rmdir(out)  # taken as new: the directory is renamed into its place
    try:
        with safe_files.atomic_directory(out, "accuracy", overwrite=overwrite, owned=owned_by_granchain) as tmp:
            _write_study_files(study, tmp)
    except OSError as e:
        raise RunDirError(f"{out}: could not write the study ({e}); nothing was left behind") from None
    return [out / "accuracy.csv", out / "accuracy.png", out / "accuracy.md"]


def _write_study_files(study: AccuracyStudy, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with safe_files.create_new(out / "accuracy.csv") as fh:
        w = csv.writer(fh)
        w.writerow(["method", "setting", "steps", "wall_time", "error_peak_force", "error_wave_speed", "reference"])
        for p in [*study.points, *study.plan_points]:
            w.writerow(
                [
                    p.method + (" (planned)" if p in study.plan_points else ""),
                    repr(p.setting),
                    p.steps,
                    repr(p.wall_time),
                    repr(p.error_peak),
                    "" if p.error_speed is None else repr(p.error_speed),
                    p.reference,
                ]
            )
    fig, ax = plt.subplots(figsize=(7, 5))
    for m in dict.fromkeys(p.method for p in study.points):
        pts = [p for p in study.points if p.method == m]
        label = STUDY_METHODS[m].label
        if len(study.references) > 1:
            label += f" vs converged {_name(pts[0].reference)}"
        (line,) = ax.loglog([p.wall_time for p in pts], [max(p.error_peak, 1e-16) for p in pts], "o-", label=label)
        for q in (q for q in study.plan_points if q.method == m):
            ax.loglog(
                [q.wall_time],
                [max(q.error_peak, 1e-16)],
                "*",
                ms=13,
                mec="k",
                color=line.get_color(),
                label=f"{label}: planned for rtol {PLAN_RTOL:g} (dt {q.setting:.3g} s)",
            )
    for (r, ref), ls in zip(study.references.items(), (":", "-."), strict=False):
        ax.axhline(ref.error, color="gray", ls=ls, label=f"converged {_name(r)}'s own error (Richardson)")
    if not study.references:
        ax.axhline(study.reference_error, color="gray", ls=":", label="converged reference's own error (Richardson)")
    ax.axhline(PLAN_RTOL, color="0.5", ls="--", lw=0.8, label=f"rtol {PLAN_RTOL:g}")
    ax.set_xlabel("wall time (s, median of repeats; LAMMPS start-up excluded)")
    ax.set_ylabel("max relative error of peak forces")
    import textwrap

    text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in str(study.scene.title or ""))
    title = "\n".join(textwrap.wrap(f"Work-precision: {text or study.scene.source}", 80))
    ax.set_title(title, fontsize=9, parse_math=False)  # the scene's own text, not mathtext
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    try:
        safe_files.save_figure(fig, out / "accuracy.png", dpi=120)
    finally:
        plt.close(fig)
    with safe_files.create_new(out / "accuracy.md") as fh:
        fh.write(summary_text(study))


def _name(method: str) -> str:
    facts = INTEGRATORS.get(method)
    return method if facts is None else facts.label


def reference_lines(study: AccuracyStudy) -> list[str]:
    """What each row is measured against, as Markdown lines: each converged run, its own error, its
    peak and the methods measured against it; with two, the definitions' difference; methods not run."""
    if not study.references:
        return [
            f"Converged reference RK4 at dt = {study.reference_timestep:.3g} s, its own error "
            f"(Richardson) {study.reference_error:.1e}.",
        ]
    lines = ["Each method is measured against a converged run whose peak is the same quantity:"]
    for r, ref in study.references.items():
        lines.append(
            f"- converged {_name(r)} at dt = {ref.timestep:.3g} s ({ref.how}), its own error {ref.error:.1e}; "
            f"its peak: {ref.peak}; measures {', '.join(ref.measures)}"
        )
    if study.definition_gap is not None:
        lines.append(
            f"- the two converged runs' peaks differ by {study.definition_gap:.1e}: different quantities (the "
            f"{study.scene.damping.noun}'s force), not step error; a method's error is of its own peak, not the other's"
        )
    lines += [f"- not run: {m} ({why})" for m, why in study.skipped.items()]
    return lines


def summary_text(study: AccuracyStudy) -> str:
    """The study as Markdown: the measured contacts, the converged runs each method is measured against
    and their own errors, and a table per method."""
    lines = [
        f"# Work-precision: {study.scene.title or study.scene.source}",
        "",
        f"Measured contacts: {study.contacts.min()}..{study.contacts.max()} ({len(study.contacts)}).",
        "",
        *reference_lines(study),
        "",
    ]
    lines.append("Observed orders (fit of log error vs log dt, points above 10x their reference's own error):")
    orders = study.orders()
    for m, o in orders.items():
        against = next(p.reference for p in study.points if p.method == m)
        lines.append(f"- {m}: {o:.2f} (against converged {_name(against)})")
    lines += [
        "",
        "| target | cheapest method | setting | wall time (s) | error | measured against |",
        "|---|---|---|---|---|---|",
    ]
    for t in TARGETS:
        p = study.cheapest(t)
        if p is None:
            lines.append(f"| {t:g} | none reached it | | | | |")
        else:
            setting = f"rtol {p.setting:g}" if p.method == "dop853" else f"dt {p.setting:.3g} s"
            lines.append(
                f"| {t:g} | {p.method} | {setting} | {p.wall_time:.3g} | {p.error_peak:.1e} | "
                f"converged {_name(p.reference)} |"
            )
    if study.plan_points:
        lines += [
            "",
            f"The planner's choice for rtol {PLAN_RTOL:g} (the stars on the diagram), measured:",
            "",
            "| method | planned dt (s) | wall time (s) | error | meets rtol | measured against |",
            "|---|---|---|---|---|---|",
        ]
        lines += [
            f"| {q.method} | {q.setting:.3g} | {q.wall_time:.3g} | {q.error_peak:.1e} | "
            f"{'yes' if q.error_peak <= PLAN_RTOL else 'no'} | converged {_name(q.reference)} |"
            for q in study.plan_points
        ]
    if study.one_time:
        lines += [
            "",
            "One-time costs (not in the wall times): "
            + ", ".join(f"{k} {v:.3g} s" for k, v in study.one_time.items() if v is not None),
        ]
    if study.dump_errors:
        lines += [
            "",
            "Dump-derived peaks vs in-run peaks (LAMMPS), max relative error:",
            "",
            "| dump every (steps) | raw samples | parabola-refined |",
            "|---|---|---|",
        ]
        lines += [f"| {s} | {r:.1e} | {f:.1e} |" for s, r, f in study.dump_errors]
    return "\n".join(lines) + "\n"
