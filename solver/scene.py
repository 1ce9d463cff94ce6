"""Parse and validate a scene file (TOML): the single source of a run's set-up.

The scene is deep-merged over `defaults.toml`, then validated by the pydantic models
below. Unknown keys are refused. Every error names the file, the dotted key and the
reason, so the CLI can print it and exit with status 2 before anything is written.
"""

from __future__ import annotations

import copy
import tomllib
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Literal, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from .errors import SceneError
from .scene_open import Body, Inlet, Outlet, check_open_boundaries, fill_inlet_defaults

DEFAULTS_PATH = Path(__file__).with_name("defaults.toml")

Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
WallKind = Literal["free_slip", "no_slip", "frictional"]
OUTPUT_FIELDS = ("velocity", "density", "pressure", "mass", "material", "acceleration", "rank")


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class SceneInfo(Strict):
    name: str
    description: str = ""
    dimension: Literal[1, 2, 3]
    spacing: Positive
    end_time: Positive
    gravity: list[float]


class Domain(Strict):
    min: list[float]
    max: list[float]


class Walls(Strict):
    x_min: WallKind | None = None
    x_max: WallKind | None = None
    y_min: WallKind | None = None
    y_max: WallKind | None = None
    z_min: WallKind | None = None
    z_max: WallKind | None = None
    friction_angle: Annotated[float, Field(ge=0.0, lt=90.0)] | None = (
        None  # degrees, Coulomb friction of "frictional" walls (required for them)
    )

    def kinds(self):
        return [
            k
            for k in (self.x_min, self.x_max, self.y_min, self.y_max, self.z_min, self.z_max)
            if k is not None
        ]


class Water(Strict):
    """Weakly compressible Newtonian water: Tait EOS (9), stress (8), (10)-(11)."""

    model: Literal["water"]
    density: Positive
    viscosity: NonNegative
    typical_velocity: Positive
    sound_speed_factor: Positive
    eos_exponent: Positive

    @property
    def sound_speed(self):
        return self.sound_speed_factor * self.typical_velocity  # c = 10 v_typ (seed 2.1)


class Soil(Strict):
    """Elasto-perfectly plastic soil: sigma = -p delta + s (seed eq. 12), s by Hooke's law with
    the Jaumann rate (13)-(15), p = K (rho/rho0 - 1) (17), yield by Mohr-Coulomb (16, seed) or
    Drucker-Prager with non-associated flow (Bui et al. 2008), or none (elastic, for checks)."""

    model: Literal["soil"]
    density: Positive
    youngs_modulus: Positive
    poisson_ratio: Annotated[float, Field(ge=0.0, lt=0.5)]
    friction_angle: Annotated[float, Field(ge=0.0, lt=90.0)]  # degrees
    cohesion: NonNegative
    dilatancy_angle: Annotated[float, Field(ge=0.0, lt=90.0)] = 0.0  # degrees (Drucker-Prager only)
    yield_model: Literal["mohr_coulomb", "drucker_prager", "elastic"] = "mohr_coulomb"
    # a reduced K for eq. (17) (seed 2.2, after Bui 2007); None: E / 3(1 - 2 nu)
    bulk_modulus: Positive | None = None
    # water-soil coupling (seed eq. 18), required when the scene has water (the seed gives neither):
    # porosity n (then `density` is the dry density (1 - n) rho_grain) and hydraulic conductivity k
    porosity: Annotated[float, Field(gt=0.0, lt=1.0)] | None = None
    permeability: Positive | None = None  # m/s

    @property
    def shear_modulus(self):
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def bulk(self):
        if self.bulk_modulus is not None:
            return self.bulk_modulus
        return self.youngs_modulus / (3.0 * (1.0 - 2.0 * self.poisson_ratio))

    @property
    def sound_speed(self):
        return float(np.sqrt((self.bulk + 4.0 * self.shear_modulus / 3.0) / self.density))  # P-wave speed

    @property
    def k0(self):
        return 1.0 - np.sin(np.radians(self.friction_angle))  # Jaky (1944)


Material = Annotated[Union[Water, Soil], Field(discriminator="model")]


class RectangleBlock(Strict):
    name: str
    material: str
    shape: Literal["rectangle"]
    min: list[float]
    max: list[float]
    hydrostatic: bool = False
    geostatic: bool = False  # soil: start at sigma_v = rho g depth, sigma_h = K0 sigma_v
    fixed: bool = False  # wall particles: never moved, contribute to neighbour sums
    saturated: bool = False  # soil: pore-water particles fill the block (docs/seepage.md)
    water_table: float | None = None  # saturated: level of the free water surface (default: see docs)
    pore_water: str | None = None  # saturated: the water material (default: the scene's only one)


