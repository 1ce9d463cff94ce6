"""The overflow nappe onto a rigid bed, SPH against OpenFOAM (issue 11 item 8;
verification/overflow_nappe_rigid_bed.py): the measuring rules on known particle sets, the first
impact of a short run against ballistics and the OpenFOAM early data (CI), the full comparison
(nightly)."""

from types import SimpleNamespace

import numpy as np
import pytest

from verification import overflow_nappe_rigid_bed as nappe


class _Particles:
    def __init__(self, **arrays):
        self.arrays = arrays
        self.n_owned = len(arrays["x"])

    def owned(self, name):
        return self.arrays[name]


def _pool(depth, dx=0.005, x_end=0.25):
    """A still pool on the bed: a lattice from the bed up to `depth`, hydrostatic pressure."""
    xs = np.arange(0.5 * dx, x_end, dx)
    ys = nappe.Y_BED + np.arange(0.5 * dx, depth, dx)
    x = np.array(np.meshgrid(xs, ys, indexing="ij")).reshape(2, -1).T
    n = len(x)
    p = nappe.RHO0 * nappe.G * (nappe.Y_BED + depth - x[:, 1])
    ps = _Particles(
        x=x,
        v=np.tile([0.5, 0.0], (n, 1)),
        p=p,
        rho=np.full(n, nappe.RHO0),
        mass=np.full(n, nappe.RHO0 * dx * dx),
    )
    return SimpleNamespace(particles=ps, h=1.3 * dx)  # h = 1.3 dx: solver/defaults.toml


def test_rigid_bed_scene_replaces_the_soil_by_one_body_and_starts_empty():
    sc = nappe.scene(0.11, 0.005, 0.1)
    assert not sc.blocks and "sand" not in sc.materials
    (body,) = sc.bodies
    assert [0.0, nappe.Y_BED] in body.vertices and [0.0, nappe.Y_CROWN] in body.vertices
    assert sc.inlets[0].discharge == 0.11 and sc.inlets[0].prefill_time == 0.0
    assert sc.outlets[0].min == [0.25, nappe.Y_BED]  # the outlet of the scour scene, unchanged


def test_measuring_rules_on_a_still_pool():
    """A 50 mm pool of 5 mm particles: the phi = 1/2 surface is the volume-equivalent surface (the
    pool's top, within the interpolation error of the kernel, < dx/5), the depth sum(phi dy) its
    depth, the bed pressure rho g H (hydrostatic extrapolation is exact here), u the particles'."""
    depth = 0.05
    sim = _pool(depth)
    grid = nappe.Grid(nappe.Y_BED + 0.1, sim.h)
    s = nappe.Sampler(grid)
    s.add(sim)
    phi, u, p = s.means()
    avg = nappe.reduce_average(grid, phi, u, p)
    inner = (grid.x > 0.03) & (grid.x < 0.22)  # away from the pool's open ends
    upper = np.interp(grid.x[inner], avg["nappe"][:, 0], avg["nappe"][:, 1])
    assert np.all(np.abs(upper - (nappe.Y_BED + depth)) < 0.001)
    assert np.all(np.isnan(avg["nappe"][:, 2]))  # no air under the water: no lower surface
    assert np.all(np.abs(avg["bed"][inner, 2] - depth) < 0.001)
    assert np.all(np.abs(p[inner] / (nappe.RHO0 * nappe.G * depth) - 1) < 0.01)
    wet = avg["vel"][avg["vel"][:, 2] > 0.5]
    assert np.allclose(wet[:, 3], 0.5) and np.allclose(wet[:, 4], 0.0)


def test_metrics_of_the_reference_against_itself_are_zero():
    of = nappe.load_of(0.11, "2p5")
    m = nappe.metrics(of, of)
    assert all(abs(v) < 1e-12 for k, v in m.items() if np.isfinite(v)), m


def test_first_impact_follows_ballistics_and_openfoam(tmp_path):
    """q = 0.11 at 5 mm to 0.045 s (the jet's lowest water reaches the bed): the leading edge and the
    lowest water within one particle spacing of the free jet (x = u_c t, y = crown - g t^2/2) and of
    the OpenFOAM 2.5 mm first impact. Tolerance dx: the inlet releases whole layers of dx, so the
    head is placed to a layer, and the README of reference_cases (sec. 4) set one particle before
    any SPH run; OpenFOAM itself is within 1.2-3.4 mm of ballistics."""
    r = nappe.simulate(0.11, 0.005, end_time=0.045, out=tmp_path, log=lambda *a: None)
    assert r["body_leaks"] == 0 and r["wall_reflections"] == 0
    head = nappe.read(tmp_path / "head_q0p11_dx5mm_sph.csv")
    assert len(head) == 9 and np.all(np.isfinite(head))
    for ref in (nappe.ballistic_head(0.11), nappe.of_head(0.11)["2p5"]):
        m = nappe.early_metrics(head, ref)
        assert m["front_x_max_abs_diff_m"] <= 0.005, m
        assert m["lowest_y_max_abs_diff_m"] <= 0.005, m
    # the jet's surfaces two cells behind its head (reference_cases/README.md sec. 4's rule) follow the
    # ballistic jet of a y_c-thick nappe within dx: the SPH inlet is round(y_c/dx) dx thick (105 mm
    # for y_c = 107.2 mm), so its upper surface sits about 2.2 mm low (measured: upper 2.3 mm max, 2.1 mm
    # rms; lower 1.1 mm max)
    early = nappe.read(tmp_path / "early_q0p11_dx5mm_sph.csv")
    u_c = (nappe.G * 0.11) ** (1 / 3)
    sel = early[(early[:, 0] < 0.045) & (early[:, 1] <= u_c * early[:, 0] - 2 * 0.005)]
    assert len(sel) >= 20
    upper, lower = nappe.ballistic_surfaces(sel[:, 1], 0.11)
    assert np.max(np.abs(sel[:, 2] - upper)) <= 0.005
    assert np.max(np.abs(sel[:, 3] - lower)) <= 0.005


@pytest.mark.nightly
def test_nightly_full_comparison(tmp_path):
    """Both q at 5 mm to 3 s (a few CPU minutes), every judged metric within its tolerance except
    the documented known failures."""
    res = nappe.run(nappe.DEFAULT_RESOLUTION, out_dir=tmp_path)
    failed = [c.line() for c in res.checks if not c.passed and c.metric not in nappe.KNOWN_FAILURES]
    assert not failed, "\n".join(failed)
