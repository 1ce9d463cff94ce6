"""What the seepage coupling's pass structures cost at least (issue 10, item 7; docs/seepage.md, Speed).

    NUMBA_NUM_THREADS=1 taskset -c 1 nice -n 10 .venv/bin/python benchmarks/seepage_floor.py

On the state of benchmarks/bench_seepage_step.py (2D sand bed, ~10k soil particles, one pore-water
particle per soil particle, ~252k pairs in each of the two soil-water lists), one thread, CPU-time
minima over interleaved rounds, each figure also as a share of the dry soil step timed in the same
rounds (the issue's budget: 0.40):
  * the coupling as built: the mixture's three terms and the seed form's two;
  * floors: one sweep of a list that only gathers x (sum of r^2), and one that also evaluates W;
  * the least physics any formulation has, the drag on both ends of every pair: two gather sweeps
    (one per list, as the seed form does) or one sweep of the soil rows that scatters the water's
    share into its rows (each pair visited once);
  * two candidate structures of the mixture with fewer sweeps: (a) two sweeps, the buoyancy pair
    taking the water particle's own pressure p_a instead of p^_a and the gradient correction on the
    soil side (p~_b and L_b known at the end of the soil row, so the water sweep needs no third one);
    (b) one sweep of the soil rows with every pore-pressure quantity lagged by a step, the water's
    sums (drag, storage, buoyancy, p^, moment matrix: 13 of them) scattered into a per-row buffer;
    (c) two sweeps, the water's p^_a and L_a taken from the previous step: a soil sweep (p~_b and
    the soil's force, split around p~_b) and the water side as built.
The kernels below are timing probes, 2D only: they do the candidate's arithmetic and memory
traffic (the same sums, gathers and scatters) but their results are not used by the solver and
not checked against it; a structure that proves fast enough would be built as a term and tested.
"""

from __future__ import annotations

import time

import numpy as np
from bench_seepage_step import DEPTH, N_SOIL, SEEPAGE_TERMS, WATER, WIDTH
from dam_break_setup import disordered

from solver.config import kernel
from solver.kernels import cubic_spline_dwdr, cubic_spline_w
from solver.physics.seepage import pair_correction
from solver.simulation import Simulation
from verification import seepage_common as sc


def bed(saturated, formulation="mixture"):
    """bench_seepage_step.bed with a choice of formulation."""
    dx = (WIDTH * DEPTH / N_SOIL) ** 0.5
    blocks = [{"name": "bed", "material": "sand", "shape": "rectangle", "min": [0.0, 0.0],
               "max": [WIDTH, DEPTH], "geostatic": True, "saturated": saturated}]  # fmt: skip
    mats = {"sand": sc.sand(0.4, permeability=1e-3)}
    if saturated:
        mats["water"] = sc.WATER
        blocks.append({"name": "pond", "material": "water", "shape": "rectangle", "min": [0.0, DEPTH],
                       "max": [WIDTH, DEPTH + WATER], "hydrostatic": True})  # fmt: skip
    else:
        mats["sand"] = {k: v for k, v in mats["sand"].items() if k not in ("porosity", "permeability")}
    domain = [WIDTH, DEPTH + WATER + 0.05]
    return disordered(Simulation(sc.scene("seepage_bench", dx, 1.0, domain, mats, blocks, formulation)))


