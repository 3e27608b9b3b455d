"""The example notebook (examples/granchain_tour.ipynb) runs top to bottom in a real Jupyter kernel
(nbclient, ipykernel): a scene written inline, runs on both backends, the comparison, load_run, a small
campaign, a LAMMPS dump opened in ASE; its figures are shown as images; it is kept in git without
outputs."""

from __future__ import annotations

import base64
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
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors
    images = [
        base64.b64decode(o.data["image/png"])
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.outputs
        if o.output_type in ("execute_result", "display_data") and "image/png" in o.data
    ]
    # granchain's own figures (histories, peaks, heat map) and the notebook's (comparison, campaign)
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
    html = [
        o.data["text/html"] for c in nb.cells for o in getattr(c, "outputs", []) if "text/html" in o.get("data", {})
    ]
    assert any(h.startswith("<table><caption>granchain RunResult") for h in html)
