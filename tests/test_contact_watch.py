"""The run watch holds each contact to its own bodies' radii (granchain.invariants.contact_overlap_bounds),
in both backends: a run whose every overlap stays below its own bound is never stopped, a genuine
blow-up still is, on the same step and contact in both, with a message naming the contact."""

from __future__ import annotations

import re
from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.invariants import InvariantError, contact_overlap_bounds
from granchain.scene import parse_scene
from granchain.templates import PLUGIN_DECK_OPTIONS, render_deck
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_scene

from .conftest import make_scene_text
from .test_plugin_watch import _halt, legacy
from .test_varied_chains import MIN_RADIUS, STEEP_TAPER, chain_text

OVERLAP = "overlap far below the radius"


def _taper(loading: str, extra: str = "", taper: float = 0.85, beads: int = 20, timestep: float = 1e-7):
    text = make_scene_text(beads=beads, loading=loading, end_time=2e-5, timestep=timestep)
    return parse_scene(text.replace('material = "brass"', f'material = "brass"\ntaper = {taper!r}') + extra, "t.toml")


#: a bead 1 kicked at 1000 m/s at a coarse step: beads pass far into each other within 40 steps
BLOW_UPS = {
    "taper": _taper('kind = "velocity"\nvelocity = 1000.0'),
    "striker": _taper('kind = "striker"\nvelocity = 1000.0'),
    "taper and wall": _taper('kind = "velocity"\nvelocity = 1000.0', '[boundary]\nfar_end = "wall"\n'),
}


def _stop(sc, backend: str) -> InvariantError:
    with pytest.raises(InvariantError) as e:
        run_scene(sc, backend=backend, method="verlet", force=True)
    return e.value


@pytest.mark.parametrize("name", sorted(BLOW_UPS))
def test_a_blow_up_is_stopped_on_the_same_step_and_contact_in_both_backends(name):
    """A genuine blow-up on chains whose contacts have bounds of their own (a taper, a striker, a wall):
    both backends stop on the overlap watch at the same step, name the same contact (a striker's is
    contact 0, as the scene numbers it) and say which bodies it joins."""
    sc = BLOW_UPS[name]
    ref, lmp = _stop(sc, "reference"), _stop(sc, "lammps")
    assert ref.invariant == OVERLAP, str(ref)
    assert lmp.invariant == OVERLAP, str(lmp)
    assert (lmp.step, lmp.contact) == (ref.step, ref.contact)
    bodies = "the striker and bead 1" if name == "striker" else f"beads {ref.contact} and {ref.contact + 1}"
    for err in (ref, lmp):
        assert f"contact {ref.contact}: " in str(err)
        assert bodies in str(err)
        assert "half the smaller radius" in str(err)
    # the reference's overlap is beyond the bound of that contact's own beads, which it names
    m = re.search(r", (\S+) m, exceeds its bound (\S+) m", str(ref))
    assert m, str(ref)
    bound = contact_overlap_bounds(sc)[ref.contact if name == "striker" else ref.contact - 1]
    assert float(m.group(2)) == pytest.approx(bound, rel=1e-2)
    assert float(m.group(1)) > float(m.group(2))


@pytest.mark.parametrize("np_", [1, 2])
def test_the_built_in_watch_and_compute_chain_fmax_stop_alike_on_per_contact_bounds(tmp_path, np_):
    """On a deck with a bound per contact (d_fwatch), compute chain/fmax fwatch and the built-ins'
    d_fc/d_fwatch with compute reduce stop on the same step and atom once the bounds are lowered below
    the forces a sound run reaches, on one rank and on two (the bounds move with their atoms)."""
    sc = plan_scene(STEEP_TAPER, method="verlet").scene
    d = render_deck(sc, options=PLUGIN_DECK_OPTIONS)
    assert "chain/fmax fwatch" in d.deck
    low = d.deck.replace('"(c_watch_max[1] > 1.0)', '"(c_watch_max[1] > 0.01)')
    assert low != d.deck
    new = _halt(low, d.data, tmp_path / "new", np_)
    assert new == _halt(legacy(low), d.data, tmp_path / "old", np_)
    assert new[0] == "watch"


def test_a_uniform_chain_keeps_one_bound_and_a_taper_gets_one_per_contact():
    """Uniform chains keep the deck's one force number; a taper's contacts each get the force their
    law gives at half the smaller radius of their own beads, so contact 1's bound is far above the one
    the smallest bead's radius gives."""
    uniform = render_deck(parse_scene(make_scene_text(), "u.toml"))
    assert "d_fwatch" not in uniform.deck
    assert "Watch" not in uniform.data
    taper = render_deck(_taper('kind = "velocity"\nvelocity = 1.0', taper=0.8))
    assert "read_data       chain.data fix watch_bound NULL Watch\n" in taper.deck
    rows = [r.split() for r in taper.data.split("\nWatch\n\n", 1)[1].splitlines()]
    assert [int(r[0]) for r in rows] == list(range(1, 21))  # every atom: contacts 1-19, bead 20 with 19's
    f = np.array([float(r[1]) for r in rows])
    assert f[-1] == f[-2]
    assert np.all(np.diff(f[:-1]) < 0)  # smaller beads, smaller bounds
    assert f[0] / f[-1] > 0.8**-18  # contact 1's bound is not the smallest beads'


