"""One validated description of a simulation: a TOML scene file read into frozen dataclasses.

Every problem with a scene is reported as a :class:`SceneError` that names the file, the key,
the value and what is allowed, before anything runs. Contact i is the contact between bead i
and bead i+1 (the paper's F_{i,i+1}); beads and contacts are numbered from 1 in scene files
and output tables.

The package's modules, bottom up: ``limits`` (the values a scene may take), ``section`` (reading
one TOML table with clear errors), ``writer`` (a scene as a dict and as TOML text), ``display`` (how
objects show themselves: printable text, numbers, the HTML table, a scene's facts), ``model`` (the
dataclasses and the quantities derived from them), ``read_sections`` (one reader per section) and
``reader`` (a file, text or dict to a validated :class:`Scene`; Scene.replace's keys set and read).
"""

from __future__ import annotations

from granchain.scene.display import KEY_UNITS
from granchain.scene.limits import (
    AUTO,
    DURATION_TEXT,
    FAR_ENDS,
    LAWS,
    LOADING_KINDS,
    MAX_BEADS,
    MAX_FORCE,
    MAX_SCENE_BYTES,
    MAX_TIME,
    MAX_VARIED_BEADS,
    MIN_DURATION,
    MIN_TAU,
    MIN_TIMESTEP,
    TIME_TEXT,
)
from granchain.scene.model import Chain, Contact, Effects, Loading, Outputs, Run, Scene, UnplannedChainError
from granchain.scene.reader import SECTIONS, bundled_scenes, load_scene, parse_scene, scene_from_dict, set_key
from granchain.scene.section import SceneError, _did_you_mean, _Section, _shown
from granchain.scene.writer import dump_toml, scene_to_dict

__all__ = [
    "AUTO",
    "DURATION_TEXT",
    "FAR_ENDS",
    "KEY_UNITS",
    "LAWS",
    "LOADING_KINDS",
    "MAX_BEADS",
    "MAX_FORCE",
    "MAX_SCENE_BYTES",
    "MAX_TIME",
    "MAX_VARIED_BEADS",
    "MIN_DURATION",
    "MIN_TAU",
    "MIN_TIMESTEP",
    "SECTIONS",
    "TIME_TEXT",
    "UnplannedChainError",
    "Chain",
    "Contact",
    "Effects",
    "Loading",
    "Outputs",
    "Run",
    "Scene",
    "SceneError",
    "_Section",
    "_did_you_mean",
    "_shown",
    "bundled_scenes",
    "dump_toml",
    "load_scene",
    "parse_scene",
    "scene_from_dict",
    "scene_to_dict",
    "set_key",
]
