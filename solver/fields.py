"""Particle fields that every plan has, or that several terms share.

A term's own fields (viscous stress, soil stress, ...) are declared in its module. Which
rule an image uses for a field (Mirror) and whether the field is constant per particle
decide how the step loop keeps ghosts and images current (solver/plan.py).
"""

import numpy as np

from .particles import FieldSpec, Mirror


def kinematics(dim: int) -> dict[str, FieldSpec]:
    """The fields of every plan: positions, momentum and mass of each particle."""
    return {
        "x": FieldSpec(dim, np.float64, "position", Mirror.POSITION),
        "x_ref": FieldSpec(dim, np.float64, "position at the last neighbour rebuild (skin check)"),
        "v": FieldSpec(dim, np.float64, "velocity at step n (predicted)", Mirror.VELOCITY),
        "v_half": FieldSpec(dim, np.float64, "leap-frog velocity at n+1/2 (eq. 25)", Mirror.VELOCITY),
        "acc": FieldSpec(dim, np.float64, "momentum rate (eqs. 7, 20, 21)"),
        "rho": FieldSpec(0, np.float64, "density at step n (predicted)", Mirror.SCALAR),
        "drho": FieldSpec(0, np.float64, "continuity rate (eq. 6)"),
        "mass": FieldSpec(0, np.float64, "particle mass", Mirror.SCALAR, constant=True),
        "material": FieldSpec(0, np.int32, "material id", Mirror.SCALAR, constant=True),
        "id": FieldSpec(0, np.int64, "global particle id", constant=True),
    }


RHO_HALF = FieldSpec(0, np.float64, "leap-frog density at n+1/2 (eq. 24)")
PRESSURE = FieldSpec(0, np.float64, "pressure, Tait EOS (eq. 9)", Mirror.SCALAR)
WATER_FRACTION = FieldSpec(
    0,
    np.float64,
    "water volume fraction at creation: 1 free water, n pore water (EOS reference n rho0)",
    Mirror.SCALAR,
    constant=True,
    default=1.0,
)

# The seed seepage's pore water is at its true density (EOS unchanged), so it cannot reuse
# water_fraction; this label only tells the density diffusion to leave it out (docs/seepage.md).
PORE_LABEL = FieldSpec(
    0,
    np.float64,
    "seed seepage: 1 free water, n pore water at creation (left out of the density diffusion)",
    Mirror.SCALAR,
    constant=True,
    default=1.0,
)


def x_prev(dim: int) -> FieldSpec:
    """x at step n, kept through the drift for the midpoint continuity (numerics.leapfrog =
    "midpoint_density"); mirrored like x, so an image's x_prev is the image of its source's."""
    return FieldSpec(dim, np.float64, "position at step n (midpoint continuity)", Mirror.POSITION)


RHO_REF = FieldSpec(
    0,
    np.float64,
    "hydrostatic reference density rho^H at step n (Fourtakas et al. 2019 density diffusion)",
    Mirror.SCALAR,
)
