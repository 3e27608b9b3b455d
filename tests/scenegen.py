"""A hypothesis strategy for valid scenes of every law, loading kind and combination of effects.

Every combination is drawn (per-bead chains with a wall, precompression or a striker, precompression
with a striker); a chain of several materials under a plastic law draws metals with a yield strength
and leaves the law's k to them (docs/effects.md, mixing rules). A drawn scene that is refused is a
failure of the generator (or of the scene reader), not skipped.
"""

from __future__ import annotations

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

    chain = f"beads = {beads}\nradius = {radius!r}\n"
    plastic = LAWS[law].history
    # several materials under a plastic law: metals whose yield strength sets each contact's k
    names = sorted(n for n, m in MATERIALS.items() if m.yield_strength is not None or not plastic)
    if per_bead == "materials":
        chain += "material = [" + ", ".join(f'"{draw(st.sampled_from(names))}"' for _ in range(beads)) + "]\n"
    else:
        chain += f'material = "{draw(st.sampled_from(sorted(MATERIALS)))}"\n'
    if per_bead == "taper":
        chain += f"taper = {draw(st.floats(0.95, 0.995))!r}\n"
    contact = f'law = "{law}"\n'
    for key, (lo, hi) in LAWS[law].scene_key_ranges.items():
        if per_bead == "materials" and key == "plastic_stiffness":
            continue  # each contact's k from its softer material's yield strength
        contact += f"{key} = {draw(st.floats(lo, hi))!r}\n"
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
