"""What a deck writes for the run to read back: its files, the per-atom vectors it declares and,
of them, the columns of its results dump (RESULT_COLUMNS, the one list)."""

from __future__ import annotations

from dataclasses import dataclass

from granchain.physics.effects import active_effects

LAMMPS_FILES = ("deck.lmp", "chain.data")

#: The per-atom results a LAMMPS run ends with: the one list. The deck's last command writes them,
#: by atom ID at full precision, into RESULTS_DUMP (the results block of chain.lmp.j2), and
#: granchain.lammps.runner.read_results reads them back by the dump's own column names, for runs
#: through the Python module and for plain-LAMMPS runs (granchain collect) alike; a column added
#: here is written by every deck rendered from now on and read by both. Each is a dump custom
#: column; a per-atom vector d_NAME is written only when the deck declares it (d_amax: a law with
#: history; the built-in granular yardstick has d_fpeak and d_tpeak only) and is read as NAME.
RESULT_COLUMNS = (
    "x",  # final position (m)
    "vx",  # final velocity (m/s)
    "d_fpeak",  # running peak force of the contact that lives on this atom (N)
    "d_tpeak",  # its time (s)
    "d_fmin",  # the smallest force since that peak (complete peaks)
    "d_flead",  # the leading pulse: the contact's first maximum above the floor (N)
    "d_tlead",  # its time (s)
    "d_amax",  # a law with history: the largest overlap so far (m)
    "d_speak",  # a sensor bead ([outputs] sensors): the running peak of its average force (N)
    "d_stpeak",  # its time (s)
    "d_sfmin",  # the smallest average force since that peak
)

#: a deck with sensor beads' per-atom vectors (pair_style ... sensors): the average force, its two
#: previous samples, its running peak, the peak's time, the smallest since
SENSOR_VECTORS = ("d_sfc", "d_sprev", "d_sprev2", "d_speak", "d_stpeak", "d_sfmin")

#: the deck's results dump (RESULT_COLUMNS) and the run's last step and time ("step time"); the
#: dump is the last file a deck writes, so its presence marks a finished run
RESULTS_DUMP = "peaks.dump"
RUN_END_FILE = "run_end.txt"


def result_columns(declared) -> list[str]:
    """RESULT_COLUMNS that a deck declaring these per-atom vectors (d_NAME) can write."""
    return [c for c in RESULT_COLUMNS if not c.startswith("d_") or c in set(declared)]


@dataclass(frozen=True)
class PerAtom:
    """The per-atom vectors a deck declares (fix contact ... property/atom) and, of them, the
    energies dissipated so far; the results dump writes the RESULT_COLUMNS among them.

    Attributes
    ----------
    vectors : tuple of str
        Every per-atom vector the deck declares (d_NAME), in declaration order.
    dissipated : tuple of str
        Those holding energy dissipated so far at the atom's contact, J (a law's d_edis, a
        dashpot's): their sum is the energy balance's dissipated term.
    """

    vectors: tuple[str, ...]
    dissipated: tuple[str, ...] = ()

    @classmethod
    def of(cls, scene) -> PerAtom:
        """The chain deck's: force, its last two values, running peak and its time; a law with history:
        alpha_max and the energy it dissipated; a dashpot: its energy; completion; the leading pulse."""
        history = scene.contact.law_class.history
        dissipated = (["d_edis"] if history else []) + [v for e in active_effects(scene) for v in e.dissipated_vectors]
        vectors = ["d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak"] + (["d_amax"] if history else [])
        sensors = SENSOR_VECTORS if scene.outputs.sensors else ()
        return cls((*vectors, *dissipated, "d_fmin", "d_flead", "d_tlead", *sensors), tuple(dissipated))

    @property
    def results(self) -> list[str]:
        """The columns of the results dump this deck writes (result_columns of its vectors)."""
        return result_columns(self.vectors)


#: the per-atom vectors of the built-in granular yardstick: the chain deck's first five, which its
#: run watch, stop check and results dump read (pair_style granular fills none of them)
BUILTIN_GRANULAR_PER_ATOM = PerAtom(("d_fc", "d_fprev", "d_fprev2", "d_fpeak", "d_tpeak"))
