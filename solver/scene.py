"""Parse and validate a scene file (TOML): the single source of a run's set-up.

The scene is deep-merged over `defaults.toml`, then validated by the pydantic models
below. Unknown keys are refused. Types are strict (a boolean is not a number, a number is
not a boolean or a string; an integer is accepted where a float is meant) and every float
must be finite. Every error names the file, the dotted key and the reason, so the CLI can
print it and exit with status 2 before anything is written.

Besides the per-key rules, a scene must be runnable on a real machine: at most
MAX_PARTICLES particles, MAX_CELLS neighbour cells over the domain, MAX_SNAPSHOTS output
times and MAX_STEPS time steps by an a-priori estimate of dt (see `_check_resources`).
"""

from __future__ import annotations

import copy
import math
import re
import tomllib
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Literal, TypeVar, Union

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    create_model,
    field_validator,
    model_validator,
)

from .errors import SceneError
from .sand_state import SandState
from .scene_open import (
    Body,
    Inlet,
    InletDefaults,
    Outlet,
    OutletDefaults,
    check_open_boundaries,
    fill_open_defaults,
)

DEFAULTS_PATH = Path(__file__).with_name("defaults.toml")
SCENES_DIR = Path(__file__).with_name("scenes")  # the scenes shipped with the package

# Limits of a runnable scene (the issue-13 decision; README "Scenes"). Far above any run this
# code targets, low enough that a typo (a spacing in mm written as m, a huge end time) is
# refused at once instead of exhausting memory or running for years.
MAX_PARTICLES = 1_000_000_000  # ~400 GB at the measured 391 B per particle (README "Speed")
MAX_CELLS = 1_000_000_000  # neighbour cells of size 2h over the domain: 8 GB of cell starts
MAX_SNAPSHOTS = 100_000  # output times: one HDF5 and one VTK file each, in one directory
MAX_STEPS = 1_000_000_000  # a-priori steps: 4.6 days for 1000 particles at 2.5 M particle-steps/s

Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
WallKind = Literal["free_slip", "no_slip", "frictional", "wall_function"]
OUTPUT_FIELDS = ("velocity", "density", "pressure", "mass", "material", "acceleration", "rank") + (
    "suspended", "shields", "eroded_share"  # the erosion law's state (solver/physics/shields_pickup.py)
)  # fmt: skip
EROSION_FIELDS = ("suspended", "shields", "eroded_share")
# what a picture (output.render_field) can colour by -> the output field it needs (None: always written)
RENDER_FIELDS = {
    "speed": "velocity",
    "density": "density",
    "pressure": "pressure",
    "mass": "mass",
    "material": None,
    "rank": None,
}


class Strict(BaseModel):
    # strict: no bool -> number, number -> str or str -> number coercion (an int is still a float)
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


E = TypeVar("E")
# an option spelled as a string in the scene, one of an enum's values (strict mode would want the enum)
Choice = Annotated[E, Field(strict=False)]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


