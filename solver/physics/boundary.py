"""Straight walls by symmetric image particles (Libersky et al. 1993; seed sec. 2.5).

Every local particle within the list radius of a wall gets an image mirrored across it
(and across both walls near a corner). An image is stored as its source row plus a sign
and an offset per axis:  x' = s x + o,  v' = s v  (normal velocity reversed, tangential
kept: free slip), and a tensor T'_ab = s_a s_b T_ab, which is seed eq. (23) for one wall
(diagonal kept, off-diagonal reversed) and its composition at a corner.
No-slip walls (v' = -v, Takeda et al. 1994) keep the image stress unchanged, T' = T: their
velocity field is odd across the wall, so dv_t/dn and the shear stress it builds are even.
Reversing the shear stress there (eq. 23) would cancel the wall's shear traction in the
momentum sum, and soil would slide along a "no-slip" floor (tests/test_soil_walls.py).
Frictional walls (Coulomb, mu = tan(walls.friction_angle); soil): an image mirrored across one
frictional wall is a no-slip image while its source sticks, |tau| <= mu sigma_n (shear traction
tau and compressive normal stress sigma_n of the source on the wall plane), and when it slips the
tangential velocity is kept (free slip) and the image shear is set to tau' = 2 tau_w - tau, so
that the pair's mean shear (tau + tau') / 2, the traction the wall exerts, is tau_w, of size
mu sigma_n and opposing the sliding velocity (frictional_images, after each stress update).
Sliding goes on until the source's tangential speed falls below what one step of gravity gives.
Images are chosen when the neighbour lists are rebuilt and refreshed every step.
"""

from __future__ import annotations

import numpy as np

from ..config import kernel


def wall_planes(scene):
    """Per axis: (has lower wall, lower plane, has upper wall, upper plane)."""
    dim = scene.dim
    has_lo = np.zeros(dim, dtype=np.bool_)
    has_hi = np.zeros(dim, dtype=np.bool_)
    for a, axis in enumerate("xyz"[:dim]):
        has_lo[a] = getattr(scene.walls, f"{axis}_min") is not None
        has_hi[a] = getattr(scene.walls, f"{axis}_max") is not None
    return has_lo, np.asarray(scene.domain.min, float), has_hi, np.asarray(scene.domain.max, float)


@kernel
def _image_choices(xi, reach, has_lo, lo, has_hi, hi, choice):
    """choice[a] = 0 (no mirror), 1 (mirror at lower wall) or 2 (upper); returns count of mirrored axes."""
    k = 0
    for a in range(xi.shape[0]):
        choice[a] = 0
        if has_lo[a] and xi[a] - lo[a] < reach:
            choice[a] = 1
            k += 1
        elif has_hi[a] and hi[a] - xi[a] < reach:
            choice[a] = 2
            k += 1
    return k


@kernel
def find_images(x, n_local, reach, has_lo, lo, has_hi, hi, src, sign, offset):
    """Fill image tables; returns the number of images (call with big enough arrays, or
    with zero-length ones to count)."""
    dim = x.shape[1]
    choice = np.zeros(dim, dtype=np.int64)
    n = 0
    cap = src.shape[0]
    for i in range(n_local):
        k = _image_choices(x[i], reach, has_lo, lo, has_hi, hi, choice)
        if k == 0:
            continue
        # every non-empty subset of the mirrored axes gives one image (corner: 3 images)
        for mask in range(1, 1 << dim):
            ok = True
            for a in range(dim):
                if (mask >> a) & 1 and choice[a] == 0:
                    ok = False
            if not ok:
                continue
            if n < cap:
                src[n] = i
                for a in range(dim):
                    if (mask >> a) & 1:
                        sign[n, a] = -1.0
                        offset[n, a] = 2.0 * (lo[a] if choice[a] == 1 else hi[a])
                    else:
                        sign[n, a] = 1.0
                        offset[n, a] = 0.0
            n += 1
    return n


@kernel  # images are a thin layer: a serial loop, and no parallel compile cost
def refresh_image_vectors(first, src, sign, offset, x, v, vsign=None):
    """Image positions and velocities from their sources (free slip; with vsign, the
    velocity signs of images across no-slip walls, v' = -v: Takeda et al. 1994)."""
    dim = x.shape[1]
    for k in range(src.shape[0]):
        i = first + k
        j = src[k]
        for a in range(dim):
            x[i, a] = sign[k, a] * x[j, a] + offset[k, a]
            if vsign is not None:
                v[i, a] = vsign[k, a] * v[j, a]
            else:
                v[i, a] = sign[k, a] * v[j, a]


