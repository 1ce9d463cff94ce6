"""Rigid bodies of any polygon (`[[bodies]]`, 2D): image particles across their edges, and a leak
guard (issue 11 item 3).

Why images and not wall particles. The seed's walls are symmetric image particles (sec. 2.5,
Libersky et al. 1993), so a polygon body made the same way treats water and soil exactly as the
box walls do: each phase sees mirror images of its own particles (water: pressure and velocity,
soil: stress by eq. 23 generalised to a rotated wall), nothing crosses phases, and no new
material or boundary pressure model is needed. Fixed wall particles (the `fixed = true` blocks)
belong to one material and hence one phase: water does not feel a fixed soil block except through
the seepage drag, and soil does not feel a fixed water block, so a body that must stop both would
need two overlapping particle sets whose cross-phase drag and buoyancy act on the fluid near the
wall, or a wall phase with its own extrapolated pressure (Adami et al. 2012) and stress for soil.

Images. A local particle at signed distance 0 <= dist < reach outside an edge (outward normal n),
whose foot lies on the edge, gets an image mirrored across the edge's line: x' = R x + o with
R = I - 2 n n^T and o = 2 (a . n) n (a a point of the edge); velocities v' = R v (free slip:
normal part reversed, tangential kept) and tensors T' = R T R^T, which is eq. (23) for an
axis-aligned edge. Pressures are the source's plus the hydrostatic difference to the image's place
(hydrostatic_image_pressure.py, numerics.image_pressure = "hydrostatic"), as at the box walls.
A particle within reach of a convex vertex whose foot lies on neither edge (the wedge outside the
corner) is mirrored through the vertex, x' = 2 v - x, as if the corner were rounded to a point:
the wall normal there is m = (x - v)/|x - v|, so R = I - 2 m m^T (radial velocity reversed,
tangential kept). Without it a jet aimed at a corner (a square turned 45
degrees) drove particles into the body (tests/test_bodies.py). At a concave vertex between a body
and a box wall the corner image (the image of an image) is missing.

Who sees which image. Each image carries the region that made it (its tag: an edge's strip or a
convex vertex's wedge), and a particle sees an image only if it lies in that same region itself
(prune_to_own_region, once per neighbour-list rebuild): it sees the body through one mirror, the
one of the edge it faces or of the corner whose wedge it is in. This is the principle of the
multiple boundary tangent method (Yildiz, Rook & Suleman 2009, Int. J. Numer. Meth. Engng 77,
1416-1438: each particle mirrors its neighbours across the tangent at its own nearest boundary
point), kept here with images made once per source. Near a convex corner each of the three
regions' image sets fills the body's inside once over (edge strip: a mirror of that strip; wedge:
a point mirror of the wedge), so every particle there sees the body filled once. Two earlier rules
failed: with every pair kept, a particle in the wedge saw the body three times over (both edges'
images and the vertex's); dropping only the pairs whose target lies behind the image's mirror line
(the fix of the overflow's images compressing the pore water under the caisson's crown,
docs/history/scour_study_history.md) left one-sided image sets beside the corner, and still water there
ran at up to 0.4 m/s (tests/test_bodies.py::test_still_water_stays_still_beside_a_convex_body_corner). The
region rule still drops those crown pairs: pore water beside the face faces the face, not the crown.

Repulsion backstop. As at the box walls (wall_repulsion.py), the image force vanishes as a particle
reaches the wall (dW/dr = 0 at r = 0), so a jet drove particles through the edges (the strict xfails
of tests/test_bodies.py): each edge and convex vertex also carries Monaghan's (1994) Lennard-Jones
backstop within dx/2 (body_repulsion.py), zero beyond it, so no particle of an undisturbed lattice feels it.

Leak guard. After each drift, every owned particle found inside a body is counted (the leak
counter reported in run.json) and put back by reflecting it across the nearest edge, with its
velocity's normal part reversed, as the box walls' specular reflection does (README, "Walls cannot
pull"). A run that holds has a leak counter of 0.
"""

from __future__ import annotations

import numpy as np

from ..config import kernel
from ..particles import Mirror
from ..scene_open import polygon_area
from ..term import Equation, Stage, Term