class SceneInfo(Strict):
    name: str
    description: str = ""
    dimension: int
    spacing: Positive
    end_time: Positive
    gravity: list[float]

    @field_validator("name")
    @classmethod
    def _plain_name(cls, v):
        if not _NAME.fullmatch(v):
            raise ValueError(
                "must be a plain name (letters, digits, '.', '_', '-'; not starting with '.' or '-'): "
                "it names the default output directory runs/<name>"
            )
        return v

    @field_validator("dimension")
    @classmethod
    def _two_or_three(cls, v):
        if v not in (2, 3):
            raise ValueError(f"must be 2 or 3, got {v} (the kernels and walls are written for 2D and 3D)")
        return v


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
    """Elasto-plastic soil: sigma = -p delta + s (seed eq. 12), s by Hooke's law with the Jaumann
    rate (13)-(15), p = K (rho/rho0 - 1) (17), yield by Mohr-Coulomb (16, seed) or Drucker-Prager
    with non-associated flow (Bui et al. 2008), or none (elastic, for checks); once yielded
    perfectly plastic (the seed's) or with the rate-dependent friction mu(I) (docs/rheology.md)."""

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
    # erosion at the bed surface (solver/physics/shields_pickup.py, docs/erosion.md): the median grain
    # size d50 (m), a material property independent of the particle spacing; the bed erodes only when
    # it is given. critical_shields: None = Soulsby & Whitehouse (1997) from d50; a value overrides it
    grain_size: Positive | None = None
    critical_shields: Positive | None = None
    # the yielded soil's rheology (solver/physics/soil_stress.py, docs/rheology.md): "perfectly_plastic"
    # (seed eq. 16; Bui et al. 2008) or "mu_I", a rate-dependent friction mu(I) = mu_s + friction_increment
    # / (inertial_number_i0 / I + 1), I = gamma_dot d50 / sqrt(p / rho_grain) (Jop, Forterre & Pouliquen
    # 2006); mu_I needs grain_size. numerics.rheology = "perfectly_plastic" (the seed's scheme) overrides it
    rheology: Literal["perfectly_plastic", "mu_I"] = "perfectly_plastic"
    friction_increment: NonNegative = 0.26  # mu_2 - mu_s (defaults.toml: Jop et al. 2005)
    inertial_number_i0: Positive = 0.279  # I_0 (defaults.toml: Jop et al. 2005)
    # a sand with a state (solver/sand_state.py, docs/sand.md): void ratio, critical-state line, Bolton's
    # state-dependent peak friction and dilatancy; friction_angle is then the critical-state angle phi_cv.
    # None: the seed's constant friction and dilatancy. numerics.sand_state = "none" (the seed's scheme)
    # overrides it
    state: SandState | None = None

    @property
    def grain_density(self):
        """rho_grain of the inertial number: density / (1 - n) with a porosity, else the density itself."""
        return self.density / (1.0 - self.porosity) if self.porosity is not None else self.density

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
MODELS = {"water": Water, "soil": Soil}


def _defaults_model(cls):
    """The [material_defaults.<model>] table: every key of the model except `model`, optional,
    with the model's own constraints."""
    fields = {}
    for name, info in cls.model_fields.items():
        if name == "model":
            continue
        ann = Annotated[(info.annotation, *info.metadata)] if info.metadata else info.annotation
        fields[name] = (ann | None, None)
    return create_model(f"{cls.__name__}Defaults", __base__=Strict, **fields)


class MaterialDefaults(Strict):
    """Per-model defaults, filled into every material of that model that leaves the key out;
    a scene may change them (its values are honoured like the file's)."""

    water: _defaults_model(Water) | None = None
    soil: _defaults_model(Soil) | None = None


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
    MIDPOINT_DENSITY = "midpoint_density"  # rho at whole steps, continuity at the drift's midpoint


class DensityDiffusion(StrEnum):
    """Density diffusion added to the continuity equation (numerics.density_diffusion)."""

    NONE = "none"  # the seed's continuity, eq. (6), alone
    MOLTENI = "molteni"  # delta-SPH of Molteni & Colagrossi (2009)
    FOURTAKAS = "fourtakas"  # the same on the dynamic density rho - rho^H (Fourtakas et al. 2019)


class Scheme(StrEnum):
    """A preset of every numerics option (numerics.scheme): explicit keys override it."""

    DEFAULT = "default"  # the values of defaults.toml
    SEED = "seed"  # the seed paper's exact scheme (SCHEMES below)


