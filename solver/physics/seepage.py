"""Water-soil coupling: the seepage force (seed eq. 18) and, in the mixture formulation, the pore
pressure acting on the soil skeleton (buoyancy, effective stress).

Both phases are their own particle sets that overlap in a saturated bed; each phase's SPH density
is its mass per unit mixture volume (apparent density: (1 - n) rho_grain for the skeleton, which is
the soil material's `density`, its dry density; n rho_w for pore water in the mixture formulation).
Every water-soil pair (water a, soil b) exchanges one force, equal and opposite, so momentum is
conserved pair by pair (docs/seepage.md derives each term):

  drag       F_ab = V_a V_b C W_ab (v_a - v_b)                    C = n gamma_w / k    ("seed")
                                                                 C = n^2 gamma_w / k  ("mixture")
  buoyancy   F_ab = -(1 - n) V_a V_b (p^_a - p~_b) grad_b W_ab     ("mixture" only)

with F_ab the force on soil b, the water getting -F_ab. "seed" is exactly the seed's eqs. (18),
(20), (21) with the erratum of DESIGN.md (the sums run over the other phase with one pair value of
f = gamma_w n (v_w - v_s) / k, the force per unit volume of pore water: Darcy's q = k i). The
mixture form is Biot's (1941) two-phase mixture as used in SPH by Bui & Nguyen (2017, Int. J.
Solids Struct. 125:244): per unit mixture volume the skeleton feels div sigma' - (1 - n) grad p + R
and the water -n grad p - R, R = n^2 gamma_w (v_w - v_s) / k (Biot/Prevost drag, Morikawa & Asai
2022 eqs. 7, 9). The water's own pass gives -grad p; the pair buoyancy, a difference-form gradient
of p with p~_b the pore pressure interpolated at the soil particle (Shepard) and p^_a that
interpolated back at the water particle (so no water particle feels its own pressure through a
support cut by a wall), gives -(1 - n) grad p to the skeleton and +(1 - n) grad p to the water.
Wall particles of fixed water blocks take no part in the pairs (they are walls, not pore water).
numerics.pore_pressure_at_water = "linear" (opt-in) takes p^_a from a weighted linear fit of p~ over
the soil neighbours instead, exact where a bed's surface under water cuts the soil support
(docs/seepage.md, case 4).
In the mixture form the water's continuity also feels the pores squeezed by the skeleton (Biot's
storage: D ln rho_w/Dt gets -(phi/n) div v_s, phi = 1 - n the solid fraction at the water
particle), which is what drives consolidation, and pore water starts at n rho_w with that as its
EOS reference (tait_eos.py: p from rho / rho_ref).

The drag is explicit and its stiffness limits the step: the relaxation rate of a pair's relative
velocity is lambda = lambda_a + lambda_b, lambda_i = sum_j K_ij / m_i (~ n g / k (1 + n rho_w /
rho_s)); dt <= cfl.drag / lambda_max (numerics.cfl.drag), evaluated every step from these sums.

Three passes, one loop over the pairs each (docs/seepage.md, "Speed"): p~ at the soil (Shepard,
state stage); the water side, which interpolates p^ back onto the water and sums its pair forces
and Biot's storage in the same loop (the buoyancy sums split around p^_a, which is not known
until the loop ends); the soil side, pair by pair, reading the pairs' V W and V W'/r that the p~
pass left over the same list (mixture; the seed form computes them). p~ and p^ are refreshed on
ghosts and images in between (the plan derives it from what each term reads and writes). Per-row
gathering needs no atomics and serves ghost and image neighbours as they are; rows are split over
threads in chunks of equal work (row_chunks).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import get_num_threads, prange

from ..config import kernel
from ..kernels import cubic_spline_dwdr, cubic_spline_w
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..scene import Seepage, Soil
from ..tensors import N_SYM
from ..term import Equation, Stage, Term
from ..timestep import Constraint
from .bed_shear import bed_shear_on
from .erodible import erosion_materials
from .fixed_particles import FIXED

PORE_PRESSURE = FieldSpec(
    0, np.float64, "pore pressure interpolated: p~ at soil, p^ at water (mixture buoyancy)", Mirror.SCALAR
)

# A geometric tensor: across a no-slip wall the image's tensor signs are +1 (kept for the stress), so
# its shear component would keep its sign there; only free-slip walls mirror it exactly.
PAIR_CORRECTION = FieldSpec(
    N_SYM,
    np.float64,
    "buoyancy pair's gradient correction L = kappa M^-1 at water (Bonet & Lok 1999)",
    Mirror.TENSOR,
)


@dataclass(frozen=True)
class SeepageSettings:
    """Per-material constants of the coupling, indexed by material id (zeros for water)."""

    formulation: Seepage
    drag: np.ndarray  # C of the drag per unit mixture volume per unit relative velocity (N s / m^4)
    solid: np.ndarray  # 1 - n of each soil material (mixture buoyancy), 0 in the seed form
    grain_density: np.ndarray  # rho_grain = rho_dry / (1 - n), for the solid fraction at water
    cfl_drag: float
    one_soil: int | None = None  # the soil material id if there is only one (a compile-time switch)
    walls: bool = False  # the scene has fixed water blocks (wall particles): they are left out
    linear: bool = False  # p^ by a linear fit (numerics.pore_pressure_at_water = "linear")
    kappa: float = 0.0  # the SPH gradient's normalisation on a lattice (mixture: the buoyancy pair's target)
    # 1 per eroding soil material whose free water feels the wall shear instead of the drag
    # (bed_shear.py); None: the drag on every pair
    erodes: np.ndarray | None = None

    @classmethod
    def of(cls, scene, materials):
        """The coupling of a scene with water and soil, or None."""
        if not (materials.has_phase(Phase.WATER) and materials.has_phase(Phase.SOIL)):
            return None
        rho_w = max(float(materials.rho0[k]) for k in materials.ids_of_phase(Phase.WATER))
        g = float(np.linalg.norm(scene.scene.gravity)) or STANDARD_GRAVITY
        gamma_w = rho_w * g
        form = scene.numerics.seepage
        n_mat = len(materials.names)
        drag, solid, grain = np.zeros(n_mat), np.zeros(n_mat), np.zeros(n_mat)
        for k, name in enumerate(materials.names):
            mat = scene.materials[name]
            if not isinstance(mat, Soil):
                continue
            n, perm = mat.porosity, mat.permeability
            drag[k] = (n if form == Seepage.SEED else n * n) * gamma_w / perm
            solid[k] = 0.0 if form == Seepage.SEED else 1.0 - n
            grain[k] = mat.density / (1.0 - n)
        walls = any(b.fixed and scene.materials[b.material].model == "water" for b in scene.blocks)
        soils = materials.ids_of_phase(Phase.SOIL)
        one = int(soils[0]) if len(soils) == 1 else None
        linear = scene.numerics.pore_pressure_at_water == "linear"
        kappa = 0.0
        if form == Seepage.MIXTURE and GRADIENT_CORRECTION:
            kappa = lattice_gradient_normalisation(scene.dim, scene.numerics.h_over_dx)
        erodes = None
        if bed_shear_on(scene, materials):
            erodes = np.zeros(n_mat, np.uint8)
            erodes[erosion_materials(scene, materials)] = 1
        return cls(form, drag, solid, grain, scene.numerics.cfl.drag, one, walls, linear, kappa, erodes)

    @property
    def corrected(self):
        """The buoyancy pair carries the kernel-gradient correction (mixture form)."""
        return self.kappa > 0.0

    @property
    def free_water(self):
        """Free water over an eroding bed feels the wall shear, not the drag (bed_shear.py)."""
        return self.erodes is not None

    @property
    def mixture(self):
        return self.formulation == Seepage.MIXTURE


GRADIENT_CORRECTION = True
"""The mixture's buoyancy pair renormalised to the water's own pressure pass (docs/seepage.md, "One
normalisation for the pore water's two pressure operators"); False only for before/after diagnostics."""

# Where the pair's soil support counts as full (the Shepard sum sum_b V_b W_ab): the correction is
# blended in between these (a lattice with one row cut at 2 dx gives 0.969-0.990, full ones 0.9996-1.0002).
FULL_SUPPORT = (0.98, 0.995)


def lattice_gradient_normalisation(dim, h_over_dx):
    """kappa = -sum_b V_b (dW/dr / r) d_x^2 over a square (cubic) lattice of spacing dx around a
    lattice point, V_b = dx^dim: the factor by which the SPH gradient of a linear field reads on a
    lattice (1.0105 for the cubic spline at h = 1.3 dx), what the pore water's own pressure pass (the
    symmetric form over its own lattice) reads."""
    from ..kernels import cubic_spline_normalisation

    h = float(h_over_dx)
    reach = int(np.ceil(2.0 * h)) + 1
    axes = np.meshgrid(*([np.arange(-reach, reach + 1, dtype=float)] * dim), indexing="ij")
    d = np.stack([a.ravel() for a in axes], axis=1)
    r = np.linalg.norm(d, axis=1)
    big_r = r / h
    a, b = np.clip(2.0 - big_r, 0.0, None), np.clip(1.0 - big_r, 0.0, None)
    dwdr = cubic_spline_normalisation(dim, h) * (-0.5 * a * a + 2.0 * b * b) / h
    f = np.where(r > 0.0, dwdr / np.where(r > 0.0, r, 1.0), 0.0)
    return float(-(f * d[:, 0] ** 2).sum())


STANDARD_GRAVITY = 9.81
"""g in gamma_w = rho_w g when a scene switches gravity off: k is measured under gravity, so the drag
C = n^2 rho_w g / k (= n^2 mu / k_intrinsic) keeps its value (as Morikawa & Asai 2022 do)."""


@kernel
def no_drag(free_a, suspended_b, erodes_b):
    """True when the water particle a and the soil particle b of an eroding soil exchange no
    seepage drag: Darcy's drag is between pore water and the bed it fills. Free water over the bed
    feels the bed's wall shear instead (bed_shear.py), and soil the flow has picked up (suspended)
    has left the bed: the free water around it drags it, the bed's pore water does not."""
    if erodes_b == 0:
        return False
    if suspended_b != 0:
        return free_a == 0
    return free_a != 0


@kernel
def row_chunks(start, n_chunks):
    """Row bounds of n_chunks contiguous chunks of a list's rows with about equal work (pairs + rows):
    the pair loops run one chunk per thread. An even split of the rows is not even in work: water
    rows above a bed have no soil neighbours, and rows come in cell order, so they all went to
    the second thread (seepage on water, 2 threads: 0.90 against 1.11 ms). Each row's sums are
    the same whatever the chunking."""
    n = start.shape[0] - 1
    bounds = np.empty(n_chunks + 1, np.int64)
    first = np.int64(start[0])  # int64 arithmetic also for the unsigned view
    total = np.int64(start[n]) - first + n
    t = 0
    bounds[0] = 0
    for c in range(1, n_chunks):
        goal = total * c // n_chunks
        while t < n and np.int64(start[t]) - first + t < goal:
            t += 1
        bounds[c] = t
    bounds[n_chunks] = n
    return bounds


@kernel
def one_chunk(n):
    """The bounds of a single chunk of n rows (chunks=None: the loops run serially)."""
    bounds = np.zeros(2, np.int64)
    bounds[1] = n
    return bounds


def thread_chunks(start):
    """row_chunks for the current Numba thread count (the chunks argument of the pair loops)."""
    return row_chunks(start, get_num_threads())


@kernel(parallel=True)
def pore_pressure_at_soil(targets, start, index, x, vol, p, h, norm, pore, is3d=None, chunks=None, vw=None,
                          vf=None):  # fmt: skip
    """p~_b = sum_a V_a p_a W_ab / sum_a V_a W_ab over the water neighbours a of soil b (Shepard
    interpolation); 0 for soil with no water within reach (dry soil). vol: V = m / rho of every row
    (RowVolumes). Call with the lists' unsigned views and a C-contiguous x, as soil_rates: x is read
    through a flat view at a compile-time stride. chunks: row_chunks' bounds, one chunk per thread
    (None: one chunk); the three pair loops of the coupling take both alike.
    vw, vf (optional, one entry per pair of the list): V_a W_ab and V_a W'(r_ab) / r_ab written for
    seepage_on_soil, which runs over the same list with x and rho unchanged and then reads them in
    list order instead of a square root, a division and a gather per pair (docs/seepage.md, Speed)."""
    three = is3d is not None
    dim = 3 if three else 2
    if x.shape[1] != dim:
        raise ValueError("pore_pressure_at_soil: x must have 3 columns with is3d=True, 2 without")
    xf = x.reshape(x.size)
    bounds = one_chunk(targets.shape[0]) if chunks is None else chunks
    for c in prange(bounds.shape[0] - 1):
        for t in range(bounds[c], bounds[c + 1]):
            b = targets[t]
            xb0, xb1 = x[b, 0], x[b, 1]
            xb2 = x[b, 2] if three else 0.0
            num = den = 0.0
            for s in range(start[t], start[t + 1]):
                a = index[s]
                xa = a * dim
                d0 = xb0 - xf[xa]
                d1 = xb1 - xf[xa + 1]
                d2 = xb2 - xf[xa + 2] if three else 0.0
                r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300  # as in seepage_on_soil
                w = vol[a] * cubic_spline_w(r, h, norm)
                num += w * p[a]
                den += w
                if vw is not None:
                    vw[s] = w
                    vf[s] = vol[a] * cubic_spline_dwdr(r, h, norm) / r
            pore[b] = num / den if den > 0.0 else 0.0


RIDGE = 1e-2
"""Ridge of the linear p^ fit, times the mean variance of the neighbours' offsets: a direction in
which the soil neighbours have (almost) no spread, e.g. water two rows above a bed that sees only its
top row, gets no slope (Shepard's value) instead of a slope fitted to round-off."""


@kernel
def linear_fit_at_origin(s, sp, m0, m1, m2, c00, c01, c02, c11, c12, c22, r0, r1, r2, three):
    """alpha of the weighted fit p - p0 ~ alpha + beta . d from the sums s = sum w, sp = sum w (p - p0),
    m = sum w d, c = sum w d d^T, r = sum w (p - p0) d: beta from the centred normal equations
    (c - m m^T / s + ridge) beta = r - m sp / s, alpha = (sp - m . beta) / s."""
    a00 = c00 - m0 * m0 / s
    a01 = c01 - m0 * m1 / s
    a11 = c11 - m1 * m1 / s
    y0 = r0 - m0 * sp / s
    y1 = r1 - m1 * sp / s
    if three:
        a02 = c02 - m0 * m2 / s
        a12 = c12 - m1 * m2 / s
        a22 = c22 - m2 * m2 / s
        y2 = r2 - m2 * sp / s
        ridge = RIDGE * (a00 + a11 + a22) / 3.0
        a00 += ridge
        a11 += ridge
        a22 += ridge
        k00 = a11 * a22 - a12 * a12
        k01 = a02 * a12 - a01 * a22
        k02 = a01 * a12 - a02 * a11
        det = a00 * k00 + a01 * k01 + a02 * k02
        if not det > 0.0:
            return sp / s
        k11 = a00 * a22 - a02 * a02
        k12 = a01 * a02 - a00 * a12
        k22 = a00 * a11 - a01 * a01
        beta0 = (k00 * y0 + k01 * y1 + k02 * y2) / det
        beta1 = (k01 * y0 + k11 * y1 + k12 * y2) / det
        beta2 = (k02 * y0 + k12 * y1 + k22 * y2) / det
        return (sp - m0 * beta0 - m1 * beta1 - m2 * beta2) / s
    ridge = RIDGE * (a00 + a11) / 2.0
    a00 += ridge
    a11 += ridge
    det = a00 * a11 - a01 * a01
    if not det > 0.0:
        return sp / s
    beta0 = (a11 * y0 - a01 * y1) / det
    beta1 = (a00 * y1 - a01 * y0) / det
    return (sp - m0 * beta0 - m1 * beta1) / s


@kernel
def pair_correction(m0, m1, m2, m3, m4, m5, den, kappa, is3d):
    """L = kappa M^-1 (Bonet & Lok 1999, eq. 45's renormalisation matrix times the lattice
    normalisation kappa), M = -sum_b V_b (W'/r) d (x) d over a water particle's soil neighbours (6
    components, solver/tensors.py order), blended to the identity where the soil support is cut
    (Shepard sum den below FULL_SUPPORT) or M is near singular. Returns L's 6 components."""
    lo, hi = FULL_SUPPORT
    s = min(max((den - lo) / (hi - lo), 0.0), 1.0)
    if is3d is None:
        det = m0 * m1 - m3 * m3
        i0, i1, i2, i3, i4, i5 = m1, m0, 0.0, -m3, 0.0, 0.0
    else:
        i0 = m1 * m2 - m4 * m4
        i1 = m0 * m2 - m5 * m5
        i2 = m0 * m1 - m3 * m3
        i3 = m4 * m5 - m3 * m2
        i4 = m3 * m5 - m0 * m4
        i5 = m3 * m4 - m1 * m5
        det = m0 * i0 + m3 * i3 + m5 * i5
    scale = kappa ** (3 if is3d is not None else 2)
    if not det > 0.25 * scale:  # a support cut to half in some direction: no correction
        s = 0.0
    c = s * kappa / det if s > 0.0 else 0.0
    return (1.0 - s + c * i0, 1.0 - s + c * i1, (1.0 - s + c * i2) if is3d is not None else 1.0,
            c * i3, c * i4, c * i5)  # fmt: skip


@kernel(parallel=True)
def seepage_on_water(targets, start, index, x, v, rho, mass, vol, material, drag, solid, grain_density, h,
                     norm, acc, drho=None, p=None, pore=None, is3d=None, wall=None, one_soil=None,
                     linear=None, corr=None, kappa=0.0, chunks=None, free_water=None, suspended=None,
                     erodes=None):  # fmt: skip
    """Water rows a, one loop over their soil neighbours b (u = v_a - v_b, d = x_b - x_a,
    F = W'(r) / r):
      * with p and pore (mixture): p^_a = sum_b V_b p~_b W_ab / sum_b V_b W_ab (Shepard, the soil's
        p~ from pore_pressure_at_soil smoothed back onto the water; p_a for water with no soil
        within reach), written into pore[a]. The buoyancy pair needs p^_a, not p_a: with p_a a water
        particle whose soil support is cut (next to a wall of water particles) feels its own
        pressure, -(1 - n) p_a sum_b V_b grad_a W_ab, which pushes a compressed particle into the
        wall (docs/seepage.md, "Pore water along a wall");
      * acc_a -= sum_b F_ab / m_a (the pair force of the module docstring), the buoyancy summed
        split around p^_a so that it is not needed inside the loop:
          sum_b phi_b V_b (p^_a - p~_b) F d = (p^_a - p0) sum_b phi_b V_b F d
                                              - sum_b phi_b V_b (p~_b - p0) F d,   phi = 1 - n,
        p0 the first neighbour's p~ (a reference that keeps the cancellation at the size of the
        pressure differences);
      * with drho (mixture), Biot's storage drho_a += -rho_a (phi_a / (1 - phi_a)) div v_s(x_a),
        phi_a = sum_b (m_b / rho_grain) W_ab the solid fraction (at most 0.95) and
        div v_s = sum_b V_b (v_b - v~) . grad_a W_ab, v~ the Shepard soil velocity, summed
        relative to v_a: div v_s = sum_b V_b F (u . d) - (S . B) / sum_b V_b W_ab,
        S = sum_b V_b W_ab u, B = sum_b V_b F d.
    linear (numerics.pore_pressure_at_water = "linear"): p^_a is instead the value at x_a of the
    weighted linear fit of p~ over the soil neighbours (moving least squares of order 1, weights V_b W_ab,
    a ridge of RIDGE times the mean variance against a support with no spread in some direction):
    exact for a linear p~ where Shepard's is off by grad p . (centroid - x_a), which at a cut soil
    support (a bed's free surface under water) is O(h) (docs/seepage.md, case 4).
      * with corr (mixture, corrected): the buoyancy of the pair carries L_a, the kernel-gradient
        correction pair_correction builds from M_a = -sum_b V_b F d (x) d and kappa, written into
        corr[a] for the soil side: the water then reads kappa (1 - n) grad p from the pair at any
        offset of its lattice from the skeleton's, what its own pressure pass reads (docs/seepage.md,
        case 2). L_a multiplies the pair's vector d, one matrix per pair, so the soil side (which
        reads corr[a]) sums the same pair terms: still equal and opposite.
    Returns the largest lambda_a = sum_b K_ab / m_a. wall: the fixed flags (None without fixed
    blocks); wall particles of fixed water blocks are walls, not pore water: they get p^ (an output)
    and nothing else. one_soil: the material id when the scene has one soil material (then the
    per-material constants are loop invariants), else None. free_water, suspended, erodes (an eroding
    bed with numerics.bed_shear = "log_law", bed_shear.py; None otherwise): the pairs of free water
    (outside the bed) with the bed of an eroding soil (not suspended) carry no drag (bed_shear.py
    gives them the wall shear instead); the buoyancy and the storage keep them."""
    three = is3d is not None
    dim = 3 if three else 2
    if x.shape[1] != dim or v.shape[1] != dim:
        raise ValueError("seepage_on_water: x and v must have 3 columns with is3d=True, 2 without")
    xf = x.reshape(x.size)
    vflat = v.reshape(v.size)
    worst = 0.0
    bounds = one_chunk(targets.shape[0]) if chunks is None else chunks
    for c in prange(bounds.shape[0] - 1):
        for t in range(bounds[c], bounds[c + 1]):
            a = targets[t]
            xa0, xa1 = x[a, 0], x[a, 1]
            va0, va1 = v[a, 0], v[a, 1]
            xa2 = x[a, 2] if is3d is not None else 0.0
            va2 = v[a, 2] if is3d is not None else 0.0
            first, last = start[t], start[t + 1]
            p0 = 0.0
            if pore is not None and last > first:
                p0 = pore[index[first]]
            f0 = f1 = f2 = lam = 0.0
            den = num = q0 = q1 = q2 = g0 = g1 = g2 = 0.0
            phi = s0 = s1 = s2 = b0 = b1 = b2 = div = 0.0
            x0 = x1 = x2 = xden = 0.0  # the free pairs' drag sums (one soil material), taken out after
            l0 = l1 = l2 = c00 = c01 = c02 = c11 = c12 = c22 = r0 = r1 = r2 = 0.0  # linear p^ only
            m0 = m1 = m2 = m3 = m4 = m5 = 0.0
            for s in range(first, last):
                b = index[s]
                if one_soil is None:
                    mb = material[b]
                else:
                    mb = one_soil
                xb = b * dim
                d0 = xf[xb] - xa0
                d1 = xf[xb + 1] - xa1
                d2 = xf[xb + 2] - xa2 if three else 0.0
                u0 = va0 - vflat[xb]
                u1 = va1 - vflat[xb + 1]
                u2 = va2 - vflat[xb + 2] if three else 0.0
                r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
                vol_b = vol[b]
                w = cubic_spline_w(r, h, norm)
                vw = vol_b * w
                vf = vol_b * cubic_spline_dwdr(r, h, norm) / r  # unused (and not computed) in the seed form
                free = False
                if free_water is not None:
                    free = no_drag(free_water[a], suspended[b], erodes[mb])
                if one_soil is None and not free:
                    kw = vw * drag[mb]  # K_ab / V_a
                    f0 += kw * u0
                    f1 += kw * u1
                    f2 += kw * u2
                    lam += kw
                if one_soil is not None and free:
                    x0 += vw * u0
                    x1 += vw * u1
                    x2 += vw * u2
                    xden += vw
                if drho is not None or one_soil is not None:
                    s0 += vw * u0  # the drag's sum with one soil material, and the storage's S
                    s1 += vw * u1
                    s2 += vw * u2
                den += vw
                if drho is not None or (pore is not None and one_soil is not None):
                    b0 += vf * d0  # B, shared by the storage and (one soil material) the buoyancy
                    b1 += vf * d1
                    b2 += vf * d2
                if pore is not None:
                    num += vw * pore[b]
                    sf = vf if one_soil is not None else solid[mb] * vf  # (1 - n) applied after the loop
                    sfp = sf * (pore[b] - p0)
                    g0 += sfp * d0
                    g1 += sfp * d1
                    g2 += sfp * d2
                    if one_soil is None:
                        q0 += sf * d0
                        q1 += sf * d1
                        q2 += sf * d2
                    if linear is not None:
                        l0 += vw * d0
                        l1 += vw * d1
                        l2 += vw * d2
                        c00 += vw * d0 * d0
                        c01 += vw * d0 * d1
                        c02 += vw * d0 * d2
                        c11 += vw * d1 * d1
                        c12 += vw * d1 * d2
                        c22 += vw * d2 * d2
                        r0 += vw * (pore[b] - p0) * d0
                        r1 += vw * (pore[b] - p0) * d1
                        r2 += vw * (pore[b] - p0) * d2
                    if corr is not None:
                        m0 -= vf * d0 * d0
                        m1 -= vf * d1 * d1
                        m3 -= vf * d0 * d1
                        if is3d is not None:
                            m2 -= vf * d2 * d2
                            m4 -= vf * d1 * d2
                            m5 -= vf * d0 * d2
                if drho is not None:
                    phi += mass[b] / grain_density[mb] * w
                    div += vf * (u0 * d0 + u1 * d1 + u2 * d2)
            if one_soil is not None:  # C is a loop invariant: the drag from S = sum_b V_b W_ab u
                kd = drag[one_soil]
                f0, f1, f2, lam = kd * (s0 - x0), kd * (s1 - x1), kd * (s2 - x2), kd * (den - xden)
            if pore is not None and one_soil is not None:
                sol = solid[one_soil]
                q0, q1, q2 = sol * b0, sol * b1, sol * b2
                g0 *= sol
                g1 *= sol
                g2 *= sol
            if pore is not None:
                p_hat = num / den if den > 0.0 else p[a]
                if linear is not None and den > 0.0:
                    sp = num - p0 * den
                    three = is3d is not None
                    p_hat = p0 + linear_fit_at_origin(
                        den, sp, l0, l1, l2, c00, c01, c02, c11, c12, c22, r0, r1, r2, three
                    )
                pore[a] = p_hat
                excess = p_hat - p0
                e0 = excess * q0 - g0  # buoyancy / V_a along d: -sum_b phi_b V_b (p^_a - p~_b) F d
                e1 = excess * q1 - g1
                e2 = excess * q2 - g2
                if corr is not None:
                    c0, c1, c2, c3, c4, c5 = pair_correction(m0, m1, m2, m3, m4, m5, den, kappa, is3d)
                    corr[a, 0], corr[a, 1], corr[a, 2] = c0, c1, c2
                    corr[a, 3], corr[a, 4], corr[a, 5] = c3, c4, c5
                    e0, e1, e2 = (
                        c0 * e0 + c3 * e1 + c5 * e2, c3 * e0 + c1 * e1 + c4 * e2, c5 * e0 + c4 * e1 + c2 * e2
                    )  # fmt: skip
                f0 -= e0
                f1 -= e1
                f2 -= e2
            if wall is not None and wall[a]:
                continue  # a wall particle: p^ only
            vol_a = mass[a] / rho[a]
            inv_m = vol_a / mass[a]
            acc[a, 0] -= f0 * inv_m
            acc[a, 1] -= f1 * inv_m
            if is3d is not None:
                acc[a, 2] -= f2 * inv_m
            worst = max(worst, lam * inv_m)
            if drho is not None and den > 0.0:
                div -= (s0 * b0 + s1 * b1 + s2 * b2) / den
                phi = min(phi, 0.95)  # a water particle is never entirely inside grains
                drho[a] += -rho[a] * phi / (1.0 - phi) * div
    return worst


@kernel(parallel=True)
def seepage_on_soil(targets, start, index, x, v, rho, mass, vol, material, drag, solid, h, norm, acc,
                    pore=None, is3d=None, wall=None, corr=None, chunks=None, vw=None, vf=None,
                    free_water=None, suspended=None, erodes=None):  # fmt: skip
    """Soil rows b, one loop over their water neighbours a: add sum_a F_ab / m_b (the pair force of
    the module docstring) with pore holding p^ on the water rows (seepage_on_water) and p~ on the
    soil rows (pore_pressure_at_soil); None in the seed formulation (no buoyancy):
      sum_a F_ab = V_b C sum_a V_a W_ab u_ab - phi_b V_b sum_a V_a (p^_a - p~_b) F d
    (u = v_a - v_b, d = x_b - x_a, F = W'(r) / r). The water side sums the same pair terms: equal
    and opposite to round-off. Returns the largest relaxation rate lambda_b = sum_a K_ab / m_b.
    wall: the fixed flags (None without fixed blocks); wall particles of fixed water blocks are
    walls, not pore water, and take no part in the coupling. corr: the water side's L_a (corrected
    mixture; None otherwise): the buoyancy's d becomes L_a d, as on the water side. vw, vf: the
    pairs' V_a W_ab and V_a W'/r that pore_pressure_at_soil wrote over the same list (mixture; None:
    computed here). free_water, suspended, erodes: as in seepage_on_water (free pairs carry no drag)."""
    three = is3d is not None
    dim = 3 if three else 2
    if x.shape[1] != dim or v.shape[1] != dim:
        raise ValueError("seepage_on_soil: x and v must have 3 columns with is3d=True, 2 without")
    xf = x.reshape(x.size)
    vflat = v.reshape(v.size)
    cf = corr.reshape(corr.size) if corr is not None else xf
    worst = 0.0
    bounds = one_chunk(targets.shape[0]) if chunks is None else chunks
    for c in prange(bounds.shape[0] - 1):
        for t in range(bounds[c], bounds[c + 1]):
            b = targets[t]
            xb0, xb1 = x[b, 0], x[b, 1]
            vb0, vb1 = v[b, 0], v[b, 1]
            xb2 = x[b, 2] if is3d is not None else 0.0
            vb2 = v[b, 2] if is3d is not None else 0.0
            p_b = pore[b] if pore is not None else 0.0
            den = w0 = w1 = w2 = g0 = g1 = g2 = 0.0
            for s in range(start[t], start[t + 1]):
                a = index[s]
                if wall is not None and wall[a]:
                    continue
                xa = a * dim
                d0 = xb0 - xf[xa]
                d1 = xb1 - xf[xa + 1]
                d2 = xb2 - xf[xa + 2] if three else 0.0
                if vw is None:
                    r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
                    vol_a = vol[a]
                    w_s = vol_a * cubic_spline_w(r, h, norm)
                    f_s = vol_a * cubic_spline_dwdr(r, h, norm) / r  # not computed in the seed form
                else:
                    w_s = vw[s]
                    f_s = vf[s]
                free = False
                if free_water is not None:
                    free = no_drag(free_water[a], suspended[b], erodes[material[b]])
                if not free:  # free water over the bed: the wall shear instead (bed_shear.py)
                    den += w_s
                    w0 += w_s * (vflat[xa] - vb0)
                    w1 += w_s * (vflat[xa + 1] - vb1)
                    if three:
                        w2 += w_s * (vflat[xa + 2] - vb2)
                if pore is not None:
                    vfp = f_s * (pore[a] - p_b)
                    if corr is None:
                        g0 += vfp * d0
                        g1 += vfp * d1
                        g2 += vfp * d2
                    elif three:
                        ca = a * N_SYM
                        g0 += vfp * (cf[ca] * d0 + cf[ca + 3] * d1 + cf[ca + 5] * d2)
                        g1 += vfp * (cf[ca + 3] * d0 + cf[ca + 1] * d1 + cf[ca + 4] * d2)
                        g2 += vfp * (cf[ca + 5] * d0 + cf[ca + 4] * d1 + cf[ca + 2] * d2)
                    else:  # 2D: L_a's xz, yz and zz components do not enter
                        ca = a * N_SYM
                        g0 += vfp * (cf[ca] * d0 + cf[ca + 3] * d1)
                        g1 += vfp * (cf[ca + 3] * d0 + cf[ca + 1] * d1)
            mb = material[b]
            vol_b = mass[b] / rho[b]
            k = vol_b * drag[mb]
            cb = -solid[mb] * vol_b
            inv_m = 1.0 / mass[b]
            acc[b, 0] += (k * w0 + cb * g0) * inv_m
            acc[b, 1] += (k * w1 + cb * g1) * inv_m
            if is3d is not None:
                acc[b, 2] += (k * w2 + cb * g2) * inv_m
            worst = max(worst, k * den * inv_m)
    return worst


PAIR_KERNEL = "seepage: V W and V W'/r of the soil <- water pairs"
"""ctx.shared key: (the list's index array, V_a W_ab, V_a W'/r), left by pore pressure at soil for
seepage on soil in the same step, which takes it (once) if it is of its own list."""


class PorePressureAtSoil(Term):
    """p~ at every owned soil particle from its water neighbours (mixture buoyancy)."""

    name = "pore pressure at soil"
    stage = Stage.STATE
    targets = Phase.SOIL
    neighbours = Phase.WATER

    @classmethod
    def build(cls, scene, materials):
        settings = SeepageSettings.of(scene, materials)
        return cls() if settings is not None and settings.mixture else None

    def __init__(self):
        super().__init__()
        self.fields = {"pore_pressure": PORE_PRESSURE}
        self.volumes = RowVolumes()
        self._vw = self._vf = np.empty(0)  # scratch: V_a W_ab, V_a W'/r per pair, for seepage on soil
        self.reads = ("x", "rho", "mass", "p")
        self.writes = ("pore_pressure",)
        self.equations = (Equation("p~_b = sum_a V_a p_a W_ab / sum_a V_a W_ab", "Shepard interpolation"),)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        start, index = nl.unsigned()
        if self._vw.shape[0] < nl.pairs():
            self._vw, self._vf = (np.empty(int(nl.pairs() * 1.25) + 16) for _ in range(2))
        pore_pressure_at_soil(
            nl.targets, start, index, ps["x"], self.volumes(ps), ps["p"], ctx.h, ctx.norm,
            ps["pore_pressure"], ctx.is3d, thread_chunks(start), self._vw, self._vf,
        )  # fmt: skip
        ctx.shared[PAIR_KERNEL] = (nl.index, self._vw, self._vf)


class RowVolumes:
    """V = m / rho of every row (owned, ghosts, images) in the term's scratch array (not a particle
    field: rebuilt every pass, never exchanged), for the pair loops to gather instead of dividing
    per pair (the same quotient, so the pair sums are unchanged). NumPy, not a parallel kernel: a
    parallel region costs more than these divisions on two threads of a busy host (6.8 ms against
    0.02, load 6)."""

    def __init__(self):
        self._scratch = np.empty(0)

    def __call__(self, ps):
        n = ps.n_total
        if self._scratch.shape[0] < n:
            self._scratch = np.empty(int(n * 1.25) + 16)
        np.divide(ps["mass"][:n], ps["rho"][:n], out=self._scratch[:n])
        return self._scratch


class _Coupling(Term):
    """What the two sides of the coupling share."""

    stage = Stage.RATES

    @classmethod
    def build(cls, scene, materials):
        """Both sides run whenever the scene has seepage (SeepageSettings.of)."""
        settings = SeepageSettings.of(scene, materials)
        return cls(settings) if settings is not None else None

    def __init__(self, settings: SeepageSettings):
        super().__init__()
        self.settings = settings
        self.volumes = RowVolumes()
        self.reads = ("x", "v", "rho", "mass", "material") + (("pore_pressure",) if settings.mixture else ())
        if settings.corrected:
            self.fields = {"pair_correction": PAIR_CORRECTION}
        if settings.walls:  # wall particles of fixed water blocks are walls, not pore water
            self.fields = {**self.fields, "fixed": FIXED}
            self.reads += ("fixed",)
        if settings.free_water:
            self.reads += ("free_water", "suspended")
        self.adds_to = ("acc",)
        drag = "C = n^2 gamma_w / k (Biot; Bui & Nguyen 2017)" if settings.mixture else "C = n gamma_w / k"
        equations = [
            Equation(
                f"seepage drag V_a V_b C W_ab (v_w - v_s), {drag}", "seed eqs. (18), (20), (21), erratum"
            )
        ]
        if settings.mixture:
            equations.append(
                Equation(
                    "pore pressure on the skeleton -(1 - n) V_a V_b (p^_a - p~_b) grad W",
                    "Bui & Nguyen (2017)",
                )
            )
        if settings.corrected:
            equations.append(
                Equation(
                    f"buoyancy pair's grad W times L_a = kappa M_a^-1, kappa = {settings.kappa:.4f} (the "
                    "water's own pass on a lattice)",
                    "Bonet & Lok (1999) eq. 45",
                )
            )
        self.equations = tuple(equations)


class SeepageOnWater(_Coupling):
    """The reaction on the water: minus the force on the soil, pair by pair; and (mixture) the pore
    pressure p^ at the water, which the soil side then reads on its water neighbours (ghosts and
    images refreshed in between), and the pores squeezed by the skeleton in the water's continuity.
    It runs before the soil side."""

    name = "seepage on water"
    targets = Phase.WATER
    neighbours = Phase.SOIL

    def __init__(self, settings):
        super().__init__(settings)
        if settings.mixture:
            self.fields = {**self.fields, "pore_pressure": PORE_PRESSURE}
            self.writes = ("pore_pressure",) + (("pair_correction",) if settings.corrected else ())
            self.adds_to = ("acc", "drho")
            self.equations = (
                Equation(
                    "pore pressure at water p^_a = sum_b V_b p~_b W_ab / sum_b V_b W_ab over soil b",
                    "Shepard interpolation",
                )
                if not settings.linear
                else Equation(
                    "pore pressure at water p^_a = alpha of the V_b W_ab-weighted fit p~_b ~ alpha + beta . "
                    "(x_b - x_a) over soil b",
                    "moving least squares, order 1 (docs/seepage.md, case 4)",
                ),
            ) + self.equations
            self.equations += (
                Equation(
                    "Biot storage: drho_w += -rho_w (phi / n) div v_s", "Biot (1941); Verruijt (2016) ch. 2"
                ),
            )

    def run(self, ctx):
        ps, nl, st = ctx.particles, ctx.neighbours(self), self.settings
        mix = st.mixture
        start, index = nl.unsigned()
        vol = self.volumes(ps)
        ctx.shared["seepage water rate"] = seepage_on_water(
            nl.targets, start, index, ps["x"], ps["v"], ps["rho"], ps["mass"], vol, ps["material"], st.drag,
            st.solid, st.grain_density, ctx.h, ctx.norm, ps["acc"], ps["drho"] if mix else None,
            ps["p"] if mix else None, ps["pore_pressure"] if mix else None, ctx.is3d,
            ps["fixed"] if st.walls else None, st.one_soil, True if st.linear and mix else None,
            ps["pair_correction"] if st.corrected else None, st.kappa, thread_chunks(start),
            ps["free_water"] if st.free_water else None, ps["suspended"] if st.free_water else None,
            st.erodes,
        )  # fmt: skip


class SeepageOnSoil(_Coupling):
    """The seepage force (and in the mixture form the buoyancy, from p~ at the soil and p^ at the
    water) on the soil from the water. It runs after the water side, which writes p^."""

    name = "seepage on soil"
    targets = Phase.SOIL
    neighbours = Phase.WATER

    def __init__(self, settings):
        super().__init__(settings)
        if settings.corrected:
            self.reads += ("pair_correction",)
        self.lam = 0.0  # the largest relaxation rate of the soil side at the last step
        self.dt_limit = Constraint("seepage drag", "dt <= cfl.drag / (lambda_soil + lambda_water)", None)

    def dt_now(self, ctx):
        """dt <= cfl.drag / (lambda_soil + lambda_water), the largest relaxation rates of each side."""
        lam = self.lam + ctx.shared["seepage water rate"]
        return self.settings.cfl_drag / lam if lam > 0 else np.inf

    def run(self, ctx):
        ps, nl, st = ctx.particles, ctx.neighbours(self), self.settings
        start, index = nl.unsigned()
        vol = self.volumes(ps)
        cached = ctx.shared.pop(PAIR_KERNEL, None)  # x and rho have not changed since (same step)
        vw, vf = cached[1:] if cached is not None and cached[0] is nl.index else (None, None)
        self.lam = seepage_on_soil(
            nl.targets, start, index, ps["x"], ps["v"], ps["rho"], ps["mass"], vol, ps["material"], st.drag,
            st.solid, ctx.h, ctx.norm, ps["acc"], ps["pore_pressure"] if st.mixture else None, ctx.is3d,
            ps["fixed"] if st.walls else None, ps["pair_correction"] if st.corrected else None,
            thread_chunks(start), vw, vf, ps["free_water"] if st.free_water else None,
            ps["suspended"] if st.free_water else None, st.erodes,
        )  # fmt: skip