class BodyGeometry:
    """Edges of every body, outward normals, with the vertices for point-in-polygon tests."""

    def __init__(self, scene):
        a, t, n, length, body = [], [], [], [], []
        verts, starts = [], [0]
        corner, t_in, t_out = [], [], []  # convex vertices: position, arriving and leaving edge directions
        for k, b in enumerate(scene.bodies):
            v = np.asarray(b.vertices, float)
            if polygon_area(v) < 0:
                v = v[::-1]  # counter-clockwise: the outward normal is the edge turned -90 degrees
            for i in range(len(v)):
                p, q = v[i], v[(i + 1) % len(v)]
                e = q - p
                ln = float(np.hypot(*e))
                if ln == 0:
                    continue
                a.append(p)
                t.append(e / ln)
                n.append(np.array([e[1], -e[0]]) / ln)
                length.append(ln)
                body.append(k)
            for i in range(len(v)):
                e_in, e_out = v[i] - v[i - 1], v[(i + 1) % len(v)] - v[i]
                if e_in[0] * e_out[1] - e_in[1] * e_out[0] > 0:  # left turn on a CCW polygon: convex
                    corner.append(v[i])
                    t_in.append(e_in / np.hypot(*e_in))
                    t_out.append(e_out / np.hypot(*e_out))
            verts.append(v)
            starts.append(starts[-1] + len(v))
        self.corner = np.array(corner, float).reshape(-1, 2)
        self.t_in = np.array(t_in, float).reshape(-1, 2)
        self.t_out = np.array(t_out, float).reshape(-1, 2)
        self.a = np.array(a, float).reshape(-1, 2)
        self.t = np.array(t, float).reshape(-1, 2)
        self.n = np.array(n, float).reshape(-1, 2)
        self.length = np.array(length, float)
        self.body = np.array(body, dtype=np.int64)
        self.verts = np.concatenate(verts) if verts else np.zeros((0, 2))
        self.starts = np.array(starts, dtype=np.int64)
        self.names = [b.name for b in scene.bodies]


@kernel
def find_body_images(x, n_local, reach, ea, et, en, elen, cv, cin, cout, src, rot, off, tag):
    """Images of local rows across body edges and round convex corners (fill when the tables are
    big enough); returns the count. tag: the region that made the image, edge e >= 0 or convex
    vertex c as -1 - c (prune_to_own_region)."""
    cap = src.shape[0]
    m = 0
    for i in range(n_local):
        for c in range(cv.shape[0]):
            r0 = x[i, 0] - cv[c, 0]
            r1 = x[i, 1] - cv[c, 1]
            r = np.sqrt(r0 * r0 + r1 * r1)
            if r >= reach or r == 0.0:
                continue
            if r0 * cin[c, 0] + r1 * cin[c, 1] <= 0.0 or r0 * cout[c, 0] + r1 * cout[c, 1] >= 0.0:
                continue  # not in the corner's wedge (past the arriving edge, before the leaving one)
            if m < cap:
                n0, n1 = r0 / r, r1 / r  # the wall normal of a corner rounded off to a point
                src[m] = i
                rot[m, 0, 0] = 1.0 - 2.0 * n0 * n0
                rot[m, 0, 1] = -2.0 * n0 * n1
                rot[m, 1, 0] = -2.0 * n0 * n1
                rot[m, 1, 1] = 1.0 - 2.0 * n1 * n1
                # x' = 2 v - x = R x + o
                off[m, 0] = 2.0 * cv[c, 0] - x[i, 0] - (rot[m, 0, 0] * x[i, 0] + rot[m, 0, 1] * x[i, 1])
                off[m, 1] = 2.0 * cv[c, 1] - x[i, 1] - (rot[m, 1, 0] * x[i, 0] + rot[m, 1, 1] * x[i, 1])
                tag[m] = -1 - c
            m += 1
        for e in range(ea.shape[0]):
            r0 = x[i, 0] - ea[e, 0]
            r1 = x[i, 1] - ea[e, 1]
            dist = r0 * en[e, 0] + r1 * en[e, 1]
            if dist < 0.0 or dist >= reach:
                continue
            foot = r0 * et[e, 0] + r1 * et[e, 1]
            if foot < 0.0 or foot > elen[e]:
                continue
            if m < cap:
                n0, n1 = en[e, 0], en[e, 1]
                src[m] = i
                rot[m, 0, 0] = 1.0 - 2.0 * n0 * n0
                rot[m, 0, 1] = -2.0 * n0 * n1
                rot[m, 1, 0] = -2.0 * n0 * n1
                rot[m, 1, 1] = 1.0 - 2.0 * n1 * n1
                c = 2.0 * (ea[e, 0] * n0 + ea[e, 1] * n1)
                off[m, 0] = c * n0
                off[m, 1] = c * n1
                tag[m] = e
            m += 1
    return m