SCHEMES = {
    Scheme.DEFAULT: {},
    Scheme.SEED: {
        "leapfrog": "seed",
        "image_pressure": "mirror",
        "density_diffusion": "none",
        "wall_repulsion": False,
        "erosion": "none",
        "rheology": "perfectly_plastic",
        "sand_state": "none",
    },
}
"""What each numerics.scheme sets. Precedence: defaults.toml < the preset < the scene's own keys."""


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
    scheme: Choice[Scheme] = Scheme.DEFAULT
    # defaults.toml's; with soil the seed's (_numerics_defaults)
    leapfrog: Choice[Leapfrog] = Leapfrog.MIDPOINT_DENSITY
    image_pressure: Choice[ImagePressure] = ImagePressure.HYDROSTATIC
    density_diffusion: Choice[DensityDiffusion] = DensityDiffusion.FOURTAKAS
    density_diffusion_delta: Annotated[float, Field(gt=0.0, le=1.0)] = 0.1
    wall_repulsion: bool = True
    seepage: Choice[Seepage] = Seepage.MIXTURE
    # mixture: p^ at water, the buoyancy pair's water side (docs/seepage.md): "linear" is exact at a
    # bed's free surface under water, where "shepard" is off by O(h)
    pore_pressure_at_water: Literal["shepard", "linear"] = "shepard"
    # pore water's own pressure gradient: "symmetric" (seed eq. 7) or "corrected" (the kernel-gradient-
    # corrected difference form, exact for a linear pressure; solver/physics/pore_pressure_gradient.py)
    pore_pressure_gradient: Literal["symmetric", "corrected"] = "symmetric"
    # pore water's density diffusion: "none" (pore water out of density_diffusion) or "antuono" (delta-SPH
    # with Antuono et al.'s gradient correction, on pore water only; solver/physics/seepage_pore_diffusion.py)
    pore_density_diffusion: Literal["none", "antuono"] = "none"
    pore_density_diffusion_delta: Annotated[float, Field(gt=0.0, le=1.0)] = 0.1  # docs/seepage.md
    artificial_stress: NonNegative = 0.0  # soil tensile-instability remedy, epsilon of Gray et al. (2001)
    artificial_stress_exponent: Positive = 2.55  # n of f_ij^n (Gray et al. 2001; Bui et al. 2008)
    settling_time: NonNegative = 0.0  # s of kinetic-damping settling before release (t = 0); 0 = off
    # erosion of soils with a grain_size: "shields" (Shields pick-up of the bed surface, van Rijn 1984;
    # docs/erosion.md) or "none" (the seed's continuum soil only)
    erosion: Literal["shields", "none"] = "shields"
    # between the free water and an eroding bed: "log_law" (the wall shear of the log law in place of the
    # seepage drag, solver/physics/bed_shear.py) or "drag" (the seepage drag, as on pore water)
    bed_shear: Literal["log_law", "drag"] = "log_law"
    # the yielded soil's rheology: "material" (each soil's own `rheology`) or "perfectly_plastic" (every soil
    # elastic-perfectly plastic, the seed's eq. 16 / Bui et al. 2008, whatever its `rheology` says)
    rheology: Literal["material", "perfectly_plastic"] = "material"
    # a sand's state: "material" (each soil's own `state`, solver/sand_state.py) or "none" (every soil with
    # its constant friction_angle and dilatancy_angle, the seed's, whatever its `state` says)
    sand_state: Literal["material", "none"] = "material"


