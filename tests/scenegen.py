"""A hypothesis strategy for valid scenes of every law, loading kind and combination of effects.

Every combination is drawn (per-bead chains with a wall, precompression or a striker, precompression
with a striker); a chain of several materials under a plastic law draws metals with a yield strength
and leaves the law's k to them (docs/effects.md, mixing rules). A drawn scene that is refused is a
failure of the generator (or of the scene reader), not skipped.
"""

from __future__ import annotations

from hypothesis import assume
from hypothesis import strategies as st

from granchain.physics.laws import LAWS
from granchain.physics.materials import MATERIALS
from granchain.scene import parse_scene

#: the [run] of a scene whose end time and step the planner chooses
AUTO_RUN = '[run]\nend_time = "auto"\ntimestep = "auto"\n'
#: a far-end wall and the peak forces, the sections most walled test scenes end with
WALL = '[boundary]\nfar_end = "wall"\n'
PEAKS = "[outputs]\npeak_force = true\n"


def brass_text(beads: int, loading: str, extra: str = "") -> str:
    """The tests' plain chain as TOML text: `beads` 4.76 mm brass beads, Hertz, the [loading] lines
    `loading`, end time and step "auto"; `extra` (more TOML sections) appended."""
    return (
        f'\n[chain]\nbeads = {beads}\nradius = 4.76e-3\nmaterial = "brass"\n[contact]\nlaw = "hertz"\n'
        f"[loading]\n{loading}{AUTO_RUN}{extra}"
    )


def brass_impulse_text(beads: int, impulse: float, duration: float = 1e-6, extra: str = "") -> str:
    """brass_text with bead 1 given `impulse` (N s) over `duration` (s)."""
    return brass_text(beads, f'kind = "impulse"\nimpulse = {impulse!r}\nduration = {duration!r}\n', extra)


def stainless_on_wall_text(
    kind: str, velocity: float, force: float, contact: str = 'law = "hertz"\n', histories=None
) -> str:
    """The testers' walled chain as TOML text: 20 stainless-steel-316 beads of 2.38 mm, the [contact]
    lines `contact`, a `kind` ("striker" or "velocity") load at `velocity` (m/s), precompressed by
    `force` (N), a wall, end time and step "auto", the peak forces and `histories` (a list) if given."""
    outputs = PEAKS if histories is None else f"{PEAKS}histories = {histories!r}\n"
    return (
        '\n[chain]\nbeads = 20\nradius = 2.38e-3\nmaterial = "stainless-steel-316"\n'
        f'[contact]\n{contact}[loading]\nkind = "{kind}"\nvelocity = {velocity!r}\n'
        f"[precompression]\nforce = {force!r}\n{WALL}{AUTO_RUN}{outputs}"
    )


@st.composite
def scene_texts(
    draw,
    *,
    max_beads: int = 60,
    auto: bool = True,
    law: str | None = None,
    precompressed: bool = False,
    wall: bool | None = None,
) -> str:
    """law: a registered law's name (default: drawn); precompressed: always a precompression; wall: a
    wall at the far end or not (default: drawn)."""
    law = law or draw(st.sampled_from(sorted(LAWS)))
    radius = draw(st.floats(2e-3, 1e-2))
    beads = draw(st.integers(12, max_beads))
    kind = draw(st.sampled_from(["step", "impulse", "velocity", "striker"]))
    per_bead = draw(st.sampled_from([None, "taper", "materials"]))
    wall = draw(st.booleans()) if wall is None else wall
    pre = precompressed or draw(st.booleans())
    dashpot = draw(st.one_of(st.just(0.0), st.floats(0.1, 20.0)))

    chain, contact = _chain_and_contact(draw, law, beads, radius, per_bead, taper=(0.95, 0.995))
    if kind == "step":
        loading = f"amplitude = {draw(st.floats(1.0, 1e4))!r}\nduration = {draw(st.floats(1e-6, 2e-4))!r}\n"
    elif kind == "impulse":
        loading = f"impulse = {draw(st.floats(1e-3, 0.5))!r}\nduration = {draw(st.floats(1e-7, 1e-5))!r}\n"
    elif kind == "velocity":
        loading = f"velocity = {draw(st.floats(0.05, 5.0))!r}\n"
    else:
        loading = f"velocity = {draw(st.floats(0.05, 5.0))!r}\n"
        loading += f"mass = {draw(st.floats(0.5, 10.0)) * 16000.0 * 4.18879 * radius**3!r}\n"
    n = beads - 1
    histories = sorted({1, draw(st.integers(2, n)), draw(st.integers(2, n))})
    text = f'[chain]\n{chain}\n[contact]\n{contact}\n[loading]\nkind = "{kind}"\n{loading}\n'
    if auto:
        text += '[run]\nend_time = "auto"\ntimestep = "auto"\n'
    else:
        text += "[run]\nend_time = 1e-4\ntimestep = 1e-8\n"
    text += f"[outputs]\npeak_force = true\nhistories = {histories}\n"
    if wall:
        text += '[boundary]\nfar_end = "wall"\n'
    if dashpot:
        text += f"[damping]\ndashpot = {dashpot!r}\n"
    if pre:
        # up to 50 N, within what every contact F0 compresses carries at the run watch's overlap bound
        # (a larger F0 is refused at reading: PrecompressionEffect.largest_force; a micron taper's end)
        hi = min(50.0, 0.9 * largest_precompression(text))
        text += f"[precompression]\nforce = {draw(st.floats(min(0.1, 0.5 * hi), hi))!r}\n"
    return text