@kernel
def refresh_rotated_vectors(first, src, rot, off, field, with_offset):
    """field' = R field (+ o for positions) for every body image row."""
    for k in range(src.shape[0]):
        i = first + k
        j = src[k]
        f0, f1 = field[j, 0], field[j, 1]
        field[i, 0] = rot[k, 0, 0] * f0 + rot[k, 0, 1] * f1
        field[i, 1] = rot[k, 1, 0] * f0 + rot[k, 1, 1] * f1
        if with_offset:
            field[i, 0] += off[k, 0]
            field[i, 1] += off[k, 1]
        for a in range(2, field.shape[1]):
            field[i, a] = field[j, a]


@kernel
def refresh_rotated_scalar(first, src, field):
    for k in range(src.shape[0]):
        field[first + k] = field[src[k]]


@kernel
def refresh_rotated_tensor(first, src, rot, tensor):
    """T' = R T R^T in the plane (components xx, yy, xy; 6-component storage of solver/tensors.py);
    zz kept, the out-of-plane shears rotated as vectors (zero in plane strain)."""
    for k in range(src.shape[0]):
        i = first + k
        j = src[k]
        txx, tyy, tzz, txy, tyz, txz = (
            tensor[j, 0], tensor[j, 1], tensor[j, 2], tensor[j, 3], tensor[j, 4], tensor[j, 5],
        )  # fmt: skip
        r00, r01, r10, r11 = rot[k, 0, 0], rot[k, 0, 1], rot[k, 1, 0], rot[k, 1, 1]
        # (R T)_ab then (R T R^T)_ab
        a00 = r00 * txx + r01 * txy
        a01 = r00 * txy + r01 * tyy
        a10 = r10 * txx + r11 * txy
        a11 = r10 * txy + r11 * tyy
        tensor[i, 0] = a00 * r00 + a01 * r01
        tensor[i, 1] = a10 * r10 + a11 * r11
        tensor[i, 3] = a00 * r10 + a01 * r11
        tensor[i, 2] = tzz
        tensor[i, 5] = r00 * txz + r01 * tyz
        tensor[i, 4] = r10 * txz + r11 * tyz


@kernel
def point_in_polygon(px, py, verts, first, last):
    """Even-odd rule (ray casting to +x)."""
    inside = False
    k = last - 1
    for i in range(first, last):
        xi, yi = verts[i, 0], verts[i, 1]
        xk, yk = verts[k, 0], verts[k, 1]
        if (yi > py) != (yk > py):
            xc = xi + (py - yi) * (xk - xi) / (yk - yi)
            if px < xc:
                inside = not inside
        k = i
    return inside


@kernel
def guard_bodies(n, x, v, v_half, verts, starts, ea, et, en, elen, ebody, fix):
    """Count owned rows inside a body; with `fix`, reflect each across its body's nearest edge and
    reverse its inward normal velocity. Returns (count, deepest penetration)."""
    count = 0
    deepest = 0.0
    for i in range(n):
        for b in range(starts.shape[0] - 1):
            if not point_in_polygon(x[i, 0], x[i, 1], verts, starts[b], starts[b + 1]):
                continue
            count += 1
            best = np.inf
            best_e = -1
            for e in range(ea.shape[0]):
                if ebody[e] != b:
                    continue
                r0 = x[i, 0] - ea[e, 0]
                r1 = x[i, 1] - ea[e, 1]
                foot = min(max(r0 * et[e, 0] + r1 * et[e, 1], 0.0), elen[e])
                q0 = r0 - foot * et[e, 0]
                q1 = r1 - foot * et[e, 1]
                d2 = q0 * q0 + q1 * q1
                if d2 < best:
                    best = d2
                    best_e = e
            deepest = max(deepest, np.sqrt(best))
            if fix and best_e >= 0:
                e = best_e
                dist = (x[i, 0] - ea[e, 0]) * en[e, 0] + (x[i, 1] - ea[e, 1]) * en[e, 1]  # < 0 inside
                x[i, 0] -= 2.0 * dist * en[e, 0]
                x[i, 1] -= 2.0 * dist * en[e, 1]
                for vel in (v, v_half):
                    vn = vel[i, 0] * en[e, 0] + vel[i, 1] * en[e, 1]
                    if vn < 0.0:
                        vel[i, 0] -= 2.0 * vn * en[e, 0]
                        vel[i, 1] -= 2.0 * vn * en[e, 1]
            break
    return count, deepest


