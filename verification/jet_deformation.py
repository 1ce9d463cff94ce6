"""Why the bed sinks under the plunging jet (issue 24; docs/scour_plunging.md, "Why the bed sinks
under the jet"): the plunging scour set-up (solver/scenes/scour_plunging_seed_sand_saturated.toml) run with a
set of overrides (an ablation), measuring where the hole under the jet comes from.

    python -m verification.jet_deformation run --dx 0.005 --end 0.25 [--set KEY=VALUE ...] [--tag NAME]
    python -m verification.jet_deformation table      # the ablation table from the results kept

What a run measures, under the jet (soil particles that started at JET_ZONE[0] < x < JET_ZONE[1]):
- the scour measure's depth d (solver/output/scour.py: the bed without the suspended soil and the worn
  shares), over the jet zone;
- the *eroded* part: the suspended particles' area plus the worn shares of the others that started in the
  zone, as an equivalent depth (area / zone width);
- the *deforming* part: the mean downward displacement of the bed (non-suspended) particles that started
  at a given depth below the surface (10, 20, 40 mm: interpolated between the rows either side), and
  their mean volumetric strain rho0 / rho - 1 (the skeleton's own compression: < 0 compacted);
- the state of the top rows: the vertical effective stress sigma'_v = p - s_yy (seed eq. 12, compression
  positive), the share of particles on the yield surface (solver/physics/soil_stress.yield_excess > -1e-3),
  the pore pressure in excess of hydrostatic and its vertical gradient i against the critical gradient
  i_c = gamma' / gamma_w (Terzaghi 1943), beside and under the jet;
- a time series every SERIES_EVERY s (t, p_max, p_mean, sink, sigma'_v): the largest and the mean water
  pressure within dx of the initial surface under the jet (the impact transient), the mean sinkage (mm) of
  the row that started nearest 10 mm down and its mean sigma'_v.
The results go to verification/results/jet_deformation/<tag>_dx<dx>mm.json with the CPU and wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

from verification import seepage_common as sc

RESULTS = Path(__file__).with_name("results") / "jet_deformation"
SETUP = "plunging_seed_sand"  # the ablations kept: issue 24, the seed's sand (docs/scour_plunging.md)
Q = 0.11  # the study's case of the issue (saturated, q = 0.11)
SURFACE = 0.105  # m, the layer's top (scour_plunging_*.toml)
JET_ZONE = (
    0.15,
    0.25,
)  # m, where the nappe lands (docs/scour_plunging.md: the jet's lower surface at x ~ 0.15 m)
BESIDE = (0.25, 0.35)  # m, downstream of the landing, where the bed heaves
DEPTHS = (0.010, 0.020, 0.040)  # m below the surface: the rows the split reports
SERIES_EVERY = 5.0e-4  # s
FIELD_WINDOWS = ((0.05, 0.15), (0.15, 0.25))  # s: the fields are averaged over these windows
FIELD_TOP = 0.14  # m: the grid reaches 35 mm above the layer's top (the water over the bed)
# per cell: water count and head sum, soil count and sums of sigma'_v, sigma'_h, yielded, v_y
FIELD_SUMS = ("n_w", "head", "n_s", "sv", "sh", "yielded", "vy")
YIELDED = -1.0e-3  # yield_excess above this: on the yield surface (the return mapping lands on f = 0)
G = 9.81


def scene(dx, end, sets=()):
    from solver.scene import parse_scene
    from verification.scour_study import SETUPS, scene_raw

    raw = scene_raw("saturated", Q, dx, end, sets=list(sets) + ["output.render=false"], setup=SETUP)
    return parse_scene(raw, SETUPS["plunging"].scene_path("saturated"))


def _soil(sim):
    return sc.soil_rows(sim)


def _water(sim):
    return sc.water_rows(sim)


class Probe:
    """The measures above, from the initial state of the soil particles (by id)."""

    def __init__(self, sim):
        from solver.output.scour import grid_for_scene

        ps = sim.particles
        soil = _soil(sim)
        self.dx = sim.scene.scene.spacing
        self.ids0 = ps["id"][soil].copy()
        self.x0 = ps["x"][soil, :2].copy()
        self.rho0 = float(sim.plan.materials.rho0[ps["material"][soil[0]]])
        self.grid = grid_for_scene(sim.scene)
        self.zone = (self.grid.x_bins > JET_ZONE[0]) & (self.grid.x_bins < JET_ZONE[1])
        self.z0 = self._surface(sim)
        self.depth0 = SURFACE - self.x0[:, 1]
        self.in_zone = (self.x0[:, 0] > JET_ZONE[0]) & (self.x0[:, 0] < JET_ZONE[1])
        self.rows = np.unique(np.round(self.depth0, 9))
        mat = sim.scene.materials["sand"]
        n = mat.porosity
        self.gamma_dash = (mat.density - (1.0 - n) * 1000.0) * G  # (1 - n)(rho_grain - rho_w) g
        self.i_c = self.gamma_dash / (1000.0 * G)
        self.soil_model = sim.plan.materials.soil
        self.series = []
        self._next = 0.0
        # time-averaged fields on a fixed grid of dx cells (FIELD_WINDOWS): the noise averages out
        self.nx = int(round(0.63 / self.dx))
        self.ny = int(round(FIELD_TOP / self.dx))
        self.fields = {w: {k: np.zeros((self.nx, self.ny)) for k in FIELD_SUMS} for w in FIELD_WINDOWS}

    def _surface(self, sim):
        from solver.output.scour import surface_profile

        ps = sim.particles
        soil = _soil(sim)
        bed = soil[ps["suspended"][soil] == 0] if "suspended" in ps else soil
        worn = ps["eroded_share"][bed] if "eroded_share" in ps else np.zeros(len(bed))
        return surface_profile(ps["x"][bed, :2], self.grid, np.clip(1.0 - worn, 0.0, 1.0))

    def _aligned(self, sim, name):
        """A soil field in the order of the initial soil particles (NaN-free: soil never leaves here,
        the outlet is over the end wall; a particle that did leave is dropped by `alive`)."""
        ps = sim.particles
        soil = _soil(sim)
        order = np.argsort(ps["id"][soil])
        ids = ps["id"][soil][order]
        pos = np.searchsorted(ids, self.ids0)
        pos = np.clip(pos, 0, len(ids) - 1)
        alive = ids[pos] == self.ids0
        return ps[name][soil][order][pos], alive

    def sample(self, sim):
        ps = sim.particles
        x, alive = self._aligned(sim, "x")
        susp = (self._aligned(sim, "suspended")[0] != 0) if "suspended" in ps else np.zeros(len(x), bool)
        worn = self._aligned(sim, "eroded_share")[0] if "eroded_share" in ps else np.zeros(len(x))
        rho = self._aligned(sim, "rho")[0]
        bed = alive & ~susp
        sink = self.x0[:, 1] - x[:, 1]
        zone = self.in_zone
        # the hole: the scour measure over the jet zone
        z = self._surface(sim)
        drop = (self.z0 - z)[self.zone]
        beside = (self.grid.x_bins > BESIDE[0]) & (self.grid.x_bins < BESIDE[1])
        width = JET_ZONE[1] - JET_ZONE[0]
        eroded = (np.sum(zone & susp) + np.sum(np.clip(worn[zone & ~susp], 0.0, 1.0))) * self.dx**2 / width
        rows = {}
        for d in self.rows[self.rows < 0.06]:
            sel = zone & bed & (np.abs(self.depth0 - d) < 1e-9)
            if sel.any():
                rows[f"{d * 1000:.2f}"] = {
                    "sink_mm": 1000 * float(sink[sel].mean()),
                    "sink_max_mm": 1000 * float(sink[sel].max()),
                    "dx_mm": 1000 * float(np.abs(x[sel, 0] - self.x0[sel, 0]).mean()),
                    "vol_strain": float((self.rho0 / rho[sel] - 1.0).mean()),
                }
        keys = sorted(rows, key=float)
        depths = np.array([float(k) / 1000 for k in keys])
        at = {}
        for d in DEPTHS:
            at[f"{d * 1000:g}"] = {
                q: float(np.interp(d, depths, [rows[k][q] for k in keys])) for q in ("sink_mm", "vol_strain")
            }
        out = {
            "t": float(sim.t),
            "d_jet_mm": 1000 * float(max(drop.max(), 0.0)),
            "eroded_mm": 1000 * float(eroded),
            "suspended": int(np.sum(susp & zone)),
            "rise_beside_mm": 1000 * float((z - self.z0)[beside].max()),
            "drop_beside_mm": 1000 * float((self.z0 - z)[beside].max()),
            "at_depth": at,
            "rows": rows,
        }
        out.update(self.state(sim, z))
        return out

    def state(self, sim, z_surface):
        """Under and beside the jet, by depth below the bed's current surface (bands dx thick, the top
        8): the skeleton's vertical and horizontal effective stress (compression positive), the share
        on the yield surface, and the water's head h = p / gamma_w + y (every water particle in the band,
        pore or free), its RMS scatter in the band (the acoustic and odd-even noise), and the vertical
        head gradient i = dh/dy between bands (> 0: flow down; upward flow beats gravity at -i > i_c)."""
        from solver.physics.soil_stress import yield_excess

        ps = sim.particles
        soil = _soil(sim)
        water = _water(sim)
        res = {}
        bed = soil[ps["suspended"][soil] == 0] if "suspended" in ps else soil
        xs, ys = ps["x"][bed, 0], ps["x"][bed, 1]
        ds = np.interp(xs, self.grid.x_bins, z_surface) - ys
        sv = ps["mean_stress"][bed] - ps["stress_dev"][bed, 1]
        sh = ps["mean_stress"][bed] - ps["stress_dev"][bed, 0]
        f = yield_excess(bed, ps["mean_stress"], ps["stress_dev"], ps["material"], self.soil_model)
        xw, yw = ps["x"][water, 0], ps["x"][water, 1]
        dw = np.interp(xw, self.grid.x_bins, z_surface) - yw
        head = ps["p"][water] / (1000.0 * G) + yw
        edges = self.dx * np.arange(0, 9)  # depth bands, top down
        centres = 0.5 * (edges[:-1] + edges[1:])

        def prof(sel, d, v, fn=np.mean):
            out = []
            for a, b in zip(edges[:-1], edges[1:]):
                m = sel & (d >= a) & (d < b)
                out.append(float(fn(v[m])) if m.sum() else None)
            return out

        for name, (lo, hi) in (("jet", JET_ZONE), ("beside", BESIDE)):
            s_band = (xs > lo) & (xs < hi)
            w_band = (xw > lo) & (xw < hi)
            h_prof = prof(w_band, dw, head)
            ok = [k for k, v in enumerate(h_prof) if v is not None]
            grads = [
                (h_prof[b] - h_prof[a]) / (centres[b] - centres[a])
                for a, b in zip(ok[:-1], ok[1:])
                if b == a + 1
            ]  # dh/d(depth): > 0 head rising with depth = upward flow; i = dh/dy = -dh/d(depth)
            i_vals = [-g for g in grads]
            res[name] = {
                "depth_mm": [round(1000 * c, 3) for c in centres],
                "sigma_v_eff_pa": prof(s_band, ds, sv),
                "sigma_h_eff_pa": prof(s_band, ds, sh),
                "yielded_share": prof(s_band, ds, (f > YIELDED).astype(float)),
                "head_mm": [None if v is None else 1000 * v for v in h_prof],
                "head_rms_mm": prof(w_band, dw, head, lambda v: 1000 * float(np.std(v))),
                "i_top": i_vals[0] if i_vals else None,
                "i_min": min(i_vals) if i_vals else None,
                "i_max": max(i_vals) if i_vals else None,
            }
        res["i_c"] = self.i_c
        return res

    def on_step(self, sim):
        if sim.t + 1e-12 < self._next:
            return
        self._next += SERIES_EVERY
        ps = sim.particles
        water = _water(sim)
        x = ps["x"][water]
        near = (x[:, 0] > JET_ZONE[0]) & (x[:, 0] < JET_ZONE[1]) & (np.abs(x[:, 1] - SURFACE) < self.dx)
        p_near = ps["p"][water][near]
        p_max = float(p_near.max()) if near.any() else 0.0
        p_mean = float(p_near.mean()) if near.any() else 0.0
        soil = _soil(sim)
        # the row nearest 10 mm down: its mean sinkage (by id: the rows are re-sorted in cell order)
        d_row = self.rows[np.argmin(np.abs(self.rows - DEPTHS[0]))]
        want = self.ids0[self.in_zone & (np.abs(self.depth0 - d_row) < 1e-9)]
        sel = np.isin(ps["id"][soil], want)
        y0 = SURFACE - d_row
        sink = float((y0 - ps["x"][soil][sel, 1]).mean()) if sel.any() else np.nan
        sv = ps["mean_stress"][soil][sel] - ps["stress_dev"][soil][sel, 1]
        self.series.append((float(sim.t), p_max, p_mean, 1000 * sink, float(np.mean(sv))))
        for w, acc in self.fields.items():
            if w[0] <= sim.t < w[1]:
                self._accumulate(sim, acc, water, soil)

    def _cells(self, x):
        i = np.clip((x[:, 0] / self.dx).astype(np.int64), 0, self.nx - 1)
        j = np.clip((x[:, 1] / self.dx).astype(np.int64), 0, self.ny - 1)
        return i, j

    def _accumulate(self, sim, acc, water, soil):
        from solver.physics.soil_stress import yield_excess

        ps = sim.particles
        i, j = self._cells(ps["x"][water])
        np.add.at(acc["n_w"], (i, j), 1.0)
        np.add.at(acc["head"], (i, j), ps["p"][water] / (1000.0 * G) + ps["x"][water, 1])
        bed = soil[ps["suspended"][soil] == 0] if "suspended" in ps else soil
        i, j = self._cells(ps["x"][bed])
        f = yield_excess(bed, ps["mean_stress"], ps["stress_dev"], ps["material"], self.soil_model)
        np.add.at(acc["n_s"], (i, j), 1.0)
        np.add.at(acc["sv"], (i, j), ps["mean_stress"][bed] - ps["stress_dev"][bed, 1])
        np.add.at(acc["sh"], (i, j), ps["mean_stress"][bed] - ps["stress_dev"][bed, 0])
        np.add.at(acc["yielded"], (i, j), (f > YIELDED).astype(float))
        np.add.at(acc["vy"], (i, j), ps["v"][bed, 1])

    def mean_fields(self):
        """{window: {name: mean over the window per cell (NaN where nothing was)}} for the npz."""
        out = {}
        for w, acc in self.fields.items():
            tag = f"{w[0]:g}-{w[1]:g}"
            with np.errstate(invalid="ignore", divide="ignore"):
                out[f"head_{tag}"] = acc["head"] / acc["n_w"]
                out[f"nw_{tag}"] = acc["n_w"]
                for k in ("sv", "sh", "yielded", "vy"):
                    out[f"{k}_{tag}"] = acc[k] / acc["n_s"]
                out[f"ns_{tag}"] = acc["n_s"]
        return out


def steady_head(x, head_top, depth=SURFACE, length=0.63, y=None):
    """Darcy's steady head in the layer (Laplace's equation: the seepage is steady once the drainage
    time D^2 / c_v,eff has passed, 0.05 s for D = 0.105 m at c = 30 m/s, docs/seepage.md), for a head
    head_top(x) on its top (the water's over the bed) and no flow through its base and end walls:
        h(x, y) = sum_k a_k cos(k pi x / L) cosh(k pi y / L) / cosh(k pi D / L),
    a_k the cosine coefficients of head_top (a half-range cosine series satisfies dh/dx = 0 at
    x = 0, L; cosh satisfies dh/dy = 0 at the base y = 0). Returns (h, dh/dy) at (x, y) (y: the
    heights, default the top); dh/dy < 0 below the top is downward flow, > 0 upward."""
    x = np.asarray(x, float)
    y = np.array([depth]) if y is None else np.asarray(y, float)
    # the coefficients from head_top sampled at x (bins of equal width over 0..L, midpoint rule)
    w = length / len(x)
    k = np.arange(len(x))  # as many modes as samples: the DCT-II, exact at the samples
    basis = np.cos(np.outer(k, np.pi * x / length))
    a = basis @ head_top * w * 2.0 / length
    a[0] *= 0.5
    kk = k[:, None] * np.pi / length
    # cosh(k y)/cosh(k D) without overflow: exp(k (y - D)) (1 + exp(-2 k y)) / (1 + exp(-2 k D))
    ratio = (
        np.exp(kk * (y[None, :] - depth)) * (1 + np.exp(-2 * kk * y[None, :])) / (1 + np.exp(-2 * kk * depth))
    )
    dratio = (
        kk
        * np.exp(kk * (y[None, :] - depth))
        * (1 - np.exp(-2 * kk * y[None, :]))
        / (1 + np.exp(-2 * kk * depth))
    )
    h = np.einsum("k,kx,ky->xy", a, basis, ratio)
    dh = np.einsum("k,kx,ky->xy", a, basis, dratio)
    return h, dh


PENETRATION_DEPTHS = ((0.005, 0.015), (0.015, 0.03), (0.03, 0.05))  # m below the bed's top cell
HEAVE_DEPTHS = (0.005, 0.010, 0.020, 0.040)  # m: prisms of Terzaghi's heave check
SIDES = {"upstream": (0.05, 0.15), "downstream": (0.25, 0.40)}  # m: where the check looks, beside the jet
LOAD_SMOOTHING = 0.02  # m: running mean of the bed load (the footprint is ~0.1 m; the raw mean is noisy)
WET = 0.5  # water particles per sample in a cell above the bed for its head to count as the load (else p = 0)


def seepage_check(npz, window="0.15-0.25", smoothing=LOAD_SMOOTHING):
    """The run's time-averaged pore pressure against Darcy's for the same load, and Terzaghi's heave
    check beside the jet.

    The load: per column the mean head of the water in the two cells above the bed's top cell (the
    bed: cells more than half full of soil; cells with at least WET water particles per sample; p = 0,
    the head of an empty surface, where neither is), run through a mean over `smoothing`. Darcy:
    steady_head of that load in the layer as it started (the hole's few mm left out). Penetration:
    under the jet (JET_ZONE), the run's excess head (over the hydrostatic head of a water table at
    the layer's top) at PENETRATION_DEPTHS below the
    bed's top cell against Darcy's at the same cells, 1 when the jet's pressure has drained into the
    bed as Darcy says. Heave (Terzaghi 1943): a prism of depth d fails when the excess head at its foot
    over its top exceeds i_c d, i_c = gamma' / gamma_w; F = i_c d / (h(top - d) - h(top)) from Darcy's
    head, the smallest over each side of SIDES."""
    z = np.load(npz)
    dx = float(z["dx"])
    head, n_s, n_w = z[f"head_{window}"], z[f"ns_{window}"], z[f"nw_{window}"]
    samples = np.nanmax(n_s)  # a cell full of soil holds one soil particle at every sample
    full, wet = n_s / samples, n_w / samples
    nx = head.shape[0]
    x = (np.arange(nx) + 0.5) * dx
    rows = int(round(SURFACE / dx))
    top = np.array([np.flatnonzero(f > 0.5).max() if (f > 0.5).any() else rows - 1 for f in full])
    load = np.empty(nx)
    for i in range(nx):
        above = [head[i, top[i] + k] for k in (1, 2) if wet[i, top[i] + k] >= WET]
        load[i] = np.mean(above) if above else (top[i] + 1.5) * dx
    k = max(1, int(round(smoothing / dx)))
    load = np.convolve(np.pad(load, (k // 2, k - 1 - k // 2), mode="edge"), np.ones(k) / k, mode="valid")
    y = (np.arange(rows) + 0.5) * dx
    darcy, _ = steady_head(x, load, y=y)
    jet = np.flatnonzero((x > JET_ZONE[0]) & (x < JET_ZONE[1]))
    penetration = []
    for d0, d1 in PENETRATION_DEPTHS:
        run_ex, darcy_ex = [], []
        for i in jet:
            depth = (top[i] + 1) * dx - y  # below the top of the bed's top cell
            cells = [
                j for j in np.flatnonzero((depth > d0) & (depth <= d1 + 1e-9)) if np.isfinite(head[i, j])
            ]
            if cells:
                run_ex.append(np.mean([head[i, j] - SURFACE for j in cells]))
                darcy_ex.append(np.mean([darcy[i, j] - SURFACE for j in cells]))
        penetration.append(float(np.mean(run_ex) / np.mean(darcy_ex)))
    i_c = 1.15  # (rho_dry - (1 - n) rho_w) / rho_w of the seed's sand: (1800 - 650) / 1000
    h_top, _ = steady_head(x, load, y=[SURFACE])
    heave = {}
    for d in HEAVE_DEPTHS:
        h_d, _ = steady_head(x, load, y=[SURFACE - d])
        excess = h_d[:, 0] - h_top[:, 0]
        f = np.where(excess > 0, i_c * d / np.maximum(excess, 1e-12), np.inf)
        for side, (lo, hi) in SIDES.items():
            sel = (x > lo) & (x < hi)
            j = int(np.argmin(np.where(sel, f, np.inf)))
            heave[(side, d)] = (float(f[j]), float(x[j]))
    return {"x": x, "load": load, "penetration": penetration, "heave": heave, "i_c": i_c}


def check_table(out=RESULTS, window="0.15-0.25"):
    """seepage_check of every run kept with its fields (markdown)."""
    lines = [
        "| run | dx (mm) | jet load (kPa above hydrostatic, max) | penetration at 5-15 / 15-30 / 30-50 mm |"
        " heave F upstream, d = 5 / 10 / 20 / 40 mm | downstream |",
        "|---|---|---|---|---|---|",
    ]
    for npz in sorted(out.glob("*.npz")):
        r = seepage_check(npz, window)
        jet = (r["x"] > JET_ZONE[0]) & (r["x"] < JET_ZONE[1])
        pen = " / ".join(f"{v:.2f}" for v in r["penetration"])
        up = " / ".join(f"{r['heave'][('upstream', d)][0]:.2f}" for d in HEAVE_DEPTHS)
        down = " / ".join(f"{r['heave'][('downstream', d)][0]:.2f}" for d in HEAVE_DEPTHS)
        load = (r["load"][jet].max() - SURFACE) * 1000.0 * G / 1000.0
        dx = float(np.load(npz)["dx"])
        lines.append(
            f"| {npz.stem.rsplit('_dx', 1)[0]} | {dx * 1000:g} | {load:.2f} | {pen} | {up} | {down} |"
        )
    return "\n".join(lines)


def run(dx, end, sets=(), tag="base", every=0.05, out=RESULTS):
    from solver.simulation import Simulation

    sim = Simulation(scene(dx, end, sets))
    probe = Probe(sim)
    times = list(np.round(np.arange(every, end + 1e-9, every), 9))
    load0 = os.getloadavg()[0]
    samples, wall, cpu = sc.run_timed(sim, times, probe.sample, on_step=probe.on_step)
    result = {
        "tag": tag,
        "dx": dx,
        "end": end,
        "sets": list(sets),
        "steps": sim.step_count,
        "cpu_s": cpu,
        "wall_s": wall,
        "load": [load0, os.getloadavg()[0]],
        "threads": int(os.environ.get("NUMBA_NUM_THREADS", "0")),
        "command": "python -m verification.jet_deformation run --dx {} --end {}{} --tag {}".format(
            dx, end, "".join(f" --set {s}" for s in sets), tag
        ),
        "i_c": probe.i_c,
        "samples": samples,
        "series": probe.series,
    }
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{tag}_dx{dx * 1000:g}mm.json"
    path.write_text(json.dumps(result, indent=1) + "\n")
    np.savez_compressed(path.with_suffix(".npz"), dx=dx, **probe.mean_fields())
    last = samples[-1]
    print(
        f"{tag} dx={dx * 1000:g} mm t={last['t']:.3f}: d_jet {last['d_jet_mm']:.2f} mm,"
        f" eroded {last['eroded_mm']:.2f} mm,"
        f" sink@10/20/40 {[round(v['sink_mm'], 2) for v in last['at_depth'].values()]} mm;"
        f" {cpu:.0f} s CPU, {wall:.0f} s wall, {sim.step_count} steps",
        flush=True,
    )
    return result


# m, by where the bed particles started: under the void behind the nappe, under its landing, under the
# rest of the jet, and downstream
BUDGET_ZONES = {
    "upstream": (0.08, 0.145),
    "landing": (0.15, 0.20),
    "jet": (0.20, 0.25),
    "beside": (0.25, 0.35),
}


def force_budget(sim, probe, sums):
    """Add, per zone of BUDGET_ZONES and per initial soil row (k = 0 the top row), the vertical and
    horizontal force per unit volume rho a (N/m^3) that each rates term puts on the bed's particles,
    the soil pass split into its stress divergence and its artificial viscosity, into `sums`
    {(term, zone, k): [fx, fy, count]}. The rates are taken at the current time exactly as a step
    takes them (predict, the state stage, the rates stage term by term), and every array they
    touch is put back, so the run goes on as without the budget (a scene without pick-up only: the
    state stage's pick-up would erode twice)."""
    from solver.term import Stage

    ps = sim.particles
    n = ps.n_owned
    names = {f.value for f in sim.plan.integrated} | {f.rate for f in sim.plan.integrated}
    names |= set(sim.plan.accumulated) | {"p", "mean_stress", "stress_dev", "pore_pressure"}
    saved = {k: ps[k].copy() for k in names if k in ps}
    sim.predict()
    for k in sim.plan.accumulated:
        ps[k][:n] = 0.0
    sim._run(Stage.STATE)
    soil = _soil(sim)
    ids = ps["id"][soil]
    order = np.argsort(probe.ids0)
    pos = np.searchsorted(probe.ids0[order], ids)
    pos = order[np.clip(pos, 0, len(order) - 1)]
    x0, d0 = probe.x0[pos], probe.depth0[pos]
    k_row = np.round((d0 - 0.5 * probe.dx) / probe.dx).astype(int)
    bed = (ps["suspended"][soil] == 0) if "suspended" in ps else np.ones(len(soil), bool)
    rho = ps["rho"][soil]
    groups = []
    for zone, (lo, hi) in BUDGET_ZONES.items():
        for k in range(8):
            sel = bed & (x0[:, 0] > lo) & (x0[:, 0] < hi) & (k_row == k)
            if sel.any():
                groups.append((zone, k, sel))

    def add(term, acc):
        f = acc[soil] * rho[:, None]
        for zone, k, sel in groups:
            e = sums.setdefault((term, zone, k), [0.0, 0.0, 0])
            e[0] += float(f[sel, 0].sum())
            e[1] += float(f[sel, 1].sum())
            e[2] += int(sel.sum())

    prev = ps["acc"][:n].copy()
    for item in sim.plan.schedule.get(Stage.RATES, ()):
        sim.refresh(item.refresh)
        item.term.run(sim.ctx)
        now = ps["acc"][:n]
        if item.term.name == "soil rates" and item.term.av_alpha is not None:
            with_av = now - prev
            keep = ps["acc"][:n].copy()
            ps["acc"][:n] = 0.0
            alpha, beta = item.term.av_alpha, item.term.av_beta
            item.term.av_alpha = item.term.av_beta = None
            item.term.run(sim.ctx)
            item.term.av_alpha, item.term.av_beta = alpha, beta
            stress = ps["acc"][:n].copy()
            add("soil stress", stress)
            add("soil AV", with_av - stress)
            ps["acc"][:n] = keep
        else:
            add(item.term.name, now - prev)
        prev = ps["acc"][:n].copy()
    add("total", ps["acc"][:n])
    for k, v in saved.items():
        ps[k][...] = v


def budget_run(dx, end=0.1, window=(0.03, 0.1), every=1.0e-3, sets=(), tag="budget", out=RESULTS):
    """force_budget averaged over `window` every `every` s; a scene without pick-up (the sand's
    critical Shields number raised). Writes <tag>_dx<dx>mm_budget.json."""
    from solver.simulation import Simulation

    sets = list(sets) + ["materials.sand.critical_shields=10.0"]
    sim = Simulation(scene(dx, end, sets))
    probe = Probe(sim)
    sums = {}
    times = list(np.round(np.arange(window[0], window[1] + 1e-9, every), 9))
    _, wall, cpu = sc.run_timed(sim, times, lambda s: force_budget(s, probe, sums))
    table = {f"{t}|{z}|{k}": [v[0] / v[2], v[1] / v[2]] for (t, z, k), v in sums.items()}
    res = {"dx": dx, "window": window, "sets": sets, "cpu_s": cpu, "wall_s": wall, "mean_force": table}
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{tag}_dx{dx * 1000:g}mm_budget.json").write_text(json.dumps(res, indent=1) + "\n")
    return res


def load(out=RESULTS):
    return [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]


def table(cases, at=0.25):
    """The ablation table (markdown): per run at time `at`, the jet zone's hole, its eroded part, the
    mean sinkage of the bed that started 10 / 20 / 40 mm down, and the run's command and CPU time."""
    head = (
        "| run | dx (mm) | d under the jet (mm) | eroded (mm) | sinkage at 10 / 20 / 40 mm (mm) | steps |"
        " CPU (s) | command (`python -m verification.jet_deformation run ...`) |"
        "\n|---|---|---|---|---|---|---|---|"
    )
    rows = []
    for c in sorted(cases, key=lambda c: (-c["dx"], c["tag"] != "base", c["tag"])):
        s = min(c["samples"], key=lambda s: abs(s["t"] - at))
        sink = " / ".join(f"{v['sink_mm']:.2f}" for v in s["at_depth"].values())
        sets = " ".join(f"--set {x}" for x in c["sets"])
        rows.append(
            f"| {c['tag']} | {c['dx'] * 1000:g} | {s['d_jet_mm']:.1f} | {s['eroded_mm']:.2f} | {sink} |"
            f" {c['steps']} | {c['cpu_s']:.0f} |"
            f" `--dx {c['dx']} --end {c['end']:g} --tag {c['tag']} {sets}` |"
        )
    return "\n".join([head] + rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--dx", type=float, default=0.005)
    r.add_argument("--end", type=float, default=0.25)
    r.add_argument("--set", action="append", default=[])
    r.add_argument("--tag", default="base")
    r.add_argument("--every", type=float, default=0.05)
    b = sub.add_parser("budget")
    b.add_argument("--dx", type=float, default=0.005)
    b.add_argument("--set", action="append", default=[])
    b.add_argument("--tag", default="budget")
    sub.add_parser("table")
    sub.add_parser("check")
    a = ap.parse_args(argv)
    if a.cmd == "run":
        run(a.dx, a.end, a.set, a.tag, a.every)
    elif a.cmd == "budget":
        budget_run(a.dx, sets=a.set, tag=a.tag)
    elif a.cmd == "check":
        print(check_table())
    else:
        print(table(load()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
