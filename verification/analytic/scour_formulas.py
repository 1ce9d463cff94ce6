"""Published formulas for the equilibrium (long-run) scour depth under plunging and overflow
jets, and the hydraulics of the scour set-up that feeds them (docs/scour_setup.md).

NumPy only; SI units throughout. Notation of Mason & Arumugam (1985):

    q   unit discharge [m^2/s]
    H   head drop: upstream water (energy) level minus tailwater level [m]
    h   tailwater depth above the original bed [m]
    d   grain size [m] (d50 or dm, d90, d95 as each formula states)
    D   scour depth measured from the TAILWATER LEVEL [m]; the depth below the
        original bed is D - h (scour_below_bed)

Sources and how far each was checked here:

* Kolatus and Tschopp (vertical / overfall jets), as given in Bezzola (2012),
  Vorlesungsmanuskript Flussbau, ETH Zurich, and implemented in the CRAN package hydReng 1.0.0
  (scour_vert; its tests print Kolatus T0 = 7.722174 m for q = 4 m^2/s, H = 5 m,
  d90 = 0.15 m and 6.457918 m for H = 3 m; our tests reproduce both).
* Schoklitsch (1932), Veronese (1937) and Mason & Arumugam (1985): the coefficients as
  compiled by Mason & Arumugam (1985, J. Hydraul. Eng. 111(2), 220-235, Table 1) and
  Whittaker & Schleiss (1984, VAW Mitteilung 73, annex); the full texts could not be opened
  here, so the coefficients are the commonly quoted ones. Two internal checks support them
  (tests): Schoklitsch's SI coefficient 0.521 is his 4.75 with d90 in mm, and Veronese's
  grain-size form equals his grain-free form at d = 5 mm, the size below which he dropped d.
* Rand (1955), Flow geometry at straight drop spillways, Proc. ASCE 81, paper 791: the
  drop-number fits (as quoted by Chanson, Hydraulics of Open Channel Flow, 2004, and the
  NRCS NEH-11 drop-spillway method).

Searched for and not implemented (only abstracts or secondary summaries could be read in the
stored library, not the coefficients): Bormann & Julien (1991, J. Hydraul. Eng. 117(5)), Stein,
Julien & Alonso (1993, J. Hydraul. Res. 31(6); abstract: equations for the equilibrium depth and
its rate of growth, for any bed including cohesive, scour very rapid below 95 % of equilibrium),
Hoffmans (1998, 2009) and Hoffmans & Verheij (2011, Maritime Eng. 164(4): equilibrium depth from
Newton's second law for a control volume, Breusers' time scale), Pagliara, Hager & Minor (2006;
the general form tau + D = K q^a H^b g^c d^e (rho/(rho_s - rho))^f with a static and a dynamic
equilibrium, as summarised by Pagliara et al., Water 12(3) 718, 2020). docs/scour_study.md lists
what each would add.

None of these formulas covers our set-up (a 10 mm drop, sand of 0.5 mm or a 5 mm SPH
continuum): every prediction here is an extrapolation, and validity() says by how much.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G = 9.81


# ----------------------------------------------------------------------------- hydraulics
def critical_depth(q, g: float = G):
    """y_c = (q^2/g)^(1/3) of a rectangular channel (e.g. Chow 1959, Open-Channel
    Hydraulics, eq. 3-9)."""
    return (np.asarray(q, float) ** 2 / g) ** (1.0 / 3.0)


def supercritical_depth(q: float, energy: float, g: float = G) -> float:
    """The supercritical root y < y_c of y + q^2 / (2 g y^2) = energy (specific energy
    above the bed), by bisection (the function is monotone on (0, y_c))."""
    yc = float(critical_depth(q, g))
    if energy < 1.5 * yc:
        raise ValueError(f"specific energy {energy} below the critical 1.5 y_c = {1.5 * yc}")
    lo, hi = 1e-9 * yc, yc
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid + q * q / (2.0 * g * mid * mid) > energy:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class SetupHydraulics:
    """The overflow of docs/scour_setup.md for one q: the crest at critical depth, the fall
    onto the soil, the flow leaving over the unscoured soil without losses."""

    q: float
    fall: float  # crown above the soil surface [m]
    y_c: float  # critical depth over the crown [m]
    u_c: float  # q / y_c [m/s]
    energy_up: float  # upstream energy level above the soil surface: fall + 1.5 y_c [m]
    h_tail: float  # supercritical depth downstream, same energy (no losses) [m]
    head_drop: float  # H = energy_up - h_tail [m]
    impact_speed: float  # speed of the nappe's lower surface at the soil, sqrt(u_c^2 + 2 g fall)

    @property
    def froude_tail(self) -> float:
        return self.q / self.h_tail / np.sqrt(G * self.h_tail)


def setup_hydraulics(
    q: float, fall: float = 0.01, g: float = G, h_tail: float | None = None
) -> SetupHydraulics:
    """The hydraulics of the set-up for one q; h_tail overrides the loss-free supercritical
    tailwater (e.g. with the depth the OpenFOAM reference measures downstream)."""
    yc = float(critical_depth(q, g))
    uc = q / yc
    e_up = fall + 1.5 * yc
    ht = supercritical_depth(q, e_up, g) if h_tail is None else float(h_tail)
    return SetupHydraulics(
        q=q,
        fall=fall,
        y_c=yc,
        u_c=uc,
        energy_up=e_up,
        h_tail=ht,
        head_drop=e_up - ht,
        impact_speed=float(np.sqrt(uc * uc + 2.0 * g * fall)),
    )


def rand_1955_drop(q, drop, g: float = G) -> dict:
    """Rand (1955) geometry of a free overfall drop of height `drop`, in terms of the drop
    number D = q^2 / (g drop^3): drop length L_d/drop = 4.30 D^0.27, pool depth under the
    nappe y_p/drop = 1.00 D^0.22, depth at the toe y_1/drop = 0.54 D^0.425, sequent depth
    y_2/drop = 1.66 D^0.27."""
    q = np.asarray(q, float)
    dn = q * q / (g * drop**3)
    return {
        "drop_number": dn,
        "drop_length": 4.30 * dn**0.27 * drop,
        "pool_depth": 1.00 * dn**0.22 * drop,
        "toe_depth": 0.54 * dn**0.425 * drop,
        "sequent_depth": 1.66 * dn**0.27 * drop,
    }


# ----------------------------------------------------------------------------- scour formulas
def schoklitsch_1932(q, H, d90):
    """D = 0.521 H^0.2 q^0.57 / d90^0.32 (d90 in m; 4.75 with d90 in mm)."""
    return 0.521 * np.asarray(H, float) ** 0.2 * np.asarray(q, float) ** 0.57 / np.asarray(d90, float) ** 0.32


def veronese_1937a(q, H, dm):
    """D = 0.202 H^0.225 q^0.54 / dm^0.42 (dm, the mean size, in m)."""
    return (
        0.202 * np.asarray(H, float) ** 0.225 * np.asarray(q, float) ** 0.54 / np.asarray(dm, float) ** 0.42
    )


def veronese_1937b(q, H):
    """D = 1.90 H^0.225 q^0.54, Veronese's grain-free limit (dm < 5 mm)."""
    return 1.90 * np.asarray(H, float) ** 0.225 * np.asarray(q, float) ** 0.54