class Output(Strict):
    interval: Positive
    times: list[float] | None = None
    fields: list[Literal[OUTPUT_FIELDS]]
    vtk: bool
    render: bool
    render_field: str
    # checkpoints (solver/output/checkpoint.py; defaults and reasons in defaults.toml)
    checkpoint_interval: NonNegative  # simulated s between checkpoints; 0 = none by simulated time
    checkpoint_wall_interval: NonNegative  # wall-clock s between checkpoints; 0 = none by wall clock
    checkpoint_keep: Annotated[int, Field(ge=1)]  # the newest this many are kept
    checkpoint_at_end: bool  # one more when the run completes (to extend it with a later end_time)

    @field_validator("times")
    @classmethod
    def _some_times(cls, v):
        if v is not None and not v:
            raise ValueError("needs at least one output time (or leave it out and give an interval)")
        return v


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
    material_defaults: MaterialDefaults = MaterialDefaults()
    artificial_viscosity_defaults: dict[Literal["water", "soil"], ArtificialViscosity] = {}
    inlets: list[Inlet] = []  # open boundaries and rigid bodies: solver/scene_open.py
    outlets: list[Outlet] = []
    bodies: list[Body] = []
    inlet_defaults: InletDefaults  # values in defaults.toml
    outlet_defaults: OutletDefaults  # values in defaults.toml

    @property
    def dim(self):
        return self.scene.dimension

    @property
    def h(self):
        return self.numerics.h_over_dx * self.scene.spacing

    def output_times(self):
        """The snapshot times; the last is always end_time, so a run reaches end_time even when the
        listed output.times end before it (a scene run longer with --set scene.end_time=...)."""
        if self.output.times is not None:
            times = np.asarray(sorted(self.output.times), dtype=float)
            if times[-1] < self.scene.end_time * (1 - 1e-12):
                times = np.append(times, self.scene.end_time)
            return times
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
    has_soil = any(isinstance(m, Soil) for m in s.materials.values())
    if not has_soil:
        for key, value in (
            ("artificial_stress", s.numerics.artificial_stress),
            ("settling_time", s.numerics.settling_time),
        ):
            if value > 0:
                raise _Inconsistent(
                    f"numerics.{key}", f"= {value} acts on soil only, and this scene has no soil material"
                )
        if "frictional" in s.walls.kinds():
            raise _Inconsistent("walls", "a 'frictional' wall acts on soil only, and this scene has no soil")
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
            if len(block.vertices) < 3 or any(len(v) != 2 for v in block.vertices):
                raise _Inconsistent(f"{key}.vertices", "needs three or more [x, y] points")
            corners = np.array(block.vertices, float)
        if block.geostatic and not isinstance(s.materials[block.material], Soil):
            raise _Inconsistent(
                f"{key}.geostatic", "only soil blocks can start geostatic (water: hydrostatic)"
            )
        if block.hydrostatic and not isinstance(s.materials[block.material], Water):
            raise _Inconsistent(
                f"{key}.hydrostatic", "only water blocks can start hydrostatic (soil: geostatic = true)"
            )
        if block.hydrostatic and block.geostatic:
            raise _Inconsistent(f"{key}", "hydrostatic and geostatic exclude each other")
        if block.hydrostatic and s.scene.gravity[-1] > 0:
            # the profile hangs from a free surface at the block's top: upward gravity would put the
            # column in tension, below the Tait EOS's limit -B for a strong enough g (NaN densities)
            raise _Inconsistent(
                f"{key}.hydrostatic", "needs gravity pointing down (scene.gravity's last component <= 0)"
            )
        if np.any(corners < lo - eps) or np.any(corners > hi + eps):
            raise _Inconsistent(key, "lies (partly) outside the domain")
        extent = corners.max(axis=0) - corners.min(axis=0)
        if np.any(extent < dx):
            raise _Inconsistent(
                "scene.spacing", f"{dx} m is larger than block '{block.name}' ({extent.min():.4g} m)"
            )
    if s.numerics.leapfrog != Leapfrog.SEED and any(m.model != "water" for m in s.materials.values()):
        raise _Inconsistent(
            "numerics.leapfrog",
            "midpoint_density is implemented for water-only scenes (with soil, leave the key out: the "
            "default is then 'seed')",
        )
    for name in s.numerics.artificial_viscosity:
        if name not in s.materials:
            raise _Inconsistent(f"numerics.artificial_viscosity.{name}", "no material of that name")
    if "pressure" in s.output.fields and not any(isinstance(m, Water) for m in s.materials.values()):
        raise _Inconsistent(
            "output.fields",
            "'pressure' is the water pressure (Tait EOS), and this scene has no water material",
        )
    asked = [f for f in s.output.fields if f in EROSION_FIELDS]
    if asked and not _erodes(s):
        raise _Inconsistent(
            "output.fields",
            f"'{asked[0]}' belongs to the erosion law, and nothing erodes in this scene (it needs water, "
            "a soil with a grain_size and numerics.erosion = 'shields')",
        )
    field = s.output.render_field
    if field not in RENDER_FIELDS:
        raise _Inconsistent(
            "output.render_field",
            f"'{field}' is not a field a picture can show (one of: {', '.join(RENDER_FIELDS)})",
        )
    if RENDER_FIELDS[field] is not None and RENDER_FIELDS[field] not in s.output.fields:
        raise _Inconsistent(
            "output.render_field", f"'{field}' needs '{RENDER_FIELDS[field]}' in output.fields"
        )
    if s.output.times is None and s.scene.end_time / s.output.interval > MAX_SNAPSHOTS:
        raise _Inconsistent(
            "output.interval",
            f"gives {s.scene.end_time / s.output.interval:.3g} snapshots, more than {MAX_SNAPSHOTS}",
        )
    if s.output.times is not None and len(s.output.times) > MAX_SNAPSHOTS:
        raise _Inconsistent("output.times", f"more than {MAX_SNAPSHOTS} output times")
    times = s.output_times()
    if np.any(times < 0) or np.any(times > s.scene.end_time * (1 + 1e-12)):
        raise _Inconsistent("output.times", "every output time must lie in [0, end_time]")
    _check_seepage(s)
    _check_rheology(s)
    _check_sand_state(s)
    for key, reason in check_open_boundaries(s):
        raise _Inconsistent(key, reason)
    _check_resources(s)
    from .geometry import overlapping_blocks  # lazy: importing the scene does not import matplotlib

    overlap = overlapping_blocks(s)
    if overlap is not None:
        (i, j), n = overlap
        raise _Inconsistent(
            f"blocks[{j}]",
            f"overlaps blocks[{i}] ('{s.blocks[i].name}') in {n} particle position(s): two particles "
            "at one place double the density there",
        )