class PolygonBlock(Strict):
    name: str
    material: str
    shape: Literal["polygon"]
    vertices: list[list[float]]
    hydrostatic: bool = False
    geostatic: bool = False
    fixed: bool = False
    saturated: bool = False
    water_table: float | None = None
    pore_water: str | None = None


Block = Annotated[Union[RectangleBlock, PolygonBlock], Field(discriminator="shape")]


class ArtificialViscosity(Strict):
    alpha: NonNegative
    beta: NonNegative


class Cfl(Strict):
    sound: Positive
    force: Positive
    viscous: Positive
    drag: Positive = 1.0  # dt <= drag / lambda_max of the seepage drag (docs/seepage.md)
    collapse_fraction: Positive


class Leapfrog(StrEnum):
    """Time levels of the leap-frog (numerics.leapfrog)."""

    SEED = "seed"  # rho and v at half steps (seed eqs. 24-25)
    SYMPLECTIC_DENSITY = "symplectic_density"  # rho at whole steps, from v at n+1/2 after the drift


class ImagePressure(StrEnum):
    """What an image particle's pressure (soil: normal stress) is (numerics.image_pressure)."""

    MIRROR = "mirror"  # its source's (seed sec. 2.5)
    HYDROSTATIC = "hydrostatic"  # its source's plus the static increment between the two points


class Seepage(StrEnum):
    """The water-soil coupling (numerics.seepage; docs/seepage.md)."""

    MIXTURE = "mixture"  # drag n^2 gamma_w dv / k plus the pore pressure on the skeleton (Bui & Nguyen 2017)
    SEED = "seed"  # the seed's eqs. (18), (20), (21): the seepage force only


class Numerics(Strict):
    kernel: Literal["cubic_spline"]
    h_over_dx: Annotated[float, Field(ge=1.0, le=2.0)]
    viscous_stress: bool
    xsph_epsilon: Annotated[float, Field(ge=0.0, le=1.0)]
    neighbour_skin: Annotated[float, Field(ge=0.0, le=2.0)]
    cfl: Cfl
    artificial_viscosity: dict[str, ArtificialViscosity] = {}
    leapfrog: Leapfrog = Leapfrog.SEED
    image_pressure: ImagePressure = ImagePressure.MIRROR
    seepage: Seepage = Seepage.MIXTURE
    artificial_stress: NonNegative = 0.0  # soil tensile-instability remedy, epsilon of Gray et al. (2001)
    artificial_stress_exponent: Positive = 2.55  # n of f_ij^n (Gray et al. 2001; Bui et al. 2008)
    settling_time: NonNegative = 0.0  # s of kinetic-damping settling before release (t = 0); 0 = off


class Output(Strict):
    interval: Positive
    times: list[float] | None = None
    fields: list[Literal[OUTPUT_FIELDS]]
    vtk: bool
    render: bool
    render_field: str


class Parallel(Strict):
    """MPI domain decomposition (solver/parallel): ignored by serial runs."""

    rebalance_every: Annotated[int, Field(ge=0)] = 100  # steps between load checks; 0 = never
    imbalance_threshold: Annotated[float, Field(ge=1.0)] = (
        1.1  # new cuts when max/mean particles exceeds this
    )


class Scene(Strict):
    scene: SceneInfo
    domain: Domain
    walls: Walls
    materials: dict[str, Material]
    blocks: list[Block] = []  # at least one block or inlet (checked below)
    numerics: Numerics
    output: Output
    parallel: Parallel = Parallel()
    material_defaults: dict[str, dict] = {}
    artificial_viscosity_defaults: dict[str, ArtificialViscosity] = {}
    inlets: list[Inlet] = []  # open boundaries and rigid bodies: solver/scene_open.py
    outlets: list[Outlet] = []
    bodies: list[Body] = []
    inlet_defaults: dict = {}

    @property
    def dim(self):
        return self.scene.dimension

    @property
    def h(self):
        return self.numerics.h_over_dx * self.scene.spacing

    def output_times(self):
        if self.output.times is not None:
            return np.asarray(sorted(self.output.times), dtype=float)
        n = int(np.floor(self.scene.end_time / self.output.interval + 1e-9))
        times = self.output.interval * np.arange(0, n + 1)
        if times[-1] < self.scene.end_time * (1 - 1e-12):
            times = np.append(times, self.scene.end_time)
        return times

    def artificial_viscosity(self, material_name):
        return self.numerics.artificial_viscosity[material_name]

    @model_validator(mode="after")
    def _consistent(self):
        _check_consistency(self)
        return self


