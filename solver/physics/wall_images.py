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
Frictional walls (Coulomb) start as no-slip images; solver/physics/frictional_walls.py
switches them to slip per image.

Images are chosen when the neighbour lists are rebuilt (this term's on_rebuild) and take
each field a term reads from neighbours by the field's Mirror rule (solver/particles.py)
whenever the step loop refreshes it.
"""

from __future__ import annotations

import numpy as np

from ..config import kernel
from ..neighbors import verlet_radius
from ..particles import Mirror
from ..tensors import SYM_AXES
from ..term import Equation, Stage, Term
from .bodies import BodyGeometry, BodyImages


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
def refresh_image_positions(first, src, sign, offset, x):
    """x' = s x + o for every image row."""
    for k in range(src.shape[0]):
        i = first + k
        j = src[k]
        for a in range(x.shape[1]):
            x[i, a] = sign[k, a] * x[j, a] + offset[k, a]


@kernel  # images are a thin layer: a serial loop, and no parallel compile cost
def refresh_image_velocities(first, src, vsign, v):
    """v' = s v per axis: the mirror sign across free-slip walls, -1 on every axis across
    no-slip walls (Takeda et al. 1994)."""
    for k in range(src.shape[0]):
        i = first + k
        j = src[k]
        for a in range(v.shape[1]):
            v[i, a] = vsign[k, a] * v[j, a]


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


@kernel
def static_increment(gravity, x, rho, i, j):
    """rho_j g . (x_i - x_j): the static pressure difference from source j down to image i."""
    gdx = 0.0
    for a in range(x.shape[1]):
        gdx += gravity[a] * (x[i, a] - x[j, a])
    return rho[j] * gdx


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
        # polygon bodies (solver/physics/bodies.py): their images follow the box walls' images
        self.bodies = BodyImages(BodyGeometry(scene), reach) if scene.bodies else None
        kinds = [(getattr(scene.walls, f"{ax}_min"), getattr(scene.walls, f"{ax}_max")) for ax in "xyz"[:dim]]
        # frictional walls are no-slip while stuck (solver/physics/frictional_walls.py)
        self.no_slip_lo = np.array([k[0] in ("no_slip", "frictional") for k in kinds])
        self.no_slip_hi = np.array([k[1] in ("no_slip", "frictional") for k in kinds])
        self.n = 0
        self.vsign = None
        self.tsign = None
        self._slip = {}  # name -> buffer of slip_velocity

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
        particles.ensure_capacity(n_local + n)
        box = (self.has_lo, self.lo, self.has_hi, self.hi) if self.any else None
        nb = self.bodies.rebuild(particles, n_local + n, box) if self.bodies is not None else 0
        particles.n_image = n + nb

    def prune(self, particles, lists):
        """The neighbour lists without pairs that see a body image from behind its mirror line."""
        if self.bodies is None:
            return lists
        return self.bodies.prune(particles, lists, particles.n_local + self.n)

    def tables(self):
        """The box walls' images (the body images after them have rotation tables of their own)."""
        return self.src[: self.n], self.sign[: self.n], self.offset[: self.n]

    def sources(self):
        """The source row of every image, box walls' then bodies' (image rows n_local + k)."""
        if self.bodies is None or self.bodies.n == 0:
            return self.src[: self.n]
        return np.concatenate((self.src[: self.n], self.bodies.src[: self.bodies.n]))

    def velocity_signs(self):
        """Per-image velocity signs, v'_a = t_a v_a: the mirror signs when every wall is free
        slip; with no-slip walls, -1 on every axis for an image across one."""
        return self.vsign if self.vsign is not None else self.sign[: self.n]

    def tensor_signs(self):
        """Per-image axis signs for tensors, T'_ab = t_a t_b T_ab: the mirror sign across
        free-slip walls (eq. 23), +1 across no-slip walls (stress unchanged)."""
        return self.tsign if self.tsign is not None else self.sign[: self.n]

    def slip_velocity(self, particles, name):
        """The velocity field `name` with the box walls' images carrying the free-slip mirror v' = s v
        whatever the walls' kind (Term.slip_image_velocity); the field itself when no wall is no-slip.
        Body images are free slip already."""
        field = particles[name]
        if self.vsign is None or self.n == 0:
            return field
        buf = self._slip.get(name)
        if buf is None or buf.shape != field.shape:
            buf = self._slip[name] = np.empty_like(field)
        n = particles.n_total
        buf[:n] = field[:n]
        refresh_image_velocities(particles.n_local, self.src[: self.n], self.sign[: self.n], buf)
        return buf

    def refresh(self, particles, names, specs):
        """Copy each named field from the sources to the images by its Mirror rule."""
        if self.bodies is not None:
            self.bodies.refresh(particles, names, specs, particles.n_local + self.n)
        if self.n == 0:
            return
        src, sign, offset = self.tables()
        first = particles.n_local
        for name in names:
            rule = specs[name].mirror
            if rule is Mirror.POSITION:
                refresh_image_positions(first, src, sign, offset, particles[name])
            elif rule is Mirror.VELOCITY:
                refresh_image_velocities(first, src, self.velocity_signs(), particles[name])
            elif rule is Mirror.DIRECTION:  # the free-slip mirror whatever the wall's kind
                refresh_image_velocities(first, src, sign, particles[name])
            elif rule is Mirror.SCALAR:
                refresh_image_scalar(first, src, particles[name])
            elif rule is Mirror.TENSOR:
                refresh_image_tensor(first, src, self.tensor_signs(), SYM_AXES, particles[name])
            else:
                raise ValueError(f"field '{name}' has no mirror rule for images")


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


class WallImages(Term):
    """The walls of the box as image particles: present when the scene has a wall."""

    name = "wall images"
    stage = Stage.REBUILD

    @classmethod
    def build(cls, scene, materials):
        return cls(scene) if scene.walls.kinds() or scene.bodies else None

    def __init__(self, scene):
        super().__init__()
        self.walls = ImageWalls(scene, reach=verlet_radius(scene))
        self.equations = (
            Equation(
                "an image of each particle within the list radius of a wall",
                "seed sec. 2.5, Libersky et al. (1993)",
            ),
            Equation(
                "image tensors T'_ab = s_a s_b T_ab; kept across no-slip walls",
                "seed eq. (23); Takeda et al. (1994)",
            ),
        )
        kinds = {k for k in scene.walls.kinds()} | ({"polygon bodies (free slip)"} if scene.bodies else set())
        self._summary = ", ".join(sorted(kinds))

    def on_rebuild(self, ctx):
        self.walls.rebuild(ctx.particles)

    def tables(self):
        return self.walls.tables()

    def sources(self):
        return self.walls.sources()

    def prune(self, particles, lists):
        return self.walls.prune(particles, lists)

    def refresh(self, particles, names, specs):
        self.walls.refresh(particles, names, specs)

    def slip_velocity(self, particles, name):
        return self.walls.slip_velocity(particles, name)

    def explain(self):
        return [f"wall kinds: {self._summary}"]
