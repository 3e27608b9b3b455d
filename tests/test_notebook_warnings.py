"""The first LAMMPS run in a notebook shows no TqdmWarning (issue 43 item 7): MDAnalysis imports
tqdm.auto, which in a Jupyter kernel without ipywidgets warns "IProgress not found"; granchain
silences that warning where it imports MDAnalysis, and nowhere else."""

from __future__ import annotations

import subprocess
import sys
import textwrap

#: a fresh interpreter that looks like a Jupyter kernel to tqdm.autonotebook (ipykernel's shell module
#: loaded, IPython's shell a ZMQInteractiveShell) without ipywidgets
KERNEL_LIKE = textwrap.dedent(
    """
    import sys, types, warnings
    shell = type("ZMQInteractiveShell", (), {})()
    sys.modules["ipykernel.zmqshell"] = types.ModuleType("ipykernel.zmqshell")
    ipython = types.ModuleType("IPython")
    ipython.get_ipython = lambda: shell
    sys.modules["IPython"] = ipython
    sys.modules["ipywidgets"] = None  # not installed
    warnings.simplefilter("always")
    """
)


def _warnings_of(code: str) -> str:
    out = subprocess.run(
        [sys.executable, "-c", KERNEL_LIKE + textwrap.dedent(code)], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    return out.stderr


def test_granchain_imports_mdanalysis_without_tqdms_notebook_warning():
    stderr = _warnings_of(
        """
        from granchain.postprocess.dumps import read_dump
        try:  # MDAnalysis is imported first, then the missing file refused
            read_dump("/nonexistent/chain.dump")
        except (OSError, ValueError):
            pass
        """
    )
    assert "IProgress not found" not in stderr
    assert "TqdmWarning" not in stderr


def test_the_warning_is_silenced_only_there():
    """tqdm.auto imported by the user's own code in the same kernel still warns."""
    stderr = _warnings_of(
        """
        import granchain
        import tqdm.auto
        """
    )
    assert "IProgress not found" in stderr
