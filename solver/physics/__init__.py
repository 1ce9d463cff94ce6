"""The physics terms, one module each, in the order they run within each stage of a step.

Adding a term: write its module (a Term subclass with its kernel, see solver/term.py and
docs/adding_a_term.md) and add one line to TERMS. Registration order is execution order
within a stage; a term that needs another's output comes after it.
"""

from .artificial_stress import ArtificialStress, ArtificialStressForce
from .bed_shear import BedShearOnSoil, BedShearOnWater, FreeWater
from .bed_surface import BedSurface
from .bodies import BodyGuard
from .body_repulsion import BodyRepulsion
from .density_diffusion import DensityDiffusionRate, HydrostaticReference
from .equilibrium_soil_images import EquilibriumSoilImages
from .fixed_particles import FixedParticles
from .fluid_rates import FluidRates
from .frictional_walls import FrictionalWalls
from .gravity import Gravity
from .hydrostatic_image_pressure import HydrostaticImagePressure
from .inlet import Inlets
from .midpoint_continuity import MidpointContinuity, MidpointStart
from .outlet import OutletBuffers, Outlets
from .pore_water_release import PoreWaterRelease
from .seepage import PorePressureAtSoil, SeepageOnSoil, SeepageOnWater
from .seepage_pore_diffusion import PoreDensityDiffusion, PoreDensityGradient
from .shields_pickup import ShieldsPickup
from .soil_rates import SoilRates
from .soil_stress import SoilReturnMapping, SoilStressState
from .tait_eos import TaitEquationOfState
from .viscous_stress import ViscousStress
from .wall_function import WallFunctionShear
from .wall_images import WallImages
from .wall_repulsion import WallRepulsion

TERMS = (
    WallImages,
    Gravity,
    WallRepulsion,
    BodyRepulsion,
    TaitEquationOfState,
    HydrostaticImagePressure,
    HydrostaticReference,
    PoreDensityGradient,  # after the reference it reads
    PorePressureAtSoil,
    SoilStressState,
    BedSurface,  # erosion: after the stress it leaves alone, before the pick-up that reads it
    FreeWater,  # water outside the bed, for the pick-up's wall shear and the drag
    PoreWaterRelease,  # pore water outside the bed becomes free water (after the flags it reads)
    ShieldsPickup,  # zeroes the stress of what it suspends, before anything reads the stress
    ArtificialStress,
    EquilibriumSoilImages,
    FrictionalWalls,
    ViscousStress,
    FluidRates,
    WallFunctionShear,
    DensityDiffusionRate,
    PoreDensityDiffusion,
    SoilRates,
    ArtificialStressForce,
    SeepageOnWater,  # before the soil side, which reads the p^ it writes
    SeepageOnSoil,
    BedShearOnWater,  # erosion: the wall shear in place of the drag on the free water over the bed
    BedShearOnSoil,
    FixedParticles,
    OutletBuffers,  # after every rate: buffer particles receive none
    SoilReturnMapping,
    MidpointStart,
    MidpointContinuity,
    BodyGuard,  # after the drift: leaks counted and reflected before particles are added or removed
    Inlets,
    Outlets,  # Stage.LEAVING: before the state check and the bodies' guard
)
