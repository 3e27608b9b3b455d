"""The example notebook (examples/granchain_tour.ipynb) runs top to bottom in a real Jupyter kernel
(nbclient, ipykernel): a scene written inline, runs on both backends, the comparison, load_run, a small
campaign, a LAMMPS dump opened in ASE (with ``units="si"``, the call docs/notebook.md gives) and in
granchain's dump view; its figures are shown as images; no cell writes to stderr or shows a warning; it
is kept in git without outputs."""

from __future__ import annotations

import base64
import re
from pathlib import Path

import nbformat
import pytest

NOTEBOOK = Path(__file__).resolve().parent.parent / "examples" / "granchain_tour.ipynb"


def test_the_notebook_is_kept_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [], cell.source[:60]
            assert cell.execution_count is None, cell.source[:60]


@pytest.mark.slow
def test_the_notebook_runs_in_a_jupyter_kernel(tmp_path, monkeypatch):
    from nbclient import NotebookClient

    monkeypatch.setenv("TMPDIR", str(tmp_path))  # the notebook's run directories (tempfile.mkdtemp)
    monkeypatch.setenv("GRANCHAIN_QUIET", "1")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    # a warning in a kernel is written to stderr (warnings.showwarning); a red box in the notebook
    stderr = [o.text for o in outputs if o.output_type == "stream" and o.name == "stderr"]
    assert not stderr, stderr
    shown = [o.get("text", "") + str(o.get("data", {}).get("text/plain", "")) for o in outputs]
    assert not [t for t in shown if "Warning" in t], shown
    images = [
        base64.b64decode(o.data["image/png"])
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.outputs
        if o.output_type in ("execute_result", "display_data") and "image/png" in o.data
    ]
    # granchain's own figures (histories, peaks, comparison, heat map) and the notebook's (campaign)
    assert len(images) >= 5
    assert all(i.startswith(b"\x89PNG") and len(i) > 10_000 for i in images)
    texts = "\n".join(
        o.data.get("text/plain", "")
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.outputs
        if o.output_type == "execute_result"
    )
    assert "<RunResult: Notebook tour" in texts
    assert "<LammpsRunResult: Notebook tour" in texts
    # ASE's velocities, read with units="si" and converted from its units, are the dump view's: a read
    # in ASE's default metal units would differ by 98x the velocity (about 7 m/s here)
    stdout = "".join(o.text for o in outputs if o.output_type == "stream" and o.name == "stdout")
    difference = float(re.search(r"largest \|v_ASE - v_view\| \(m/s\): (\S+)", stdout).group(1))
    assert difference < 1e-12
    html = [
        o.data["text/html"] for c in nb.cells for o in getattr(c, "outputs", []) if "text/html" in o.get("data", {})
    ]
    assert any(h.startswith("<table><caption>granchain RunResult") for h in html)


def test_the_notebook_uses_the_documented_readers_and_views():
    """Issue 43: the tour reads the dump with ASE as docs/notebook.md does (units="si", without which
    velocities are 98x too small), and uses scene.replace, the dump view and Comparison.plot."""
    code = "\n".join(c.source for c in nbformat.read(NOTEBOOK, as_version=4).cells if c.cell_type == "code")
    reads = re.findall(r"ase\.io\.read\((.*?)\)\n", code, flags=re.S)
    assert reads
    assert all('units="si"' in r for r in reads), reads
    assert ".replace(" in code
    assert ".dump" in code
    assert "cmp.plot()" in code  # Comparison.plot, not a comparison drawn by hand
