"""fix chain/energy (the plugin; DeckOptions.energy_fix) against what it replaces: the energy samples
written by fix print (a flush per line) and the run watch's energy balance as LAMMPS variables read by
fix ave/time and fix halt. Both decks must write the same bytes on any scene, stop on the same step with
the same value when the balance breaks, and leave every sample taken before a stop in energy.txt."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.lammps.runner import HALT_MESSAGE, LammpsError, invariant_from_lammps, run_deck
from granchain.scene import load_scene, parse_scene
from granchain.templates import PLUGIN_DECK_OPTIONS, render_deck

from .conftest import LAW_NAMES, RANDOM_LOADINGS, make_scene_text, random_scene_text

FIX = PLUGIN_DECK_OPTIONS
PRINT = dataclasses.replace(PLUGIN_DECK_OPTIONS, energy_fix=False)
#: what the deck writes (not log.lammps: it has timings)
OUTPUTS = ("energy.txt", "peaks.dump", "histories.npy", "run_end.txt", "load_end.txt")


def test_the_options_differ_only_in_the_energy_pieces():
    fix, old = (render_deck(load_scene("plastic-short-impulse"), options=o).deck for o in (FIX, PRINT))
    assert re.search(r"^fix\s+energy all chain/energy \d+ energy.txt title .* dissipated dissipated$", fix, re.M)
    assert re.search(r"^fix_modify\s+energy watch \S+ v_watch_work watch_max$", fix, re.M)
    assert not re.search(r"^fix\s+(watch_energy|watch_rel)\s", fix, re.M)
    assert re.search(r"^fix\s+energy all print ", old, re.M)
    assert re.search(r"^fix\s+watch_energy all halt", old, re.M)
    assert "chain/energy" not in old
    # precompression's extra column x[N] is read by the fix itself
    pre = render_deck(load_scene("effect-precompression"), options=FIX).deck
    assert re.search(r"^fix\s+energy all chain/energy .* first 1 extra x\[\d+\]$", pre, re.M)


def outputs_of(deck: str, data: str, work, np_: int = 1) -> dict[str, bytes]:
    _, work = run_deck(deck, data, np_=np_, work_dir=work)
    got = {f: (work / f).read_bytes() for f in OUTPUTS if (work / f).exists()}
    assert "energy.txt" in got
    assert "peaks.dump" in got
    return got


def assert_same_bytes(scene, tmp_path, np_: int = 1) -> None:
    a, b = (render_deck(scene, options=o) for o in (FIX, PRINT))
    assert a.data == b.data
    got_a = outputs_of(a.deck, a.data, tmp_path / "fix", np_)
    got_b = outputs_of(b.deck, b.data, tmp_path / "print", np_)
    assert got_a.keys() == got_b.keys()
    for name in got_a:
        assert got_a[name] == got_b[name], name
    rows = np.loadtxt(tmp_path / "fix" / "energy.txt", comments="#", ndmin=2)
    assert rows.shape[0] > 3
    assert np.all(np.isfinite(rows))


@pytest.mark.parametrize(
    "name", ["default", "plastic-short-impulse", "effect-precompression", "effect-dashpot", "effect-striker"]
)
def test_bundled_scenes_write_the_same_bytes(tmp_path, name):
    """The bundled scenes' every output file, byte for byte: the energy columns (with dissipated, with
    precompression's xN, with a striker ahead of bead 1) and all the rest."""
    assert_same_bytes(load_scene(name), tmp_path)


def test_two_ranks_write_the_same_bytes(tmp_path):
    """On two ranks bead 1 and bead N live on different ranks: x[ID] is summed over ranks."""
    text = make_scene_text(beads=120, loading='kind = "step"\namplitude = 200.0\nduration = 1e-4', end_time=3e-4)
    assert_same_bytes(parse_scene(text + "\n[precompression]\nforce = 10.0\n", source="t.toml"), tmp_path, np_=2)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    law=st.sampled_from(LAW_NAMES),
    beads=st.integers(5, 150),
    loading=st.sampled_from(sorted(RANDOM_LOADINGS)),
    size=st.floats(0.2, 5.0),
    wall=st.booleans(),
    precompression=st.sampled_from([0.0, 0.0, 20.0]),
    dashpot=st.sampled_from([0.0, 0.0, 3.0]),
)
@example(law="thornton", beads=40, loading="step", size=3.0, wall=True, precompression=20.0, dashpot=3.0)
def test_random_scenes_write_the_same_bytes(tmp_path_factory, law, beads, loading, size, wall, precompression, dashpot):
    """Random scenes (every law, loading and effect; a step load ends mid-run, so watch_work is redefined
    between runs): the fix writes fix print's bytes, and its watch lets the same runs through."""
    text = random_scene_text(
        law=law,
        beads=beads,
        loading=loading,
        size=size,
        wall=wall,
        precompression=precompression,
        dashpot=dashpot,
        end_time=1.5e-4,
        step_duration=5e-5,
        outputs="peak_force = true\nhistories = [1, 3]",
    )
    assert_same_bytes(parse_scene(text, source="test.toml"), tmp_path_factory.mktemp("run"))


