"""One validated description of a simulation: a TOML scene file read into frozen dataclasses.

Every problem with a scene is reported as a :class:`SceneError` that names the file, the key,
the value and what is allowed, before anything runs. Contact i is the contact between bead i
and bead i+1 (the paper's F_{i,i+1}); beads and contacts are numbered from 1 in scene files
and output tables.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field, make_dataclass
from pathlib import Path
from typing import Any

import numpy as np

from granchain.errors import GranchainError
from granchain.physics import materials as mat
from granchain.physics.effects import FAR_ENDS as FAR_ENDS  # the [boundary] far_end choices
from granchain.physics.effects import active_effects, effect_fields, refusal, sections
from granchain.physics.laws import LAWS as LAW_REGISTRY
from granchain.physics.laws import ContactLaw, law_class
from granchain.physics.positions import contact_quantum

LAWS = tuple(LAW_REGISTRY)  # the registered laws' names (granchain.physics.laws.LAWS)

LOADING_KINDS = ("step", "impulse", "velocity", "striker")


class SceneError(GranchainError, ValueError):
    """A scene file is invalid. The message names the file, the key, the value and the fix."""


#: the most beads a chain may have: the planner and the solvers hold a few numbers per bead and the
#: leading wave needs steps in proportion to the chain's length, so a longer chain cannot finish (the
#: planner alone needs about a second and 130 MB per million beads)
MAX_BEADS = 10**6
#: the most beads a chain whose beads differ (a taper, per-bead lists) may have: every contact gets its
#: own law, and the planner spends about 80 us per contact on them (8 s for the largest)
MAX_VARIED_BEADS = 10**5
#: the largest scene file read: the TOML reader holds it several times over and takes about a second
#: per few MB
MAX_SCENE_BYTES = 16 * 1024**2
#: the longest time a scene may give (end_time, a load's duration, snapshots, intervals): about 3 hours,
#: far beyond any stress wave in a chain of spheres; more is a typo for a shorter time
MAX_TIME = 1e4


def _shown(value: Any) -> str:
    """A value as a message shows it: its repr, shortened (a long string, a big list, deep nesting
    would make a message of megabytes, or recurse without end)."""
    import reprlib

    r = reprlib.Repr()
    r.maxstring, r.maxother, r.maxlong, r.maxlevel = 80, 80, 60, 3
    r.maxlist = r.maxtuple = r.maxdict = r.maxset = 12
    try:
        return r.repr(value)
    except RecursionError:  # pragma: no cover - reprlib bounds the depth
        return "<nested too deeply to show>"


AUTO = "auto"  # a value the planner chooses (granchain.workflows.plan)


@dataclass(frozen=True)
class Chain:
    beads: int | None  # None: "auto"
    radius: float  # m; with per-bead radii, bead 1's (the nominal one)
    material: mat.Material  # with per-bead materials, bead 1's
    material_name: str | None = None  # built-in name, or None for an inline [chain.material]
    radii: tuple[float, ...] | None = None  # per-bead radii (a list or the taper rule), or None
    materials: tuple[str, ...] | None = None  # per-bead built-in material names, or None


@dataclass(frozen=True)
class Contact:
    """The [contact] section: the law (a name in granchain.physics.laws.LAWS) and its keys."""

    law: str
    unloading_coeff: float | None = None  # beta, bilinear only
    plastic_stiffness: float | None = None  # k in N/m, bilinear only (explicit or from yield)
    yield_pressure: float | None = None  # p_y in Pa, thornton only

    @property
    def law_class(self) -> type[ContactLaw]:
        return law_class(self.law)


@dataclass(frozen=True)
class Loading:
    """f(t) = amplitude for 0 < t <= duration (Eq. 4), or an initial velocity of bead 1."""

    kind: str  # "step" | "impulse" | "velocity" | "striker"
    amplitude: float = 0.0  # N (step, impulse)
    duration: float = 0.0  # s (step, impulse)
    velocity: float = 0.0  # m/s (velocity: of bead 1; striker: of the striker)
    striker_radius: float = 0.0  # m (striker)
    striker_material: mat.Material | None = None  # (striker) default: the chain's
    striker_material_name: str | None = None
    striker_mass: float | None = None  # kg (striker) default: from radius and density

    @property
    def impulse(self) -> float:
        """I = A T (Eq. 4); for a velocity load, the momentum per unit mass is the velocity."""
        return self.amplitude * self.duration

    @property
    def is_force(self) -> bool:
        return self.kind in ("step", "impulse")


@dataclass(frozen=True)
class Run:
    end_time: float | None  # s; None: "auto"
    timestep: float | None  # s; None: "auto"
    stop_after_contact: int | None = None  # stop once the leading wave has passed this contact


@dataclass(frozen=True)
class Outputs:
    peak_force: bool | tuple[int, ...] = True  # True: every contact; or a tuple of contacts
    histories: tuple[int, ...] = ()  # contacts whose force (and bead velocity) vs time is kept
    snapshots: tuple[float, ...] = ()  # times of force/velocity profiles along the chain
    window: tuple[int, int] | None = None  # contacts used for leading peak and wave speed
    history_interval: float | str | None = None  # s between history samples ("auto", the default with histories)
    dump_interval: float | str | None = None  # s between whole-chain LAMMPS dump frames (default: none; "auto")


#: Effects beyond the paper's bare chain (granchain.physics.effects): one attribute per field of a
#: registered effect (far_end "free" | "wall", dashpot gamma in N s/m, precompression F0 in N ...), each
#: at its absent value unless the scene declares the effect
Effects = make_dataclass(
    "Effects",
    [(name, type(absent), field(default=absent)) for name, absent in effect_fields().items()],
    frozen=True,
)
Effects.__module__ = __name__
Effects.__doc__ = "Effects beyond the paper's bare chain; each is absent unless the scene declares it."


@dataclass(frozen=True)
class Scene:
    chain: Chain
    contact: Contact
    loading: Loading
    run: Run
    outputs: Outputs = field(default_factory=Outputs)
    effects: Effects = field(default_factory=Effects)
    title: str = ""
    source: str | None = None  # path of the scene file, if it came from one
    source_text: str | None = None  # the file's text, copied into run directories

    @property
    def needs_plan(self) -> bool:
        """Some value is "auto": run granchain.workflows.plan.plan_scene first."""
        return (
            self.chain.beads is None
            or self.run.end_time is None
            or self.run.timestep is None
            or AUTO in (self.outputs.history_interval, self.outputs.dump_interval)
        )

    # ---- derived quantities (definitions live in granchain.physics) ----
    @property
    def n_contacts(self) -> int:
        return self.chain.beads - 1

    @property
    def mass(self) -> float:
        return mat.bead_mass(self.chain.material, self.chain.radius)

    @property
    def diameter(self) -> float:
        return 2.0 * self.chain.radius

    @property
    def e_star(self) -> float:
        return mat.effective_modulus(self.chain.material)

    @property
    def r_star(self) -> float:
        return mat.effective_radius(self.chain.radius)

    @property
    def tau(self) -> float:
        return mat.time_scale(self.chain.material, self.chain.radius)

    @property
    def force_scale(self) -> float:
        return mat.force_scale(self.chain.material, self.chain.radius)

    @property
    def impulse_scale(self) -> float:
        return mat.impulse_scale(self.chain.material, self.chain.radius)

    def pair_law(self, e_star: float, r_star: float, materials: tuple = ()) -> ContactLaw:
        """The contact law of two bodies of effective modulus E* and radius R* and their materials (a
        flat has none): the law's for_pair, its mixing rules included."""
        return self.contact.law_class.for_pair(self.contact, e_star, r_star, self.r_star, materials)

    @property
    def law(self) -> ContactLaw:
        """The nominal bead-bead contact's law (bead 1's material and radius)."""
        return self.pair_law(self.e_star, self.r_star, (self.chain.material, self.chain.material))

    @property
    def stiffness(self) -> float:
        """Contact stiffness k of the nominal pair: Hertz k = 4 E* sqrt(R*)/3, the bilinear plastic slope."""
        return float(self.law.k)

    @property
    def per_bead(self) -> bool:
        """Beads differ in radius or material (tapered, decorated, impurity)."""
        return self.chain.radii is not None or self.chain.materials is not None

    @property
    def bead_radii(self) -> np.ndarray:
        n = self.chain.beads
        return np.asarray(self.chain.radii) if self.chain.radii else np.full(n, self.chain.radius)

    @property
    def bead_materials(self) -> list:
        n = self.chain.beads
        if self.chain.materials:
            return [mat.MATERIALS[name] for name in self.chain.materials]
        return [self.chain.material] * n

    @property
    def bead_masses(self) -> np.ndarray:
        return np.array([mat.bead_mass(m, r) for m, r in zip(self.bead_materials, self.bead_radii, strict=True)])

    @property
    def contact_quantum(self) -> float:
        """The grid of contact radii and positions (contact_quantum)."""
        return contact_quantum(self.bead_radii)

    def contact_radius(self, r: float) -> float:
        """A bead radius rounded up to the contact grid: contact distances R_i + R_j (pair_coeff d0) and
        positions (bead_positions) are sums of these, exact doubles (contact_quantum says why)."""
        q = self.contact_quantum
        return math.ceil(float(r) / q) * q

    @property
    def bead_positions(self) -> np.ndarray:
        """Centres of the beads at t = 0 before any precompression displacement, as LAMMPS's data file
        has them and everything reading LAMMPS's positions back subtracts (displacements, the run
        watch): in contact with zero force, x_1 = 0, x_(i+1) = x_i + R_i + R_(i+1) with the radii on the
        contact grid (contact_radius): exact, every at-rest overlap in LAMMPS's arithmetic exactly 0."""
        q = self.contact_quantum
        rc = np.ceil(self.bead_radii / q) * q
        return np.concatenate(([0.0], np.cumsum(rc[:-1] + rc[1:])))

    def bead_pair_law(self, r1: float, m1, r2: float, m2) -> ContactLaw:
        """The law of two beads (radius, material each): Hertz 4/3 E*_pair sqrt(R*_pair) (Johnson);
        the plastic laws' mixing rules for two materials are the law's (ContactLaw.for_pair)."""
        return self.pair_law(mat.pair_effective_modulus(m1, m2), mat.pair_effective_radius(r1, r2), (m1, m2))

    @property
    def bead_kinds(self) -> tuple[list[tuple[float, object]], list[int]]:
        """Distinct (radius, material) kinds of the chain's beads, in order of first appearance, and
        each bead's kind (one kind for a uniform chain)."""
        kinds: list[tuple[float, object]] = []
        index: dict = {}
        kind_of = []
        for r, m in zip(self.bead_radii.tolist(), self.bead_materials, strict=True):
            key = (float(r), m)
            if key not in index:
                index[key] = len(kinds)
                kinds.append(key)
            kind_of.append(index[key])
        return kinds, kind_of

    def pair_stiffness(self, r1: float, m1, r2: float, m2) -> float:
        """k of two beads (bead_pair_law)."""
        return float(self.bead_pair_law(r1, m1, r2, m2).k)

    @property
    def contact_laws(self) -> list[ContactLaw]:
        """The law of every bead-bead contact, in chain order."""
        r, m = self.bead_radii, self.bead_materials
        return [self.bead_pair_law(r[i], m[i], r[i + 1], m[i + 1]) for i in range(len(r) - 1)]

    @property
    def contact_stiffnesses(self) -> np.ndarray:
        return np.array([float(law.k) for law in self.contact_laws])

    @property
    def input_impulse(self) -> float:
        """Momentum put into the chain: A T (force loads), m v (bead 1), M V (striker)."""
        ld = self.loading
        if ld.is_force:
            return ld.impulse
        return (self.striker_mass if ld.kind == "striker" else self.mass) * ld.velocity

    @property
    def initial_momentum(self) -> float:
        """Momentum at t = 0: bead 1's m v (velocity load), the striker's M V, else 0."""
        ld = self.loading
        if ld.kind == "velocity":
            return float(self.bead_masses[0] if self.per_bead else self.mass) * ld.velocity
        if ld.kind == "striker":
            return self.striker_mass * ld.velocity
        return 0.0

    @property
    def striker_mass(self) -> float:
        ld = self.loading
        return ld.striker_mass if ld.striker_mass is not None else mat.bead_mass(ld.striker_material, ld.striker_radius)

    @property
    def striker_law(self) -> ContactLaw:
        """Striker on bead 1: the law of the striker and bead 1 (see bead_pair_law)."""
        ld = self.loading
        return self.bead_pair_law(ld.striker_radius, ld.striker_material, self.chain.radius, self.chain.material)

    @property
    def striker_stiffness(self) -> float:
        return float(self.striker_law.k)

    def flat_law(self, r: float, m) -> ContactLaw:
        """A bead (radius, material) on a rigid flat: R* = R and E* = E/(1-nu^2) (Hertz, Thornton);
        bilinear, k = 18.5 sigma_y R* with R* = R, i.e. twice the bead-bead k."""
        return self.pair_law(mat.flat_effective_modulus(m), float(r), (m,))

    @property
    def wall_law(self) -> ContactLaw:
        """Bead N on the rigid flat (flat_law of bead N's radius and material)."""
        return self.flat_law(float(self.bead_radii[-1]), self.bead_materials[-1])

    @property
    def wall_stiffness(self) -> float:
        return float(self.wall_law.k)

    @property
    def unloading_stiffness(self) -> float | None:
        """k_u of the nominal contact (bilinear), else None."""
        ku = getattr(self.law, "k_unloading", None)
        return None if ku is None else float(ku)

    @property
    def peak_contacts(self) -> tuple[int, ...]:
        """Contacts (1-based) in the peak-force table."""
        if self.outputs.peak_force is True:
            return tuple(range(1, self.n_contacts + 1))
        if self.outputs.peak_force is False:
            return ()
        return tuple(self.outputs.peak_force)

    @property
    def window(self) -> tuple[int, int]:
        """Contacts over which the leading peak and wave speed are measured.

        Default: the second and third quarters of the chain, away from the loaded end (where the
        wave forms) and from the free far end (where it reflects).
        """
        if self.outputs.window is not None:
            return self.outputs.window
        if isinstance(self.outputs.peak_force, tuple) and len(self.outputs.peak_force) >= 2:
            return (min(self.outputs.peak_force), max(self.outputs.peak_force))
        n = self.n_contacts
        a = max(1, n // 4)
        b = max(a + 1, (3 * n) // 4)
        return (a, min(b, n))

    def to_toml(self) -> str:
        """The scene as TOML text; read back by :func:`parse_scene` to an equal scene."""
        return _dump_toml(scene_to_dict(self))


# ------------------------------------------------------------------------------- reading


class _Section:
    """Reads keys from one TOML table, remembering which were used, and raises clear errors."""

    def __init__(self, file: str, name: str, table: Any):
        self.file, self.name = file, name
        if not isinstance(table, dict):
            raise SceneError(f"{file}: [{name}] must be a table, got {_shown(table)}; write it as a [{name}] section")
        self.table = dict(table)
        self.used: set[str] = set()

    def error(self, message: str) -> SceneError:
        """A SceneError about this file (message names the section, key and fix)."""
        return SceneError(f"{self.file}: {message}")

    def fail(self, key: str, value: Any, allowed: str) -> SceneError:
        return SceneError(f"{self.file}: [{self.name}] {key} = {_shown(value)} is invalid: {allowed}")

    def has(self, key: str) -> bool:
        return key in self.table

    def raw(self, key: str, default: Any = None) -> Any:
        self.used.add(key)
        return self.table.get(key, default)

    def missing(self, key: str, allowed: str) -> SceneError:
        """A required key is absent: name it, and the present key that looks like a typo of it."""
        typo = [k for k in self.table if k not in self.used and _did_you_mean(k, (key,))]
        hint = f" ({_shown(typo[0])} looks like a typo of {key!r})" if typo else ""
        return SceneError(f"{self.file}: [{self.name}] is missing {key!r}{hint}: {allowed}")

    def required(self, key: str, allowed: str) -> Any:
        if key not in self.table:
            raise self.missing(key, allowed)
        return self.raw(key)

    def number(
        self,
        key: str,
        *,
        required: bool = True,
        default: float | None = None,
        low: float | None = None,
        low_open: bool = True,
        high: float | None = None,
        high_open: bool = True,
        what: str = "",
    ) -> float | None:
        allowed = _range_text(low, low_open, high, high_open, what)
        if key not in self.table:
            if required:
                raise self.missing(key, allowed)
            return default
        v = self.raw(key)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.fail(key, v, allowed)
        v = float(v)
        if low is not None and (v <= low if low_open else v < low):
            raise self.fail(key, v, allowed)
        if high is not None and (v >= high if high_open else v > high):
            raise self.fail(key, v, allowed)
        return v

    def integer(self, key: str, *, low: int, high: int | None = None, what: str = "") -> int:
        allowed = (
            f"an integer >= {low}" + (f" and <= {high:,}" if high is not None else "") + (f" ({what})" if what else "")
        )
        v = self.required(key, allowed)
        if isinstance(v, bool) or not isinstance(v, int) or v < low or (high is not None and v > high):
            raise self.fail(key, v, allowed)
        return v

    def choice(self, key: str, choices: tuple[str, ...]) -> str:
        allowed = "one of " + ", ".join(repr(c) for c in choices)
        v = self.required(key, allowed)
        if v not in choices:
            raise self.fail(key, v, allowed)
        return v

    def forbid(self, keys: tuple[str, ...], reason: str) -> None:
        for key in keys:
            if key in self.table:
                raise SceneError(
                    f"{self.file}: [{self.name}] {key} = {_shown(self.table[key])} is not allowed here: {reason}"
                )

    def finish(self, known: tuple[str, ...]) -> None:
        for key in self.table:
            if key not in self.used:
                raise SceneError(
                    f"{self.file}: [{self.name}] has unknown key {_shown(key)} = {_shown(self.table[key])}; "
                    f"{_did_you_mean(key, known)}allowed keys: {', '.join(known)}"
                )


def _did_you_mean(key: str, known) -> str:
    """'did you mean "beads"? ' for a key one typo away from a known one, else ''."""
    import difflib

    close = difflib.get_close_matches(str(key), list(known), n=1, cutoff=0.6)
    return f"did you mean {close[0]!r}? " if close else ""


def _range_text(low, low_open, high, high_open, what) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:g}")
    text = "a finite number" + (" " + " and ".join(parts) if parts else "")
    return text + (f" ({what})" if what else "")


def bundled_scenes() -> dict[str, str]:
    """The bundled example scenes: name -> TOML text."""
    from importlib import resources

    root = resources.files("granchain") / "scenes"
    return {
        p.name.removesuffix(".toml"): p.read_text(encoding="utf-8")
        for p in sorted(root.iterdir(), key=lambda p: p.name)
        if p.name.endswith(".toml")
    }


def load_scene(path_or_name: str | Path) -> Scene:
    """Read and validate a scene.

    Parameters
    ----------
    path_or_name : str or Path
        A ``.toml`` scene file, or the name of a bundled scene (``granchain scenes`` lists them).

    Returns
    -------
    Scene
        The validated scene; values given as ``"auto"`` are left for :func:`granchain.plan`.

    Raises
    ------
    SceneError
        The file does not exist or is invalid; the message names the file, the key and the fix.
    """
    p = Path(path_or_name)
    arg = str(path_or_name)
    if not p.exists() and p.suffix != ".toml" and "/" not in arg and "\\" not in arg:
        scenes = bundled_scenes()
        if arg in scenes:
            return parse_scene(scenes[arg], source=f"<bundled scene {arg}>")
        raise SceneError(
            f"{arg}: is neither a scene file nor a bundled scene; bundled: {', '.join(scenes)} "
            "(or give the path of a .toml file)"
        )
    if not p.exists():
        raise SceneError(f"{p}: no such scene file; give the path of a .toml scene (see 'granchain scenes')")
    if not p.is_file():
        raise SceneError(f"{p}: is not a file; give the path of a .toml scene (see 'granchain scenes')")
    try:
        with open(p, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_SCENE_BYTES:
                raise SceneError(
                    f"{p}: is {size:,} bytes; a scene file is text of at most {MAX_SCENE_BYTES:,} bytes "
                    "(a per-bead list of the longest varied chain takes about 3 MB)"
                )
            data = fh.read(min(size, MAX_SCENE_BYTES) + 1)  # a file that grows while read stops here
        if len(data) > MAX_SCENE_BYTES:
            raise SceneError(f"{p}: is over {MAX_SCENE_BYTES:,} bytes; a scene file is text of at most that")
        text = data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"{p}: cannot be read as UTF-8 text ({e})") from None
    return parse_scene(text, source=str(p))


def parse_scene(text: str, source: str = "<scene>") -> Scene:
    """Parse and validate scene TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{source}: is not valid TOML: {e}") from None
    except RecursionError:  # the TOML reader recurses once per level of nested arrays or tables
        raise SceneError(
            f"{source}: nests arrays or tables too deeply for a scene file (hundreds of levels); "
            "no scene key takes more than a list of numbers"
        ) from None
    scene = scene_from_dict(data, source=source)
    return _with_source(scene, source, text)


def _with_source(scene: Scene, source: str, text: str) -> Scene:
    from dataclasses import replace

    return replace(scene, source=source, source_text=text)


SECTIONS = ("title", "chain", "contact", "loading", "run", "outputs", *sections())


def scene_from_dict(data: dict, source: str = "<scene>") -> Scene:
    for key in data:
        if key not in SECTIONS:
            raise SceneError(
                f"{source}: unknown section or key {_shown(key)}; {_did_you_mean(key, SECTIONS)}"
                f"allowed: {', '.join(SECTIONS)}"
            )
    for sec in ("chain", "contact", "loading", "run"):
        if sec not in data:
            raise SceneError(
                f"{source}: missing section [{sec}]; every scene needs [chain], [contact], [loading] and [run]"
            )
    title = data.get("title", "")
    if not isinstance(title, str):
        raise SceneError(f"{source}: title = {_shown(title)} is invalid: a string")

    chain = _read_chain(_Section(source, "chain", data["chain"]), source)
    contact = _read_contact(_Section(source, "contact", data["contact"]), chain)
    loading = _read_loading(_Section(source, "loading", data["loading"]), chain, source)
    run = _read_run(_Section(source, "run", data["run"]), loading)
    outputs = _read_outputs(_Section(source, "outputs", data.get("outputs", {})), chain, run)
    effects = _read_effects(source, data)
    scene = Scene(
        effects=effects,
        chain=chain,
        contact=contact,
        loading=loading,
        run=run,
        outputs=outputs,
        title=title,
        source=source,
    )
    _check_scales(scene, source)
    why = refusal(active_effects(scene))
    if why:
        raise SceneError(f"{source}: {why}")
    why = contact.law_class.unsupported(chain) if scene.per_bead else None
    if why:
        raise SceneError(f"{source}: {why}")
    if chain.beads == 1 and loading.kind != "striker" and effects.far_end != "wall":
        raise SceneError(
            f"{source}: [chain] beads = 1 has no contact to load: a single bead needs a striker "
            '([loading] kind = "striker") or a wall ([boundary] far_end = "wall") to touch'
        )
    return scene


#: the shortest contact time scale tau a chain may have: 1 fs (beads of a micrometre of the stiffest
#: material have 0.2 ps); a shorter one comes only from values at the edge of their ranges together
MIN_TAU = 1e-15
#: the largest static force on a contact (as a load's amplitude)
MAX_FORCE = 1e12


def _material_keys(chain: Chain) -> str:
    return "[chain] material" if chain.material_name or chain.materials else "[chain.material] values"


def _check_scales(scene: Scene, source: str) -> None:
    """Refuse a scene whose values, each within its own range, together give a chain outside double
    precision or outside any mechanics: a contact time scale below MIN_TAU, a law's constants that
    over- or underflow, a dashpot that damps faster than an attosecond, a precompression beyond
    MAX_FORCE. Each message names the keys the scene set that make it so, and the fix."""
    chain = scene.chain
    radii = (min(chain.radii), max(chain.radii)) if chain.radii else (chain.radius,)
    names = sorted(set(chain.materials)) if chain.materials else [None]
    materials = [mat.MATERIALS[n] for n in names] if chain.materials else [chain.material]
    keys = f"[chain] radius and {_material_keys(chain)}"
    for r in radii:
        for m in materials:
            tau = mat.time_scale(m, r)
            if not (math.isfinite(tau) and tau >= MIN_TAU):
                raise SceneError(
                    f"{source}: {keys} give beads of radius {r:g} m a contact time scale tau = {tau:.3g} s, "
                    f"below {MIN_TAU:g} s: no chain of real spheres is this fast; check the radius, density, "
                    "youngs_modulus and poisson_ratio (a Poisson ratio near -1 makes E* unbounded)"
                )
    laws = {"the beads' contact": (scene.law, keys + " and [contact]")}
    if scene.loading.kind == "striker":
        laws["the striker's contact"] = (scene.striker_law, "[loading] radius, material and [contact]")
    if scene.effects.far_end == "wall":
        laws["the wall's contact"] = (scene.wall_law, keys + " and [contact]")
    for what, (law, keys_of) in laws.items():
        values = {
            "k": law.k,
            **{k: getattr(law, k) for k in ("yield_overlap", "yield_force", "k_unloading") if hasattr(law, k)},
        }
        for name, v in values.items():
            v = float(v)
            if not (math.isfinite(v) and v > 0.0):
                raise SceneError(
                    f"{source}: {keys_of} give {what} a law with {name} = {v:g}, outside double precision: "
                    f"bring the {' and '.join(law.scene_keys) or 'material values'} closer to those of real beads "
                    f"(e.g. {law.example_contact or 'brass: E = 115e9 Pa'})"
                )
    gamma = float(scene.effects.dashpot)
    if gamma > 0.0:
        m_min = float(min(mat.bead_mass(m, radii[0]) for m in materials))
        if scene.loading.kind == "striker":
            m_min = min(m_min, float(scene.striker_mass))
        if m_min / gamma < MIN_TAU:
            raise SceneError(
                f"{source}: [damping] dashpot = {gamma:g} N s/m is invalid: it damps the lightest body "
                f"({m_min:.3g} kg) in m/gamma = {m_min / gamma:.3g} s, under {MIN_TAU:g} s; a dashpot of at most "
                f"{m_min / MIN_TAU:.3g} N s/m (a viscous contact is damped over microseconds: gamma of "
                "about 1 to 100 N s/m for millimetre beads)"
            )
    f0 = float(scene.effects.precompression)
    if f0 > MAX_FORCE:
        raise SceneError(
            f"{source}: [precompression] force = {f0:g} N is invalid: a static force F0 in N of at most {MAX_FORCE:g}"
        )


def _read_effects(source: str, data: dict) -> Effects:
    """The sections of the registered effects (granchain.physics.effects) the scene has."""
    fields: dict[str, Any] = {}
    for name, effect in sections().items():
        if name in data:
            fields.update(effect.read(_Section(source, name, data[name])))
    return Effects(**fields)


def _read_material(s: _Section, source: str, required: bool = True) -> tuple[mat.Material | None, str | None]:
    """`material` of a section: a built-in name or an inline table."""
    allowed = f"a built-in name ({', '.join(mat.MATERIALS)}) or a [{s.name}.material] table"
    if not required and not s.has("material"):
        return None, None
    m = s.required("material", allowed)
    if isinstance(m, str):
        if m not in mat.MATERIALS:
            raise s.fail("material", m, allowed)
        return mat.MATERIALS[m], m
    if isinstance(m, dict):
        ms = _Section(source, f"{s.name}.material", m)
        # the ranges hold every solid from aerogel and soft gels to beyond diamond; outside them the
        # derived scales (tau, E* R*^2, the contact stiffness) leave double precision
        material = mat.Material(
            density=ms.number("density", low=1.0, low_open=False, high=1e5, high_open=False, what="kg/m^3, 1 to 1e5"),
            youngs_modulus=ms.number(
                "youngs_modulus", low=1e3, low_open=False, high=1e13, high_open=False, what="Pa, 1e3 to 1e13"
            ),
            poisson_ratio=ms.number("poisson_ratio", low=-1.0, high=0.5, what="-1 < nu < 0.5"),
            yield_strength=ms.number(
                "yield_strength",
                required=False,
                low=1.0,
                low_open=False,
                high=1e13,
                high_open=False,
                what="Pa, 1 to 1e13",
            ),
        )
        ms.finish(("density", "youngs_modulus", "poisson_ratio", "yield_strength"))
        return material, None
    raise s.fail("material", m, allowed)


def _read_chain(s: _Section, source: str) -> Chain:
    if s.table.get("beads") == AUTO:
        s.raw("beads")  # mark the key as read
        beads = None  # "auto": the planner chooses (granchain plan)
    else:
        beads = s.integer("beads", low=1, high=MAX_BEADS, what='number of beads; bead 1 is the loaded end, or "auto"')
    radii = materials = None
    if isinstance(s.table.get("radius"), list):
        v = s.raw("radius")
        allowed = f"a list of {beads} radii in m, all from 1e-6 to 1 (one per bead)"
        if (
            beads is None
            or len(v) != beads
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not 1e-6 <= x <= 1.0 for x in v)
        ):
            raise s.fail("radius", v, allowed)
        radii = tuple(float(x) for x in v)
        radius = radii[0]
    else:
        radius = s.number(
            "radius",
            low=1e-6,
            low_open=False,
            high=1.0,
            high_open=False,
            what="bead radius in m (1 um to 1 m: granular-chain beads), or a list of one radius per bead",
        )
    taper = s.number(
        "taper", required=False, low=0.0, what="radius ratio of neighbouring beads: R_i = radius taper^(i-1)"
    )
    if taper is not None:
        if radii is not None or beads is None:
            raise s.fail("taper", taper, "a rule for a single nominal radius and a given number of beads")
        # the last bead's radius, in logarithms (taper^(beads-1) over- or underflows long before)
        last = math.log10(radius) + (beads - 1) * math.log10(taper)
        if not math.log10(1e-6) <= last <= 0.0:
            raise s.fail(
                "taper",
                taper,
                f"a ratio that keeps every radius from 1e-6 to 1 m: bead {beads} would have radius "
                f"10^{last:.4g} m = {radius:g} x taper^{beads - 1}; choose taper between "
                f"{(1e-6 / radius) ** (1 / max(beads - 1, 1)):.6g} and {(1 / radius) ** (1 / max(beads - 1, 1)):.6g}",
            )
    varied = taper is not None or radii is not None or isinstance(s.table.get("material"), list)
    if varied and beads is not None and beads > MAX_VARIED_BEADS:
        raise s.fail(
            "beads",
            beads,
            f"at most {MAX_VARIED_BEADS:,} beads for a chain whose beads differ (a taper or per-bead lists): each "
            f"contact gets its own law; a uniform chain takes up to {MAX_BEADS:,}",
        )
    if taper is not None:
        radii = tuple(radius * taper**i for i in range(beads))
    if isinstance(s.table.get("material"), list):
        v = s.raw("material")
        allowed = f"a list of {beads} built-in material names ({', '.join(mat.MATERIALS)}), one per bead"
        if beads is None or len(v) != beads or any(x not in mat.MATERIALS for x in v):
            raise s.fail("material", v, allowed)
        materials = tuple(v)
        material, name = mat.MATERIALS[v[0]], v[0]
    else:
        material, name = _read_material(s, source)
    s.finish(("beads", "radius", "material", "taper"))
    if len(set(radii or ())) <= 1 and len(set(materials or ())) <= 1:
        radii = materials = None  # a uniform list is the plain chain
    return Chain(beads=beads, radius=radius, material=material, material_name=name, radii=radii, materials=materials)


def _read_contact(s: _Section, chain: Chain) -> Contact:
    law = s.choice("law", LAWS)
    return Contact(law=law, **law_class(law).read_contact(s, chain))


#: the shortest loading time T: an attosecond, as the smallest impulse is 1e-18 N s. No mechanical load
#: acts over less; and an impulse's amplitude I / T must stay within what the peak-force models hold in
#: double precision (an impulse of 0.01 N s over 2.2e-308 s overflowed them, a crash, not a message)
MIN_DURATION = 1e-18
DURATION_TEXT = "loading time T in s; no mechanical load acts over less than an attosecond"
#: the shortest time step a scene may give: a million times below the shortest a chain needs (a contact
#: time scale of MIN_TAU = 1 fs, a step of a thousandth of it at the finest tolerance); a shorter one
#: makes step counts that overflow LAMMPS's and granchain's integers (5e-324 s crashed the planner)
MIN_TIMESTEP = 1e-24
TIME_TEXT = f"at most {MAX_TIME:g} s: about 3 hours, far beyond any stress wave in a chain"


def _read_loading(s: _Section, chain: Chain, source: str) -> Loading:
    kind = s.choice("kind", LOADING_KINDS)
    if kind == "step":
        s.forbid(("impulse", "velocity"), "a step load is given by amplitude (N) and duration (s)")
        a = s.number(
            "amplitude", low=1e-9, low_open=False, high=1e12, high_open=False, what="force A in N, 1e-9 to 1e12"
        )
        t = s.number("duration", low=MIN_DURATION, low_open=False, high=MAX_TIME, high_open=False, what=DURATION_TEXT)
        s.finish(("kind", "amplitude", "duration"))
        return Loading(kind=kind, amplitude=a, duration=t)
    if kind == "impulse":
        s.forbid(
            ("amplitude", "velocity"),
            "an impulse load is given by impulse (N s) and duration (s); amplitude = impulse/duration",
        )
        i = s.number(
            "impulse", low=1e-18, low_open=False, high=1e9, high_open=False, what="impulse I in N s, 1e-18 to 1e9"
        )
        t = s.number("duration", low=MIN_DURATION, low_open=False, high=MAX_TIME, high_open=False, what=DURATION_TEXT)
        s.finish(("kind", "impulse", "duration"))
        return Loading(kind=kind, amplitude=i / t, duration=t)
    if kind == "striker":
        s.forbid(
            ("amplitude", "duration", "impulse"),
            "a striker is given by velocity (m/s), radius (m), material and mass (kg, optional)",
        )
        v = s.number(
            "velocity",
            low=1e-15,
            low_open=False,
            high=1e5,
            high_open=False,
            what="the striker's speed in m/s at bead 1, 1e-15 to 1e5",
        )
        r = s.number(
            "radius",
            required=False,
            default=chain.radius,
            low=1e-6,
            low_open=False,
            high=1.0,
            high_open=False,
            what="the striker's radius in m, 1e-6 to 1 (as a bead's)",
        )
        material, name = _read_material(s, source, required=False)
        if material is None:
            material, name = chain.material, chain.material_name
        m = s.number(
            "mass",
            required=False,
            low=1e-18,
            low_open=False,
            high=1e6,
            high_open=False,
            what="the striker's mass in kg, 1e-18 to 1e6 (default: from radius and density)",
        )
        s.finish(("kind", "velocity", "radius", "material", "mass"))
        return Loading(
            kind=kind,
            velocity=v,
            striker_radius=r,
            striker_material=material,
            striker_material_name=name,
            striker_mass=m,
        )
    s.forbid(
        ("amplitude", "duration", "impulse", "radius", "material", "mass"),
        "a velocity load is given by velocity (m/s) of bead 1 at t = 0",
    )
    v = s.number(
        "velocity",
        low=1e-15,
        low_open=False,
        high=1e5,
        high_open=False,
        what="initial velocity of bead 1 in m/s, 1e-15 to 1e5",
    )
    s.finish(("kind", "velocity"))
    return Loading(kind=kind, velocity=v)


def _read_run(s: _Section, loading: Loading) -> Run:
    def num_or_auto(key: str) -> float | None:
        if s.table.get(key) == AUTO:
            s.raw(key)
            return None
        if key == "timestep":
            return s.number(
                key,
                low=MIN_TIMESTEP,
                low_open=False,
                high=MAX_TIME,
                high_open=False,
                what='s, at least 1e-24 s (a step count must stay a number), or "auto" for the planner to choose',
            )
        return s.number(
            key, low=0.0, high=MAX_TIME, high_open=False, what=f's, {TIME_TEXT}, or "auto" for the planner to choose'
        )

    end = num_or_auto("end_time")
    dt = num_or_auto("timestep")
    if dt is not None and end is not None and dt > end:
        raise s.fail("timestep", dt, f"a time step no longer than end_time = {end:g} s")
    if end is not None and loading.kind == "impulse" and end < loading.duration:
        raise s.fail(
            "end_time",
            end,
            f"at least the impulse's duration {loading.duration:g} s, or the impulse is never fully delivered",
        )
    stop = None
    if s.has("stop_after_contact"):
        stop = s.raw("stop_after_contact")
        if isinstance(stop, bool) or not isinstance(stop, int) or stop < 1:
            raise s.fail(
                "stop_after_contact",
                stop,
                "a contact number >= 1: the run stops once its force has "
                "fallen below half its peak (the leading wave has passed it)",
            )
    s.finish(("end_time", "timestep", "stop_after_contact"))
    return Run(end_time=end, timestep=dt, stop_after_contact=stop)


def _int_list(s: _Section, key: str, low: int, high: int, what: str) -> tuple[int, ...]:
    allowed = f"a list of integers from {low} to {high} ({what})"
    v = s.raw(key)
    if not isinstance(v, list) or any(isinstance(x, bool) or not isinstance(x, int) for x in v):
        raise s.fail(key, v, allowed)
    bad = [x for x in v if not low <= x <= high]
    if bad:
        raise s.fail(key, v, allowed + f"; {bad[0]} is out of range")
    if len(set(v)) != len(v):
        raise s.fail(key, v, allowed + "; without repeats")
    return tuple(sorted(v))


def _read_snapshots(s: _Section, run: Run) -> tuple[float, ...]:
    if not s.has("snapshots"):
        return ()
    v = s.raw("snapshots")
    end = run.end_time if run.end_time is not None else MAX_TIME
    allowed = f"a list of times in s with 0 < t <= end_time = {end:g}"
    if not isinstance(v, list) or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
        raise s.fail("snapshots", v, allowed)
    if any(not (0.0 < x <= end) for x in v):
        raise s.fail("snapshots", v, allowed)
    return tuple(sorted({float(x) for x in v}))


def _read_window(s: _Section, nc: int) -> tuple[int, int] | None:
    if not s.has("window"):
        return None
    v = s.raw("window")
    allowed = f"[first, last] contacts with 1 <= first < last <= {nc}"
    if (
        not isinstance(v, list)
        or len(v) != 2
        or any(isinstance(x, bool) or not isinstance(x, int) for x in v)
        or not 1 <= v[0] < v[1] <= nc
    ):
        raise s.fail("window", v, allowed)
    return (v[0], v[1])


def _read_outputs(s: _Section, chain: Chain, run: Run) -> Outputs:
    nc = chain.beads - 1 if chain.beads is not None else 10**9  # beads = "auto": the planner checks
    contacts = f"contact i is between bead i and i+1; this chain has contacts 1..{nc}"
    peak: bool | tuple[int, ...] = True
    if s.has("peak_force"):
        v = s.table["peak_force"]
        if isinstance(v, bool):
            peak = s.raw("peak_force")
        elif isinstance(v, list):
            peak = _int_list(s, "peak_force", 1, nc, contacts)
        else:
            raise s.fail("peak_force", v, f"true, false, or a list of contacts ({contacts})")
    histories = _int_list(s, "histories", 1, nc, contacts) if s.has("histories") else ()
    snapshots = _read_snapshots(s, run)
    window = _read_window(s, nc)

    def interval_or_auto(key: str, what: str):
        if s.table.get(key) == AUTO:
            s.raw(key)
            return AUTO
        v = s.number(
            key,
            required=False,
            low=0.0,
            high=MAX_TIME,
            high_open=False,
            what=what + ', or "auto" for the planner to choose',
        )
        if v is not None and run.timestep is not None and v < run.timestep:
            raise s.fail(key, v, f"at least the time step {run.timestep:g} s")
        if v is not None and run.end_time is not None and v > run.end_time:
            raise s.fail(key, v, f"at most the run's end_time {run.end_time:g} s (one sample per interval)")
        return v

    interval = interval_or_auto("history_interval", "s between history samples, at least the time step")
    if interval is None and histories:
        # every step made a 245 MB dump of 454k steps x 3 contacts: by default the planner's largest
        # interval whose dump-derived peaks stay within rtol (granchain.workflows.plan)
        interval = AUTO
    dump = interval_or_auto("dump_interval", "s between whole-chain dump frames (LAMMPS), at least the time step")
    if run.stop_after_contact is not None:
        if run.stop_after_contact > nc:
            raise SceneError(
                f"{s.file}: [run] stop_after_contact = {run.stop_after_contact} is invalid: "
                f"a contact of this chain, 1..{nc}"
            )
        if snapshots:
            raise SceneError(
                f"{s.file}: [run] stop_after_contact = {run.stop_after_contact} and [outputs] snapshots "
                "do not go together: snapshots need the run to reach their times; remove one"
            )
    s.finish(("peak_force", "histories", "snapshots", "window", "history_interval", "dump_interval"))
    return Outputs(
        peak_force=peak,
        histories=histories,
        snapshots=snapshots,
        window=window,
        history_interval=interval,
        dump_interval=dump,
    )


# ------------------------------------------------------------------------------- writing


def _loading_to_dict(ld: Loading) -> dict[str, Any]:
    if ld.kind == "step":
        return {"kind": "step", "amplitude": ld.amplitude, "duration": ld.duration}
    if ld.kind == "impulse":
        return {"kind": "impulse", "impulse": ld.impulse, "duration": ld.duration}
    if ld.kind == "velocity":
        return {"kind": "velocity", "velocity": ld.velocity}
    st: dict[str, Any] = {"kind": "striker", "velocity": ld.velocity, "radius": ld.striker_radius}
    st["material"] = ld.striker_material_name or {
        "density": ld.striker_material.density,
        "youngs_modulus": ld.striker_material.youngs_modulus,
        "poisson_ratio": ld.striker_material.poisson_ratio,
    }
    if ld.striker_mass is not None:
        st["mass"] = ld.striker_mass
    return st


def _outputs_to_dict(o: Outputs) -> dict[str, Any]:
    out: dict[str, Any] = {"peak_force": o.peak_force if isinstance(o.peak_force, bool) else list(o.peak_force)}
    lists = (("histories", o.histories), ("snapshots", o.snapshots), ("window", o.window))
    out.update({k: list(v) for k, v in lists if v})
    scalars = (("history_interval", o.history_interval), ("dump_interval", o.dump_interval))
    out.update({k: v for k, v in scalars if v is not None})
    return out


def scene_to_dict(scene: Scene) -> dict:
    c = scene.chain
    material: Any = c.material_name
    if material is None:
        material = {
            "density": c.material.density,
            "youngs_modulus": c.material.youngs_modulus,
            "poisson_ratio": c.material.poisson_ratio,
        }
        if c.material.yield_strength is not None and scene.contact.law != "bilinear":
            material["yield_strength"] = c.material.yield_strength
    d: dict[str, Any] = {}
    if scene.title:
        d["title"] = scene.title
    d["chain"] = {
        "beads": AUTO if c.beads is None else c.beads,
        "radius": list(c.radii) if c.radii else c.radius,
        "material": list(c.materials) if c.materials else material,
    }
    d["contact"] = scene.contact.law_class.contact_to_dict(scene.contact)
    d["loading"] = _loading_to_dict(scene.loading)
    d["run"] = {
        k: AUTO if v is None else v for k, v in (("end_time", scene.run.end_time), ("timestep", scene.run.timestep))
    }
    if scene.run.stop_after_contact is not None:
        d["run"]["stop_after_contact"] = scene.run.stop_after_contact
    d["outputs"] = _outputs_to_dict(scene.outputs)
    for name, effect in sections().items():
        section = effect.to_dict(scene.effects)
        if section is not None:
            d[name] = section
    return d


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + "".join(_toml_char(c) for c in v) + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


def _toml_char(c: str) -> str:
    """One character of a TOML basic string: quote and backslash escaped, control characters as
    \\uXXXX (TOML allows none raw), a lone surrogate (not a Unicode scalar value) as U+FFFD."""
    if c in '"\\':
        return "\\" + c
    o = ord(c)
    if o < 0x20 or o == 0x7F:
        return f"\\u{o:04X}"
    if 0xD800 <= o <= 0xDFFF:
        return "\ufffd"
    return c


def _dump_toml(d: dict) -> str:
    lines: list[str] = []
    for key, value in d.items():
        if not isinstance(value, dict):
            lines.append(f"{key} = {_toml_value(value)}")
    for key, value in d.items():
        if isinstance(value, dict):
            lines.append(f"\n[{key}]")
            subtables = []
            for k, v in value.items():
                if isinstance(v, dict):
                    subtables.append((k, v))
                else:
                    lines.append(f"{k} = {_toml_value(v)}")
            for k, v in subtables:
                lines.append(f"\n[{key}.{k}]")
                lines.extend(f"{kk} = {_toml_value(vv)}" for kk, vv in v.items())
    return "\n".join(lines).lstrip("\n") + "\n"
