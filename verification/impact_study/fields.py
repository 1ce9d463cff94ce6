"""Run the Lobovsky tank and record, besides the sensors, what the flow at the far wall looks like, for
the comparison with the 2D interFoam reference (reference_cases/openfoam_lobovsky_impact/compare.py).

python -m verification.impact_study.fields OUT.npz RESOLUTION [WALLS]

WALLS: the kind of all four walls (default the case's free_slip; no_slip: the interFoam reference's;
wall_function: free-slip images plus the log-law wall shear, solver/physics/wall_function.py).

Every 1 ms of simulated time from t* = 1.8: the wall pressure profile (the case's probe, one point
per height, y = 5, 15, ..., 295 mm), the mean particle pressure in boxes at the wall's foot
(x > 1.61 m - BOX_W, y bands BOX_Y: the particles' own p, no probe), and over the strip within
STRIP of the far wall the water area per unit width (sum of m / rho over STRIP: a mean depth) and
the mass-weighted mean velocity. Over the plateau window (t* 3-5.5), the corner of the far wall as
reference_cases/openfoam_lobovsky_impact/corner.py reads interFoam: the mass-weighted mean u of the
water in x > 1.56 m, y < 20 mm ("backflow"), the mean v in x > 1.59 m, y < 50 mm ("downflow"), and
the momentum and mass summed into 10 mm bins of x 1.41-1.61 m, y 0-0.2 m (for mean-flow streamlines).
"""

import sys
import time

import numpy as np

from verification import impact_pressure as ip

STRIP = 0.1  # m, width of the strip next to the far wall
BOX_W = 0.02  # m, boxes at the foot of the far wall: x > 1.61 - BOX_W, y between BOX_Y edges
BOX_Y = np.array([0.0, 0.01, 0.02, 0.04, 0.06, 0.1, 0.15])
PROFILE_Y = np.arange(0.005, 0.3, 0.01)
EVERY = 1.0e-3  # s
CORNER_X = np.linspace(1.41, 1.61, 21)  # m, bin edges of the corner's mean flow
CORNER_Y = np.linspace(0.0, 0.2, 21)
BACKFLOW_BOX = (0.05, 0.02)  # m, as corner.py: x within 50 mm of the wall, y below 20 mm
DOWNFLOW_BOX = (0.02, 0.05)


def corner_sums(x, v, m):
    """Mass, x- and y-momentum of the particles summed into the corner bins, and the mean u in the
    backflow box and v in the downflow box (nan where empty)."""
    sums = [np.histogram2d(x[:, 0], x[:, 1], bins=(CORNER_X, CORNER_Y), weights=w)[0]
            for w in (m, m * v[:, 0], m * v[:, 1])]  # fmt: skip
    means = []
    for (bw, bh), k in ((BACKFLOW_BOX, 0), (DOWNFLOW_BOX, 1)):
        s = (x[:, 0] > ip.TANK[0] - bw) & (x[:, 1] < bh)
        means.append(float((m[s] * v[s, k]).sum() / m[s].sum()) if s.any() else np.nan)
    return sums, means


def main():
    out, res = sys.argv[1], int(sys.argv[2])
    walls = sys.argv[3] if len(sys.argv) > 3 else "free_slip"
    rec = {
        "t_star": [],
        "profile": [],
        "depth": [],
        "u": [],
        "v": [],
        "box_p": [],
        "backflow": [],
        "downflow": [],
    }
    corner = np.zeros((3, len(CORNER_X) - 1, len(CORNER_Y) - 1))
    faces = [(np.array([y]), np.array([1.0])) for y in PROFILE_Y]
    probe = ip.wall_probe
    last = [-1.0]

    def wall_probe(sim, sensor_faces):
        if sim.t - last[0] >= EVERY * (1 - 1e-9):
            last[0] = sim.t
            ps = sim.particles
            n = ps.n_owned
            x, v = ps["x"][:n], ps["v"][:n]
            m, rho = ps["mass"][:n], ps["rho"][:n]
            s = x[:, 0] > ip.TANK[0] - STRIP
            rec["t_star"].append(sim.t / ip.TIME_SCALE)
            rec["profile"].append(probe(sim, faces) / (ip.RHO0 * ip.G * ip.H))
            rec["depth"].append(float((m[s] / rho[s]).sum()) / STRIP)
            b = x[:, 0] > ip.TANK[0] - BOX_W
            k = np.digitize(x[b, 1], BOX_Y) - 1
            pb = ps["p"][:n][b] / (ip.RHO0 * ip.G * ip.H)
            rec["box_p"].append(
                [float(pb[k == j].mean()) if (k == j).any() else np.nan for j in range(len(BOX_Y) - 1)]
            )
            ms = m[s].sum()
            rec["u"].append(float((m[s] * v[s, 0]).sum() / ms) if ms > 0 else 0.0)
            rec["v"].append(float((m[s] * v[s, 1]).sum() / ms) if ms > 0 else 0.0)
            sums, (back, down) = corner_sums(x, v, m)
            rec["backflow"].append(back)
            rec["downflow"].append(down)
            if ip.PLATEAU[0] <= sim.t / ip.TIME_SCALE <= ip.PLATEAU[1]:
                corner[:] += np.array(sums)
        return probe(sim, sensor_faces)

    ip.wall_probe = wall_probe
    c0 = time.process_time()
    run, wall = ip.simulate(res, walls=walls)
    np.savez(
        out,
        sensor_t_star=run["t_star"],
        sensor_p_star=run["p_star"],
        profile_y=PROFILE_Y,
        strip=STRIP,
        box_w=BOX_W,
        box_y=BOX_Y,
        cpu=time.process_time() - c0,
        wall=wall,
        status=run["status"],
        walls=walls,
        reflections=run["reflections"],
        corner_x=CORNER_X,
        corner_y=CORNER_Y,
        corner_mass=corner[0],
        corner_mom=corner[1:],
        **{k: np.array(v) for k, v in rec.items()},
    )
    print(out, run["status"], f"cpu {time.process_time() - c0:.0f} s, wall {wall:.0f} s")


if __name__ == "__main__":
    main()
