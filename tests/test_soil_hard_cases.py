"""Hard soil cases stay stable (CI size): no NaN (the run raises BlowUpError on one), no
particle through a wall, kinetic energy decaying to rest, stress within the yield surface.

Where each bound comes from (issue 13):
  * at rest: no particle moves more than dx/2 over the run (dx/2: the positional resolution of
    the particle set; a lattice site is dx away), and its energy form, the final kinetic
    energy at most KE_rest = M (dx / 2 / T)^2 / 2, the whole mass M moving at the speed that
    carries a particle dx/2 in the run's duration T (_ke_at_rest);
  * nothing through a wall: a wall crossing deeper than dx/2 puts a particle where the first
    image layer was (the lattice starts dx/2 from the wall, its image dx/2 beyond), i.e. the
    image repulsion failed (the run itself stops at h, README "Exit status");
  * yield surface: the return mapping puts the stress on the surface up to rounding; the
    excess is relative to the stress scale (yield_excess), so a few ulp (1e-15) are expected
    and 1e-9 allows 1e6 ulp of accumulated rounding while any real overshoot is O(1e-3) or more.
"""

import numpy as np
import pytest

from solver.materials import Phase
from solver.physics.soil_stress import yield_excess
from solver.simulation import Simulation
from verification.column_collapse import run, scene_at


def _scene(blocks, end_time, dx=0.01, domain=(0.5, 0.3)):
    return scene_at(
        dx,
        end_time,
        overrides={"domain": {"max": list(domain)}, "blocks": blocks, "numerics": {"artificial_stress": 0.5}},
    )


def _ke_at_rest(sim, duration):
    """KE_rest = M (dx / 2 / T)^2 / 2 (module doc): above it the body is not at rest on the
    scale the particles resolve."""
    n = sim.particles.n_owned
    return 0.5 * float(np.sum(sim.particles["mass"][:n])) * (0.5 * sim.scene.scene.spacing / duration) ** 2


def _run_and_check(sim, t_end, v0=None, at_rest=True):
    ps = sim.particles
    if v0 is not None:
        ps["v"][: ps.n_owned] = v0
    ke = []
    for t in np.linspace(0, t_end, 31)[1:]:
        sim.advance_to(t)
        n = ps.n_owned
        ke.append(0.5 * np.sum(ps["mass"][:n] * np.sum(ps["v_half"][:n] ** 2, axis=1)))
    sim.current_state()
    n = ps.n_owned
    x = ps["x"][:n]
    assert np.isfinite(x).all() and np.isfinite(ps["stress_dev"][:n]).all()
    assert (x >= sim.lo).all() and (x <= sim.hi).all()  # nothing through a wall
    assert sim.deepest_penetration < 0.5 * sim.scene.scene.spacing  # reflections (if any) stayed shallow
    assert not at_rest or ke[-1] <= _ke_at_rest(sim, t_end), (
        ke[-1],
        _ke_at_rest(sim, t_end),
        max(ke),
    )  # at rest (module doc)
    rows = sim.ctx.rows[Phase.SOIL]
    assert (
        yield_excess(rows, ps["mean_stress"], ps["stress_dev"], ps["material"], sim.plan.materials.soil).max()
        <= 1e-9
    )
    return ke


def test_tall_column_aspect_2_collapses_and_stops():
    # 0.05 m wide x 0.10 m high (aspect 2); collapse time ~ sqrt(2 H / g) = 0.14 s, run 1.5 s (~10 collapse
    # times)
    sim = Simulation(
        _scene(
            [
                {
                    "name": "c",
                    "material": "bars",
                    "shape": "rectangle",
                    "min": [0, 0],
                    "max": [0.05, 0.1],
                    "geostatic": True,
                }
            ],
            1.5,
            dx=0.005,
        )
    )
    _run_and_check(sim, 1.5)
    x = sim.particles.owned("x")
    # it did collapse: a standing column reaches x = 0.05 m; a heap at the angle of repose
    # phi = 19.8 deg against the wall with the column's area A = 0.005 m^2 runs out to
    # sqrt(2 A / tan phi) = 0.167 m; 0.1 m lies between the two
    assert x[:, 0].max() > 0.1


def test_block_dropped_at_2_m_per_s_onto_the_floor():
    sim = Simulation(
        _scene(
            [{"name": "b", "material": "bars", "shape": "rectangle", "min": [0.1, 0.05], "max": [0.2, 0.1]}],
            0.6,
            dx=0.005,
        )
    )
    _run_and_check(sim, 0.6, v0=np.array([0.0, -2.0]))
    assert sim.particles.owned("x")[:, 1].min() > 0.0


