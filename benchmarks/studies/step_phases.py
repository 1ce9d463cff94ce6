"""Where a step's time goes, phase by phase, at one and at two threads (Amdahl's ceiling).

    NUMBA_NUM_THREADS=2 python benchmarks/studies/step_phases.py --kind soil

Every term's run, every ghost/image refresh, the predictor, kick, drift, state checks and the
neighbour rebuild are timed on their own (wall and CPU time; the fastest of --blocks blocks of
--steps steps per phase), first at one thread, then at two in the same process. The "x" column
is each phase's own two-thread speed-up (wall time). On a loaded host the two-thread figures are
unreliable (the load is printed); the one-thread CPU shares say which phase a speed-up must come
from, and the serial phases' share gives Amdahl's two-thread ceiling. The rebuild is timed by
calling it directly (--rebuilds times); its measured frequency in the timed steps is printed.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import defaultdict

import numba

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # benchmarks/

import solver.simulation as simulation  # noqa: E402


class Clock:
    """Sums of wall and CPU time per phase name over the current block."""

    def __init__(self):
        self.wall = defaultdict(float)
        self.cpu = defaultdict(float)

    def wrap(self, name, fn):
        def timed(*args, **kwargs):
            w, c = time.perf_counter(), time.process_time()
            out = fn(*args, **kwargs)
            self.wall[name] += time.perf_counter() - w
            self.cpu[name] += time.process_time() - c
            return out

        return timed


def instrument(sim, clock):
    for term in sim.plan.terms:
        term.run = clock.wrap(f"term: {term.name}", term.run)
    sim.refresh = clock.wrap("ghost/image refresh", sim.refresh)
    sim.predict = clock.wrap("predict (leap-frog)", sim.predict)
    sim.rebuild = clock.wrap("rebuild (in steps)", sim.rebuild)
    for name in ("lf_kick", "lf_drift", "state_status", "max_norm2"):
        setattr(simulation, name, clock.wrap(name, getattr(simulation, name)))


def build(kind, scheme=None):
    if kind == "soil":
        from bench_soil_step import soil_collapse

        return soil_collapse(25_000)
    from dam_break_setup import dam_break

    return dam_break(25_000, **({"numerics.scheme": scheme} if scheme else {}))


def measure(sim, clock, threads, blocks, steps, rebuilds):
    numba.set_num_threads(threads)
    step = clock.wrap("step (total)", sim.step)
    for _ in range(3):
        step()
    best_wall, best_cpu = {}, {}
    r0, s0 = sim.rebuilds, sim.step_count
    for _ in range(blocks):
        clock.wall.clear()
        clock.cpu.clear()
        for _ in range(steps):
            step()
        for k in clock.wall:
            best_wall[k] = min(best_wall.get(k, 1e300), clock.wall[k] / steps)
            best_cpu[k] = min(best_cpu.get(k, 1e300), clock.cpu[k] / steps)
    freq = (sim.rebuilds - r0) / max(sim.step_count - s0, 1)
    rb_wall, rb_cpu = [], []
    for _ in range(rebuilds):
        w, c = time.perf_counter(), time.process_time()
        sim.rebuild()
        rb_wall.append(time.perf_counter() - w)
        rb_cpu.append(time.process_time() - c)
    return best_wall, best_cpu, freq, min(rb_wall), min(rb_cpu)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kind", choices=("soil", "water"), default="soil")
    ap.add_argument("--blocks", type=int, default=10)
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--rebuilds", type=int, default=5)
    ap.add_argument("--scheme", help='water only: numerics.scheme ("seed", "default"); default: the scene\'s')
    args = ap.parse_args(argv)
    sim = build(args.kind, args.scheme)
    clock = Clock()
    instrument(sim, clock)
    n = sim.particles.n_owned
    counts = [1] + ([2] if numba.config.NUMBA_NUM_THREADS >= 2 else [])
    res = {t: measure(sim, clock, t, args.blocks, args.steps, args.rebuilds) for t in counts}
    wall1, cpu1, freq, rbw1, rbc1 = res[1]
    names = sorted(wall1, key=lambda k: -cpu1[k])
    total1 = wall1["step (total)"]
    scheme = f", scheme {args.scheme}" if args.scheme else ""
    load = os.getloadavg()[0]
    print(f"{args.kind} step{scheme}, {n} particles, load {load:.1f}; ms per step (fastest block)")
    head = f"{'phase':44s} {'cpu 1t':>8s} {'share':>6s} {'wall 1t':>8s}"
    if 2 in res:
        head += f" {'wall 2t':>8s} {'x':>5s}"
    print(head)
    for k in names:
        share = cpu1[k] / cpu1["step (total)"] * 100
        line = f"{k:44s} {cpu1[k] * 1e3:8.3f} {share:5.1f}% {wall1[k] * 1e3:8.3f}"
        if 2 in res:
            w2 = res[2][0].get(k, float("nan"))
            line += f" {w2 * 1e3:8.3f} {wall1[k] / w2:5.2f}"
        print(line)
    inner = [k for k in wall1 if k not in ("step (total)", "rebuild (in steps)")]
    rest_cpu = cpu1["step (total)"] - sum(cpu1[k] for k in inner)
    rest = f"{rest_cpu * 1e3:8.3f} {rest_cpu / cpu1['step (total)'] * 100:5.1f}% "
    rest += f"{(total1 - sum(wall1[k] for k in inner)) * 1e3:8.3f}"
    print(f"{'(the rest: Python, zeroing, dt; serial)':44s} {rest}")
    one = f"one rebuild cpu {rbc1 * 1e3:.2f} ms, wall 1t {rbw1 * 1e3:.2f} ms"
    print(f"rebuild: {freq:.3f} per step; {one}", end="")
    if 2 in res:
        print(f", wall 2t {res[2][3] * 1e3:.2f} ms")
        w2 = res[2][0]["step (total)"]
        print(
            f"step at 2 threads: {w2 * 1e3:.3f} ms, {total1 / w2:.2f}x; {n / total1 / 1e6:.2f} M (1t) "
            f"{n / w2 / 1e6:.2f} M (2t) particle-steps/s wall"
        )
    else:
        print()


if __name__ == "__main__":
    main()
