"""`granchain collect` on LAMMPS output files whose values are damaged though their format is not: a
non-finite running peak, loop times that add up past any float, a histories.npy header claiming
terabytes, a run that ends at a negative step. Each is one `granchain: error:` line naming the file
(exit 2), never a traceback, a MemoryError or a run directory holding the damage; and what collect
writes loads back (load_run), displays (repr, _repr_html_) and plots."""

import re
import shutil
import struct
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.exceptions import GranchainError
from granchain.workflows.load import load_run

from . import test_hostile_collect
from .test_hostile_collect import _DAMAGE, _apply, copy_of, one_error_line

ran = test_hostile_collect.ran  # the same plain-LAMMPS run of a rendered deck, made once per module


def _peak_cell(value: str, column: int = 3):
    """peaks.dump's atom-4 row with its d_fpeak (column 3) or another column set to value."""

    def damage(d: Path) -> None:
        lines = (d / "peaks.dump").read_text().splitlines()
        row = lines[12].split()
        row[column] = value
        lines[12] = " ".join(row)
        (d / "peaks.dump").write_text("\n".join(lines) + "\n")

    return damage


def _loop_times(value: str):
    def damage(d: Path) -> None:
        text = (d / "log.lammps").read_text()
        (d / "log.lammps").write_text(re.sub(r"^Loop time of \S+", f"Loop time of {value}", text, flags=re.M))

    return damage


def _npy_shape(shape: str):
    """histories.npy's header rewritten to claim another shape (its data as it was)."""

    def damage(d: Path) -> None:
        b = (d / "histories.npy").read_bytes()
        n = struct.unpack("<H", b[8:10])[0]
        header = re.sub(r"'shape': \([^)]*\)", f"'shape': {shape}", b[10 : 10 + n].decode()).rstrip()
        (d / "histories.npy").write_bytes(b[:10] + (header.ljust(n - 1) + "\n").encode() + b[10 + n :])

    return damage


def _run_end(text: str):
    def damage(d: Path) -> None:
        (d / "run_end.txt").write_text(text)

    return damage


VALUES = {
    "a nan peak force": (_peak_cell("nan"), "peaks.dump: d_fpeak of atom 4 is nan"),
    "an inf peak force": (_peak_cell("inf"), "peaks.dump: d_fpeak of atom 4 is inf"),
    "a nan peak time": (_peak_cell("nan", 4), "peaks.dump: d_tpeak of atom 4 is nan"),
    "a -inf leading pulse": (_peak_cell("-inf", 6), "peaks.dump: d_flead of atom 4 is -inf"),
    "Loop times of 1e308": (_loop_times("1e308"), "log.lammps: its 'Loop time of' lines add up"),
    "histories.npy claiming (1e12, 3)": (_npy_shape("(1000000000000, 3)"), "histories.npy: its header says shape"),
    "histories.npy claiming fewer rows": (_npy_shape("(2, 3)"), "histories.npy: its header says shape"),
    "run_end.txt at step -5": (_run_end("-5 0.0008\n"), "run_end.txt: says step -5"),
    "run_end.txt at time -1": (_run_end("16000 -1\n"), "run_end.txt: says step 16000, time -1.0"),
    "run_end.txt at time nan": (_run_end("16000 nan\n"), "run_end.txt: says step 16000, time nan"),
}


@pytest.mark.parametrize("case", list(VALUES), ids=list(VALUES))
def test_a_damaged_value_is_one_error_line_naming_the_file(ran, tmp_path, capsys, case):
    damage, said = VALUES[case]
    d = copy_of(ran, tmp_path)
    damage(d)
    out = tmp_path / "out"
    assert main(["collect", str(d), "--out", str(out)]) == 2
    err = one_error_line(capsys)
    assert said in err, err
    assert "damaged" in err
    assert not out.exists()


_VALUE_DAMAGE = st.sampled_from(sorted(VALUES)).map(lambda k: ("value", k))


def _damage(d: Path, damage) -> None:
    if damage[0] == "value":
        VALUES[damage[1]][0](d)
    else:
        _apply(d, damage)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damages=st.lists(st.one_of(_VALUE_DAMAGE, _DAMAGE), min_size=1, max_size=3))
def test_collect_then_load_of_any_damaged_directory_works_or_is_one_error(ran, tmp_path_factory, capsys, damages):
    """Whatever collect accepts loads back, displays and plots; whatever it refuses is one line."""
    tmp = tmp_path_factory.mktemp("v")
    d = copy_of(ran, tmp)
    # a value damage edits a file's numbers: before the file damages, which may delete or garble it
    for damage in sorted(damages, key=lambda x: x[0] != "value"):
        _damage(d, damage)
    out = tmp / "out"
    rc = main(["collect", str(d), "--out", str(out)])  # a bug's exception propagates: the test fails
    err = capsys.readouterr().err
    assert rc in (0, 2), (damages, err)
    if rc == 2:
        assert err.startswith("granchain: error: "), err
        assert err.count("granchain: error:") == 1, err
    else:
        try:
            r = load_run(out)
        except GranchainError:
            pass
        else:
            repr(r)
            r._repr_html_()
    shutil.rmtree(tmp)