@kernel  # images are a thin layer: a serial loop, and no parallel compile cost
def refresh_image_scalar(first, src, field):
    for k in range(src.shape[0]):
        field[first + k] = field[src[k]]


@kernel  # images are a thin layer: a serial loop, and no parallel compile cost
def refresh_image_tensor(first, src, sign, sym_axes, tensor):
    """T'_ab = s_a s_b T_ab (seed eq. 23) for symmetric tensors in 6 components
    (solver/tensors.py); axes beyond the scene's dimension never flip."""
    dim = sign.shape[1]
    for k in range(src.shape[0]):
        i = first + k
        j = src[k]
        for c in range(sym_axes.shape[0]):
            a = sym_axes[c, 0]
            b = sym_axes[c, 1]
            sa = sign[k, a] if a < dim else 1.0
            sb = sign[k, b] if b < dim else 1.0
            tensor[i, c] = sa * sb * tensor[j, c]


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


class ImageWalls:
    """The walls of the box, and the current table of image particles."""

    def __init__(self, scene, reach):
        self.has_lo, self.lo, self.has_hi, self.hi = wall_planes(scene)
        self.reach = reach
        dim = scene.dim
        self.src = np.zeros(0, dtype=np.int64)
        self.sign = np.zeros((0, dim))
        self.offset = np.zeros((0, dim))
        self.any = bool(self.has_lo.any() or self.has_hi.any())
        kinds = [(getattr(scene.walls, f"{ax}_min"), getattr(scene.walls, f"{ax}_max")) for ax in "xyz"[:dim]]
        self.no_slip_lo = np.array(
            [k[0] in ("no_slip", "frictional") for k in kinds]
        )  # frictional: no slip while stuck
        self.no_slip_hi = np.array([k[1] in ("no_slip", "frictional") for k in kinds])
        self.frictional_lo = np.array([k[0] == "frictional" for k in kinds])
        self.frictional_hi = np.array([k[1] == "frictional" for k in kinds])
        self.frictional = bool(self.frictional_lo.any() or self.frictional_hi.any())
        self.mu = float(
            np.tan(np.radians(scene.walls.friction_angle or 0.0))
        )  # set whenever a wall is frictional
        self.fric_axis = np.zeros(0, dtype=np.int64)
        self.fric_side = np.zeros(0)
        self.vsign = None
        self.tsign = None

    def rebuild(self, particles):
        """Choose images of all local rows; appends them after the local rows."""
        x, n_local = particles["x"], particles.n_local
        args = (x, n_local, self.reach, self.has_lo, self.lo, self.has_hi, self.hi)
        n = find_images(*args, self.src[:0], self.sign[:0], self.offset[:0]) if self.any else 0
        if n > len(self.src):
            m = int(n * 1.25) + 16
            self.src = np.zeros(m, dtype=np.int64)
            self.sign = np.zeros((m, particles.dim))
            self.offset = np.zeros((m, particles.dim))
        if n:
            find_images(*args, self.src, self.sign, self.offset)
        self.n = n
        if self.no_slip_lo.any() or self.no_slip_hi.any():
            self.vsign = _velocity_signs(
                self.sign[:n], self.offset[:n], self.lo, self.hi, self.no_slip_lo, self.no_slip_hi
            )
            self.tsign = _tensor_signs(
                self.sign[:n], self.offset[:n], self.lo, self.hi, self.no_slip_lo, self.no_slip_hi
            )
        if self.frictional:
            self.fric_axis, self.fric_side = _frictional_axes(
                self.sign[:n], self.offset[:n], self.lo, self.hi, self.frictional_lo, self.frictional_hi
            )
        particles.ensure_capacity(n_local + n)
        particles.n_image = n

    def tables(self):
        return self.src[: self.n], self.sign[: self.n], self.offset[: self.n]

    def velocity_signs(self):
        """Per-image velocity signs, or None when every wall is free slip."""
        return self.vsign

    def tensor_signs(self):
        """Per-image axis signs for tensors, T'_ab = t_a t_b T_ab: the mirror sign across
        free-slip walls (eq. 23), +1 across no-slip walls (stress unchanged)."""
        return self.tsign if self.tsign is not None else self.sign[: self.n]


