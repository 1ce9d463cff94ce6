"""A plane (slot) jet plunging into a tailwater pool and scouring a saturated sand bed: the scour
depth against time (issue 24 item 3; docs/erosion.md "Verification").

Set-up (the half domain right of the jet's axis; the axis x = 0 is a free-slip wall, the symmetry
plane of the mean flow, which halves the particles and suppresses the jet's flapping): a vertical
slot jet of width B0 (half-width B0/2 modelled) and exit speed U0 leaves a slot EXIT above the
tailwater, falls through air, plunges into the pool and impinges on a saturated geostatic bed of
quartz sand BED deep and LENGTH long. The pool drains over a rigid end wall (crest CREST) into an
outlet zone, so the tailwater stands at the crest plus the overflow's critical depth. Every length is
a multiple of 10 mm = B0/2, so the study's spacings B0/2 / (2, 3, 4) fit it exactly.

The sand is the threshold case's (verification/sediment_threshold.py: d50 0.5 mm quartz, n = 0.4,
G_s = 2.65, k = 1 mm/s). The scour depth d(t) is the project's measure (solver/output/scour.py: the
kernel-interpolated bed surface without suspended soil, each surface particle thinned by its worn
share), d(t) = max_x (z_s(x, 0) - z_s(x, t)).

Reference: see verification/data/jet_scour.md. No laboratory time series of a plane jet's scour
depth could be read in the stored library (the papers' full texts were not accessible; only abstracts
and secondary notes), so this module measures, and checks against the resolution study, what the
model gives; the comparison with an experiment is reported as missing, not passed.

resolution = particles across the modelled half-slot (2, 3, 4: dx = 5, 3.33, 2.5 mm).
"""

from __future__ import annotations

import numpy as np

from . import seepage_common as sc
from .common import RESULTS

D50 = 0.5e-3
POROSITY, G_S, K = 0.4, 2.65, 1e-3
HALF_SLOT = 0.01  # B0/2 (m)
U0 = 1.0  # jet exit speed (m/s)
LENGTH, BED = 0.30, 0.06  # the sand bed (half domain)
CREST = 0.10  # end wall's crest above the base: 40 mm above the bed
POOL = 0.12  # initial water level (the crest plus about the overflow's critical depth, 22 mm)
EXIT = 0.14  # the slot's exit, 20 mm above the initial pool
WALL = 0.05  # end wall length: the outlet zone over it (>= 2h thick, solver/scene_open.py)
TOP = 0.20
DEFAULT_RESOLUTION = 2
STUDY_RESOLUTIONS = (2, 3, 4)
OUT = RESULTS / "jet_scour"
SAND = sc.sand(POROSITY, G_S * sc.RHO_W, K, grain_size=D50)


def raw_scene(resolution, end_time, output_times=None):
    dx = HALF_SLOT / resolution
    x_end = LENGTH + WALL
    return {
        "scene": {"name": "jet_scour", "dimension": 2, "spacing": dx, "end_time": end_time,
                  "gravity": [0.0, -sc.G],
                  "description": "plane slot jet plunging onto a saturated sand bed (half domain)"},
        "domain": {"min": [0.0, 0.0], "max": [x_end, TOP]},
        "walls": {"x_min": "free_slip", "y_min": "free_slip"},
        "materials": {"water": dict(sc.WATER, viscosity=1.0e-3), "sand": SAND},
        "blocks": [
            {"name": "bed", "material": "sand", "shape": "rectangle", "min": [0.0, 0.0], "max": [LENGTH, BED],
             "saturated": True, "geostatic": True, "water_table": POOL},
            {"name": "pool", "material": "water", "shape": "rectangle", "min": [0.0, BED],
             "max": [LENGTH, POOL], "hydrostatic": True},
        ],
        "bodies": [{"name": "end wall", "vertices": [[LENGTH, 0.0], [x_end, 0.0], [x_end, CREST],
                                                      [LENGTH, CREST]]}],
        "inlets": [{"name": "slot", "material": "water", "origin": [0.0, EXIT], "direction": [0.0, -1.0],
                    "across": [1.0, 0.0], "width": HALF_SLOT, "speed": U0, "discharge": U0 * HALF_SLOT}],
        "outlets": [{"name": "over the end wall", "min": [LENGTH, CREST], "max": [x_end, TOP]}],
        "output": {"interval": end_time, "vtk": False, "render": False},
    }  # fmt: skip


def scene(resolution, end_time):
    from solver.scene import parse_scene

    return parse_scene(raw_scene(resolution, end_time), "<verification jet_scour>")


def explore(resolution, end_time, every=0.05):
    """Run and print d(t) (development helper)."""
    import time

    from solver.output.scour import ScourGrid, scour_series
    from solver.simulation import Simulation

    sim = Simulation(scene(resolution, end_time))
    dx = HALF_SLOT / resolution
    grid = ScourGrid.for_layer(0.0, LENGTH, 0.0, TOP, dx, sim.scene.h)
    snaps = []
    t0 = time.process_time()
    for t in np.arange(0.0, end_time + 1e-9, every):
        if t > sim.t:
            sim.advance_to(t)
        sim.current_state()
        ps = sim.particles
        n = ps.n_owned
        snaps.append((sim.t, {"x": ps["x"][:n].copy(), "material": ps["material"][:n].copy(),
                              "suspended": ps["suspended"][:n].copy(),
                              "eroded_share": ps["eroded_share"][:n].copy()}))  # fmt: skip
        m = scour_series(snaps[:1] + snaps[-1:], [1], grid)[-1][0]
        sh = ps["shields"][:n]
        print(f"t={sim.t:.3f} d={1e3 * m.depth:.2f} mm at x={m.x_deepest:.3f} eroded={m.eroded_area * 1e6:.1f} mm2 "
              f"susp={int(ps['suspended'][:n].sum())} theta_max={sh.max():.3f} n={n} steps={sim.step_count} "
              f"cpu={time.process_time() - t0:.0f}", flush=True)
    return sim, snaps