def _erodes(s: Scene) -> bool:
    """Whether the erosion law runs (physics/erodible.erosion_materials, from the scene alone)."""
    mats = s.materials.values()
    return (
        s.numerics.erosion == "shields"
        and any(isinstance(m, Water) for m in mats)
        and any(isinstance(m, Soil) and m.grain_size is not None for m in mats)
    )


def _check_rheology(s: Scene):
    """mu(I) needs the grain size of its inertial number and a yield surface to raise."""
    for name, mat in s.materials.items():
        if not isinstance(mat, Soil) or mat.rheology != "mu_I":
            continue
        if mat.grain_size is None:
            raise _Inconsistent(
                f"materials.{name}.grain_size",
                "required by rheology = 'mu_I' (the inertial number is per grain size: I = gamma_dot d50 / "
                "sqrt(p / rho_grain))",
            )
        if mat.yield_model == "elastic":
            raise _Inconsistent(
                f"materials.{name}.rheology",
                "'mu_I' raises the yield surface of a yielding soil, and yield_model = 'elastic' has none",
            )


def _check_sand_state(s: Scene):
    """A sand with a state yields by Mohr-Coulomb in the plane of a 2D flow at the friction and dilatancy its
    state sets (docs/sand.md); its void ratio and its porosity, where both are given, are one property."""
    for name, mat in s.materials.items():
        if not isinstance(mat, Soil) or mat.state is None:
            continue
        if mat.yield_model != "mohr_coulomb":
            raise _Inconsistent(
                f"materials.{name}.yield_model",
                f"must be 'mohr_coulomb' for a sand with a state (got '{mat.yield_model}'): the state sets "
                "the friction and the dilatancy of a plane-strain Mohr-Coulomb return "
                "(solver/physics/sand_state.py)",
            )
        if s.dim != 2:
            raise _Inconsistent(
                f"materials.{name}.state",
                "a sand with a state is plane strain (its return is Mohr-Coulomb in the plane of the flow): "
                "scene.dimension must be 2",
            )
        if mat.rheology != "perfectly_plastic":
            raise _Inconsistent(
                f"materials.{name}.rheology",
                "a sand with a state sets its own friction (Bolton 1986); mu(I) is not combined with it",
            )
        if mat.friction_angle <= 5.0 * 4.0:  # Bolton's 5 I_R at the index's clip of -4
            raise _Inconsistent(
                f"materials.{name}.friction_angle",
                f"{mat.friction_angle:g} degrees: a sand with a state takes it as the critical-state angle, "
                "and its loosest state mobilises phi_cv - 20 degrees (Bolton 1986, 5 I_R at I_R = -4): give "
                "more than 20 (quartz sands about 33, Bolton 1986)",
            )
        if mat.dilatancy_angle != 0.0:
            raise _Inconsistent(
                f"materials.{name}.dilatancy_angle",
                "the state sets the dilatancy of a sand with a state (Bolton 1986): leave it out",
            )
        if mat.porosity is not None:
            e_n = mat.porosity / (1.0 - mat.porosity)
            if abs(e_n - mat.state.void_ratio) > 1e-3 * e_n:  # both written to three or more digits
                raise _Inconsistent(
                    f"materials.{name}.state.void_ratio",
                    f"{mat.state.void_ratio:g} is not the porosity's n / (1 - n) = {e_n:.4g}: the void ratio "
                    "and the porosity are one property",
                )


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
    if _erodes(s):
        for name, mat in s.materials.items():
            if isinstance(mat, Water) and mat.viscosity <= 0.0:
                raise _Inconsistent(
                    f"materials.{name}.viscosity",
                    "must be > 0 where a soil erodes (the grain size's D* and the log law's smooth wall "
                    "need it)",
                )
    for name, mat in s.materials.items():
        if isinstance(mat, Soil) and mat.critical_shields is not None and mat.grain_size is None:
            raise _Inconsistent(
                f"materials.{name}.critical_shields", "needs grain_size (a Shields number is per grain size)"
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


def estimated_dt(s: Scene):
    """(dt, limit) before anything moves: seed eqs. (28)-(30) with the scene's sound speeds,
    gravity as the force and the largest kinematic viscosity (the run's dt can only be smaller
    once particles accelerate)."""
    h = s.h
    cfl = s.numerics.cfl
    c = max(m.sound_speed for m in s.materials.values())
    limits = [(cfl.sound * h / c, "sound speed")]
    g = math.hypot(*s.scene.gravity)  # no overflow for huge components
    if g > 0:
        limits.append((cfl.force * math.sqrt(h / g), "gravity"))
    nu = max((m.viscosity / m.density for m in s.materials.values() if isinstance(m, Water)), default=0.0)
    if s.numerics.viscous_stress and nu > 0:
        limits.append((cfl.viscous * h * h / nu, "viscosity"))
    return min(limits)


def _check_resources(s: Scene):
    """Refuse scenes that no machine could run: too many particles, cells, steps (see the limits)."""
    from .geometry import estimated_particles

    n = estimated_particles(s)
    if n > MAX_PARTICLES:
        raise _Inconsistent(
            "scene.spacing", f"the blocks would hold about {n:.3g} particles, more than {MAX_PARTICLES:.0e}"
        )
    extent = np.array(s.domain.max) - np.array(s.domain.min)
    with np.errstate(over="ignore"):  # a far too large domain overflows to inf, which is refused
        cells = float(np.prod(np.ceil(extent / (2.0 * s.h)) + 2.0))
    if cells > MAX_CELLS:
        raise _Inconsistent(
            "domain",
            f"spans {cells:.3g} neighbour cells of size 2h, more than {MAX_CELLS:.0e}: is it too large?",
        )
    dt, limit = estimated_dt(s)
    steps = (s.scene.end_time + s.numerics.settling_time) / dt if dt > 0 else math.inf
    if not steps <= MAX_STEPS:
        raise _Inconsistent(
            "scene.end_time",
            f"needs about {steps:.3g} time steps (dt about {dt:.3g} s, set by the {limit}), more than "
            f"{MAX_STEPS:.0e}",
        )


def deep_merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _fill_material_defaults(merged: dict) -> dict:
    """Per-model defaults (viscosity, c factor, AV alpha/beta) filled in per material, from
    the merged [material_defaults.*] and [artificial_viscosity_defaults.*] tables (so a scene's
    own values there are honoured). Anything of the wrong shape is left for the schema to refuse."""
    merged = copy.deepcopy(merged)
    materials = merged.get("materials")
    numerics = merged.get("numerics")
    if not isinstance(materials, dict):
        return merged
    av = numerics.setdefault("artificial_viscosity", {}) if isinstance(numerics, dict) else None
    mat_defaults = merged.get("material_defaults")
    av_defaults = merged.get("artificial_viscosity_defaults")
    for name, mat in materials.items():
        model = mat.get("model") if isinstance(mat, dict) else None
        if not isinstance(model, str) or model not in MODELS:
            continue
        if isinstance(mat_defaults, dict) and isinstance(mat_defaults.get(model), dict):
            for key, value in mat_defaults[model].items():
                mat.setdefault(key, value)
        if (
            isinstance(av, dict)
            and isinstance(av_defaults, dict)
            and isinstance(av_defaults.get(model), dict)
        ):
            av.setdefault(name, dict(av_defaults[model]))
    return merged


# the tagged unions' tag keys and their choices (Material, Block above)
_UNION_CHOICES = {"model": ("water", "soil"), "shape": ("rectangle", "polygon")}
_UNION_TAGS = {tag for tags in _UNION_CHOICES.values() for tag in tags}


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
    if kind == "value_error" and err.get("ctx", {}).get("error") is not None:
        return str(err["ctx"]["error"])  # our own reason, without pydantic's "Value error, " prefix
    return err["msg"]


def _numerics_defaults(raw: dict, defaults: dict) -> dict:
    """defaults.toml's [numerics], then the preset of numerics.scheme over it (SCHEMES), then
    the scene-dependent default of the leap-frog: the midpoint-density leap-frog is for water
    only, so a scene with a soil material that does not name a leap-frog gets the seed's.
    A malformed scheme or materials table is left for the validation to refuse by its key."""
    numerics = raw.get("numerics") if isinstance(raw.get("numerics"), dict) else {}
    out = copy.deepcopy(defaults)
    scheme = numerics.get("scheme", out["numerics"].get("scheme", "default"))
    preset = SCHEMES.get(scheme, {}) if isinstance(scheme, str) else {}
    out["numerics"].update(preset)
    materials = raw.get("materials") if isinstance(raw.get("materials"), dict) else {}
    models = [m.get("model") for m in materials.values() if isinstance(m, dict)]
    if "leapfrog" not in numerics and "leapfrog" not in preset and any(m != "water" for m in models):
        out["numerics"]["leapfrog"] = Leapfrog.SEED.value
    return out


def _refusal(exc: ValidationError, path, prefix=()) -> SceneError:
    err = exc.errors()[0]
    ctx = err.get("ctx", {})
    if isinstance(ctx.get("error"), _Inconsistent):
        return SceneError(path, ctx["error"].key, str(ctx["error"]))
    key = _dotted((*prefix, *err["loc"]))
    if err["type"] in ("union_tag_not_found", "union_tag_invalid"):  # a block's shape, a material's model
        tag = ctx.get("discriminator", "").strip("'")
        choices = ", ".join(f'"{c}"' for c in _UNION_CHOICES.get(tag, ()))
        written = (
            "missing value" if err["type"] == "union_tag_not_found" else f"{ctx.get('tag')!r} is not known"
        )
        return SceneError(path, f"{key}.{tag}", f"{written}: one of {choices}")
    return SceneError(path, key, _reason(err))


def parse_scene(raw: dict, path="<scene>") -> Scene:
    defaults = tomllib.loads(DEFAULTS_PATH.read_text())
    merged = deep_merge(_numerics_defaults(raw, defaults), raw)
    _default_fields_for_the_phases(raw, merged)
    for table in ("material_defaults", "artificial_viscosity_defaults", "inlet_defaults", "outlet_defaults"):
        # checked before they are filled in, so an error names the key the user wrote
        model = MaterialDefaults if table == "material_defaults" else Scene.model_fields[table].annotation
        try:
            if isinstance(merged.get(table), dict):
                pydantic_validate(model, merged[table])
        except ValidationError as exc:
            raise _refusal(exc, path, (table,)) from None
    try:
        return Scene.model_validate(fill_open_defaults(_fill_material_defaults(merged)))
    except ValidationError as exc:
        raise _refusal(exc, path) from None


def _default_fields_for_the_phases(raw: dict, merged: dict):
    """The default output fields include the water pressure; a scene without water that did not
    choose its fields gets the defaults without it (choosing 'pressure' there is refused). An eroding
    scene (water, a soil with a grain_size, numerics.erosion = "shields") that did not choose gets
    'suspended' and 'eroded_share' too: the scour measure reads the bed without the soil the flow has
    picked up or worn away."""
    chose = isinstance(raw.get("output"), dict) and "fields" in raw["output"]
    materials = merged.get("materials")
    if chose or not isinstance(materials, dict) or not isinstance(merged.get("output"), dict):
        return
    fields = merged["output"].get("fields")
    if not isinstance(fields, list):
        return
    mats = [m for m in materials.values() if isinstance(m, dict)]
    water = any(m.get("model") == "water" for m in mats)
    if not water:
        merged["output"]["fields"] = [f for f in fields if f != "pressure"]
    numerics = merged.get("numerics") if isinstance(merged.get("numerics"), dict) else {}
    grains = any(m.get("model") == "soil" and m.get("grain_size") is not None for m in mats)
    if water and grains and numerics.get("erosion") == "shields":
        merged["output"]["fields"] = fields + [f for f in ("suspended", "eroded_share") if f not in fields]


def pydantic_validate(model, value):
    if isinstance(model, type) and issubclass(model, BaseModel):
        return model.model_validate(value)
    from pydantic import TypeAdapter

    return TypeAdapter(model, config=Strict.model_config).validate_python(value)


def load_scene(path, overrides=()) -> Scene:
    """Read, merge and validate a scene file; `overrides` are "dotted.key=value" strings
    (value in TOML syntax, e.g. parallel.rebalance_every=50) applied before validation."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(
            path, "(file)", f"no such scene file (shipped scenes: {', '.join(shipped_scenes())})"
        )
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise SceneError(path, "(file)", f"cannot be read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise SceneError(
            path, "(file)", f"is not UTF-8 text (byte {exc.start}): is it a scene file?"
        ) from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(path, "(syntax)", str(exc)) from None
    apply_overrides(raw, overrides, path)
    return parse_scene(raw, path)


def apply_overrides(raw: dict, overrides, path) -> dict:
    """Set "dotted.key=value" strings (value in TOML syntax; a bare word is a string; an array of
    tables by index, inlets.0.discharge=0.08) in a raw scene dict, in place; SceneError naming
    `path` and the key when one cannot be set. Used by load_scene and the studies' variants."""
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
            if isinstance(table, list):  # an array of tables by index: inlets.0.discharge=0.08
                if not part.isdigit() or int(part) >= len(table) or not isinstance(table[int(part)], dict):
                    raise SceneError(path, key, f"'{part}' is not an index of that array of tables")
                table = table[int(part)]
                continue
            table = table.setdefault(part, {})
            if not isinstance(table, (dict, list)):
                raise SceneError(path, key, "is not a table in the scene")
        if isinstance(table, list):
            raise SceneError(
                path,
                key,
                "names an array: only a key of one of its tables can be set (inlets.0.discharge=0.08)",
            )
        table[last] = value
    return raw


def shipped_scenes() -> list[str]:
    """Names of the scenes shipped with the package (`scoursph run NAME`)."""
    return sorted(p.stem for p in SCENES_DIR.glob("*.toml"))


def resolve_scene_path(arg) -> Path:
    """A scene argument as a file: the path itself if it exists, else a shipped scene of that
    name (`dam_break_2d` or `dam_break_2d.toml`); otherwise the path unchanged (load_scene
    then says there is no such file)."""
    path = Path(arg)
    if path.exists() or path.parent != Path("."):
        return path
    shipped = SCENES_DIR / (path.name if path.suffix == ".toml" else f"{path.name}.toml")
    return shipped if shipped.is_file() else path


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
