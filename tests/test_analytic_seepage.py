"""The analytic seepage references (verification/analytic/seepage.py) against the
tabulated Terzaghi solution and against hand-checked soil-mechanics identities."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from verification.analytic import seepage as S

DATA = Path(__file__).resolve().parent.parent / "verification" / "data"


def _read(name):
    lines = (DATA / name).read_text().splitlines()
    header = lines[1].split(",")
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[2:] if ln.strip()])
    return lines[0], header, rows


def test_degree_of_consolidation_matches_the_table():
    head, cols, rows = _read("terzaghi_consolidation.csv")
    assert "4000 terms" in head  # the table is the series itself, printed to 5 decimals
    tv, u_tab, u_fit = rows[:, 0], rows[:, 1], rows[:, 2]
    # tolerance: half a unit in the table's last printed digit (the table's own rounding)
    assert np.max(np.abs(S.terzaghi_degree(tv) - u_tab)) <= 0.5e-5 + 1e-12
    # the textbook fits in the same table, to their printed digits
    assert np.max(np.abs(S.terzaghi_degree_approx(tv) - u_fit)) <= 0.5e-5 + 1e-12


def test_isochrones_match_the_table():
    head, cols, rows = _read("terzaghi_isochrones.csv")
    assert cols[0] == "z_over_H"
    z = rows[:, 0]
    for j, name in enumerate(cols[1:], start=1):
        tv = float(name.split("=")[1])
        # printed to 4 decimals: half a unit in the last digit
        assert np.max(np.abs(S.terzaghi_excess_pore_pressure(z, tv) - rows[:, j])) <= 0.5e-4 + 1e-12, tv


def test_degree_is_one_minus_mean_excess_pore_pressure():
    z = (np.arange(4000) + 0.5) / 4000  # midpoint rule, error O(1/N^2)
    for tv in (0.01, 0.1, 0.5, 2.0):
        mean_u = S.terzaghi_excess_pore_pressure(z, tv).mean()
        assert abs((1 - mean_u) - S.terzaghi_degree(tv)[0]) < 1e-6


def test_series_limits():
    # early times: U = sqrt(4 Tv / pi) up to terms ~ exp(-1/Tv) (Craig ch. 7)
    for tv in (1e-4, 1e-3, 1e-2):
        assert S.terzaghi_degree(tv)[0] == pytest.approx(math.sqrt(4 * tv / math.pi), rel=1e-9)
    # late times: the first term alone
    tv = 3.0
    assert 1 - S.terzaghi_degree(tv)[0] == pytest.approx(8 / math.pi**2 * math.exp(-(math.pi**2) / 4 * tv))
    # the face is drained, the base is impermeable (du/dz = 0 there)
    assert S.terzaghi_excess_pore_pressure(0.0, 0.2)[0] == 0.0
    a, b = S.terzaghi_excess_pore_pressure([1 - 1e-4, 1.0], 0.2)
    assert abs(a - b) < 1e-7
    assert S.terzaghi_degree(0.0)[0] == 0.0
    with pytest.raises(ValueError):
        S.terzaghi_excess_pore_pressure(0.5, 0.0)


def test_compressible_water_slows_consolidation():
    k, n, m_v = 1e-4, 0.4, 1e-6
    assert S.consolidation_coefficient(k, m_v) == pytest.approx(k / (9810 * m_v))
    k_w = S.water_bulk_modulus(20.0)  # 4e5 Pa: n / K_w = 1e-6 = m_v
    assert k_w == 4e5
    assert S.consolidation_coefficient_eff(k, m_v, n, k_w) == pytest.approx(
        0.5 * S.consolidation_coefficient(k, m_v)
    )
    assert S.skempton_b(m_v, n, k_w) == pytest.approx(0.5)
    # real water (c = 1480 m/s) changes c_v by less than 0.02 %
    big = S.water_bulk_modulus(1480.0)
    assert S.consolidation_coefficient_eff(k, m_v, n, big) / S.consolidation_coefficient(k, m_v) > 0.9998


def test_oedometric_modulus():
    assert S.oedometric_modulus(1.0, 0.0) == 1.0
    assert S.oedometric_modulus(1.0, 0.25) == pytest.approx(1.2)
    assert S.oedometric_modulus(1.0, 0.3) == pytest.approx(0.7 / (1.3 * 0.4))


def test_critical_gradient_three_ways():
    g_s, n = 2.65, 0.4
    e = S.void_ratio(n)
    assert S.porosity(e) == pytest.approx(n)
    ic = S.critical_gradient_from_gs(g_s, e)
    assert ic == pytest.approx(0.99)  # (1.65)(0.6)
    rho_s = g_s * 1000
    d = S.bed_densities(rho_s, n)
    assert S.critical_gradient(rho_s, n, "grain") == pytest.approx(ic)
    assert S.critical_gradient(d["dry"], n, "dry") == pytest.approx(ic)
    assert S.critical_gradient(d["saturated"], n, "saturated") == pytest.approx(ic)
    with pytest.raises(ValueError):
        S.critical_gradient(rho_s, n, "bulk")
    # without buoyancy the skeleton's dry weight must be lifted: (1-n) G_s = 1.59
    assert S.critical_gradient_without_buoyancy(rho_s, n) == pytest.approx(1.59)


def test_bed_profiles():
    rho_s, n, hw = 2650.0, 0.4, 0.2
    z = np.linspace(0, 0.1, 11)
    p = S.saturated_bed_profiles(z, rho_s, n, water_depth=hw)
    gw = 9810.0
    assert np.allclose(p["pore"], gw * (hw + z))
    assert np.allclose(p["effective"], (1 - n) * (rho_s - 1000) * 9.81 * z)
    assert np.allclose(p["total"], p["pore"] + p["effective"])
    # at the critical upward gradient the effective stress vanishes everywhere
    ic = S.critical_gradient(rho_s, n)
    q = S.saturated_bed_profiles(z, rho_s, n, water_depth=hw, upward_gradient=ic)
    assert np.allclose(q["effective"], 0.0, atol=1e-9)


def test_darcy():
    assert S.darcy_discharge(1e-3, 0.5) == pytest.approx(5e-4)
    assert S.seepage_velocity(1e-3, 0.5, 0.4) == pytest.approx(1.25e-3)


def test_drag_rate_and_cost_figures():
    n, k, rho_s = 0.4, 1e-3, 2650.0
    d = S.bed_densities(rho_s, n)
    rate = S.drag_relaxation_rate(n * n * 9810 / k, d["water_apparent"], d["dry"])
    # (n g / k)(1 + n rho_w / ((1-n) rho_s)) = 3924 * 1.2516
    assert rate == pytest.approx(9.81 * n / k * (1 + 400 / 1590))
    c = S.terzaghi_cost(height=0.1, dx=0.005, k=1e-4, e_young=1e6, nu=0.0, n=n, c_water=20.0, rho_s=rho_s)
    assert c["c_v_eff_over_c_v"] == pytest.approx(0.5)
    assert c["c_soil"] == pytest.approx(math.sqrt(1e6 / 1590))
    assert c["dt"] == pytest.approx(0.25 * 1.3 * 0.005 / c["c_soil"])
    assert c["steps"] == math.ceil(c["t_end"] / c["dt"])