def mason_arumugam_1985(q, H, h, d, g: float = G):
    """D = K q^x H^y h^w / (g^v d^z) with K = 6.42 - 3.10 H^0.10, v = 0.30, w = 0.15,
    x = 0.60 - H/300, y = 0.15 + H/200, z = 0.10 (d the mean size in m; H in m)."""
    H = np.asarray(H, float)
    K = 6.42 - 3.10 * H**0.10
    x = 0.60 - H / 300.0
    y = 0.15 + H / 200.0
    return (
        K
        * np.asarray(q, float) ** x
        * H**y
        * np.asarray(h, float) ** 0.15
        / (g**0.30 * np.asarray(d, float) ** 0.10)
    )


def kolatus(q, H, d90):
    """T0 = 0.78 H^0.35 q^0.7 / d90^0.4, full overfall (Bezzola 2012; d90 in m)."""
    return 0.78 * np.asarray(H, float) ** 0.35 * np.asarray(q, float) ** 0.7 / np.asarray(d90, float) ** 0.4


def tschopp(q, H, d90):
    """T0 = 2.76 q^0.5 H^0.25 - 7.22 d90, full overfall (Bezzola 2012; d90 in m)."""
    return 2.76 * np.asarray(q, float) ** 0.5 * np.asarray(H, float) ** 0.25 - 7.22 * np.asarray(d90, float)


def kolatus_validity(q, H, d90):
    """Kolatus' range of validity: 5 <= q^0.5 H^0.25 / d90 <= 25 (Bezzola 2012)."""
    return np.asarray(q, float) ** 0.5 * np.asarray(H, float) ** 0.25 / np.asarray(d90, float)