@kernel
def in_image_region(px, py, tag, ea, et, en, elen, cv, cin, cout):
    """Whether the point lies where find_body_images would mirror it by the rule `tag` (reach aside):
    in front of edge e with its foot on the edge (tag e >= 0), or in the wedge outside convex
    vertex c (tag -1 - c)."""
    if tag >= 0:
        r0, r1 = px - ea[tag, 0], py - ea[tag, 1]
        foot = r0 * et[tag, 0] + r1 * et[tag, 1]
        return r0 * en[tag, 0] + r1 * en[tag, 1] >= 0.0 and 0.0 <= foot <= elen[tag]
    c = -1 - tag
    r0, r1 = px - cv[c, 0], py - cv[c, 1]
    return r0 * cin[c, 0] + r1 * cin[c, 1] > 0.0 and r0 * cout[c, 0] + r1 * cout[c, 1] < 0.0


@kernel
def prune_to_own_region(targets, start, index, x, first, tag, ea, et, en, elen, cv, cin, cout,
                        new_start, new_index):  # fmt: skip
    """Keep a pair (target i, body image k) only if the target lies in the region whose mirror made
    the image (in_image_region with the image's tag): each target sees the body through one mirror,
    that of the edge it faces or of the corner whose wedge it is in, so the body's inside is filled
    once. Returns the pairs kept; with new_index of length 0 it only counts them (new_start filled
    either way)."""
    n_img = tag.shape[0]
    fill = new_index.shape[0] > 0
    m = 0
    new_start[0] = 0
    for t in range(targets.shape[0]):
        i = targets[t]
        for s in range(start[t], start[t + 1]):
            j = index[s]
            k = j - first
            if 0 <= k < n_img:
                if not in_image_region(x[i, 0], x[i, 1], tag[k], ea, et, en, elen, cv, cin, cout):
                    continue
            if fill:
                new_index[m] = j
            m += 1
        new_start[t + 1] = m
    return m


class BodyImages:
    """The current table of body images (rows after the box walls' images)."""

    def __init__(self, geometry: BodyGeometry, reach):
        self.geo = geometry
        self.reach = reach
        self.src = np.zeros(0, dtype=np.int64)
        self.rot = np.zeros((0, 2, 2))
        self.off = np.zeros((0, 2))
        self.tag = np.zeros(0, dtype=np.int64)  # the edge (>= 0) or convex vertex (-1 - c) that made it
        self.n = 0

    def rebuild(self, particles, first, box=None):
        """Choose images of the local rows; they occupy rows [first, first + n). Returns n.
        box = (has_lo, lo, has_hi, hi) of the box walls: a body image within reach beyond a box wall
        is mirrored across it too (the corner image where a body meets a box wall, as the box walls'
        own corners have)."""
        g = self.geo
        tables = (g.a, g.t, g.n, g.length, g.corner, g.t_in, g.t_out)
        args = (particles["x"], particles.n_local, self.reach) + tables
        n = find_body_images(*args, self.src[:0], self.rot[:0], self.off[:0], self.tag[:0])
        self._room(n, 0)
        if n:
            find_body_images(*args, self.src, self.rot, self.off, self.tag)
        if box is not None and n:
            n = self._box_corners(particles["x"], n, *box)
        self.n = n
        particles.ensure_capacity(first + n)
        return n

    def _room(self, m, keep):
        """Tables with room for m images, keeping the first `keep`."""
        if m <= len(self.src):
            return
        size = int(m * 1.25) + 16
        for name in ("src", "rot", "off", "tag"):
            old = getattr(self, name)
            new = np.zeros((size,) + old.shape[1:], dtype=old.dtype)
            new[:keep] = old[:keep]
            setattr(self, name, new)

    def _box_corners(self, x, n, has_lo, lo, has_hi, hi):
        """Append, for each body image within reach of a box wall, its mirror across that wall (seen by
        the targets in the region that made the body image: its tag)."""
        src, rot, off, tag = (getattr(self, name)[:n].copy() for name in ("src", "rot", "off", "tag"))
        pos = np.einsum("kab,kb->ka", rot, x[src]) + off
        extra = []
        for a in range(2):
            for has, plane, near in (
                (has_lo[a], lo[a], pos[:, a] - lo[a]),
                (has_hi[a], hi[a], hi[a] - pos[:, a]),
            ):
                k = np.flatnonzero(near < self.reach) if has else []
                if not len(k):
                    continue
                flip = np.ones(2)
                flip[a] = -1.0
                shift = np.zeros(2)
                shift[a] = 2.0 * plane
                extra.append((src[k], flip[None, :, None] * rot[k], flip * off[k] + shift, tag[k]))
        m = n + sum(len(e[0]) for e in extra)
        self._room(m, n)
        for s_, r_, o_, g_ in extra:
            k = len(s_)
            self.src[n : n + k], self.rot[n : n + k], self.off[n : n + k] = s_, r_, o_
            self.tag[n : n + k] = g_
            n += k
        return n

    def prune(self, particles, lists, first):
        """Neighbour lists in which each target sees only the images made by the mirror of its own
        region (prune_to_own_region): the edge it faces, or the convex corner whose wedge it is in."""
        if self.n == 0:
            return lists
        g = self.geo
        x, tag = particles["x"], self.tag[: self.n]
        tables = (g.a, g.t, g.n, g.length, g.corner, g.t_in, g.t_out)
        out = {}
        for key, nl in lists.items():
            new_start = np.zeros(len(nl.targets) + 1, dtype=np.int64)
            args = (nl.targets, nl.start, nl.index, x, first, tag) + tables
            m = prune_to_own_region(*args, new_start, nl.index[:0])
            if m == len(nl.index):
                out[key] = nl
                continue
            new_index = np.empty(m, dtype=nl.index.dtype)
            prune_to_own_region(*args, new_start, new_index)
            out[key] = type(nl)(nl.targets, new_start, new_index)
        return out

    def refresh(self, particles, names, specs, first):
        if self.n == 0:
            return
        src, rot, off = self.src[: self.n], self.rot[: self.n], self.off[: self.n]
        for name in names:
            rule = specs[name].mirror
            if rule is Mirror.POSITION:
                refresh_rotated_vectors(first, src, rot, off, particles[name], True)
            elif rule is Mirror.VELOCITY or rule is Mirror.DIRECTION:  # body images are free slip
                refresh_rotated_vectors(first, src, rot, off, particles[name], False)
            elif rule is Mirror.SCALAR:
                refresh_rotated_scalar(first, src, particles[name])
            elif rule is Mirror.TENSOR:
                refresh_rotated_tensor(first, src, rot, particles[name])
            else:
                raise ValueError(f"field '{name}' has no mirror rule for images")