def largest_precompression(text: str) -> float:
    """The largest F0 (N) a scene's text without [precompression] may be given (PrecompressionEffect.
    largest_force over the contacts F0 would compress)."""
    from granchain.physics.effects.precompression import PrecompressionEffect

    tiny = parse_scene(text + "[precompression]\nforce = 1e-12\n", source="generated.toml")
    return PrecompressionEffect.largest_force(tiny)[0]


def overlap_fraction(scene) -> float:
    """The overlap at the planner's largest expected force, as a fraction of the smallest radius."""
    from granchain.physics.estimates import expected_peak_force

    f = float(scene.effects.precompression) + expected_peak_force(scene)
    alpha = float(scene.law.static_overlap(f))  # on the virgin curve
    radii = scene.bead_radii if scene.chain.beads else [scene.chain.radius]
    return float(alpha / min(radii))


def scenes(max_overlap: float = 0.05, **kw):
    """Valid scenes whose loads the contact laws describe: the expected overlap stays below
    max_overlap x the radius (a load that crushes the beads is refused by the run watch, tested in
    test_hard_cases and test_invariants, not here)."""
    parsed = scene_texts(**kw).map(lambda t: parse_scene(t, source="generated.toml"))
    return parsed.filter(lambda sc: overlap_fraction(sc) < max_overlap)


#: the most steps a generated figure scene's run may take: the reference's RK4 on at most 12 beads
#: runs them in well under a second, so 30 draws and their figures fit the fast set
FIGURE_STEPS = 20_000
#: a title wider than any figure (the axes titles wrap it: canvas.Figure)
LONG_TITLE = "A generated chain whose title runs on " + "and on " * 24 + "past every figure's width"


def _chain_and_contact(draw, law: str, beads: int, radius: float, per_bead, taper: tuple) -> tuple[str, str]:
    """The [chain] and [contact] lines of a generated scene: one material, one per bead (per_bead =
    "materials") or a taper (per_bead = "taper", its ratio drawn in `taper`), and the law's keys drawn in
    their ranges (scene_key_ranges)."""
    chain = f"beads = {beads}\nradius = {radius!r}\n"
    plastic = LAWS[law].history
    # several materials under a plastic law: metals whose yield strength sets each contact's k
    names = sorted(n for n, m in MATERIALS.items() if m.yield_strength is not None or not plastic)
    if per_bead == "materials":
        chain += "material = [" + ", ".join(f'"{draw(st.sampled_from(names))}"' for _ in range(beads)) + "]\n"
    else:
        chain += f'material = "{draw(st.sampled_from(sorted(MATERIALS)))}"\n'
    if per_bead == "taper":
        chain += f"taper = {draw(st.floats(*taper))!r}\n"
    contact = f'law = "{law}"\n'
    for key, (lo, hi) in LAWS[law].scene_key_ranges.items():
        if per_bead == "materials" and key == "plastic_stiffness":
            continue  # each contact's k from its softer material's yield strength
        contact += f"{key} = {draw(st.floats(lo, hi))!r}\n"
    return chain, contact