class _Inconsistent(ValueError):
    def __init__(self, key, reason):
        self.key = key
        super().__init__(reason)


def _check_consistency(s: Scene):
    """Checks that span several keys; each raises with the key a user must edit."""
    dim, dx = s.dim, s.scene.spacing
    for key, vec in (
        ("scene.gravity", s.scene.gravity),
        ("domain.min", s.domain.min),
        ("domain.max", s.domain.max),
    ):
        if len(vec) != dim:
            raise _Inconsistent(key, f"needs {dim} components for a {dim}D scene, got {len(vec)}")
    lo, hi = np.array(s.domain.min), np.array(s.domain.max)
    if np.any(hi <= lo):
        raise _Inconsistent("domain.max", "must be greater than domain.min in every direction")
    reach = 2.0 * s.h * (1.0 + s.numerics.neighbour_skin / 2.0)
    if np.any(hi - lo < 2.0 * reach):
        raise _Inconsistent(
            "domain", f"must be at least {2 * reach:.4g} m wide in every direction (two kernel supports)"
        )
    for axis in "xyz"[dim:]:
        for side in ("min", "max"):
            if getattr(s.walls, f"{axis}_{side}") is not None:
                raise _Inconsistent(f"walls.{axis}_{side}", f"no {axis} axis in a {dim}D scene")
    if "frictional" in s.walls.kinds() and s.walls.friction_angle is None:
        raise _Inconsistent(
            "walls.friction_angle", "required for a 'frictional' wall (the literature gives no default)"
        )
    if not s.materials:
        raise _Inconsistent("materials", "at least one material is needed")
    if not s.blocks and not s.inlets:
        raise _Inconsistent("blocks", "at least one particle block (or inlet) is needed")
    eps = 1e-9 * float(np.max(hi - lo))
    for k, block in enumerate(s.blocks):
        key = f"blocks[{k}]"
        if block.material not in s.materials:
            raise _Inconsistent(
                f"{key}.material", f"unknown material '{block.material}' (known: {', '.join(s.materials)})"
            )
        if isinstance(block, RectangleBlock):
            bmin, bmax = np.array(block.min, float), np.array(block.max, float)
            if len(bmin) != dim or len(bmax) != dim:
                raise _Inconsistent(f"{key}.min", f"needs {dim} components")
            if np.any(bmax <= bmin):
                raise _Inconsistent(f"{key}.max", "must be greater than min in every direction")
            corners = np.array([bmin, bmax])
        else:
            if dim != 2:
                raise _Inconsistent(f"{key}.shape", "polygons are 2D only")
            corners = np.array(block.vertices, float)
            if corners.ndim != 2 or corners.shape[1] != 2 or len(corners) < 3:
                raise _Inconsistent(f"{key}.vertices", "needs three or more [x, y] points")
        if getattr(block, "geostatic", False) and not isinstance(s.materials[block.material], Soil):
            raise _Inconsistent(
                f"{key}.geostatic", "only soil blocks can start geostatic (water: hydrostatic)"
            )
        if np.any(corners < lo - eps) or np.any(corners > hi + eps):
            raise _Inconsistent(key, "lies (partly) outside the domain")
        extent = corners.max(axis=0) - corners.min(axis=0)
        if np.any(extent < dx):
            raise _Inconsistent(
                "scene.spacing", f"{dx} m is larger than block '{block.name}' ({extent.min():.4g} m)"
            )
    if s.numerics.leapfrog != Leapfrog.SEED and any(m.model != "water" for m in s.materials.values()):
        raise _Inconsistent("numerics.leapfrog", "symplectic_density is implemented for water-only scenes")
    for name in s.numerics.artificial_viscosity:
        if name not in s.materials:
            raise _Inconsistent(f"numerics.artificial_viscosity.{name}", "no material of that name")
    times = s.output_times()
    if np.any(times < 0) or np.any(times > s.scene.end_time * (1 + 1e-12)):
        raise _Inconsistent("output.times", "every output time must lie in [0, end_time]")
    _check_seepage(s)
    for key, reason in check_open_boundaries(s):
        raise _Inconsistent(key, reason)