def _halt(deck: str, data: str, work) -> tuple[tuple[str, str, str], bytes]:
    with pytest.raises(LammpsError) as e:
        run_deck(deck, data, work_dir=work)
    msg = str(e.value)
    m = re.search(HALT_MESSAGE, msg)
    assert m, msg
    return m.groups(), (work / "energy.txt").read_bytes()


def _kicked(deck: str, kick: float) -> str:
    """The deck with every bead's velocity raised by kick (m/s) before its second run: energy created
    that the balance's work does not hold, mid-run (after the load ended and watch_work was redefined)."""
    runs = [m.start() for m in re.finditer(r"^run\s", deck, re.M)]
    assert len(runs) >= 2
    at = runs[1]
    return deck[:at] + f"velocity        all set {kick!r} NULL NULL sum yes\n" + deck[at:]


@pytest.mark.parametrize("name", ["default", "plastic-short-impulse", "effect-precompression"])
def test_a_broken_balance_stops_both_on_the_same_step_and_value(tmp_path, name):
    """Energy created before the deck's second run: both watches stop on the same step, in that run,
    naming the same atom and sign; and energy.txt holds the same samples up to the stop (the fix
    writes its buffer before it stops the run).

    The relative error in the value agrees to 1e-12, not to the bit: the variables' formula read
    v_watch_e, v_watch_work and v_watch_scale as LAMMPS passes a v_ reference, %.15g text (a relative
    change of up to 5e-15 in each, so about 2e-14 in the balance), while the fix keeps the doubles."""
    sc = load_scene(name)
    a, b = (render_deck(sc, options=o) for o in (FIX, PRINT))
    first_run = int(re.search(r"^run\s+(\d+)", a.deck, re.M).group(1))
    (fix_id, step, value), text_a = _halt(_kicked(a.deck, 20.0), a.data, tmp_path / "fix")
    (old_id, old_step, old_value), text_b = _halt(_kicked(b.deck, 20.0), b.data, tmp_path / "print")
    assert fix_id == old_id == "watch_energy"
    assert step == old_step
    assert int(step) > first_run
    v, w = float(value), float(old_value)
    assert v > 0
    assert w > 0
    assert int(v) == int(w)
    assert abs((v - int(v)) - (w - int(w))) < 1e-12
    assert text_a == text_b
    assert text_a.count(b"\n") > 2
    err = LammpsError(f"Fix chain/energy condition watch_energy met on step {step} with value {value}")
    broken = invariant_from_lammps(err, sc)
    assert broken is not None
    assert broken.invariant == "energy balance"
    assert broken.step == int(step)


def test_samples_before_another_stop_are_written(tmp_path):
    """Another fix stops the run with an error half-way through its steps: the fix (deleted with the
    failed instance) has written every sample taken before, as fix print had."""
    sc = load_scene("default")
    got = []
    for o, tag in ((FIX, "fix"), (PRINT, "print")):
        d = render_deck(sc, options=o)
        half = d.total_steps // 2
        stop = f"variable        half equal step>={half}\nfix             half all halt 10 v_half > 0 error hard\n"
        deck = d.deck.replace("thermo_style", stop + "thermo_style", 1)
        with pytest.raises(LammpsError, match=f"halt condition for fix-id half met on step {half}"):
            run_deck(deck, d.data, work_dir=tmp_path / tag)
        got.append((tmp_path / tag / "energy.txt").read_bytes())
    rows = np.loadtxt(tmp_path / "fix" / "energy.txt", comments="#", ndmin=2)
    assert got[0] == got[1]
    assert rows.shape[0] > 10


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("fix             e2 all chain/energy 10 e2.txt first 1", "needs title and first"),
        ('fix             e2 all chain/energy 0 e2.txt title "#" first 1', "N must be > 0"),
        ('fix             e2 all chain/energy 10 e2.txt title "#" first 1 extra ke', "x\\[ID\\] or v_NAME"),
        ('fix             e2 all chain/energy 10 e2.txt title "#" first 1 dissipated nope', "no compute nope"),
        ("fix_modify      energy watch 0 v_watch_work watch_max", "BOUND must be > 0"),
    ],
)
def test_bad_arguments_are_refused(tmp_path, line, message):
    d = render_deck(load_scene("default"), options=FIX)
    deck = d.deck.replace("thermo_style", line + "\nthermo_style", 1)
    with pytest.raises(LammpsError, match=message):
        run_deck(deck, d.data, work_dir=tmp_path)


def test_file_none_keeps_the_watch_without_samples(tmp_path):
    """FILE none (the benchmarks' deck without outputs): no energy.txt, and the balance check still stops
    a run whose energy was created, on the step the deck with samples stops."""
    d = render_deck(load_scene("default"), options=FIX)
    none, n = re.subn(r"^(fix\s+energy all chain/energy \d+ )energy\.txt ", r"\g<1>none ", d.deck, flags=re.M)
    assert n == 1
    (fix_id, step, _), _ = _halt(_kicked(d.deck, 20.0), d.data, tmp_path / "file")
    with pytest.raises(LammpsError, match=f"chain/energy condition watch_energy met on step {step} "):
        run_deck(_kicked(none, 20.0), d.data, work_dir=tmp_path / "none")
    assert not (tmp_path / "none" / "energy.txt").exists()