class BodyGuard(Term):
    """After each drift: particles found inside a body are counted (leaks) and reflected out."""

    name = "rigid bodies"
    stage = Stage.AFTER_DRIFT

    @classmethod
    def build(cls, scene, materials):
        return cls(scene) if scene.bodies else None

    def __init__(self, scene):
        super().__init__()
        self.geo = BodyGeometry(scene)
        self.writes = ("x", "v", "v_half")
        self.fix = True  # reflect leaked particles out (tests switch it off to see a leak uncorrected)
        self.leaks = 0  # this rank's count of particle-steps found inside a body
        self.deepest = 0.0
        self.equations = (
            Equation(
                "image particles across polygon edges, x' = R x + o, v' = R v, T' = R T R^T",
                "seed sec. 2.5, eq. (23) rotated; Libersky et al. (1993)",
            ),
            Equation(
                "a particle sees only the images of its own region (edge strip or corner wedge)",
                "multiple boundary tangent principle, Yildiz, Rook & Suleman (2009)",
            ),
            Equation("particles inside a body counted (leaks) and reflected out", "this project"),
        )

    def explain(self):
        return [f"body '{n}'" for n in self.geo.names]

    def state(self):
        return {"leaks": self.leaks, "deepest": self.deepest}

    def restore(self, state):
        self.leaks, self.deepest = int(state["leaks"]), float(state["deepest"])

    def regroup_state(self, states, size):
        """Per-rank leak counts (a restart on another rank count): the sum on rank 0, zero elsewhere;
        the deepest leak is a maximum, held by every rank."""
        deepest = max(float(s["deepest"]) for s in states)
        leaks = sum(int(s["leaks"]) for s in states)
        return [{"leaks": leaks, "deepest": deepest}] + [{"leaks": 0, "deepest": deepest}] * (size - 1)

    def run(self, ctx):
        ps, g = ctx.particles, self.geo
        count, deepest = guard_bodies(
            ps.n_owned,
            ps["x"],
            ps["v"],
            ps["v_half"],
            g.verts,
            g.starts,
            g.a,
            g.t,
            g.n,
            g.length,
            g.body,
            self.fix,
        )
        self.leaks += count
        self.deepest = max(self.deepest, deepest)
