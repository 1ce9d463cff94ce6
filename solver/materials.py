"""Material models and their parameters, flattened into per-material arrays for kernels.

Each material gets an integer id (its order in the scene) and a phase: particles of one
phase interact through that phase's terms (water-water: seed eqs. 6-11, 19, 22; soil-soil:
seed eqs. 12-17, 19, 20); terms between phases (seepage) sum over the other phase.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from .scene import Scene, Soil, Water


class Phase(IntEnum):
    """The phase of a material: which terms act on its particles."""

    WATER = 0
    SOIL = 1

    @property
    def label(self):
        return self.name.lower()


class YieldModel(IntEnum):
    """Soil yield criterion, as the integer the return-mapping kernel branches on."""

    ELASTIC = 0  # no yield (checks)
    MOHR_COULOMB = 1  # seed eq. (16)
    DRUCKER_PRAGER = 2  # Bui et al. (2008)


@dataclass(frozen=True)
class SoilConstants:
    """Per-material soil constants (zeros for non-soil materials), indexed by material id."""

    bulk: np.ndarray  # K of eq. (17)
    shear: np.ndarray  # G of eq. (13)
    tan_phi: np.ndarray  # Mohr-Coulomb, eq. (16)
    cohesion: np.ndarray
    alpha_phi: np.ndarray  # Drucker-Prager plane-strain fit (Bui et al. 2008, eq. 27)
    k_c: np.ndarray
    alpha_psi: np.ndarray  # same fit with the dilatancy angle (non-associated flow)
    yield_model: np.ndarray  # int32, YieldModel
    # mu(I) once yielded (docs/rheology.md; Jop et al. 2006): mu_2 - mu_s (0: perfectly plastic), I_0, and
    # d50 sqrt(rho_grain), so that I = gamma_dot d50 sqrt(rho_grain) / sqrt(p)
    friction_increment: np.ndarray
    inertial_number_i0: np.ndarray
    grain_inertia: np.ndarray
    # a sand with a state (solver/sand_state.py, solver/physics/sand_state.py; zeros: constant phi and psi):
    # e0, e_min, e_max, the critical line's e_Gamma, lambda_c, xi, p_a, Bolton's Q, and phi_cv (degrees)
    state_e0: np.ndarray
    state_e_min: np.ndarray
    state_e_max: np.ndarray
    state_e_gamma: np.ndarray
    state_lambda: np.ndarray
    state_xi: np.ndarray
    state_p_a: np.ndarray
    state_q: np.ndarray
    phi_cv: np.ndarray

    @property
    def has_state(self):
        """True if any soil is a sand with a state (then its state sets its cone)."""
        return bool(np.any(self.state_e_max > 0.0))

    @property
    def rate_dependent(self):
        """True if any soil flows with mu(I) (then the rates compute the shear rate)."""
        return bool(np.any(self.friction_increment > 0.0))


def build_soil_constants(scene: Scene, names) -> SoilConstants | None:
    cols = {
        k: np.zeros(len(names))
        for k in (
            "bulk", "shear", "tan_phi", "cohesion", "alpha_phi", "k_c", "alpha_psi",
            "friction_increment", "inertial_number_i0", "grain_inertia",
            "state_e0", "state_e_min", "state_e_max", "state_e_gamma", "state_lambda", "state_xi",
            "state_p_a", "state_q", "phi_cv",
        )
    }  # fmt: skip
    model = np.zeros(len(names), dtype=np.int32)
    any_soil = False
    for k, name in enumerate(names):
        mat = scene.materials[name]
        if not isinstance(mat, Soil):
            continue
        any_soil = True
        tphi = np.tan(np.radians(mat.friction_angle))
        tpsi = np.tan(np.radians(mat.dilatancy_angle))
        cols["bulk"][k] = mat.bulk
        cols["shear"][k] = mat.shear_modulus
        cols["tan_phi"][k] = tphi
        cols["cohesion"][k] = mat.cohesion
        cols["alpha_phi"][k] = tphi / np.sqrt(9.0 + 12.0 * tphi**2)  # Bui et al. (2008), plane strain
        cols["k_c"][k] = 3.0 * mat.cohesion / np.sqrt(9.0 + 12.0 * tphi**2)
        cols["alpha_psi"][k] = tpsi / np.sqrt(9.0 + 12.0 * tpsi**2)
        model[k] = YieldModel[mat.yield_model.upper()]
        if mat.rheology == "mu_I" and scene.numerics.rheology == "material":
            cols["friction_increment"][k] = mat.friction_increment
            cols["inertial_number_i0"][k] = mat.inertial_number_i0
            cols["grain_inertia"][k] = mat.grain_size * np.sqrt(mat.grain_density)
        if mat.state is not None and scene.numerics.sand_state == "material":
            st = mat.state
            cols["state_e0"][k] = st.void_ratio
            cols["state_e_min"][k] = st.min_void_ratio
            cols["state_e_max"][k] = st.max_void_ratio
            cols["state_e_gamma"][k] = st.critical_void_ratio
            cols["state_lambda"][k] = st.critical_lambda
            cols["state_xi"][k] = st.critical_xi
            cols["state_p_a"][k] = st.reference_pressure
            cols["state_q"][k] = st.bolton_q
            cols["phi_cv"][k] = mat.friction_angle
    return SoilConstants(yield_model=model, **cols) if any_soil else None


@dataclass(frozen=True)
class MaterialTable:
    """Per-material constants indexed by material id (what the Numba kernels read)."""

    names: tuple[str, ...]
    phase: np.ndarray  # int32
    rho0: np.ndarray  # reference density (kg/m^3)
    sound_speed: np.ndarray  # c (m/s)
    eos_b: np.ndarray  # B = rho0 c^2 / lambda, seed eq. (9)
    eos_exponent: np.ndarray  # lambda
    viscosity: np.ndarray  # dynamic viscosity mu (Pa s), seed eq. (10)
    av_alpha: np.ndarray  # Monaghan artificial viscosity, seed eq. (19)
    av_beta: np.ndarray
    soil: SoilConstants | None = None  # present only when the scene has a soil material

    def index(self, name):
        return self.names.index(name)

    def ids_of_phase(self, phase: Phase):
        return [k for k in range(len(self.names)) if self.phase[k] == phase]

    def has_phase(self, phase: Phase):
        return bool(self.ids_of_phase(phase))


def tait_density(p, rho0, b, exponent):
    """Inverse of eq. (9), used to start a water block in hydrostatic equilibrium."""
    return rho0 * (1.0 + p / b) ** (1.0 / exponent)


def build_material_table(scene: Scene) -> MaterialTable:
    names = tuple(scene.materials)
    n = len(names)
    cols = {
        k: np.zeros(n)
        for k in ("rho0", "sound_speed", "eos_b", "eos_exponent", "viscosity", "av_alpha", "av_beta")
    }
    phase = np.zeros(n, dtype=np.int32)
    for k, name in enumerate(names):
        mat = scene.materials[name]
        if isinstance(mat, Water):
            phase[k] = Phase.WATER
            c = mat.sound_speed
            cols["rho0"][k] = mat.density
            cols["sound_speed"][k] = c
            cols["eos_exponent"][k] = mat.eos_exponent
            cols["eos_b"][k] = mat.density * c * c / mat.eos_exponent  # B = rho0 c^2 / lambda (seed 2.1)
            cols["viscosity"][k] = mat.viscosity
        elif isinstance(mat, Soil):
            phase[k] = Phase.SOIL
            cols["rho0"][k] = mat.density
            cols["sound_speed"][k] = mat.sound_speed  # c = sqrt((K + 4G/3) / rho0)
        av = scene.artificial_viscosity(name)
        cols["av_alpha"][k], cols["av_beta"][k] = av.alpha, av.beta
    return MaterialTable(names=names, phase=phase, soil=build_soil_constants(scene, names), **cols)