@st.composite
def _figure_effects(draw, beads: int, law: str) -> tuple[str, str, bool, bool]:
    """The [chain], [contact] and [loading] lines of a figure scene, whether it ends on a wall, and
    whether it is precompressed; beads: 1..12 (one bead touches a striker or a wall)."""
    kind = draw(st.sampled_from(["step", "impulse", "velocity", "striker", "harmonic"]))
    pre = draw(st.booleans()) or kind == "harmonic"  # a drive on a chain that holds together
    # one bead needs a striker or a wall to touch, and a precompressed one a wall to carry its push
    wall = draw(st.booleans()) or (beads == 1 and (kind != "striker" or pre)) or pre and beads == 1
    radius = draw(st.floats(2e-3, 1e-2))
    per_bead = draw(st.sampled_from([None, "taper", "materials"])) if beads >= 3 else None
    chain, contact = _chain_and_contact(draw, law, beads, radius, per_bead, taper=(0.8, 0.99))
    loading = {
        "step": lambda: f"amplitude = {draw(st.floats(1.0, 1e3))!r}\nduration = {draw(st.floats(1e-6, 5e-5))!r}\n",
        "impulse": lambda: f"impulse = {draw(st.floats(1e-3, 0.05))!r}\nduration = {draw(st.floats(1e-7, 1e-5))!r}\n",
        "velocity": lambda: f"velocity = {draw(st.floats(0.05, 2.0))!r}\n",
        "striker": lambda: (
            f"velocity = {draw(st.floats(0.05, 2.0))!r}\n"
            f"mass = {draw(st.floats(0.5, 10.0)) * 16000.0 * 4.18879 * radius**3!r}\n"
        ),
        "harmonic": lambda: (
            f"amplitude = {draw(st.floats(0.01, 1.0))!r}\nfrequency = {draw(st.floats(2e3, 2e4))!r}\ncycles = 3\n"
        ),
    }[kind]()
    text = f'[chain]\n{chain}\n[contact]\n{contact}\n[loading]\nkind = "{kind}"\n{loading}\n'
    return text, wall, pre


@st.composite
def _figure_outputs(draw, beads: int, end: float, struck: bool) -> str:
    """[outputs] of a figure scene: the peaks, histories (none, a few, or every contact: a heat map's
    source from 10), sensors, snapshots (none, a few, or 20: the heat map's) and a title."""
    n = beads - 1
    out = "[outputs]\npeak_force = true\n"
    which = draw(st.sampled_from(["none", "few", "all"])) if n else "none"
    if which != "none":
        few = sorted(set(draw(st.lists(st.integers(1, n), min_size=1, max_size=3))))
        out += f"histories = {list(range(1, n + 1)) if which == 'all' else few}\n"
    if n and draw(st.booleans()):
        first = 1 if struck else 2  # a force load's bead 1 has no contact on its loaded face to average
        out += f"sensors = {sorted(set(draw(st.lists(st.integers(first, beads), min_size=1, max_size=3))))}\n"
    count = draw(st.sampled_from([0, 1, 3, 20]))
    if count:
        out += f"snapshots = {[end * (i + 1) / count for i in range(count - 1)] + [end]!r}\n"
    return out


def planned_steps(text: str) -> tuple[int, float, float]:
    """The steps of a scene text's run as granchain.run plans it on the reference (its integrator's
    step), and the planned end time and step (s)."""
    from granchain import plan
    from granchain.schedule import scene_step_plan

    run = plan(parse_scene(text, source="generated.toml")).scene
    return sum(g.steps for g in scene_step_plan(run)), run.run.end_time, run.run.timestep


@st.composite
def figure_scene_texts(draw, max_steps: int = FIGURE_STEPS) -> str:
    """Scenes for the figures, cheap to run: 1-12 beads of every law, loading kind and effect the
    figures draw differently (a wall, gravity, precompression, a dashpot, a taper or several
    materials, sensors, histories, snapshots, a long title), the planner's time step and an end time
    within max_steps of it (the planner's own end time if that is shorter)."""
    law = draw(st.sampled_from(sorted(LAWS)))
    beads = draw(st.integers(1, 12))
    body, wall, pre = draw(_figure_effects(beads, law))
    if wall:
        body += WALL
        if draw(st.booleans()):
            body += f"[gravity]\ng = {draw(st.floats(1.0, 100.0))!r}\n"
    if draw(st.booleans()):
        body += f"[damping]\ndashpot = {draw(st.floats(0.1, 20.0))!r}\n"
    if pre:
        hi = min(50.0, 0.9 * largest_precompression(body + AUTO_RUN))
        body += f"[precompression]\nforce = {draw(st.floats(min(0.1, 0.5 * hi), hi))!r}\n"
    assume(overlap_fraction(parse_scene(body + AUTO_RUN, source="generated.toml")) < 0.05)
    _, end, dt = planned_steps(body + AUTO_RUN)
    end = min(end, max_steps * dt) * draw(st.sampled_from([1.0, 0.5]))
    title = draw(st.sampled_from(["", 'title = "a short title"\n', f'title = "{LONG_TITLE}"\n']))
    outputs = draw(_figure_outputs(beads, end, 'kind = "striker"' in body))
    text = f'{title}{body}[run]\nend_time = {end!r}\ntimestep = "auto"\n{outputs}'
    assume(planned_steps(text)[0] <= max_steps)
    return text