def _check_seepage(s: Scene):
    """Water that can reach soil needs the soil's n and k; saturated blocks need pore water."""
    waters = [name for name, m in s.materials.items() if isinstance(m, Water)]
    if waters:
        for name, mat in s.materials.items():
            if isinstance(mat, Soil):
                for key in ("porosity", "permeability"):
                    if getattr(mat, key) is None:
                        raise _Inconsistent(
                            f"materials.{name}.{key}",
                            "required when the scene has water (seepage force, seed eq. 18); the seed gives "
                            "no value: choose one with a source (docs/seepage.md)",
                        )
    for k, block in enumerate(s.blocks):
        key = f"blocks[{k}]"
        if not block.saturated:
            for extra in ("water_table", "pore_water"):
                if getattr(block, extra) is not None:
                    raise _Inconsistent(
                        f"{key}.{extra}", "only for a saturated soil block (saturated = true)"
                    )
            continue
        if not isinstance(s.materials.get(block.material), Soil):
            raise _Inconsistent(f"{key}.saturated", "only soil blocks can be saturated")
        if block.pore_water is None and len(waters) != 1:
            reason = (
                "needs a water material in the scene" if not waters else f"choose one of {', '.join(waters)}"
            )
            raise _Inconsistent(f"{key}.pore_water", f"a saturated block {reason}")
        if block.pore_water is not None and block.pore_water not in waters:
            raise _Inconsistent(f"{key}.pore_water", f"'{block.pore_water}' is not a water material")


def deep_merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _fill_material_defaults(raw: dict, defaults: dict) -> dict:
    """Per-model defaults (viscosity, c factor, AV alpha/beta) filled in per material."""
    raw = copy.deepcopy(raw)
    av = raw.setdefault("numerics", {}).setdefault("artificial_viscosity", {})
    for name, mat in (raw.get("materials") or {}).items():
        if not isinstance(mat, dict):
            continue
        model = mat.get("model")
        for key, value in defaults.get("material_defaults", {}).get(model, {}).items():
            mat.setdefault(key, value)
        if model in defaults.get("artificial_viscosity_defaults", {}):
            av.setdefault(name, dict(defaults["artificial_viscosity_defaults"][model]))
    return raw


_UNION_TAGS = {"water", "soil", "rectangle", "polygon"}


def _dotted(loc) -> str:
    """pydantic's error location as the dotted key a user wrote (discriminator tags dropped:
    a tag follows the material name or block index of a tagged union)."""
    parts = []
    for k, item in enumerate(loc):
        if k >= 2 and loc[k - 2] in ("materials", "blocks") and isinstance(item, str) and item in _UNION_TAGS:
            continue
        parts.append(f"[{item}]" if isinstance(item, int) else ("." if parts else "") + str(item))
    return "".join(parts) or "(top level)"


def _reason(err) -> str:
    kind = err["type"]
    if kind == "extra_forbidden":
        return "unknown key (not in the scene schema)"
    if kind == "missing":
        return "missing value"
    return err["msg"]


def parse_scene(raw: dict, path="<scene>") -> Scene:
    defaults = tomllib.loads(DEFAULTS_PATH.read_text())
    merged = _fill_material_defaults(deep_merge(defaults, raw), defaults)
    merged = fill_inlet_defaults(merged, defaults)
    try:
        return Scene.model_validate(merged)
    except ValidationError as exc:
        err = exc.errors()[0]
        ctx_error = err.get("ctx", {}).get("error")
        if isinstance(ctx_error, _Inconsistent):
            raise SceneError(path, ctx_error.key, str(ctx_error)) from None
        raise SceneError(path, _dotted(err["loc"]), _reason(err)) from None


def load_scene(path, overrides=()) -> Scene:
    """Read, merge and validate a scene file; `overrides` are "dotted.key=value" strings
    (value in TOML syntax, e.g. parallel.rebalance_every=50) applied before validation."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(path, "(file)", "no such scene file")
    try:
        raw = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(path, "(syntax)", str(exc)) from None
    for item in overrides:
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise SceneError(path, item, "a command-line override must read key=value")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()  # a bare word is a string: walls.x_max=free_slip
        table = raw
        *parents, last = key.strip().split(".")
        for part in parents:
            table = table.setdefault(part, {})
            if not isinstance(table, dict):
                raise SceneError(path, key, "is not a table in the scene")
        table[last] = value
    return parse_scene(raw, path)


def scene_to_toml(scene: Scene) -> str:
    """The merged scene as TOML text (saved next to every output)."""
    return _to_toml(scene.model_dump(mode="json", exclude_none=True))


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(type(v))


def _to_toml(d: dict, prefix="") -> str:
    lines, tables, arrays = [], [], []
    for k, v in d.items():
        if isinstance(v, dict):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.append((k, v))
        else:
            lines.append(f"{k} = {_toml_value(v)}")
    out = "\n".join(lines) + ("\n" if lines else "")
    for k, v in tables:
        name = f"{prefix}{k}"
        out += f"\n[{name}]\n" + _to_toml(v, name + ".")
    for k, items in arrays:
        for item in items:
            out += f"\n[[{prefix}{k}]]\n" + _to_toml(item, f"{prefix}{k}.")
    return out
