"""`granchain run`'s lines: an observable that does not apply to the run's scene is not a row of its own;
one line per reason says which do not apply and why, and summary.json keeps every one with its reason."""

from __future__ import annotations

import io
from contextlib import redirect_stdout

from granchain.cli.terminal import print_result
from granchain.scene import parse_scene
from granchain.workflows.run import run_scene
from tests.scenegen import PEAKS, brass_text

#: a short struck chain on a free far end (no wall's event, no drive: both kinds do not apply)
FREE = brass_text(8, 'kind = "velocity"\nvelocity = 0.5\n', PEAKS)
#: the same on a wall with its event asked for: the wall's event quantities apply and are rows
WALLED = FREE.replace("[outputs]", '[boundary]\nfar_end = "wall"\n[outputs]\nevent = true')


def lines_of(text: str) -> tuple[list[str], dict]:
    result = run_scene(parse_scene(text, source="lines.toml"), backend="reference")
    out = io.StringIO()
    with redirect_stdout(out):
        print_result(result, "run-dir")
    return out.getvalue().splitlines(), result.summary()


def rows(lines: list[str]) -> set[str]:
    """The observables named at the start of a row ("  name (unit)   value ...")."""
    return {line.split()[0] for line in lines if line.startswith("  ") and not line.startswith("   ")}


def test_what_does_not_apply_is_one_line_per_reason():
    lines, s = lines_of(FREE)
    inapplicable, missing = s["observables_inapplicable"], s["observables_missing"]
    assert "wall_max_force" in inapplicable
    assert "far_end_amplitude" in inapplicable
    assert not rows(lines) & set(inapplicable), "an observable that does not apply has a row of its own"
    said = [line for line in lines if line.strip() and any(missing[k] in line for k in inapplicable)]
    reasons = {missing[k] for k in inapplicable}
    assert len(said) == len(reasons), said  # each reason once
    assert all(line.split()[:3] == ["not", "applicable", "(observables)"] for line in said), said
    for reason in reasons:
        names = [k for k in inapplicable if missing[k] == reason]
        more = f" and {len(names) - 1} more" if len(names) > 1 else ""
        assert any(f"{names[0]}{more}: {reason}" in line for line in said), reason


def test_what_applies_keeps_its_row():
    lines, s = lines_of(WALLED)
    assert "wall_max_force" not in s["observables_inapplicable"]
    assert "wall_max_force" in rows(lines)
    assert "leading_peak_force" in rows(lines)  # measured, or unmeasured with its reason: a row either way