def kolatus_hole_lengths(q, H, d95, g: float = G) -> tuple:
    """Distance from the overfall to the deepest point, l1 = 3.9 H^0.27 q^0.54 /
    (g^0.27 d95^0.08), and the hole's total length, l2 = 2.7 H^0.45 q^0.9 /
    (g^0.45 d95^0.8) (Bezzola 2012; d95 in m)."""
    q, H, d95 = (np.asarray(v, float) for v in (q, H, d95))
    l1 = 3.9 * H**0.27 * q**0.54 / (g**0.27 * d95**0.08)
    l2 = 2.7 * H**0.45 * q**0.9 / (g**0.45 * d95**0.8)
    return l1, l2


def scour_below_bed(D, h):
    """Formulas give D from the tailwater level; the scour below the original bed is D - h."""
    return np.asarray(D, float) - np.asarray(h, float)


def hole_extent_at_repose(depth, x_deepest, friction_angle_deg):
    """Where the hole's slopes, at the angle of repose (taken as the friction angle),
    reach the original bed on either side of the deepest point (a geometric lower bound
    of the hole; a deposition mound follows downstream)."""
    run = np.asarray(depth, float) / np.tan(np.radians(friction_angle_deg))
    return np.asarray(x_deepest, float) - run, np.asarray(x_deepest, float) + run


# ----------------------------------------------------------------------------- grain thresholds
def shields_critical(d, rho_s: float = 2650.0, rho: float = 1000.0, nu: float = 1.0e-6, g: float = G):
    """Critical Shields parameter of a grain of size d (Soulsby 1997, Dynamics of Marine Sands,
    eqs. 75-76, after Soulsby & Whitehouse 1997): theta_cr = 0.30 / (1 + 1.2 D*) + 0.055 (1 -
    exp(-0.020 D*)), D* = d (g (s - 1) / nu^2)^(1/3), s = rho_s / rho."""
    dstar = np.asarray(d, float) * (g * (rho_s / rho - 1.0) / nu**2) ** (1.0 / 3.0)
    return 0.30 / (1.0 + 1.2 * dstar) + 0.055 * (1.0 - np.exp(-0.020 * dstar))


def critical_shear_stress(d, rho_s: float = 2650.0, rho: float = 1000.0, nu: float = 1.0e-6, g: float = G):
    """tau_cr = theta_cr (rho_s - rho) g d [Pa] (Shields' definition)."""
    d = np.asarray(d, float)
    return shields_critical(d, rho_s, rho, nu, g) * (rho_s - rho) * g * d


def threshold_equivalent_grain(tau: float, rho_s: float = 2650.0, rho: float = 1000.0) -> float:
    """The grain size whose Shields threshold is tau [Pa], by bisection in log d over 1 um - 1 m
    (tau_cr grows monotonically with d there)."""
    lo, hi = np.log(1e-6), np.log(1.0)
    tau_lo, tau_hi = (float(critical_shear_stress(np.exp(x), rho_s, rho)) for x in (lo, hi))
    if not tau_lo < tau < tau_hi:
        raise ValueError(f"threshold {tau} Pa outside the grain range 1 um - 1 m")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if float(critical_shear_stress(np.exp(mid), rho_s, rho)) < tau:
            lo = mid
        else:
            hi = mid
    return float(np.exp(0.5 * (lo + hi)))


def sph_bed_threshold(unit_weight: float, dx: float, friction_angle_deg: float) -> float:
    """The shear stress [Pa] that moves the SPH bed's top row over the row below it: the
    Mohr-Coulomb strength at one spacing's depth, gamma dx tan(phi) (gamma: the submerged unit
    weight of the mixture for saturated soil, the dry unit weight for dry soil; an estimate,
    docs/scour_study.md)."""
    return unit_weight * dx * float(np.tan(np.radians(friction_angle_deg)))


# ----------------------------------------------------------------------------- our set-up
@dataclass(frozen=True)
class Grains:
    """The grain sizes a formula needs, for one mapping of the SPH continuum (see
    docs/scour_setup.md: the continuum has no grain size)."""

    label: str
    d50: float
    d90: float
    d95: float


SAND = Grains("medium sand (k = 1e-3 m/s via Hazen)", d50=0.5e-3, d90=1.0e-3, d95=1.2e-3)
PARTICLE = Grains("SPH particle spacing 5 mm", d50=5e-3, d90=5e-3, d95=5e-3)


def threshold_grains(
    unit_weight: float = 1150.0 * G,
    dx: float = 0.005,
    friction_angle_deg: float = 33.0,
    bed: str = "saturated",
):
    """The uniform grain whose Shields threshold equals the SPH bed's frictional threshold
    (sph_bed_threshold); defaults: the saturated scene (submerged mixture 1150 kg/m^3,
    docs/scour_setup.md sec. 3), 5 mm, 33 deg."""
    d = threshold_equivalent_grain(sph_bed_threshold(unit_weight, dx, friction_angle_deg))
    return Grains(f"grain with the {bed} 5 mm SPH bed's threshold ({1000 * d:.0f} mm)", d50=d, d90=d, d95=d)