@kernel
def sweep_x(targets, start, index, x, out):
    """Floor: gather x, sum r^2."""
    xf = x.reshape(x.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1 = x[b, 0], x[b, 1]
        acc = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            d0 = xb0 - xf[2 * a]
            d1 = xb1 - xf[2 * a + 1]
            acc += d0 * d0 + d1 * d1
        out[b] = acc


@kernel
def sweep_w(targets, start, index, x, vol, h, norm, out):
    """Floor: gather x and V, evaluate W, sum V W."""
    xf = x.reshape(x.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1 = x[b, 0], x[b, 1]
        den = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            d0 = xb0 - xf[2 * a]
            d1 = xb1 - xf[2 * a + 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            den += vol[a] * cubic_spline_w(r, h, norm)
        out[b] = den


@kernel
def drag_gather(targets, start, index, x, v, vol, h, norm, kd, acc):
    """One end's drag, gathered per row: kd V_b sum_a V_a W_ab (v_a - v_b)."""
    xf = x.reshape(x.size)
    vf = v.reshape(v.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1, vb0, vb1 = x[b, 0], x[b, 1], v[b, 0], v[b, 1]
        s0 = s1 = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            xa = 2 * a
            d0 = xb0 - xf[xa]
            d1 = xb1 - xf[xa + 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            w = vol[a] * cubic_spline_w(r, h, norm)
            s0 += w * (vf[xa] - vb0)
            s1 += w * (vf[xa + 1] - vb1)
        acc[b, 0] += kd * vol[b] * s0
        acc[b, 1] += kd * vol[b] * s1


@kernel
def drag_scatter(targets, start, index, x, v, vol, h, norm, kd, acc):
    """Both ends' drag in one sweep of the soil rows, the water end scattered (each pair once)."""
    xf = x.reshape(x.size)
    vf = v.reshape(v.size)
    af = acc.reshape(acc.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1, vb0, vb1 = x[b, 0], x[b, 1], v[b, 0], v[b, 1]
        kb = kd * vol[b]
        s0 = s1 = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            xa = 2 * a
            d0 = xb0 - xf[xa]
            d1 = xb1 - xf[xa + 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            w = vol[a] * cubic_spline_w(r, h, norm)
            f0 = w * (vf[xa] - vb0)
            f1 = w * (vf[xa + 1] - vb1)
            s0 += f0
            s1 += f1
            af[xa] -= kb * f0
            af[xa + 1] -= kb * f1
        acc[b, 0] += kb * s0
        acc[b, 1] += kb * s1


@kernel
def two_sweeps_soil(targets, start, index, x, v, vol, p, h, norm, kd, sol, kappa, acc, pore, lcorr):
    """Candidate (a), soil rows: p~_b, L_b = kappa M_b^-1 and the soil's force with the pair
    -(1 - n) V_a V_b (p_a - p~_b) L_b grad W, summed split around p~_b (known at the row's end)."""
    xf = x.reshape(x.size)
    vf_ = v.reshape(v.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1, vb0, vb1 = x[b, 0], x[b, 1], v[b, 0], v[b, 1]
        den = s0 = s1 = num = y0 = y1 = z0 = z1 = m0 = m1 = m3 = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            xa = 2 * a
            d0 = xb0 - xf[xa]
            d1 = xb1 - xf[xa + 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            vw = vol[a] * cubic_spline_w(r, h, norm)
            vf = vol[a] * cubic_spline_dwdr(r, h, norm) / r
            den += vw
            s0 += vw * (vf_[xa] - vb0)
            s1 += vw * (vf_[xa + 1] - vb1)
            num += vw * p[a]
            y0 += vf * p[a] * d0
            y1 += vf * p[a] * d1
            z0 += vf * d0
            z1 += vf * d1
            m0 -= vf * d0 * d0
            m1 -= vf * d1 * d1
            m3 -= vf * d0 * d1
        q = num / den if den > 0 else 0.0
        c0, c1, _, c3, _, _ = pair_correction(m0, m1, 0.0, m3, 0.0, 0.0, den, kappa, None)
        lcorr[b, 0], lcorr[b, 1], lcorr[b, 3] = c0, c1, c3
        e0 = y0 - q * z0
        e1 = y1 - q * z1
        acc[b, 0] += vol[b] * (kd * s0 - sol * (c0 * e0 + c3 * e1))
        acc[b, 1] += vol[b] * (kd * s1 - sol * (c3 * e0 + c1 * e1))
        pore[b] = q


@kernel
def two_sweeps_water(targets, start, index, x, v, vol, mass, rho, p, pore, lcorr, h, norm, kd, sol, ginv,
                     acc, drho):  # fmt: skip
    """Candidate (a), water rows: drag, Biot's storage and the buoyancy pair with the soil sweep's
    p~_b and L_b (split around p_a)."""
    xf = x.reshape(x.size)
    vf_ = v.reshape(v.size)
    cf = lcorr.reshape(lcorr.size)
    for t in range(targets.shape[0]):
        a = targets[t]
        xa0, xa1, va0, va1 = x[a, 0], x[a, 1], v[a, 0], v[a, 1]
        den = s0 = s1 = b0 = b1 = g0 = g1 = k0 = k1 = phi = div = 0.0
        for s in range(start[t], start[t + 1]):
            b = index[s]
            xb = 2 * b
            d0 = xf[xb] - xa0
            d1 = xf[xb + 1] - xa1
            u0 = va0 - vf_[xb]
            u1 = va1 - vf_[xb + 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            w = cubic_spline_w(r, h, norm)
            vw = vol[b] * w
            vf = vol[b] * cubic_spline_dwdr(r, h, norm) / r
            cb = 6 * b
            e0 = cf[cb] * d0 + cf[cb + 3] * d1
            e1 = cf[cb + 3] * d0 + cf[cb + 1] * d1
            den += vw
            s0 += vw * u0
            s1 += vw * u1
            b0 += vf * d0
            b1 += vf * d1
            k0 += vf * e0
            k1 += vf * e1
            g0 += vf * pore[b] * e0
            g1 += vf * pore[b] * e1
            phi += mass[b] * ginv * w
            div += vf * (u0 * d0 + u1 * d1)
        e0 = p[a] * k0 - g0
        e1 = p[a] * k1 - g1
        inv = 1.0 / rho[a]
        acc[a, 0] -= (kd * s0 - sol * e0) * inv
        acc[a, 1] -= (kd * s1 - sol * e1) * inv
        if den > 0.0:
            div -= (s0 * b0 + s1 * b1) / den
            phi = min(phi, 0.95)
            drho[a] += -rho[a] * phi / (1 - phi) * div


@kernel
def one_sweep_lagged(targets, start, index, x, v, vol, p, pore, corr, h, norm, kd, sol, acc, ws):
    """Candidate (b): soil rows; p^_a, p~_b and L_a from the previous step; the water's 13 sums
    (den, S, B, buoyancy, phi, div, p^ numerator, M) scattered into ws[a]."""
    xf = x.reshape(x.size)
    vf_ = v.reshape(v.size)
    cf = corr.reshape(corr.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1, vb0, vb1 = x[b, 0], x[b, 1], v[b, 0], v[b, 1]
        q_b = pore[b]
        vb = vol[b]
        den = s0 = s1 = g0 = g1 = num = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            xa = 2 * a
            d0 = xb0 - xf[xa]
            d1 = xb1 - xf[xa + 1]
            u0 = vf_[xa] - vb0
            u1 = vf_[xa + 1] - vb1
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            w = cubic_spline_w(r, h, norm)
            f = cubic_spline_dwdr(r, h, norm) / r
            vw = vol[a] * w
            dp = pore[a] - q_b
            ca = 6 * a
            e0 = cf[ca] * d0 + cf[ca + 3] * d1
            e1 = cf[ca + 3] * d0 + cf[ca + 1] * d1
            den += vw
            s0 += vw * u0
            s1 += vw * u1
            num += vw * p[a]
            g0 += vol[a] * f * dp * e0
            g1 += vol[a] * f * dp * e1
            bw = vb * w
            bf = vb * f
            ws[a, 0] += bw
            ws[a, 1] += bw * u0
            ws[a, 2] += bw * u1
            ws[a, 3] += bf * d0
            ws[a, 4] += bf * d1
            ws[a, 5] += bf * dp * e0
            ws[a, 6] += bf * dp * e1
            ws[a, 7] += bw
            ws[a, 8] += bf * (u0 * d0 + u1 * d1)
            ws[a, 9] += bw * q_b
            ws[a, 10] -= bf * d0 * d0
            ws[a, 11] -= bf * d1 * d1
            ws[a, 12] -= bf * d0 * d1
        acc[b, 0] += vb * (kd * s0 - sol * g0)
        acc[b, 1] += vb * (kd * s1 - sol * g1)
        pore[b] = num / den if den > 0 else 0.0


@kernel
def soil_sweep_lagged(targets, start, index, x, v, vol, p, pore, corr, h, norm, kd, sol, acc):
    """Candidate (c), soil rows: p~_b now, and the soil's force with the water's p^_a and L_a of the
    previous step, -(1 - n) V_a V_b (p^_a - p~_b) L_a grad W, summed split around p~_b (known at the
    row's end); the water sweep is then the built one (it computes p^_a and L_a for the next step)."""
    xf = x.reshape(x.size)
    vf_ = v.reshape(v.size)
    cf = corr.reshape(corr.size)
    for t in range(targets.shape[0]):
        b = targets[t]
        xb0, xb1, vb0, vb1 = x[b, 0], x[b, 1], v[b, 0], v[b, 1]
        den = s0 = s1 = num = y0 = y1 = z0 = z1 = 0.0
        for s in range(start[t], start[t + 1]):
            a = index[s]
            xa = 2 * a
            d0 = xb0 - xf[xa]
            d1 = xb1 - xf[xa + 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-300
            vw = vol[a] * cubic_spline_w(r, h, norm)
            vf = vol[a] * cubic_spline_dwdr(r, h, norm) / r
            ca = 6 * a
            e0 = vf * (cf[ca] * d0 + cf[ca + 3] * d1)
            e1 = vf * (cf[ca + 3] * d0 + cf[ca + 1] * d1)
            den += vw
            s0 += vw * (vf_[xa] - vb0)
            s1 += vw * (vf_[xa + 1] - vb1)
            num += vw * p[a]
            y0 += pore[a] * e0
            y1 += pore[a] * e1
            z0 += e0
            z1 += e1
        q = num / den if den > 0 else 0.0
        acc[b, 0] += vol[b] * (kd * s0 - sol * (y0 - q * z0))
        acc[b, 1] += vol[b] * (kd * s1 - sol * (y1 - q * z1))
        pore[b] = q


def main(rounds=25):
    sims = {"dry": bed(False), "mixture": bed(True), "seed": bed(True, "seed")}
    mix = sims["mixture"]
    ctx, ps = mix.ctx, mix.particles
    by_name = {t.name: t for t in mix.plan.terms}
    soil_list = ctx.neighbours(by_name["pore pressure at soil"])
    water_list = ctx.neighbours(by_name["seepage on water"])
    (ss, si), (ws_, wi) = soil_list.unsigned(), water_list.unsigned()
    st, wt = soil_list.targets, water_list.targets
    n = ps.n_total
    x, v = np.ascontiguousarray(ps["x"][:n]), np.ascontiguousarray(ps["v"][:n])
    vol = ps["mass"][:n] / ps["rho"][:n]
    p, mass, rho = ps["p"][:n].copy(), ps["mass"][:n].copy(), ps["rho"][:n].copy()
    pore, corr = ps["pore_pressure"][:n].copy(), np.ascontiguousarray(ps["pair_correction"][:n])
    acc, drho, out = np.zeros((n, 2)), np.zeros(n), np.zeros(n)
    ws, lc = np.zeros((n, 13)), np.zeros((n, 6))
    h, norm, kd, sol, kappa = ctx.h, ctx.norm, 1e3, 0.6, 1.0105

    def terms_of(sim):
        ts = [t for t in sim.plan.terms if t.name in SEEPAGE_TERMS]
        return lambda: [t.run(sim.ctx) for t in ts]

    def one_sweep():
        ws[:] = 0.0
        one_sweep_lagged(st, ss, si, x, v, vol, p, pore, corr, h, norm, kd, sol, acc, ws)

    calls = {
        "dry soil step (the reference)": sims["dry"].step,
        "mixture as built: 3 sweeps (p~, water, soil)": terms_of(mix),
        "seed form as built: 2 sweeps (water, soil)": terms_of(sims["seed"]),
        "floor: 1 sweep gathering x": lambda: sweep_x(st, ss, si, x, out),
        "floor: 1 sweep with W": lambda: sweep_w(st, ss, si, x, vol, h, norm, out),
        "drag only, soil rows (gather)": lambda: drag_gather(st, ss, si, x, v, vol, h, norm, kd, acc),
        "drag only, water rows (gather)": lambda: drag_gather(wt, ws_, wi, x, v, vol, h, norm, kd, acc),
        "drag only, both ends in 1 sweep (scatter)": lambda: drag_scatter(
            st, ss, si, x, v, vol, h, norm, kd, acc
        ),  # fmt: skip
        "(a) 2 sweeps, p_a pair: soil sweep": lambda: two_sweeps_soil(
            st, ss, si, x, v, vol, p, h, norm, kd, sol, kappa, acc, pore, lc
        ),
        "(a) 2 sweeps, p_a pair: water sweep": lambda: two_sweeps_water(
            wt, ws_, wi, x, v, vol, mass, rho, p, pore, lc, h, norm, kd, sol, 1 / 2650, acc, drho
        ),
        "(b) 1 sweep, lagged, 13 sums scattered": one_sweep,
        "(c) 2 sweeps, p^ and L lagged: soil sweep": lambda: soil_sweep_lagged(
            st, ss, si, x, v, vol, p, pore, corr, h, norm, kd, sol, acc
        ),
        "(c) ... water sweep (the built term)": lambda: by_name["seepage on water"].run(ctx),
    }
    for call in calls.values():  # compile, warm
        call()
    best = dict.fromkeys(calls, np.inf)
    for _ in range(rounds):
        for name, call in calls.items():
            start = time.process_time()
            call()
            best[name] = min(best[name], time.process_time() - start)
    best["(a) 2 sweeps together"] = (
        best["(a) 2 sweeps, p_a pair: soil sweep"] + best["(a) 2 sweeps, p_a pair: water sweep"]
    )
    best["drag only, 2 gather sweeps together"] = (
        best["drag only, soil rows (gather)"] + best["drag only, water rows (gather)"]
    )
    best["(c) 2 sweeps together"] = (
        best["(c) 2 sweeps, p^ and L lagged: soil sweep"] + best["(c) ... water sweep (the built term)"]
    )
    dry = best["dry soil step (the reference)"]
    print(f"pairs: soil <- water {soil_list.pairs()}, water <- soil {water_list.pairs()}; CPU-time minima")
    print(f"{'':48s} {'ms':>7s} {'share':>6s}")
    for name, t in best.items():
        print(f"{name:48s} {1e3 * t:7.3f} {t / dry:6.2f}")
    print(f"budget (issue 10): 0.40 x the dry step = {0.4e3 * dry:.2f} ms")


if __name__ == "__main__":
    main()
