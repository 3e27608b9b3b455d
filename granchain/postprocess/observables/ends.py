"""The end contacts' peaks: the striker's contact with bead 1 and bead N's contact with the far-end wall.

Each is an Observable (base's rules: its name, unit, definition, where it applies) and one row of
END_PEAKS, the only list of them. Unlike the window's observables, summary.json writes an end peak at
its top level, beside ``observables`` (``wall_peak_force``, ``wall_peak_complete``; the striker's
with its final velocity), as it always has: ``summary_keys`` are those keys, and every place that
names an end peak (summary.json and its check, loading a run back, the error bars, ``granchain
run``'s lines, a figure's text, ``compare``'s rows and reasons) reads them from END_PEAKS.

An end peak is the contact's first complete maximum (granchain.peaks): ``complete_field`` False (a
running maximum, the wave still passing when the run ended) is not a peak. The wall's contact carries
the precompression's static force F0 at rest: ``static_force`` gives what its dynamic force is above.
"""

from __future__ import annotations

from typing import ClassVar

from granchain.postprocess.observables.base import Measurement, Observable

#: an end peak's error bar (both of them)
_BAR = "the time step's error from the companion runs at 2 dt and 4 dt, each its own first complete maximum"


class EndPeak(Observable):
    """The first complete maximum of an end contact's force (a ChainSolution field of the same name),
    its time (``time_field``) and whether it is a peak (``complete_field``)."""

    unit = "N"
    needs = frozenset({"peaks"})
    error_bar = _BAR
    #: the ChainSolution fields beside the force: its time, and False where it is a running maximum
    time_field: ClassVar[str]
    complete_field: ClassVar[str]
    #: the keys summary.json writes at its top level for it (ChainSolution fields of the same names)
    summary_keys: ClassVar[tuple[str, ...]]
    #: the contact in words ("the striker's", "the wall's"), as a run's lines and a figure say it
    label: ClassVar[str]
    #: why compare has no value for it where a run has none
    not_measured: ClassVar[str]

    def static_force(self, scene) -> float:
        """The force its contact carries at rest (N): none for the striker's."""
        return 0.0

    def measure(self, scene, solution) -> Measurement:
        """The peak and its time, or None and why (not a complete peak when the run ended)."""
        value = getattr(solution, self.name)
        when = getattr(solution, self.time_field)
        if value is None or getattr(solution, self.complete_field) is False:
            return Measurement(None, {self.time_field: None}, self.not_measured)
        return Measurement(float(value), {self.time_field: when})


class StrikerPeakForce(EndPeak):
    """The striker's contact with bead 1: its peak force, its time and the striker's final velocity."""

    name = "striker_peak_force"
    definition = "the first complete maximum of the striker's contact force on bead 1"
    companions: ClassVar[dict[str, str]] = {"striker_time_of_peak": "s"}
    shares_reason = ("striker_time_of_peak",)
    time_field = "striker_time_of_peak"
    complete_field = "striker_peak_complete"
    summary_keys = ("striker_peak_force", "striker_peak_complete", "striker_velocity")
    label = "the striker's"
    not_measured = "the striker's contact force did not fall to half its peak"
    applies_where = 'a struck chain ([loading] kind = "striker")'

    def applies(self, scene) -> str | None:
        """None for a striker's load, else why not."""
        return None if scene.loading.kind == "striker" else "no striker: the load is not a striker's"


class WallPeakForce(EndPeak):
    """Bead N's contact with the far-end wall: its peak force (total: F0 included) and its time."""

    name = "wall_peak_force"
    definition = "the first complete maximum of bead N's contact force on the far-end wall (total, F0 included)"
    companions: ClassVar[dict[str, str]] = {"wall_time_of_peak": "s"}
    shares_reason = ("wall_time_of_peak",)
    time_field = "wall_time_of_peak"
    complete_field = "wall_peak_complete"
    summary_keys = ("wall_peak_force", "wall_peak_complete")
    label = "the wall's"
    not_measured = "the wave did not reach or pass the wall (its force falling to half its peak)"
    applies_where = 'a chain on a far-end wall ([boundary] far_end = "wall")'

    def applies(self, scene) -> str | None:
        """None on a walled chain, else why not."""
        return None if scene.effects.far_end == "wall" else "no far-end wall: a free far end has no wall contact"

    def static_force(self, scene) -> float:
        """The precompression's static force F0 (N), which the wall's contact carries at rest."""
        return float(scene.effects.precompression)


#: name -> end peak, in the chain's order (the striker's end first), as a run's lines and compare show them
END_PEAKS: dict[str, EndPeak] = {o.name: o for o in (StrikerPeakForce(), WallPeakForce())}


def end_summary(solution) -> dict:
    """summary.json's top-level end-peak keys of a run: each end peak's summary_keys where it has one
    (the wall's before the striker's, the order summary.json has always written them in)."""
    out: dict = {}
    for obs in reversed(END_PEAKS.values()):
        if getattr(solution, obs.name) is not None:
            out.update({k: getattr(solution, k) for k in obs.summary_keys})
    return out


def end_summary_keys() -> tuple[str, ...]:
    """Every top-level key summary.json may write for an end peak (summary_check's and load's)."""
    return tuple(k for obs in END_PEAKS.values() for k in obs.summary_keys)
