"""Soil: elasto-perfectly plastic continuum, the terms of seed sec. 2.2 and Bui et al. (2008).

  total stress      sigma = -p delta + s                                   seed eq. (12)
  deviatoric rate   ds/dt = 2G (eps' ) + s R^T + R s  (Jaumann)             seed eqs. (13)-(15)
  mean stress       p = K (rho/rho0 - 1) (+ K eps_vp, plastic dilation)      seed eq. (17)
  yield             Mohr-Coulomb scale-back sqrt(J2) <= c + p tan(phi)       seed eq. (16)
                    or Drucker-Prager, plane-strain fit, non-associated flow,
                    tension cracking and scale-back                           Bui et al. (2008)
  continuity        over soil neighbours                                     seed eq. (6)
  momentum          eq. (20) without seepage, with Monaghan AV                seed eqs. (19), (20)
  artificial stress tensile-instability remedy                               Gray, Monaghan & Swift (2001)

Pressure p is positive in compression. Stress tensors are 6 components (solver/tensors.py);
2D is plane strain (s_zz is kept and evolves). Seepage (seed eq. 18) will be a separate
soil-water pass adding into the same `acc` rows, so nothing here needs to change for it.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_dwdr, cubic_spline_w
from ..tensors import positive_part

YIELD_ELASTIC, YIELD_MOHR_COULOMB, YIELD_DRUCKER_PRAGER = 0, 1, 2


@kernel
def sqrt_j2(s0, s1, s2, s3, s4, s5):
    """sqrt(J2) = sqrt(s:s / 2) for a deviatoric tensor in 6 components."""
    return np.sqrt(0.5 * (s0 * s0 + s1 * s1 + s2 * s2) + s3 * s3 + s4 * s4 + s5 * s5)


@kernel
def _scaled(r, s0, s1, s2, s3, s4, s5):
    """Radial scale-back of the deviatoric stress by r (seed eq. 16; Bui et al. 2008)."""
    return r * s0, r * s1, r * s2, r * s3, r * s4, r * s5


@kernel
def return_map(p, s0, s1, s2, s3, s4, s5, model, bulk, shear, tan_phi, cohesion, alpha_phi, k_c, alpha_psi):
    """Admissible (p, s) from a trial state; returns (p, s0..s5, dvol, dcrack): dvol the plastic
    volumetric strain increment (dilation positive), dcrack the part of it that is tension cracking.

    The volumetric increment is what keeps p = K (rho/rho0 - 1 + eps_vp) incremental: a cracked
    (stretched) particle restarts from the cut-off when recompressed, as in the rate form
    dsigma/dt = K tr(eps) delta + ... of Bui et al. (2008), instead of carrying a tensile deficit
    that makes loosened soil flow like a zero-pressure fluid. soil_stress_state puts the cracking
    part into the density, not into eps_vp (see there).
    Mohr-Coulomb (seed eq. 16): tension cut-off p >= -c / tan(phi) (no tensile strength of a
    cohesionless soil), then s scaled by s_f / sqrt(J2) when sqrt(J2) > s_f = c + p tan(phi).
    Drucker-Prager (Bui et al. 2008, f = alpha_phi I1 + sqrt(J2) - k_c, I1 = -3p):
      tension cracking: p < -k_c / (3 alpha_phi) (beyond the apex) -> apex, s = 0;
      otherwise f > 0 -> plastic multiplier dl = f / (G + 9 K alpha_phi alpha_psi) of the
      non-associated potential g = alpha_psi I1 + sqrt(J2): sqrt(J2) -= G dl, p += 3 K alpha_psi dl
      (plastic dilation 3 alpha_psi dl raises p in a confined state); lands on f = 0 exactly.
    """
    dvol = 0.0
    dcrack = 0.0
    if model == YIELD_MOHR_COULOMB:
        if tan_phi > 0.0 and p < -cohesion / tan_phi:
            dvol = dcrack = (-cohesion / tan_phi - p) / bulk
            p = -cohesion / tan_phi
        sf = max(cohesion + p * tan_phi, 0.0)
        j = sqrt_j2(s0, s1, s2, s3, s4, s5)
        if j > sf:
            s0, s1, s2, s3, s4, s5 = _scaled(sf / j, s0, s1, s2, s3, s4, s5)
    elif model == YIELD_DRUCKER_PRAGER:
        p_apex = -k_c / (3.0 * alpha_phi) if alpha_phi > 0.0 else -1e300
        if p < p_apex:
            dvol = dcrack = (p_apex - p) / bulk
            p = p_apex
            s0 = s1 = s2 = s3 = s4 = s5 = 0.0
        else:
            j = sqrt_j2(s0, s1, s2, s3, s4, s5)
            f = j - k_c - 3.0 * alpha_phi * p
            if f > 0.0:
                dl = f / (shear + 9.0 * bulk * alpha_phi * alpha_psi)
                p += 3.0 * bulk * alpha_psi * dl
                dvol = 3.0 * alpha_psi * dl
                s0, s1, s2, s3, s4, s5 = _scaled(max(j - shear * dl, 0.0) / j, s0, s1, s2, s3, s4, s5)
    return p, s0, s1, s2, s3, s4, s5, dvol, dcrack


@kernel(parallel=True)
def soil_stress_state(
    rows,
    rho,
    s,
    material,
    rho0,
    bulk,
    shear,
    tan_phi,
    cohesion,
    alpha_phi,
    k_c,
    alpha_psi,
    yield_model,
    mean_stress,
    eps_vp=None,
    update_history=False,
):
    """For each row: p from eq. (17) (with the stored plastic dilation, if any), then the
    return mapping; writes p to mean_stress and the admissible s in place. With
    update_history (after the leap-frog kick, on the half-step density) the plastic dilation
    (psi) is accumulated in eps_vp, and tension cracking resets the density instead:
        rho <- rho + rho0 dcrack,   i.e. rho = rho0 (1 + p_cut / K - eps_vp),
    the density at which eq. (17) gives the cut-off pressure p_cut. A crack opens between
    particles; the material keeps the density of its stress-free (cut-off) state. Carried in
    eps_vp instead (as before issue 14), the crack opening let a detached grain's density fall
    without bound: continuity (seed eq. 6) keeps lowering it while neighbours recede, and the
    cut-off keeps p = p_cut whatever rho is. At rho -> 0 the particle's volume m/rho and
    sigma/rho^2 grow without bound, and at rho_i + rho_j < 0 the artificial viscosity
    (eq. 19, 2 / (rho_i + rho_j)) pulls a particle into its image instead of resisting: the
    issue-14 column collapses ended so. p evolves exactly as before (continuity's rate does not
    depend on rho_i); only the density used as a volume and in eqs. (19), (20) changes."""
    for t in prange(rows.shape[0]):
        i = rows[t]
        m = material[i]
        e = rho[i] / rho0[m] - 1.0
        if eps_vp is not None:
            e += eps_vp[i]
        p, a0, a1, a2, a3, a4, a5, dvol, dcrack = return_map(
            bulk[m] * e,
            s[i, 0],
            s[i, 1],
            s[i, 2],
            s[i, 3],
            s[i, 4],
            s[i, 5],
            yield_model[m],
            bulk[m],
            shear[m],
            tan_phi[m],
            cohesion[m],
            alpha_phi[m],
            k_c[m],
            alpha_psi[m],
        )
        mean_stress[i] = p
        s[i, 0] = a0
        s[i, 1] = a1
        s[i, 2] = a2
        s[i, 3] = a3
        s[i, 4] = a4
        s[i, 5] = a5
        if eps_vp is not None and update_history:
            if dcrack > 0.0:  # tension cracking (dvol = dcrack): back to the cut-off density
                rho[i] += rho0[m] * dcrack
            else:  # plastic dilatancy (psi)
                eps_vp[i] += dvol


@kernel(parallel=True)
def artificial_stress(rows, rho, mean_stress, s, eps, art, three=False):
    """Gray, Monaghan & Swift (2001) artificial stress, as used for soil by Bui et al. (2008):
    in the principal frame R'_aa = -eps sigma'_aa / rho^2 where sigma'_aa > 0 (tension), else 0,
    rotated back. 2D plane strain: the in-plane 2x2 part in closed form, zz is principal;
    3D: the positive part of the full tensor by Jacobi rotations (tensors.positive_part)."""
    for t in prange(rows.shape[0]):
        i = rows[t]
        p = mean_stress[i]
        sxx = s[i, 0] - p
        syy = s[i, 1] - p
        szz = s[i, 2] - p
        sxy = s[i, 3]
        f = -eps / (rho[i] * rho[i])
        if three:
            pos = positive_part(sxx, syy, szz, sxy, s[i, 4], s[i, 5])
            for k in range(6):
                art[i, k] = f * pos[k]
            continue
        theta = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
        c = np.cos(theta)
        sn = np.sin(theta)
        s1 = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy
        s2 = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy
        r1 = f * s1 if s1 > 0.0 else 0.0
        r2 = f * s2 if s2 > 0.0 else 0.0
        art[i, 0] = c * c * r1 + sn * sn * r2
        art[i, 1] = sn * sn * r1 + c * c * r2
        art[i, 2] = f * szz if szz > 0.0 else 0.0
        art[i, 3] = c * sn * (r1 - r2)
        art[i, 4] = 0.0
        art[i, 5] = 0.0


@kernel
def jaumann(s0, s1, s2, s3, s4, s5, w01, w02, w12):
    """J = W s - s W (= s^{ag} R^{bg} + s^{gb} R^{ag} of seed eq. 13 with R antisymmetric),
    components (xx, yy, zz, xy, yz, xz); W_ab = (dv^a/dx^b - dv^b/dx^a)/2 (eq. 15)."""
    j00 = 2.0 * (w01 * s3 + w02 * s5)
    j11 = 2.0 * (w12 * s4 - w01 * s3)
    j22 = -2.0 * (w02 * s5 + w12 * s4)
    j01 = w01 * (s1 - s0) + w02 * s4 + w12 * s5
    j12 = w12 * (s2 - s1) - w01 * s5 - w02 * s3
    j02 = w02 * (s2 - s0) + w01 * s4 - w12 * s3
    return j00, j11, j22, j01, j12, j02


@kernel(parallel=True)
def soil_rates(
    targets,
    start,
    index,
    x,
    v,
    rho,
    mean_stress,
    s,
    mass,
    material,
    sound_speed,
    shear,
    h,
    norm,
    drho,
    acc,
    ds,
    av_alpha=None,
    av_beta=None,  # Monaghan artificial viscosity, seed eq. (19)
    art=None,
    art_n=2.55,
    inv_w_dx=0.0,  # artificial stress (Gray et al. 2001): f_ij^n (R_i + R_j)
):
    """Continuity (6), momentum (20) without seepage, and the Hooke-Jaumann rate (13)-(15).
    Adds into drho and acc; writes ds. The velocity gradient is
    g_ab = dv^b/dx^a = sum_j (m_j/rho_j) (v_j^b - v_i^b) dW_ij/dx_i^a (Liu & Liu 2003, eq. 4.31)."""
    three = x.shape[1] == 3
    hh = 0.01 * h * h
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = x[i, 2] if three else 0.0
        vi2 = v[i, 2] if three else 0.0
        rho_i = rho[i]
        ri2 = 1.0 / (rho_i * rho_i)
        pi = mean_stress[i]
        # sigma_i / rho_i^2, eq. (12)
        q00 = (s[i, 0] - pi) * ri2
        q11 = (s[i, 1] - pi) * ri2
        q22 = (s[i, 2] - pi) * ri2
        q01 = s[i, 3] * ri2
        q12 = s[i, 4] * ri2
        q02 = s[i, 5] * ri2
        mi = material[i]
        quiet_i = True  # R_i = 0 (no tension): the common case, see below
        if art is not None:
            quiet_i = (
                art[i, 0] == 0.0
                and art[i, 1] == 0.0
                and art[i, 2] == 0.0
                and art[i, 3] == 0.0
                and art[i, 4] == 0.0
                and art[i, 5] == 0.0
            )
        d_rho = 0.0
        a0 = a1 = a2 = 0.0
        g00 = g01 = g02 = g10 = g11 = g12 = g20 = g21 = g22 = 0.0
        for k in range(start[t], start[t + 1]):
            j = index[k]
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            d2 = xi2 - x[j, 2] if three else 0.0
            u0 = vi0 - v[j, 0]
            u1 = vi1 - v[j, 1]
            u2 = vi2 - v[j, 2] if three else 0.0
            r2 = d0 * d0 + d1 * d1 + d2 * d2
            r = np.sqrt(r2) + 1e-300
            vr = u0 * d0 + u1 * d1 + u2 * d2
            fr = cubic_spline_dwdr(r, h, norm) / r  # grad_i W_ij = fr x_ij
            m_j = mass[j]
            rho_j = rho[j]
            rj2 = 1.0 / (rho_j * rho_j)
            d_rho += m_j * vr * fr  # eq. (6)
            pj = mean_stress[j]
            t00 = q00 + (s[j, 0] - pj) * rj2  # eq. (20): sigma_i/rho_i^2 + sigma_j/rho_j^2
            t11 = q11 + (s[j, 1] - pj) * rj2
            t01 = q01 + s[j, 3] * rj2
            diag = 0.0
            if av_alpha is not None:  # eq. (19) with beta phi^2 (erratum)
                mj = material[j]
                phi = h * min(vr, 0.0) / (r2 + hh)
                c_bar = 0.5 * (sound_speed[mi] + sound_speed[mj])
                alpha = 0.5 * (av_alpha[mi] + av_alpha[mj])
                beta = 0.5 * (av_beta[mi] + av_beta[mj])
                diag -= (-alpha * c_bar * phi + beta * phi * phi) * 2.0 / (rho_i + rho_j)
            fn = 0.0
            if art is not None:  # Gray et al. (2001): + f^n (R_i + R_j)
                # skipped when R_i = R_j = 0 (both particles in compression), where it adds exactly
                # zero: the kernel value and the power f^n were 60 % of a cohesionless soil step
                if not (
                    quiet_i
                    and art[j, 0] == 0.0
                    and art[j, 1] == 0.0
                    and art[j, 2] == 0.0
                    and art[j, 3] == 0.0
                    and art[j, 4] == 0.0
                    and art[j, 5] == 0.0
                ):
                    fn = (cubic_spline_w(r, h, norm) * inv_w_dx) ** art_n
                    t00 += fn * (art[i, 0] + art[j, 0])
                    t11 += fn * (art[i, 1] + art[j, 1])
                    t01 += fn * (art[i, 3] + art[j, 3])
            fm = m_j * fr
            if three:
                t22 = q22 + (s[j, 2] - pj) * rj2
                t12 = q12 + s[j, 4] * rj2
                t02 = q02 + s[j, 5] * rj2
                if art is not None and fn != 0.0:
                    t22 += fn * (art[i, 2] + art[j, 2])
                    t12 += fn * (art[i, 4] + art[j, 4])
                    t02 += fn * (art[i, 5] + art[j, 5])
                a0 += fm * ((t00 + diag) * d0 + t01 * d1 + t02 * d2)
                a1 += fm * (t01 * d0 + (t11 + diag) * d1 + t12 * d2)
                a2 += fm * (t02 * d0 + t12 * d1 + (t22 + diag) * d2)
            else:
                a0 += fm * ((t00 + diag) * d0 + t01 * d1)
                a1 += fm * (t01 * d0 + (t11 + diag) * d1)
            f = fr * m_j / rho_j  # velocity gradient (Liu & Liu 2003)
            w0 = -u0 * f
            w1 = -u1 * f
            g00 += w0 * d0
            g01 += w1 * d0
            g10 += w0 * d1
            g11 += w1 * d1
            if three:
                w2 = -u2 * f
                g02 += w2 * d0
                g12 += w2 * d1
                g20 += w0 * d2
                g21 += w1 * d2
                g22 += w2 * d2
        drho[i] += d_rho
        acc[i, 0] += a0
        acc[i, 1] += a1
        if three:
            acc[i, 2] += a2
        # eq. (14): strain rate e_ab = (g_ab + g_ba)/2; eq. (15): W_ab = (dv^a/dx^b - dv^b/dx^a)/2 = (g_ba -
        # g_ab)/2
        third = (g00 + g11 + g22) / 3.0
        two_g = 2.0 * shear[mi]
        w01 = 0.5 * (g10 - g01)
        w02 = 0.5 * (g20 - g02)
        w12 = 0.5 * (g21 - g12)
        j00, j11, j22, j01, j12, j02 = jaumann(
            s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5], w01, w02, w12
        )
        ds[i, 0] = two_g * (g00 - third) + j00  # eq. (13)
        ds[i, 1] = two_g * (g11 - third) + j11
        ds[i, 2] = two_g * (g22 - third) + j22
        ds[i, 3] = two_g * 0.5 * (g01 + g10) + j01
        ds[i, 4] = two_g * 0.5 * (g12 + g21) + j12
        ds[i, 5] = two_g * 0.5 * (g02 + g20) + j02


def yield_excess(rows, mean_stress, s, material, soil):
    """f / (scale) for the given rows: > 0 means outside the yield surface (NumPy; diagnostics, tests)."""
    m = material[rows]
    p = mean_stress[rows]
    ss = s[rows]
    j = np.sqrt(
        0.5 * (ss[:, 0] ** 2 + ss[:, 1] ** 2 + ss[:, 2] ** 2) + ss[:, 3] ** 2 + ss[:, 4] ** 2 + ss[:, 5] ** 2
    )
    model = soil.yield_model[m]
    limit = np.where(
        model == YIELD_DRUCKER_PRAGER,
        soil.k_c[m] + 3.0 * soil.alpha_phi[m] * p,
        soil.cohesion[m] + soil.tan_phi[m] * p,
    )
    scale = np.maximum(np.abs(p), 1.0) * np.maximum(soil.tan_phi[m], 1e-3) + soil.cohesion[m]
    return np.where(model == YIELD_ELASTIC, -1.0, (j - limit) / scale)