FORMULAS = {
    "Schoklitsch 1932": lambda hy, gr: schoklitsch_1932(hy.q, hy.head_drop, gr.d90),
    "Veronese 1937 A": lambda hy, gr: veronese_1937a(hy.q, hy.head_drop, gr.d50),
    "Veronese 1937 B": lambda hy, gr: veronese_1937b(hy.q, hy.head_drop),
    "Mason & Arumugam 1985": lambda hy, gr: mason_arumugam_1985(hy.q, hy.head_drop, hy.h_tail, gr.d50),
    "Kolatus (Bezzola 2012)": lambda hy, gr: kolatus(hy.q, hy.head_drop, gr.d90),
    "Tschopp (Bezzola 2012)": lambda hy, gr: tschopp(hy.q, hy.head_drop, gr.d90),
}

# nominal exponent of q at fixed H, h and d
Q_EXPONENT = {
    "Schoklitsch 1932": 0.57,
    "Veronese 1937 A": 0.54,
    "Veronese 1937 B": 0.54,
    "Mason & Arumugam 1985": "0.60 - H/300",
    "Kolatus (Bezzola 2012)": 0.70,
    "Tschopp (Bezzola 2012)": "0.5 (minus a constant)",
}


def predictions(q_values, grains: Grains = SAND, fall: float = 0.01, h_tail=None) -> dict:
    """Every formula at every q of the set-up: D (from the tailwater level), the depth
    below the original bed, and the effective exponent of q of that depth in our set-up
    (a log-log fit over q_values: here H and h grow with q too). h_tail: one tailwater
    depth per q instead of the loss-free one."""
    q_values = np.asarray(q_values, float)
    tails = [None] * len(q_values) if h_tail is None else [float(h) for h in h_tail]
    hyd = [setup_hydraulics(float(q), fall, h_tail=h) for q, h in zip(q_values, tails)]
    out = {"q": q_values, "hydraulics": hyd, "grains": grains, "formulas": {}}
    h = np.array([hy.h_tail for hy in hyd])
    for name, f in FORMULAS.items():
        D = np.array([float(f(hy, grains)) for hy in hyd])
        below = scour_below_bed(D, h)
        ok = below > 0
        slope = float(np.polyfit(np.log(q_values[ok]), np.log(below[ok]), 1)[0]) if ok.sum() >= 2 else np.nan
        out["formulas"][name] = {"D_from_tailwater": D, "below_bed": below, "q_exponent_in_setup": slope}
    out["kolatus_validity_ratio"] = np.array(
        [float(kolatus_validity(hy.q, hy.head_drop, grains.d90)) for hy in hyd]
    )
    return out


def table(pred: dict) -> str:
    """Markdown table of predictions() (depth below the original bed, m)."""
    qs = pred["q"]
    head = (
        "| formula | q exponent (nominal) | "
        + " | ".join(f"q = {q:.2f}" for q in qs)
        + " | exponent in set-up |"
    )
    rule = "|---|---|" + "---|" * len(qs) + "---|"
    rows = [head, rule]
    for name, r in pred["formulas"].items():
        cells = " | ".join(f"{v:.3f}" for v in r["below_bed"])
        rows.append(f"| {name} | {Q_EXPONENT[name]} | {cells} | {r['q_exponent_in_setup']:.2f} |")
    return "\n".join(rows)


if __name__ == "__main__":
    qs = np.array([0.06, 0.07, 0.08, 0.09, 0.10, 0.11])
    for hy in (setup_hydraulics(q) for q in qs):
        print(
            f"q={hy.q:.2f}: y_c={hy.y_c:.4f} u_c={hy.u_c:.3f} h_t={hy.h_tail:.4f} "
            f"Fr_t={hy.froude_tail:.2f} H={hy.head_drop:.4f} v_imp={hy.impact_speed:.3f}"
        )
    # the tailwater the OpenFOAM reference measures at x = 0.20 m (2.5 mm mesh), for comparison
    cfd = {"q": np.array([0.06, 0.11]), "h": np.array([0.0647, 0.1074])}
    for gr in (SAND, PARTICLE):
        p = predictions(cfd["q"], gr, h_tail=cfd["h"])
        print(f"\n{gr.label}, CFD tailwater {cfd['h']} m:")
        print(table(p))
    for gr in (SAND, PARTICLE):
        p = predictions(qs, gr)
        print(
            f"\n{gr.label}: scour depth below the original bed [m]; Kolatus validity ratio "
            f"{p['kolatus_validity_ratio'].round(1)} (valid 5..25)"
        )
        print(table(p))