@pytest.mark.xfail(
    strict=True,
    reason="the lone toe-tip particle of the stair-stepped 15 deg wedge (dx = 1 cm) slides "
    "1.4 dx in the first 0.5 s and stops (geostatic K0 stress on a 1-particle step face, thinner than the "
    "kernel support); the heap body stands since the no-slip image fix (creep < 1 mm, v < 3e-4 m/s at 3 s); "
    "a 0.3 s kinetic-damping settling phase (numerics.settling_time) does not cure it (2.2 dx at 1 cm, 1.3 "
    "dx "
    "creep at 5 mm); see verification/soil_self_weight.py and verification/results/column_collapse/README.md",
)
def test_settled_heap_stays_at_rest_for_10_collapse_times():
    # a 15 deg heap (below phi = 19.8 deg), geostatic start; collapse time of the column ~0.3 s -> 3 s
    heap = {
        "name": "heap",
        "material": "bars",
        "shape": "polygon",
        "vertices": [[0, 0], [0.3, 0], [0, 0.08]],
        "geostatic": True,
    }
    sim = Simulation(_scene([heap], 3.0, dx=0.01))
    x0 = sim.particles.owned("x").copy()
    ids0 = sim.particles.owned("id").copy()
    _run_and_check(sim, 3.0)
    ps = sim.particles
    order = np.argsort(ps.owned("id"))
    moved = np.linalg.norm(ps.owned("x")[order] - x0[np.argsort(ids0)], axis=1)
    # at rest: no particle moved more than half a spacing in 3 s (creep would accumulate beyond it)
    assert moved.max() < 0.5 * 0.01, moved.max()
    v = ps.owned("v_half")
    assert np.abs(v).max() < 0.5 * 0.01 / 3.0  # at rest: no faster than dx/2 over the run (module doc)


def _deposit(dx, scheme="seed", at_rest=True):
    # The settled heap of issue 3: the deposit a collapse leaves, a heap shaped and settled by
    # its own flow, run on for 10 collapse times. Collapse time t_c: from release until the
    # kinetic energy falls below 1 % of its peak (the "at rest" definition of
    # verification/column_collapse.py). Health checks on the way (_run_and_check): no NaN, nothing
    # through a wall, stress within the yield surface. Returns what _deposit_stays_at_rest judges.
    sim = Simulation(scene_at(dx, 1.0, overrides={"numerics": {"scheme": scheme}}))
    ps = sim.particles
    samples = np.linspace(0.0, 1.0, 41)[1:]
    ke = []
    for t in samples:
        sim.advance_to(t)
        n = ps.n_owned
        ke.append(0.5 * np.sum(ps["mass"][:n] * np.sum(ps["v_half"][:n] ** 2, axis=1)))
    ke = np.array(ke)
    peak = ke.max()
    after_peak = np.arange(len(ke)) > ke.argmax()
    t_c = float(samples[np.flatnonzero(after_peak & (ke < 0.01 * peak))[0]])
    n = ps.n_owned
    x1 = ps["x"][:n][np.argsort(ps["id"][:n])].copy()
    long_ke = _run_and_check(_Offset(sim, sim.t), 10 * t_c, at_rest=at_rest)
    n = ps.n_owned
    moved = np.linalg.norm(ps["x"][:n][np.argsort(ps["id"][:n])] - x1, axis=1)
    return {
        "ke": long_ke,
        "ke_at_rest": _ke_at_rest(sim, 10 * t_c),
        "peak": peak,
        "moved_dx": moved.max() / dx,
        "reflections": sim.wall_reflections,
    }


def _deposit_stays_at_rest(dx, scheme="seed"):
    # kinetic energy decaying to rest: the mean over the last third of the long run is not above the
    # first third's, and all of it stays below 1 % of the collapse's peak; no creep: no particle moves
    # more than dx/2 (the positional resolution of the particle set) over the 10 t_c.
    d = _deposit(dx, scheme)
    long_ke = d["ke"]
    third = len(long_ke) // 3
    assert np.mean(long_ke[-third:]) <= np.mean(long_ke[:third]), long_ke
    assert max(long_ke) < 0.01 * d["peak"], (max(long_ke), d["peak"])
    assert d["moved_dx"] < 0.5, d["moved_dx"]
    return d


@pytest.mark.nightly
def test_collapse_deposit_stays_at_rest_for_10_collapse_times():
    # dx = 5 mm (800 particles, ~20 s), the coarsest spacing of the resolution study, seed scheme;
    # nightly: make test holds the CI-size deposit with the defaults (below) and the seed's known defect.
    # Measured (t = 1 -> 4 s): kinetic energy 1.2e-6 -> 1e-7 J/m (peak ~0.8 J/m), largest
    # displacement 0.33 dx (a bottom-row particle at the old toe), none beyond dx/2.
    _deposit_stays_at_rest(0.005)


