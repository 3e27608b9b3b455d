"""What the Python API returns beyond a RunResult: the comparison of the two backends on a scene
(granchain.compare), as a pandas table with both results."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from granchain.results import RunResult, printable


@dataclass(repr=False)
class Comparison:
    """LAMMPS against the reference on one scene: ``table`` (pandas DataFrame indexed by quantity),
    ``lammps`` and ``reference`` (the two RunResults), ``rows`` (postprocess.comparison_table.CompareRow),
    ``rtol``, and ``path`` (the compare directory, when one was written).

    ``ok`` is True when every measured quantity agrees within rtol plus both runs' measured errors.
    """

    rows: list
    lammps: RunResult
    reference: RunResult
    rtol: float
    path: Path | None = None

    @property
    def table(self):
        """One row per quantity: unit, lammps, reference, their relative difference, each run's
        measured error (absolute, in the quantity's unit), the model value and its source, ok, and
        why a quantity was not measured. ``attrs["units"]`` maps each quantity to its unit."""
        return compare_frame(self.rows)

    @property
    def ok(self) -> bool:
        """Every quantity agrees within rtol plus both runs' measured errors (CompareRow.ok: one that
        only one run measured fails, one that neither measured does not)."""
        return all(r.ok for r in self.rows)

    def plot(self, kind: str = "peaks", ax=None):
        """The figure ``granchain plot COMPARE_DIR`` writes for this comparison, as a matplotlib Figure
        (not shown, not saved, pyplot's state untouched), drawn from the runs in memory.

        kind: "peaks" (compare_peaks.png: the peak force along the chain in both runs, their relative
        difference below) or "histories" (compare_histories.png). ax: (top, bottom) Axes to draw into,
        their Figure returned (granchain.workflows.plots.overlays.figure_compare).
        """
        from granchain.workflows.plots.overlays import figure_compare

        return figure_compare(self, kind, ax=ax)

    def disagreements(self) -> list[str]:
        """The quantities that differ by more than rtol plus both runs' errors."""
        return [r.quantity for r in self.rows if not r.ok]

    def __repr__(self) -> str:
        """A few lines: the scene, both runs' methods and steps, rtol and the verdict (which differ)."""
        title = printable(self.lammps.scene.title or self.lammps.scene.source or "untitled scene", 120)
        bad = self.disagreements()
        method = printable(self.reference.solution.method, 40)  # a loaded run's, from its summary.json
        verdict = "all agree" if not bad else f"{len(bad)} differ: {', '.join(bad)}"
        lines = [
            f"<Comparison: {title}",
            f"  lammps verlet dt = {self.lammps.solution.timestep:.4g} s; reference {method} "
            f"dt = {self.reference.solution.timestep:.4g} s; rtol {self.rtol:g}: {verdict}",
            f"  {len(self.rows)} quantities (.table: a pandas DataFrame)",
        ]
        if self.path is not None:
            lines.append(f"  compare directory: {printable(str(self.path), 200)}")
        return "\n".join(lines) + ">"

    def _repr_html_(self) -> str:
        import html

        head = html.escape(repr(self).splitlines()[1].strip())
        return f"<p>{head}</p>" + self.table._repr_html_()


def compare_frame(rows):
    """CompareRows as a pandas DataFrame indexed by quantity (see Comparison.table)."""
    import pandas as pd

    df = pd.DataFrame(
        {
            "unit": [r.unit for r in rows],
            "lammps": [r.a for r in rows],
            "reference": [r.b for r in rows],
            "relative_difference": [r.rel_diff for r in rows],
            "lammps_error": [r.error_a for r in rows],
            "reference_error": [r.error_b for r in rows],
            "model": [r.model if r.model_applies else None for r in rows],
            "model_source": [r.model_source for r in rows],
            "ok": [r.ok for r in rows],
            "not_measured": [r.not_measured or "" for r in rows],
        },
        index=pd.Index([r.quantity for r in rows], name="quantity"),
    )
    for c in ("lammps", "reference", "relative_difference", "lammps_error", "reference_error", "model"):
        df[c] = df[c].astype(float)
    df.attrs["units"] = {r.quantity: r.unit for r in rows}
    df.attrs["description"] = (
        "LAMMPS against the reference: values in each quantity's unit; errors absolute, measured from "
        "companion runs at 2 dt and 4 dt; relative_difference |a - b| / max(|a|, |b|)"
    )
    return df