def _velocity_signs(sign, offset, lo, hi, no_slip_lo, no_slip_hi):
    """Product over the walls an image is mirrored across of that wall's velocity flip:
    free slip flips the normal component, no slip flips all (v' = -v)."""
    vs = np.ones_like(sign)
    for a in range(sign.shape[1]):
        mirrored = sign[:, a] < 0
        at_lo = mirrored & (np.abs(offset[:, a] - 2 * lo[a]) <= np.abs(offset[:, a] - 2 * hi[a]))
        at_hi = mirrored & ~at_lo
        for rows, noslip in ((at_lo, no_slip_lo[a]), (at_hi, no_slip_hi[a])):
            if noslip:
                vs[rows] *= -1.0
            else:
                vs[rows, a] *= -1.0
    return vs


def _tensor_signs(sign, offset, lo, hi, no_slip_lo, no_slip_hi):
    """Axis signs for image tensors: -1 only for an axis mirrored across a free-slip wall."""
    ts = np.ones_like(sign)
    for a in range(sign.shape[1]):
        mirrored = sign[:, a] < 0
        at_lo = mirrored & (np.abs(offset[:, a] - 2 * lo[a]) <= np.abs(offset[:, a] - 2 * hi[a]))
        at_hi = mirrored & ~at_lo
        ts[at_lo, a] = 1.0 if no_slip_lo[a] else -1.0
        ts[at_hi, a] = 1.0 if no_slip_hi[a] else -1.0
    return ts


@kernel
def _static_increment(gravity, x, rho, i, j):
    """rho_j g . (x_i - x_j): the static pressure difference from source j down to image i."""
    gdx = 0.0
    for a in range(x.shape[1]):
        gdx += gravity[a] * (x[i, a] - x[j, a])
    return rho[j] * gdx


@kernel
def add_hydrostatic_image_pressure(first, src, x, rho, gravity, p):
    """p_image = p_source + rho_source g . (x_image - x_source): the mirror pressure plus the
    hydrostatic difference between the two points (numerics.image_pressure = "hydrostatic")."""
    for k in range(src.shape[0]):
        p[first + k] += _static_increment(gravity, x, rho, first + k, src[k])


@kernel  # images are a thin layer: a serial loop
def add_equilibrium_image_stress(first, src, x, rho, gravity, mean_stress, stress):
    """The soil analogue of add_hydrostatic_image_pressure (numerics.image_pressure =
    "hydrostatic"): the image's stress is its source's plus the static increment of the normal
    stress along gravity, sigma' = sigma - q g^ g^ with q = rho_source g . (x_image - x_source)
    (compression positive: static equilibrium d sigma_vv / dv = rho g along the vertical v). An
    image below its source is then more compressed than it, as the soil below a floor would
    be, so a particle pressed into the image layer is pushed back, where the mirror image
    alone (seed eq. 23) leaves it in neutral equilibrium at the wall. As p and s:
    dp = q / 3, ds = -q (g^ g^ - I / 3). Side walls: g . dx = 0, no change. On a frictional
    wall that slips, frictional_images then sets the image shear itself, replacing the shear
    part of this increment, which is non-zero only when gravity is not normal to the wall."""
    dim = x.shape[1]
    g2 = 0.0
    for a in range(dim):
        g2 += gravity[a] * gravity[a]
    if g2 == 0.0:
        return
    gn = np.zeros(3)
    for a in range(dim):
        gn[a] = gravity[a] / np.sqrt(g2)
    for k in range(src.shape[0]):
        i = first + k
        q = _static_increment(gravity, x, rho, i, src[k])
        mean_stress[i] += q / 3.0
        stress[i, 0] -= q * (gn[0] * gn[0] - 1.0 / 3.0)
        stress[i, 1] -= q * (gn[1] * gn[1] - 1.0 / 3.0)
        stress[i, 2] -= q * (gn[2] * gn[2] - 1.0 / 3.0)
        stress[i, 3] -= q * gn[0] * gn[1]
        stress[i, 4] -= q * gn[1] * gn[2]
        stress[i, 5] -= q * gn[0] * gn[2]


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