def test_seed_scheme_leaves_the_ci_size_deposit_moving():
    # Known defect of the seed's mirror images, pinned (it was a strict xfail): at dx = 1 cm bottom-row
    # particles pressed to y ~ 0 during the collapse (inside the image layer, where the self-image's
    # repulsion vanishes) stay in neutral equilibrium at the wall and keep moving. How it shows
    # depends on round-off (the deposit is chaotic at this level): one particle slipped 3.7 dx at
    # t ~ 5.3 s before the soil speed-up of issue 12; since then the final kinetic energy is 10x the
    # at-rest bound (2.3e-4 against 2.2e-5 J/m) with no particle beyond dx/2. Pinned: the deposit is
    # not at rest by one of the two criteria of _deposit_stays_at_rest (the slip breaks the energy
    # bound, so only the health checks of _run_and_check apply on the way).
    d = _deposit(0.01, "seed", at_rest=False)
    assert d["moved_dx"] > 0.5 or d["ke"][-1] > d["ke_at_rest"], (d["moved_dx"], d["ke"][-1], d["ke_at_rest"])


def test_defaults_keep_the_ci_size_deposit_at_rest_for_10_collapse_times():
    # The same deposit with the defaults (equilibrium image stress, numerics.image_pressure =
    # "hydrostatic", and the wall repulsion): at rest, no creep beyond dx/2, no reflection.
    d = _deposit_stays_at_rest(0.01, "default")
    assert d["reflections"] == 0


class _Offset:
    """A Simulation seen with its clock shifted by t0 (for _run_and_check's sample times)."""

    def __init__(self, sim, t0):
        self._sim, self._t0 = sim, t0

    def advance_to(self, t):
        self._sim.advance_to(self._t0 + t)

    def __getattr__(self, name):
        return getattr(self._sim, name)


def test_settling_phase_drains_the_start_transient():
    # numerics.settling_time (kinetic damping, Cundall 1971) as the alternative to a geostatic
    # start: a 0.30 x 0.05 m layer at dx = 1 cm started from zero stress. Without settling it
    # releases with the elastic transient of its own weight (kinetic energy ~1e-7 J/m at
    # 0.05 s); after 0.3 s of settling (~10 periods of the layer's lowest mode, 4 H / c_s ~
    # 0.02 s) the released layer is at rest to round-off. Bound: 1e-6 of the undamped start's
    # kinetic energy, a discrimination threshold with both sides stated: without settling the
    # ratio is 1 by definition, with it ~1e-20 is measured (kinetic-damping resets remove the
    # transient's energy geometrically), so a damping that works is far below 1e-6 and one
    # that does not is at 1.
    def layer(settle):
        blk = {"name": "layer", "material": "bars", "shape": "rectangle", "min": [0, 0], "max": [0.3, 0.05]}
        sim = Simulation(
            scene_at(
                0.01,
                0.2,
                overrides={
                    "domain": {"max": [0.3, 0.2]},
                    "walls": {"x_max": "free_slip"},
                    "blocks": [blk],
                    "numerics": {"settling_time": settle},
                },
            )
        )
        return sim, _run_and_check(sim, 0.2)

    plain, ke_plain = layer(0.0)
    settled, ke_settled = layer(0.3)
    assert plain.settling is None and settled.settling["resets"] > 0 and settled.t == pytest.approx(0.2)
    assert max(ke_settled) < 1e-6 * max(ke_plain), (max(ke_settled), max(ke_plain))


def test_column_collapse_ci_size_comes_to_rest_inside_yield_surface():
    res = run(10)  # dx = 1 cm, 200 particles
    by_name = {c.metric: c for c in res.checks}
    # at rest by the case's own definition of its final state (residual KE below 1 % of the
    # peak, verification/column_collapse.py); measured 1.8e-5 at dx = 1 cm
    assert by_name["kinetic energy final / peak"].passed, by_name["kinetic energy final / peak"].line()
    assert by_name["max yield excess f/scale"].passed
    # a collapse happened and stayed in the tank: from the 5 mm runout error (-11 % of 0.442 m)
    # and the study's observed order 1.27 (README), the 1 cm runout is about
    # 0.442 (1 - 0.11 * 2^1.27) = 0.325 m; 0.3 allows that, 0.6 m is the tank's end wall
    assert 0.3 < res.series["runout"] < 0.6
