"""Jinja2 LAMMPS decks: a base chain deck plus one block per effect the scene declares.

render_deck(scene) returns the deck text and the data file it reads (chain.data). chain.lmp.j2 includes
a piece per effect: contact (the scene's law: its pair style and coefficients), damping, dissipation,
wall, loading_<force | velocity | striker>, precompression, energy, the run watch, histories, dumps, a
stop check, and a snapshot write_dump at each snapshot time. Its blocks (contact, energy_watch,
results) are what a yardstick overrides: render_deck(scene, yardstick="builtin") renders
builtin_granular.lmp.j2, which {% extends %} it with LAMMPS's built-in pair_style granular.

The templates read the scene's own objects (scene.loading, scene.effects, scene.law, ...) and a few
computed ones: layout (AtomLayout), schedule (Schedule), per_atom (PerAtom), pair_coeffs (PairCoeff),
watch (Watch), stop (StopCheck). Every number is written with the float_repr filter (repr(float)), the
shortest text that reads back to the same double. StrictUndefined: a missing value is an error. Free
text (title, file name) enters a deck only through the `comment` filter, as an inert comment; any
other template value that is not one line of printable text is an error.

The package's modules: ``filters`` (the templates' filters and value check), ``columns`` (the files
and per-atom columns a deck writes), ``atoms`` (atom IDs and types, the data file, pair
coefficients), ``run_control`` (steps, run watch, stop check) and ``deck`` (render_deck).
"""

from __future__ import annotations

from granchain.peaks import lead_floor
from granchain.templates.atoms import (
    MAX_BEAD_KINDS,
    AtomLayout,
    PairCoeff,
    atom_layout,
    bead_kinds,
    largest_radius,
    pair_coeffs,
    render_data,
)
from granchain.templates.columns import (
    BUILTIN_GRANULAR_PER_ATOM,
    LAMMPS_FILES,
    RESULT_COLUMNS,
    RESULTS_DUMP,
    RUN_END_FILE,
    PerAtom,
    result_columns,
)
from granchain.templates.deck import (
    DECK_OPTIONS,
    DECK_SLOTS,
    PLUGIN_DECK_OPTIONS,
    Deck,
    DeckOptions,
    _env,
    builtin_granular_refusal,
    effect_blocks,
    energy_columns,
    render_deck,
)
from granchain.templates.filters import comment, float_repr, law_parameters
from granchain.templates.run_control import WATCH_EVERY, Schedule, StopCheck, Watch

__all__ = [
    "BUILTIN_GRANULAR_PER_ATOM",
    "DECK_OPTIONS",
    "DECK_SLOTS",
    "LAMMPS_FILES",
    "MAX_BEAD_KINDS",
    "PLUGIN_DECK_OPTIONS",
    "RESULTS_DUMP",
    "RESULT_COLUMNS",
    "RUN_END_FILE",
    "WATCH_EVERY",
    "AtomLayout",
    "Deck",
    "DeckOptions",
    "PairCoeff",
    "PerAtom",
    "Schedule",
    "StopCheck",
    "Watch",
    "_env",
    "atom_layout",
    "bead_kinds",
    "builtin_granular_refusal",
    "comment",
    "effect_blocks",
    "energy_columns",
    "float_repr",
    "largest_radius",
    "law_parameters",
    "lead_floor",
    "pair_coeffs",
    "render_data",
    "render_deck",
    "result_columns",
]
