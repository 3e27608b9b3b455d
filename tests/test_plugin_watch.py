"""The deck's plugin pieces against the LAMMPS built-ins they replace and against the reference
solver: the run watch's computes chain/fmax and chain/momentum, fix chain/nve, and the neighbour list
checked every 10 steps with the pair style's stop at a dangerous build.

The legacy deck is rendered here from the current one by putting the built-ins back (atom-style variables
and compute reduce, fix nve, a neighbour check every step): it must give the same doubles."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from granchain.lammps.runner import LammpsError, lammps_result, read_results, run_deck
from granchain.scene import load_scene
from granchain.templates import PLUGIN_DECK_OPTIONS, DeckOptions, render_deck
from granchain.workflows.run import run_reference

from .conftest import law_example, make_scene

WATCH_NEW = "compute         watch_max all chain/fmax\n"
WATCH_OLD = (
    "variable        watch_fc atom d_fc\n"
    "variable        watch_id atom id\n"
    "compute         watch_max all reduce max v_watch_fc v_watch_id replace 2 1\n"
)
#: the same with each contact against its own bound (a chain whose contacts' bounds differ: d_fwatch)
WATCH_NEW_BOUND = "compute         watch_max all chain/fmax fwatch\n"
WATCH_OLD_BOUND = (
    "variable        watch_fc atom d_fc/d_fwatch\n"
    "variable        watch_id atom id\n"
    "compute         watch_max all reduce max v_watch_fc v_watch_id replace 2 1\n"
)
MOMENTUM_NEW = "compute         watch_p all chain/momentum\n"
MOMENTUM_OLD = "variable        watch_mv atom mass*vx\ncompute         watch_p all reduce sum v_watch_mv\n"
PLUGIN = DeckOptions(watch_computes=True)
NVE = DeckOptions(watch_computes=True, chain_nve=True)


def _sub(pattern: str, repl: str, deck: str) -> str:
    new, k = re.subn(pattern, repl, deck, flags=re.M)
    assert k == 1, f"the deck has no line {pattern!r}"
    return new


def legacy(deck: str) -> str:
    """The deck with LAMMPS's built-ins in place of the plugin's pieces and a neighbour check every step."""
    assert deck.count(WATCH_NEW) + deck.count(WATCH_NEW_BOUND) == 1
    assert deck.count(MOMENTUM_NEW) <= 1
    deck = deck.replace(WATCH_NEW, WATCH_OLD).replace(WATCH_NEW_BOUND, WATCH_OLD_BOUND)
    deck = deck.replace(MOMENTUM_NEW, MOMENTUM_OLD)
    deck = _sub(r"^neigh_modify\s+every \d+ delay 0 check yes", "neigh_modify    every 1 delay 0 check yes", deck)
    if "chain/nve" in deck:
        deck = _sub(r"^(fix\s+integrate\s+\S+\s+)chain/nve$", r"\1nve", deck)
    commands = "\n".join(_commands(deck))
    assert "chain/fmax" not in commands
    assert "chain/momentum" not in commands
    assert "chain/nve" not in commands
    return deck


def _run(deck: str, data: str, tmp: Path, np_: int = 1) -> dict[str, np.ndarray]:
    _, work = run_deck(deck, data, np_=np_, work_dir=tmp)
    res = read_results(work)
    res["energy"] = np.loadtxt(work / "energy.txt", comments="#", ndmin=2)
    return res


def test_the_deck_uses_the_plugin_pieces():
    deck = render_deck(load_scene("default"), options=PLUGIN).deck
    assert WATCH_NEW in deck
    assert MOMENTUM_NEW in deck
    assert not re.search(r"^compute\s+watch\w*\s+\S+\s+reduce", deck, re.M)
    assert re.search(r"^neigh_modify\s+every 10 delay 0 check yes binsize \S+$", deck, re.M)
    assert re.search(r"^neigh_modify\s+every 10 delay 0 check yes", render_deck(load_scene("default")).deck, re.M)
    builtins = render_deck(load_scene("default"), options=DeckOptions(neigh_every=1)).deck
    assert _commands(legacy(deck)) == _commands(builtins)  # legacy() is the deck with the built-ins


def _commands(deck: str) -> list[str]:
    return [line for line in deck.splitlines() if not line.startswith("#")]
    assert re.search(r"^fix\s+integrate all chain/nve$", render_deck(load_scene("default"), options=NVE).deck, re.M)


@pytest.mark.parametrize("name", ["default", "plastic-short-impulse", "effect-wall", "effect-precompression"])
@pytest.mark.parametrize("options", [PLUGIN, NVE], ids=["nve", "chain-nve"])
def test_deck_gives_the_legacy_numbers(tmp_path, name, options):
    d = render_deck(load_scene(name), options=options)
    a = _run(legacy(d.deck), d.data, tmp_path / "legacy")
    b = _run(d.deck, d.data, tmp_path / "new")
    assert a.keys() == b.keys()
    for key in a:
        assert np.array_equal(a[key], b[key]), key  # the same expressions: the same doubles


def test_deck_on_two_ranks(tmp_path):
    d = render_deck(load_scene("default"), options=NVE)
    a = _run(legacy(d.deck), d.data, tmp_path / "a")
    b = _run(d.deck, d.data, tmp_path / "b", np_=2)
    for key in ("x", "vx", "fpeak", "tpeak"):
        np.testing.assert_allclose(b[key], a[key], rtol=1e-12, atol=1e-15 * np.max(np.abs(a[key])))


@pytest.mark.parametrize("law", ["hertz", "thornton"])
def test_chain_nve_deck_equals_reference_verlet(tmp_path, law):
    """fix chain/nve and the sparse neighbour check against the reference solver's velocity Verlet, step for
    step (the bar of tests/test_lammps.py), on a chain whose far end flies off (beads leave the
    shrink-wrapped box between neighbour checks)."""
    sc = make_scene(
        beads=30,
        law=law,
        contact_extra=law_example(law),
        loading='kind = "velocity"\nvelocity = 30.0',
        end_time=2e-4,
        timestep=2e-8,
        outputs="histories = [1, 10]",
    )
    d = render_deck(sc, options=NVE)
    info, work = run_deck(d.deck, d.data, work_dir=tmp_path, total_steps=d.total_steps)
    a = lammps_result(sc, work, info["wall_time"], {}).solution
    b = run_reference(sc, "verlet").solution

    def rel(x, y):
        return np.nanmax(np.abs(x - y)) / np.nanmax(np.abs(y))

    assert rel(a.peak_force, b.peak_force) < 1e-9
    assert rel(a.velocity, b.velocity) < 1e-9
    assert rel(a.displacement, b.displacement) < 1e-9
    assert rel(a.history_force, b.history_force) < 1e-9
    assert rel(a.history_velocity, b.history_velocity) < 1e-9


def _halt(deck: str, data: str, tmp: Path, np_: int = 1) -> tuple[str, ...]:
    with pytest.raises(LammpsError) as e:
        run_deck(deck, data, np_=np_, work_dir=tmp)
    m = re.search(r"halt condition for fix-id (\w+) met on step (\d+) with value (\S+)", str(e.value))
    assert m, str(e.value)
    return m.groups()


@pytest.mark.parametrize("np_", [1, 2])
def test_watch_computes_stop_on_the_same_step_and_atom(tmp_path, np_):
    """A force bound the default scene's pulse crosses: both watches halt on the same step and name the
    same atom (compute chain/fmax is compute reduce max ... replace)."""
    d = render_deck(load_scene("default"), options=PLUGIN)
    low = re.sub(r"\(c_watch_max\[1\] > \S+\)", "(c_watch_max[1] > 2000.0)", d.deck)
    assert low != d.deck
    old = _halt(legacy(low), d.data, tmp_path / "a", np_)
    new = _halt(low, d.data, tmp_path / "b", np_)
    assert old == new


def test_momentum_watch_stops_on_the_same_step(tmp_path):
    """An expected momentum off by 1%: both momentum watches halt at the first energy sample, same value."""
    d = render_deck(load_scene("default"), options=PLUGIN)
    off = re.sub(r'^(variable\s+watch_p_expected equal )"(.*)"$', r'\1"1.01*(\2)"', d.deck, flags=re.M)
    assert off != d.deck
    assert _halt(legacy(off), d.data, tmp_path / "a") == _halt(off, d.data, tmp_path / "b")


def test_chain_nve_refuses_motion_off_the_axis(tmp_path):
    d = render_deck(load_scene("default"), options=NVE)
    deck = d.deck.replace(
        "read_data       chain.data", "read_data       chain.data\nvelocity        all set NULL 1.0 NULL"
    )
    with pytest.raises(LammpsError, match="chain/nve integrates along x only"):
        run_deck(deck, d.data, work_dir=tmp_path)


def _skin(deck: str, skin: str) -> str:
    return _sub(r"^neighbor\s+\S+ bin$", f"neighbor        {skin} bin", deck)


def test_dangerous_build_fails_the_run(tmp_path):
    """A skin so small that beads move more than half of it between two checks: LAMMPS would count a
    dangerous build and carry on; the pair style fails the run at its end, also one a soft halt ends
    early. Checked every step, the same deck runs."""
    d = render_deck(load_scene("default"))
    with pytest.raises(LammpsError, match="dangerous neighbour list build"):
        run_deck(_skin(d.deck, "1e-9"), d.data, work_dir=tmp_path / "sparse")
    early = (
        "variable        early equal step>=40\nfix             early all halt 20 v_early > 0 error soft\nthermo_style"
    )
    soft = _skin(d.deck, "1e-9").replace("thermo_style", early, 1)
    with pytest.raises(LammpsError, match="dangerous neighbour list build") as e:
        run_deck(soft, d.data, work_dir=tmp_path / "soft")
    assert "Last input line: run " in str(e.value)
    every1 = _sub(r"^neigh_modify\s+every 10 ", "neigh_modify    every 1 ", _skin(d.deck, "1e-9"))
    run_deck(every1, d.data, work_dir=tmp_path / "every1")


def test_sparse_check_needs_the_distance_check(tmp_path):
    d = render_deck(load_scene("default"))
    deck = _sub(r"^neigh_modify\s+every 10 delay 0 check yes", "neigh_modify    every 10 delay 0 check no", d.deck)
    with pytest.raises(LammpsError, match="needs 'check yes'"):
        run_deck(deck, d.data, work_dir=tmp_path)


@pytest.mark.parametrize("name", ["default", "plastic-short-impulse", "effect-precompression"])
def test_energy_watch_reads_the_balance_of_its_own_step(tmp_path, name):
    """The energy watch's halt reads the relative balance kept by fix ave/time (f_watch_rel: evaluated
    once a check, not at each of the halt's four reads). At every check, across the deck's runs (load,
    load end, free flight), the kept value must be the balance of that very step: a print after the
    halt writes it beside v_watch_rel evaluated afresh. Fails if the two fixes' steps or order differ.
    (The deck without fix chain/energy, DeckOptions(energy_fix=False): tests/test_energy_fix.py holds
    the two to the same samples and stops.)"""
    d = render_deck(load_scene(name), options=dataclasses.replace(PLUGIN_DECK_OPTIONS, energy_fix=False))
    every = int(re.search(r"^fix\s+watch_energy all halt (\d+) ", d.deck, re.M).group(1))
    line = f'fix             check_rel all print {every} "$(step) $(v_watch_rel:%.17g) $(f_watch_rel:%.17g)"'
    line += " file rel.txt screen no"
    deck, n = re.subn(r"^(fix\s+watch_energy all halt .*)$", lambda m: m.group(1) + "\n" + line, d.deck, flags=re.M)
    assert n == 1
    _, work = run_deck(deck, d.data, work_dir=tmp_path)
    rows = np.loadtxt(work / "rel.txt", comments="#", ndmin=2)
    runs = [int(s) for s in re.findall(r"^run\s+(\d+)", deck, re.M)]
    assert rows.shape[0] >= sum(runs) // every - len(runs) > 10
    assert np.count_nonzero(rows[:, 1]) > rows.shape[0] // 2  # round-off balances, not all zero
    # (a v_ reference reaches a formula as %.15g text in LAMMPS: the halt's four reads were rounded
    # so before; f_watch_rel keeps the double. Another step's balance differs in the leading digits)
    np.testing.assert_allclose(rows[:, 2], rows[:, 1], rtol=1e-14, atol=0)
