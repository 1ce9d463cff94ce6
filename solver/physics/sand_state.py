"""A sand's state sets its friction and dilatancy (Bolton 1986), and its plane-strain return (docs/sand.md).

  void ratio        e = (1 + e0) exp(eps_vp) - 1, de / (1 + e) = the plastic volumetric strain
  critical line     e_c = e_Gamma - lambda_c (p' / p_a)^xi           Li & Wang (1998)
  state index       I_R = (e_c - e) (Q - ln p'[kPa]) / (e_max - e_min), clipped to [-4, 4]:
                    Bolton's (1986) I_D (Q - ln p') - R, with his implied critical line
                    e_max - R (e_max - e_min) / (Q - ln p') replaced by e_c (so psi -> 0 on e_c)
  peak friction     phi = phi_cv + 5 I_R, dilatancy psi = 5 I_R / 0.8 (plane strain; Bolton 1986)
  yield, flow       Mohr-Coulomb in the plane of the flow at that phi, with a non-associated potential
                    of dilatancy psi (plane_strain_return; de Souza Neto, Peric & Owen 2008, ch. 8)
I_R < 0 (loose of the line) gives phi < phi_cv and psi < 0: the sand contracts as it yields, Rowe's
stress-dilatancy on the loose side, until its state reaches the line (our extension; docs/sand.md).
"""

from __future__ import annotations

import numpy as np

from ..config import kernel

INDEX_CLIP = 4.0  # Bolton (1986): 0 <= I_R <= 4; mirrored on the loose side (docs/sand.md)
LOG_FLOOR = 1.0  # Pa: ln p' of an unconfined grain (p' <= 1 Pa) is taken at 1 Pa; I_R is at its clip there
PLANE_STRAIN_FRICTION = 5.0  # phi_max - phi_cv = 5 I_R degrees in plane strain (Bolton 1986)
FRICTION_PER_DILATANCY = 0.8  # phi_max - phi_cv = 0.8 psi_max in plane strain (Bolton 1986)


@kernel
def relative_dilatancy_index(e, p, e_min, e_max, e_gamma, lam, xi, p_a, q):
    """I_R of a state (e, p' in Pa), referred to the critical-state line, clipped to +-INDEX_CLIP."""
    pp = max(p, LOG_FLOOR)
    e_c = e_gamma - lam * (max(p, 0.0) / p_a) ** xi
    i_r = (e_c - e) * (q - np.log(pp * 1e-3)) / (e_max - e_min)
    return min(max(i_r, -INDEX_CLIP), INDEX_CLIP)


@kernel
def state_angles(i_r, phi_cv):
    """(sin phi, sin psi) of Bolton's plane-strain relations: phi = phi_cv + 5 I_R, psi = 5 I_R / 0.8."""
    dphi = PLANE_STRAIN_FRICTION * i_r
    return np.sin(np.radians(phi_cv + dphi)), np.sin(np.radians(dphi / FRICTION_PER_DILATANCY))


@kernel
def plane_strain_return(p, s0, s1, s2, s3, s4, s5, sin_phi, sin_psi, cohesion, bulk, shear):
    """Mohr-Coulomb in the plane of the flow with a non-associated potential of dilatancy psi.

    f = R - m sin(phi) - c cos(phi), R the in-plane Mohr radius, m the in-plane mean (compression +);
    g = R - m sin(psi), so d eps_v^p / (d eps_1^p - d eps_3^p) = sin(psi) (Bolton's plane-strain dilatancy),
    d eps_zz^p = 0. Elastic corrector: R -= G dl, m += (K + G/3) sin(psi) dl, sigma_zz (compression +)
    += (K - 2G/3) sin(psi) dl, dl = f / (G + (K + G/3) sin(psi) sin(phi)): lands on f = 0 (docs/sand.md).
    Below the tension cut-off p < -c cot(phi), with an in-plane mean beyond the apex, or where the return
    would pass the apex (all of R returned), the soil cracks: stress-free at the cut-off (p = -c cot(phi),
    s = 0), the seed's tension cut-off. Returns (p, s0..s5, dvol, dcrack) as return_map; dcrack < 0 where
    a compressed particle is released (its density then goes to the cut-off's, soil_stress_state)."""
    cos_phi = np.sqrt(1.0 - sin_phi * sin_phi)
    p_cut = -cohesion * cos_phi / sin_phi  # the apex, R = 0 at m = -c cot(phi)
    half_diff = 0.5 * (s0 - s1)  # (sigma_xx - sigma_yy) / 2, tension +
    radius = np.sqrt(half_diff * half_diff + s3 * s3)
    mean = p - 0.5 * (s0 + s1)  # in-plane mean, compression +
    f = radius - mean * sin_phi - cohesion * cos_phi
    dl = f / (shear + (bulk + shear / 3.0) * sin_psi * sin_phi)
    new_radius = radius - shear * dl
    if p < p_cut or (f > 0.0 and (mean < p_cut or new_radius <= 0.0)):
        d = (p_cut - p) / bulk  # the apex or beyond: stress-free at the cut-off, a crack (soil_stress_state)
        return p_cut, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, d, d
    if f <= 0.0:
        return p, s0, s1, s2, s3, s4, s5, 0.0, 0.0
    scale = new_radius / radius
    mean += (bulk + shear / 3.0) * sin_psi * dl
    szz = p - s2 + (bulk - 2.0 * shear / 3.0) * sin_psi * dl  # sigma_zz, compression +
    sxx = mean - scale * half_diff  # compression +
    syy = mean + scale * half_diff
    p_new = (sxx + syy + szz) / 3.0
    return p_new, p_new - sxx, p_new - syy, p_new - szz, scale * s3, s4, s5, sin_psi * dl, 0.0


def state_constants(materials_soil):
    """The per-material tuple the stress kernel reads for sands with a state (None if there are none)."""
    s = materials_soil
    if not np.any(s.state_e_max > 0.0):
        return None
    return (
        s.state_e0, s.state_e_min, s.state_e_max, s.state_e_gamma, s.state_lambda, s.state_xi, s.state_p_a,
        s.state_q, s.phi_cv,
    )  # fmt: skip
