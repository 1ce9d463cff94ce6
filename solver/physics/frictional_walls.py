"""Coulomb frictional walls for soil (walls.* = "frictional", mu = tan(walls.friction_angle)).

An image mirrored across one frictional wall is a no-slip image while its source sticks,
|tau| <= mu sigma_n (shear traction tau and compressive normal stress sigma_n of the source on
the wall plane); when it slips the tangential velocity is kept (free slip) and the image shear
is set to tau' = 2 tau_w - tau, so that the pair's mean shear (tau + tau') / 2, the traction
the wall exerts, is tau_w, of size mu sigma_n and opposing the sliding velocity. Sliding goes
on until the source's tangential speed falls below what one step of gravity gives. Runs after
each stress update, on the images of solver/physics/wall_images.py.
"""

from __future__ import annotations

import numpy as np

from ..config import kernel
from ..materials import Phase
from ..term import Equation, Stage, Term


@kernel  # images are a thin layer: a serial loop
def frictional_images(
    first, src, offset, fric_axis, fric_side, mu, mean_stress, stress, vsign, x, v, rho, gravity, v_stick
):
    """Stick/slip of images across frictional walls (fric_axis[k] = wall normal axis, -1 = not
    frictional; fric_side[k] = +1 lower wall, -1 upper): the normal stress at the wall is the
    source's extrapolated to the wall plane by rho g_n times the distance; updates the image's velocity
    signs and sets its shear stress (see module doc). Stick: |v_t| <= v_stick and |tau| <= mu sigma_n
    (no-slip image, T' = T). Slip: the wall's shear traction is mu sigma_n, opposing the sliding
    velocity (or along tau when slip starts from rest), by tau' = 2 tau_w - tau. Returns the
    number of slipping images."""
    dim = vsign.shape[1]
    slipping = 0
    for k in range(src.shape[0]):
        a = fric_axis[k]
        if a < 0:
            continue
        j = src[k]
        i = first + k
        # compression positive, extrapolated from the source to the wall plane (offset = 2 x plane)
        # by the weight of the layer between them, d sigma_n / dn = rho g_n (static equilibrium)
        sigma_n = max(
            mean_stress[j] - stress[j, a] + rho[j] * abs(gravity[a]) * abs(x[j, a] - 0.5 * offset[k, a]), 0.0
        )
        c1 = 3 if a != 2 else 5  # shear components on the wall plane
        c2 = 5 if a == 0 else 4
        b1 = 1 if a == 0 else 0  # their tangential axes
        b2 = 1 if a == 2 else 2
        t1 = stress[j, c1] if b1 < dim else 0.0
        t2 = stress[j, c2] if b2 < dim else 0.0
        u1 = v[j, b1] if b1 < dim else 0.0
        u2 = v[j, b2] if b2 < dim else 0.0
        tau = np.sqrt(t1 * t1 + t2 * t2)
        speed = np.sqrt(u1 * u1 + u2 * u2)
        limit = mu * sigma_n
        sliding = speed > v_stick
        slip = sliding or tau > limit
        for b in range(dim):
            if b != a:
                vsign[k, b] = 1.0 if slip else -1.0
        if slip:
            slipping += 1
            if sliding:  # kinetic: oppose the sliding velocity
                w1 = fric_side[k] * limit * u1 / speed
                w2 = fric_side[k] * limit * u2 / speed
            else:  # slip starts: along the driving shear
                w1 = limit * t1 / tau
                w2 = limit * t2 / tau
            if b1 < dim:
                stress[i, c1] = 2.0 * w1 - t1
            if b2 < dim:
                stress[i, c2] = 2.0 * w2 - t2
    return slipping


def _frictional_axes(sign, offset, lo, hi, fric_lo, fric_hi):
    """Per image: the normal axis of the frictional wall it is mirrored across, or -1 (not
    mirrored across exactly one wall, or that wall is not frictional: corners stay no-slip),
    and +1 / -1 for a lower / upper wall."""
    axes = np.full(len(sign), -1, dtype=np.int64)
    side = np.zeros(len(sign))
    single = np.sum(sign < 0, axis=1) == 1
    for a in range(sign.shape[1]):
        mirrored = single & (sign[:, a] < 0)
        at_lo = mirrored & (np.abs(offset[:, a] - 2 * lo[a]) <= np.abs(offset[:, a] - 2 * hi[a]))
        at_hi = mirrored & ~at_lo
        if fric_lo[a]:
            axes[at_lo] = a
            side[at_lo] = 1.0
        if fric_hi[a]:
            axes[at_hi] = a
            side[at_hi] = -1.0
    return axes, side


class FrictionalWalls(Term):
    """Stick or slip of each image across a frictional wall, per step."""

    name = "frictional walls"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        if "frictional" not in scene.walls.kinds() or not materials.has_phase(Phase.SOIL):
            return None
        return cls(scene)

    def __init__(self, scene):
        super().__init__()
        dim = scene.dim
        kinds = [(getattr(scene.walls, f"{ax}_min"), getattr(scene.walls, f"{ax}_max")) for ax in "xyz"[:dim]]
        self.frictional_lo = np.array([k[0] == "frictional" for k in kinds])
        self.frictional_hi = np.array([k[1] == "frictional" for k in kinds])
        self.mu = float(np.tan(np.radians(scene.walls.friction_angle)))
        self.g = float(np.linalg.norm(scene.scene.gravity))
        self.lo = np.asarray(scene.domain.min, float)
        self.hi = np.asarray(scene.domain.max, float)
        self.fric_axis = np.zeros(0, dtype=np.int64)
        self.fric_side = np.zeros(0)
        self.reads = ("x", "v", "rho", "mean_stress", "stress_dev")
        self.equations = (
            Equation(
                f"Coulomb wall friction, mu = tan({scene.walls.friction_angle:g} deg): stick as no slip, "
                "slip with wall traction mu sigma_n against the sliding velocity",
                "this project (verification/results/column_collapse/README.md)",
            ),
        )

    def on_rebuild(self, ctx):
        _, sign, offset = ctx.image_tables()
        self.fric_axis, self.fric_side = _frictional_axes(
            sign, offset, self.lo, self.hi, self.frictional_lo, self.frictional_hi
        )

    def run(self, ctx):
        ps = ctx.particles
        if ps.n_image == 0:
            return
        src, _, offset = ctx.image_tables()
        walls = ctx.images.walls
        v_stick = self.g * ctx.dt_prev if ctx.dt_prev > 0 else np.inf  # one step of gravity
        frictional_images(
            ps.n_local,
            src,
            offset,
            self.fric_axis,
            self.fric_side,
            self.mu,
            ps["mean_stress"],
            ps["stress_dev"],
            walls.vsign,
            ps["x"],
            ps["v"],
            ps["rho"],
            ctx.gravity,
            v_stick,
        )
        walls.refresh(ps, ("v",), {"v": ps.specs["v"]})  # the images' velocities with the new signs