# ---- a run whose every contact stays below its own bound is not stopped


@st.composite
def fast_kicked_chains(draw):
    """A brass or steel chain kicked hard at bead 1: a taper 0.8 to 1, a dimer (mass ratio up to 20),
    or random radii (2 to 6 mm), 10 to 20 beads, 0.5 to 5 m/s, possibly walled; times "auto"."""
    n = draw(st.integers(10, 20), label="beads")
    kind = draw(st.sampled_from(["taper", "dimer", "radii"]), label="kind")
    if kind == "taper":
        lowest = max(0.8, (MIN_RADIUS / 4.76e-3) ** (1.0 / (n - 1)) * (1 + 1e-9))
        chain = f'radius = 4.76e-3\ntaper = {draw(st.floats(lowest, 1.0), label="taper")!r}\nmaterial = "brass"\n'
    elif kind == "dimer":
        r2 = 4.76e-3 / draw(st.floats(1.2, 20.0), label="mass ratio") ** (1.0 / 3.0)
        chain = f'radius = {[4.76e-3 if i % 2 == 0 else r2 for i in range(n)]!r}\nmaterial = "stainless-steel-316"\n'
    else:
        chain = f'radius = {[draw(st.floats(2e-3, 6e-3), label=f"R{i + 1}") for i in range(n)]!r}\nmaterial = "brass"\n'
    velocity = draw(st.floats(0.5, 5.0), label="velocity")
    sc = parse_scene(chain_text(chain, n, velocity, wall=draw(st.booleans(), label="wall")), source="kick.toml")
    return plan_scene(sc, method="verlet").scene


def _largest_relative_overlap(sc) -> float:
    """The largest peak overlap over its own contact's bound in a reference run with the overlap watch
    off (a wall's contact has no peak_overlap column, its bound is bead N's own radius)."""
    with mock.patch("granchain.backends.builtin.contact_overlap_bounds", return_value=None):
        s = run_scene(sc, backend="reference", method="verlet").solution
    bounds = contact_overlap_bounds(sc)
    front = 1 if sc.loading.kind == "striker" else 0
    return float(np.max(np.asarray(s.peak_overlap) / bounds[front : front + sc.n_contacts]))


@pytest.mark.slow
@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
@example(sc=plan_scene(STEEP_TAPER, method="verlet").scene)
@given(sc=fast_kicked_chains())
def test_the_watch_stops_no_run_whose_contacts_stay_below_their_own_bounds(sc):
    """Either backend may stop a run on the overlap watch only if some contact's overlap (reference,
    watch off) went beyond its own bound: tapers, dimers and random radii under fast kicks, whose big
    beads may overlap more than half the smallest bead's radius. The draws that matter most (a steep
    taper: CI's one is the explicit example) had been stopped as blow-ups by a bound on the chain's
    smallest radius."""
    stops = {}
    for backend in ("reference", "lammps"):
        try:
            run_scene(sc, backend=backend, method="verlet")
        except InvariantError as e:
            if e.invariant != OVERLAP:
                raise
            stops[backend] = str(e)
    if stops:
        assert _largest_relative_overlap(sc) > 1.0, f"a sound run stopped: {stops}"


@pytest.mark.parametrize("busiest", [0, 1, 3])
def test_the_reference_watch_numbers_every_contact_as_the_scene_does(busiest):
    """Behind a striker the scene numbers the striker's contact 0 and the chain's 1 .. N - 1: the
    energy and finite-state watches name contacts and bodies that way, like the overlap watch."""
    from types import SimpleNamespace

    from granchain.invariants import InvariantError
    from granchain.problem import ChainProblem
    from granchain.reference.observers import RunWatch
    from granchain.reference.state import ChainState

    state = ChainState(ChainProblem.from_scene(BLOW_UPS["striker"]).with_ends())
    assert state.problem.front == 1
    state.u[:] = 0.0
    state.u[busiest] = 1e-6  # the striker's or a bead's: its contact ahead is the most compressed
    watch = RunWatch(state, SimpleNamespace(listeners=[]), 1, None, 1e-12, None)
    with pytest.raises(InvariantError) as got:
        watch.check_energy(state, (1e-6, 1.0, 0.0, 0.0, 0.0))  # 1 J from nothing
    assert got.value.contact == busiest
    state.v[busiest] = np.nan
    with pytest.raises(InvariantError) as got:
        watch.check_state(state, 1e-6)
    assert got.value.contact == busiest
    assert ("the striker" if busiest == 0 else f"bead {busiest}") in str(got.value)
