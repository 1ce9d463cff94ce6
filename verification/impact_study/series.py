"""Run the Lobovsky tank and save the raw probe series (t*, p* per sensor) plus run facts.

python -m verification.impact_study.series OUT.npz RESOLUTION [key=value numerics ...] [mat.KEY=VALUE ...]
    [--checkpoint=N] [--end=T_STAR]

--checkpoint=N writes the series recorded so far to OUT.npz every N probe calls (status "partial at t* ..."),
so that a long run (H/160) that is stopped still leaves its impact record; --end=T_STAR ends the run there
(default the case's T_END = 5.6; 3.0 covers the first-impact window, not the plateau).

Also records, per step, the mean p* of the particles within 0.3 m of the far wall (a bulk acoustic
mode shows in it; a probe artefact does not).
"""

import json
import sys
import time

import numpy as np

from verification import impact_pressure as ip


def main():
    out, res = sys.argv[1], int(sys.argv[2])
    numerics, mat = {}, {}
    every, end = 0, ip.T_END
    for kv in sys.argv[3:]:
        k, v = kv.split("=", 1)
        if k == "--checkpoint":
            every = int(v)
            continue
        if k == "--end":
            end = float(v)
            continue
        try:
            v = json.loads(v)
        except json.JSONDecodeError:
            pass
        if k.startswith("mat."):
            mat[k[4:]] = v
        else:
            numerics[k] = v
    parse = ip.parse_scene

    def patched(raw, where):
        raw["materials"]["water"].update(mat)
        return parse(raw, where)

    ip.parse_scene = patched
    bulk, times, values = [], [], []
    probe = ip.wall_probe
    c0 = time.process_time()

    def wall_probe(sim, faces):
        ps = sim.particles
        n = ps.n_owned
        near = ps["x"][:n, 0] > ip.TANK[0] - 0.3
        bulk.append(float(ps["p"][:n][near].mean()) / (ip.RHO0 * ip.G * ip.H) if near.any() else 0.0)
        value = probe(sim, faces)
        if every:
            times.append(sim.t / ip.TIME_SCALE)
            values.append(value / (ip.RHO0 * ip.G * ip.H))
            if len(times) % every == 0:
                np.savez(
                    out,
                    t_star=np.array(times),
                    p_star=np.array(values),
                    bulk=np.array(bulk),
                    status=f"partial at t* {times[-1]:.4f}",
                    reflections=sim.wall_reflections,
                    steps=sim.step_count,
                    particles=n,
                    wall=float("nan"),
                    cpu=time.process_time() - c0,
                    numerics=json.dumps(numerics),
                    mat=json.dumps(mat),
                )
        return value

    ip.wall_probe = wall_probe
    run, wall = ip.simulate(res, end, **numerics)
    cpu = time.process_time() - c0
    np.savez(
        out,
        t_star=run["t_star"],
        p_star=run["p_star"],
        bulk=np.array(bulk),
        status=run["status"],
        reflections=run["reflections"],
        steps=run["steps"],
        particles=run["particles"],
        wall=wall,
        cpu=cpu,
        numerics=json.dumps(numerics),
        mat=json.dumps(mat),
    )
    m = ip.metrics(run)
    print(
        json.dumps(
            {
                "res": res,
                "numerics": numerics,
                "mat": mat,
                "wall": wall,
                "cpu": cpu,
                "steps": run["steps"],
                **{k: v for k, v in m.items() if "s2" in k or k in ("status", "reflections")},
            }
        )
    )


if __name__ == "__main__":
    main()
