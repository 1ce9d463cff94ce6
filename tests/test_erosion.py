"""The erosion law (issue 24 item 2; docs/erosion.md): the grain-scale formulas against their NumPy
twins and sources, the bed-surface and pick-up kernels against tests/naive_erosion.py, the lattice
thresholds, the plan (nothing of it without a grain size, water, or with the seed's scheme), scene
refusals, and a bed under an imposed log-law flow."""

import subprocess
import tomllib

import naive_erosion
import numpy as np
import pytest
from conftest import ENV, SCOURSPH, disordered_lattice, rectangle_block, water_and_sand_scene, write_scene
from naive import cubic_spline

from solver.kernels import cubic_spline_normalisation
from solver.neighbors import CellGrid, CellList
from solver.physics.bed_surface import bed_surface, lattice_fractions, surface_limits
from solver.physics.shields_pickup import MIN_HEIGHT, shields_pickup
from solver.plan import build_plan, explain
from solver.scene import parse_scene
from solver.sediment import (
    bed_friction_velocity,
    critical_shields,
    dimensionless_grain_size,
    pickup_rate,
    speed_at_height,
)
from verification.analytic.scour_formulas import shields_critical

NU, G, RHO_W, RHO_S = 1.0e-6, 9.81, 1000.0, 2650.0
NAMES = {"bed surface", "shields pick-up", "free water", "bed shear on water", "bed shear on soil"}
FIELDS = {"suspended", "eroded_share", "shields", "bed_fraction", "bed_normal", "free_water", "bed_shear",
          "shear_weight"}  # fmt: skip
SHEAR = {"free water", "bed shear on water", "bed shear on soil"}


# ---- grain-scale formulas ----------------------------------------------------------------------


@pytest.mark.parametrize("d", [0.06e-3, 0.2e-3, 0.5e-3, 2e-3, 20e-3])
def test_critical_shields_is_soulsby_whitehouse(d):
    """The kernel's theta_cr is the study's NumPy Soulsby (1997) eqs. 75-76 to round-off, and in the
    range of the Shields curve: 0.03-0.06 for sand and gravel (Soulsby 1997, Fig. 8)."""
    dstar = dimensionless_grain_size(d, RHO_S / RHO_W, NU, G)
    assert critical_shields(dstar) == pytest.approx(float(shields_critical(d)), rel=1e-12)
    if d >= 0.2e-3:
        assert 0.025 < critical_shields(dstar) < 0.06


def test_pickup_rate_is_van_rijn_and_zero_below_threshold():
    d, tcr = 0.5e-3, 0.0308
    dstar = dimensionless_grain_size(d, 2.65, NU, G)
    assert dstar == pytest.approx(12.648, abs=0.001)  # by hand: 5e-4 (1.65 x 9.81 / 1e-12)^(1/3) = 12.648
    for theta in (0.5 * tcr, tcr, 1.5 * tcr, 4 * tcr):
        expected = naive_erosion.van_rijn(theta, tcr, d, RHO_S, RHO_W, NU, G)
        assert pickup_rate(theta, tcr, d, 2.65, dstar, RHO_S, G) == pytest.approx(expected, rel=1e-12)
    assert pickup_rate(tcr, tcr, d, 2.65, dstar, RHO_S, G) == 0.0
    # T = 1 by hand: 0.00033 x 2650 x sqrt(1.65 x 9.81 x 5e-4) x 12.64^0.3 = 0.1684 kg/m^2/s
    assert pickup_rate(2 * tcr, tcr, d, 2.65, dstar, RHO_S, G) == pytest.approx(0.1684, rel=1e-3)


@pytest.mark.parametrize("u_star", [0.002, 0.01, 0.03, 0.1, 0.3])
@pytest.mark.parametrize("y", [0.5e-3, 2.5e-3, 7.5e-3, 0.05])
def test_log_law_inverse(u_star, y):
    """bed_friction_velocity inverts speed_at_height (fixed point to 1e-10) and agrees with the twin's
    bisection, from the smooth (u* k_s / nu = 2.5) to the rough wall (375)."""
    k_s = 2.5 * 0.5e-3
    u = speed_at_height(u_star, y, k_s, NU)
    back = bed_friction_velocity(u, y, k_s, NU)
    assert back == pytest.approx(naive_erosion.friction_velocity(u, y, k_s, NU), rel=1e-8)
    if np.log(y / naive_erosion.roughness_length(u_star, k_s, NU)) > 1.0:  # outside the law's clamp
        assert back == pytest.approx(u_star, rel=1e-8)
    assert bed_friction_velocity(0.0, y, k_s, NU) == 0.0


# ---- lattice thresholds --------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [2, 3])
def test_lattice_fractions_and_limits(dim):
    """The bed fractions of a lattice half-space by the twin's kernel over the points; the limits lie
    strictly between the rows they separate, and the second row is complete (Shepard sum ~1)."""
    second, top, above = lattice_fractions(dim, 1.3)
    n = 8
    axes = [np.arange(-n, n + 1.0)] * (dim - 1)
    pts = np.stack(np.meshgrid(*axes, np.arange(-2 * n, 1.0), indexing="ij"), -1).reshape(-1, dim)
    for row, value in zip((-1, 0, 1), (second, top, above)):
        at = np.zeros(dim)
        at[-1] = row
        assert value == pytest.approx(
            cubic_spline(np.linalg.norm(pts - at, axis=1), 1.3, dim).sum(), rel=1e-12
        )
    assert second == pytest.approx(1.0, abs=0.02)
    surface, deposit = surface_limits(dim, 1.3)
    assert above < deposit < top < surface < second


# ---- kernels against their twins ----------------------------------------------------------------


def bed_and_flow(rng, dim=2, n_side=8, dx=0.01):
    """A jittered bed (soil: material 1 erodes, 2 does not) under jittered water (material 0) with a
    sheared flow above the bed and pore water in its top three rows, some bed suspended, some water
    flagged as wall."""
    h = 1.3 * dx
    bed = disordered_lattice(n_side, dim, dx, rng)
    flow = disordered_lattice(n_side, dim, dx, rng)
    flow[:, -1] += (n_side - 3) * dx  # its bottom three rows are pore water in the bed's top rows
    x = np.vstack([flow, bed])
    nw, ns = len(flow), len(bed)
    water, soil = np.arange(nw), np.arange(nw, nw + ns)
    material = np.zeros(nw + ns, dtype=np.int32)
    material[soil] = 1 + (rng.random(ns) < 0.2)
    v = rng.normal(0, 0.05, (nw + ns, dim))
    v[water, 0] += np.maximum(0.2 + 3.0 * (x[water, -1] - n_side * dx), 0.0)  # a shear flow over the bed
    rho = np.where(material == 0, 1000.0, 1590.0) * (1 + rng.normal(0, 0.01, nw + ns))
    mass = np.where(material == 0, 1000.0, 1590.0) * dx**dim
    suspended = np.zeros(nw + ns, dtype=np.uint8)
    suspended[soil] = (rng.random(ns) < 0.1) & (x[soil, -1] > (n_side - 3) * dx)
    fixed = np.zeros(nw + ns, dtype=np.uint8)
    fixed[water] = rng.random(nw) < 0.1
    phase = np.where(material == 0, 0, 1).astype(np.int32)
    radius = 2 * h * 1.1
    lo, hi = np.full(dim, -dx), np.full(dim, 2 * n_side * dx + dx)
    cells = CellList(CellGrid.covering(lo, hi, radius, pad=radius))
    cells.bin(x, len(x))
    return dict(
        x=x, v=v, rho=rho, mass=mass, material=material, water=water, soil=soil, suspended=suspended,
        fixed=fixed, h=h, dx=dx, dim=dim, norm=cubic_spline_normalisation(dim, h),
        soil_soil=cells.neighbour_list(x, soil.astype(np.int64), radius, phase, 1),
        soil_water=cells.neighbour_list(x, soil.astype(np.int64), radius, phase, 0),
        water_soil=cells.neighbour_list(x, water.astype(np.int64), radius, phase, 1),
    )  # fmt: skip


def _bed_surface(s):
    n = len(s["x"])
    fraction, normal = np.full(n, np.nan), np.full((n, s["dim"]), np.nan)
    nl = s["soil_soil"]
    bed_surface(
        nl.targets, nl.start, nl.index, s["x"], s["mass"], s["rho"], s["suspended"], s["h"], s["norm"],
        fraction, normal,
    )  # fmt: skip
    return fraction, normal


@pytest.mark.parametrize("dim", [2, 3])
def test_bed_surface_matches_twin(rng, dim):
    s = bed_and_flow(rng, dim, n_side=8 if dim == 2 else 5)
    fraction, normal = _bed_surface(s)
    f_twin, n_twin = naive_erosion.bed_surface(
        s["soil"], s["x"], s["mass"], s["rho"], s["suspended"], s["h"], dim
    )
    soil = s["soil"]
    assert np.allclose(fraction[soil], f_twin[soil], rtol=1e-12, atol=0)
    assert np.allclose(normal[soil], n_twin[soil], rtol=1e-10, atol=1e-12)
    side = (8 if dim == 2 else 5) * s["dx"]
    xs = s["x"][soil]
    inner = ((xs[:, :-1] > s["dx"]) & (xs[:, :-1] < side - s["dx"])).all(axis=1)  # away from the bed's sides
    top = soil[inner & (xs[:, -1] > side - s["dx"]) & (s["suspended"][soil] == 0)]
    assert len(top) and (normal[top, -1] > 0.5).all()  # the bed's top row points up, out of the bed


@pytest.mark.parametrize("dim", [2, 3])
def test_shields_pickup_matches_twin(rng, dim):
    """theta, the eroded share, suspension (with the stress zeroed) and deposition against the twin; the
    shares start random near 1 and dt is large (DT: the share grows ~0.002 per second at theta = 1.3
    theta_cr, dx = 1 cm), so particles do cross into suspension."""
    DT = 20.0
    s = bed_and_flow(rng, dim, n_side=8 if dim == 2 else 5)
    fraction, normal = _bed_surface(s)
    n = len(s["x"])
    share = rng.uniform(0.95, 1.0, n)
    stress = rng.normal(0, 100.0, (n, 3 if dim == 2 else 6))
    d50 = np.array([0.0, 0.5e-3, 0.0])
    dstar = np.array([0.0, dimensionless_grain_size(0.5e-3, 2.65, NU, G), 0.0])
    theta_cr = np.array([0.0, 0.0308, 0.0])
    limits = surface_limits(dim, 1.3)
    out = dict(
        suspended=s["suspended"].copy(), share=share.copy(), stress=stress.copy(), shields=np.full(n, np.nan)
    )
    nl = s["soil_water"]
    shields_pickup(
        nl.targets, nl.start, nl.index, s["x"], s["v"], s["mass"], s["rho"], s["material"], s["fixed"],
        out["suspended"], out["share"], out["shields"], fraction, normal, out["stress"], d50, theta_cr, dstar,
        np.array([0.0, 2.65, 0.0]), np.array([0.0, RHO_S, 0.0]), RHO_W, NU, G, s["dx"], s["h"], s["norm"],
        DT, *limits,
    )  # fmt: skip
    mat = [None, dict(d50=0.5e-3, theta_cr=0.0308, rho_s=RHO_S), None]
    shields, share_t, susp_t, stress_t = naive_erosion.shields_pickup(
        s["soil"], s["water"], s["x"], s["v"], s["mass"], s["rho"], s["material"], s["fixed"], s["suspended"],
        share, stress, fraction, normal, mat, RHO_W, NU, G, s["dx"], s["h"], dim, DT, *limits, MIN_HEIGHT,
    )  # fmt: skip
    soil = s["soil"]
    assert np.allclose(out["shields"][soil], shields[soil], rtol=1e-7, atol=0)
    assert np.allclose(out["share"][soil], share_t[soil], rtol=1e-6, atol=1e-12)
    assert np.array_equal(out["suspended"][soil], susp_t[soil])
    assert np.array_equal(out["stress"][soil], stress_t[soil])
    assert (shields[soil] > 0.0308).any() and (shields[soil][shields[soil] > 0] < 0.0308).any()  # both sides
    newly = soil[(out["suspended"][soil] == 1) & (s["suspended"][soil] == 0)]
    assert len(newly) > 0 and not out["stress"][newly].any()
    assert (out["shields"][soil[s["material"][soil] == 2]] == 0).all()  # no grain size, no erosion


# ---- the plan and the scene ---------------------------------------------------------------------

BOX = water_and_sand_scene("eroding_box", 0.01, 0.01, "[0.2, 0.2]") + rectangle_block(
    "bed", "sand", "[0.0, 0.0]", "[0.2, 0.05]", "saturated = true\ngeostatic = true\nwater_table = 0.1"
) + rectangle_block("flow", "water", "[0.0, 0.05]", "[0.2, 0.1]", "hydrostatic = true")  # fmt: skip
GRAIN = "porosity = 0.4\n"


def box(grain="grain_size = 5.0e-4\n", numerics=""):
    text = BOX.replace(GRAIN, GRAIN + grain) + numerics
    return parse_scene(tomllib.loads(text), "box.toml")


def test_the_erosion_terms_only_with_a_grain_size_water_and_the_default_scheme():
    eroding = build_plan(box())
    assert NAMES <= {t.name for t in eroding.terms}
    assert FIELDS <= set(eroding.fields)
    for scene in (box(grain=""), box(numerics='\n[numerics]\nscheme = "seed"\n'),
                  box(numerics='\n[numerics]\nerosion = "none"\n')):  # fmt: skip
        plan = build_plan(scene)
        assert not NAMES & {t.name for t in plan.terms} and NAMES <= set(plan.absent)
        assert not FIELDS & set(plan.fields)
    drag = build_plan(box(numerics='\n[numerics]\nbed_shear = "drag"\n'))  # erosion with the former interface
    assert not SHEAR & {t.name for t in drag.terms} and {"bed surface", "shields pick-up"} <= {
        t.name for t in drag.terms
    }
    assert not {"free_water", "bed_shear", "shear_weight"} & set(drag.fields)
    text = explain(eroding, box())
    for expected in (
        "shields pick-up: soil <- water",
        "bed surface: soil <- soil",
        "free water: water <- soil",
        "bed shear on water: water <- soil",
        "Soulsby & Whitehouse (1997)",
        "van Rijn (1984)",
        "theta_cr 0.0308",
        "Launder & Spalding (1974)",
        "suspended",
    ):
        assert expected in text, expected


WATER_LINE = "typical_velocity = 2.0\n"  # the water material's last line in BOX


@pytest.mark.parametrize(
    "edits,key,reason",
    [
        ({GRAIN: GRAIN + "critical_shields = 0.05\n"}, "materials.sand.critical_shields", "needs grain_size"),
        ({GRAIN: GRAIN + "grain_size = -1.0e-3\n"}, "materials.sand.grain_size", "greater than 0"),
        ({"": '\n[output]\nfields = ["velocity", "shields"]\n'}, "output.fields", "nothing erodes"),
        (
            {GRAIN: GRAIN + "grain_size = 5.0e-4\n", "": '\n[numerics]\nerosion = "grains"\n'},
            "numerics.erosion",
            "'shields' or 'none'",
        ),
        (
            {GRAIN: GRAIN + "grain_size = 5.0e-4\n", WATER_LINE: WATER_LINE + "viscosity = 0.0\n"},
            "materials.water.viscosity",
            "must be > 0",
        ),
    ],
)
def test_scene_refusals_name_the_key(tmp_path, edits, key, reason):
    """edits: replacements in BOX; the key "" appends its text."""
    text = BOX
    for old, new in edits.items():
        text = text + new if old == "" else text.replace(old, new)
    path = write_scene(tmp_path, text)
    r = subprocess.run(
        SCOURSPH + ["run", str(path), "--out", str(tmp_path / "o")], capture_output=True, text=True, env=ENV
    )
    assert r.returncode == 2, r.stderr
    assert key in r.stderr and reason in r.stderr and str(path) in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()


def test_a_dry_soil_with_a_grain_size_erodes_nothing():
    """Erosion needs water (which needs the soil's porosity, for the grain density): a dry column whose
    sand has a grain size plans as before."""
    from verification.column_collapse import scene_at

    dry = scene_at(0.01, end_time=0.01)
    raw = dry.model_dump()
    name = next(k for k, m in raw["materials"].items() if m["model"] == "soil")
    sand = dry.materials[name].model_copy(update={"grain_size": 5e-4})
    plan = build_plan(dry.model_copy(update={"materials": {**dry.materials, name: sand}}))
    assert not NAMES & {t.name for t in plan.terms} and "suspended" not in plan.fields


# ---- a bed under an imposed log-law flow (verification/sediment_threshold.py) --------------------


def test_threshold_case_passes_at_5mm(tmp_path):
    """The verification case in CI size: onset bracket [0.95, 1.05] theta_cr, the estimator exact."""
    from verification import sediment_threshold

    res = sediment_threshold.run(sediment_threshold.DEFAULT_RESOLUTION, out_dir=tmp_path)
    assert res.passed, "\n".join(c.line() for c in res.checks)
    assert res.figure.exists()


def test_suspended_soil_loses_its_shear_strength_and_the_rest_keeps_it():
    """Surface particles about to be worn through (share 1 - 1e-9) under 3 theta_cr are suspended
    within a step; their deviatoric stress is zero from then on, the bed below keeps its own. The row
    below becomes the bed surface and starts to erode; the rows under it do not."""
    from verification import sediment_threshold as st
    from verification.seepage_common import soil_rows

    sim = st.bed_under_log_law(st.DEFAULT_RESOLUTION, 3.0)
    ps = sim.particles
    dx = sim.scene.scene.spacing
    soil = st.middle(sim, soil_rows(sim))
    depth = st.BED - ps["x"][soil, 1]  # of the particle centres below the bed surface
    top, second, deeper = soil[depth < dx], soil[(depth > dx) & (depth < 2 * dx)], soil[depth > 2 * dx]
    sim.step()
    assert (ps["shields"][top] > 3.0 * st.critical_shields() * 0.99).all()
    ps["eroded_share"][top] = 1.0 - 1e-9
    for _ in range(5):
        sim.step()
    assert ps["suspended"][top].all()
    assert not ps["stress_dev"][top].any()
    assert (ps["eroded_share"][second] > 0).all() and not ps["suspended"][second].any()
    assert not ps["suspended"][deeper].any() and not ps["eroded_share"][deeper].any()
    assert np.abs(ps["stress_dev"][deeper]).max() > 0.0  # geostatic K0 state: s != 0 below the surface


@pytest.mark.nightly
def test_threshold_resolution_study(tmp_path):
    from verification import sediment_threshold
    from verification.common import study_failures

    rows = sediment_threshold.study(out_dir=tmp_path)
    assert not study_failures(rows)
    assert all(0.9 <= r["onset_low"] <= 1.0 <= r["onset_high"] <= 1.1 for r in rows)


def test_an_eroding_scene_writes_the_suspended_flags_and_the_scour_reads_the_bed():
    """By default an eroding scene outputs 'suspended' (a scene without erosion does not), and the
    scour surface leaves suspended soil out: a bed with its top row suspended reads a dx lower."""
    from solver.output.scour import ScourGrid, scour_series

    assert {"suspended", "eroded_share"} <= set(box().output.fields)
    assert "suspended" not in box(grain="").output.fields
    assert "suspended" not in box(numerics='\n[numerics]\nerosion = "none"\n').output.fields
    dx = 0.01
    xs, zs = np.meshgrid((np.arange(20) + 0.5) * dx, (np.arange(6) + 0.5) * dx)
    x = np.c_[xs.ravel(), zs.ravel()]
    material = np.ones(len(x), dtype=np.int32)
    top = x[:, 1] > 5 * dx
    grid = ScourGrid.for_layer(0.0, 0.2, 0.0, 0.2, dx, 1.3 * dx)
    flags = np.where(top & (x[:, 0] > 0.05) & (x[:, 0] < 0.15), 1, 0).astype(np.uint8)
    snaps = [
        (0.0, {"x": x, "material": material, "suspended": np.zeros(len(x), np.uint8)}),
        (1.0, {"x": x, "material": material, "suspended": flags}),
        (2.0, {"x": x, "material": material}),
    ]
    (m0, _), (m1, _), (m2, _) = scour_series(snaps, [1], grid)
    assert m0.depth == 0.0 and m2.depth == 0.0  # without the flags every soil particle is bed
    assert m1.depth == pytest.approx(dx, rel=0.05)  # a lattice row: the rule reads a flat bed's surface
    assert 0.05 < m1.x_deepest < 0.15
    # the worn share thins the surface particles continuously: monotone in the share, a row at 1
    depths = []
    for worn in (0.0, 0.25, 0.5, 0.75, 1.0):
        share = np.where(flags == 1, worn, 0.0)
        snap = {"x": x, "material": material, "suspended": np.zeros(len(x), np.uint8), "eroded_share": share}
        depths.append(scour_series([snaps[0], (1.0, snap)], [1], grid)[1][0].depth)
    assert depths[0] == 0.0 and all(b > a for a, b in zip(depths, depths[1:]))
    assert depths[-1] == pytest.approx(m1.depth, rel=1e-9)  # fully worn = suspended
    assert 0.25 * dx < depths[2] < 0.75 * dx


# ---- the bed shear (solver/physics/bed_shear.py) -------------------------------------------------


def _bed_shear_state(s):
    """The bed-shear fields of bed_and_flow's state: free water, then the pick-up's tau_b t_b and weights."""
    from solver.physics.bed_shear import free_water_flags

    n, dim = len(s["x"]), s["dim"]
    fraction, normal = _bed_surface(s)
    surface, deposit = surface_limits(dim, 1.3)
    free = np.full(n, 7, dtype=np.uint8)
    nl = s["water_soil"]
    free_water_flags(
        nl.targets,
        nl.start,
        nl.index,
        s["x"],
        s["mass"],
        s["rho"],
        s["suspended"],
        s["h"],
        s["norm"],
        deposit,
        free,
    )
    shear, weight = np.full((n, dim), np.nan), np.full(n, np.nan)
    d50 = np.array([0.0, 0.5e-3, 0.0])
    nl = s["soil_water"]
    shields_pickup(
        nl.targets,
        nl.start,
        nl.index,
        s["x"],
        s["v"],
        s["mass"],
        s["rho"],
        s["material"],
        s["fixed"],
        s["suspended"].copy(),
        np.zeros(n),
        np.zeros(n),
        fraction,
        normal,
        np.zeros((n, 3 if dim == 2 else 6)),
        d50,
        np.array([0.0, 0.0308, 0.0]),
        np.array([0.0, dimensionless_grain_size(5e-4, 2.65, NU, G), 0.0]),
        np.array([0.0, 2.65, 0.0]),
        np.array([0.0, RHO_S, 0.0]),
        RHO_W,
        NU,
        G,
        s["dx"],
        s["h"],
        s["norm"],
        0.0,
        surface,
        deposit,
        shear,
        weight,
        free,
    )
    return fraction, normal, free, shear, weight


@pytest.mark.parametrize("dim", [2, 3])
def test_free_water_and_wall_shear_match_twins(rng, dim):
    """The free-water flags, the pick-up's tau_b t_b and weights, and the traction's accelerations against
    the twins; the traction is equal and opposite (sum of m a is zero to round-off)."""
    from solver.physics.bed_shear import bed_shear_on_soil, bed_shear_on_water

    s = bed_and_flow(rng, dim, n_side=8 if dim == 2 else 5)
    fraction, normal, free, shear, weight = _bed_shear_state(s)
    water, soil = s["water"], s["soil"]
    deposit = surface_limits(dim, 1.3)[1]
    twin_free = naive_erosion.free_water(
        water, soil, s["x"], s["mass"], s["rho"], s["suspended"], s["h"], dim, deposit
    )
    assert np.array_equal(free[water], twin_free[water])
    assert 0 < free[water].sum() < len(water)  # the water's bottom rows reach into the bed's kernel
    mat = [None, dict(d50=0.5e-3, theta_cr=0.0308, rho_s=RHO_S), None]
    t_shear, t_weight = naive_erosion.wall_shear(
        soil,
        water,
        s["x"],
        s["v"],
        s["mass"],
        s["rho"],
        s["material"],
        s["fixed"],
        s["suspended"],
        fraction,
        normal,
        free,
        mat,
        RHO_W,
        NU,
        s["dx"],
        s["h"],
        dim,
        surface_limits(dim, 1.3)[0],
        MIN_HEIGHT,
    )
    assert np.allclose(weight[soil], t_weight[soil], rtol=1e-12, atol=0)
    assert np.allclose(shear[soil], t_shear[soil], rtol=1e-7, atol=1e-14)
    assert (weight[soil] > 0).sum() >= 5
    acc = np.zeros((len(s["x"]), dim))
    nl = s["water_soil"]
    bed_shear_on_water(
        nl.targets,
        nl.start,
        nl.index,
        s["x"],
        s["mass"],
        s["rho"],
        s["fixed"],
        free,
        shear,
        weight,
        normal,
        s["dx"],
        s["h"],
        s["norm"],
        acc,
    )
    bed_shear_on_soil(soil, s["mass"], s["rho"], shear, weight, acc)
    expected = naive_erosion.wall_shear_accelerations(
        soil,
        water,
        s["x"],
        s["mass"],
        s["rho"],
        s["fixed"],
        free,
        shear,
        weight,
        normal,
        s["dx"],
        s["h"],
        dim,
    )
    assert np.allclose(acc, expected, rtol=1e-10, atol=1e-14)
    momentum = (s["mass"][:, None] * acc).sum(axis=0)
    assert np.abs(momentum).max() <= 1e-12 * (s["mass"][:, None] * np.abs(acc)).sum()
    assert np.abs(acc[soil]).max() > 0


@pytest.mark.parametrize("one_soil", [None, 1])
def test_free_water_pairs_carry_no_drag(rng, one_soil):
    """The seepage kernels with the free-water flags differ from those without by exactly the drag
    V_a V_b C W_ab (v_a - v_b) of the pairs that carry none: free water with the bed of an eroding
    material, and pore water (not free) with suspended soil; buoyancy and storage unchanged (the seed
    form here: drag only; one_soil: the loop-invariant path)."""
    from naive import cubic_spline as w_kernel

    from solver.physics.seepage import seepage_on_soil, seepage_on_water

    s = bed_and_flow(rng, 2)
    if one_soil is not None:
        s["material"][s["soil"]] = 1
    _, _, free, _, _ = _bed_shear_state(s)
    n = len(s["x"])
    vol = s["mass"] / s["rho"]
    drag = np.array([0.0, 1.0e6, 2.0e6])
    erodes = np.array([0, 1, 0], dtype=np.uint8)

    def rates(flags):
        acc = np.zeros((n, 2))
        extra = (free, s["suspended"], erodes) if flags else (None, None, None)
        nl = s["water_soil"]
        seepage_on_water(
            nl.targets,
            *nl.unsigned(),
            s["x"],
            s["v"],
            s["rho"],
            s["mass"],
            vol,
            s["material"],
            drag,
            np.zeros(3),
            np.full(3, 2650.0),
            s["h"],
            s["norm"],
            acc,
            None,
            None,
            None,
            None,
            None,
            one_soil,
            None,
            None,
            0.0,
            None,
            *extra,
        )
        nl = s["soil_water"]
        seepage_on_soil(
            nl.targets,
            *nl.unsigned(),
            s["x"],
            s["v"],
            s["rho"],
            s["mass"],
            vol,
            s["material"],
            drag,
            np.zeros(3),
            s["h"],
            s["norm"],
            acc,
            None,
            None,
            None,
            None,
            None,
            None,
            None,
            *extra,
        )
        return acc

    diff = rates(True) - rates(False)
    expected = np.zeros((n, 2))
    for a in s["water"]:
        for b in s["soil"]:
            if not erodes[s["material"][b]]:
                continue
            if bool(free[a]) == bool(s["suspended"][b]):  # free water and suspended soil: the drag stays
                continue
            w = w_kernel(np.linalg.norm(s["x"][a] - s["x"][b]), s["h"], 2)
            force_on_b = vol[a] * vol[b] * drag[s["material"][b]] * w * (s["v"][a] - s["v"][b])
            expected[a] += force_on_b / s["mass"][a]  # the water no longer loses it
            expected[b] -= force_on_b / s["mass"][b]
    assert np.abs(expected).max() > 0
    assert np.allclose(diff, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_bed_normals_on_images_are_the_free_slip_mirror_at_every_wall_kind():
    """Mirror.DIRECTION: at a no-slip wall a velocity image is -v, but a bed normal's image is the
    geometric mirror s n, so the images of a bed next to any wall point out of the bed too."""
    scene = box(numerics="")
    raw = scene.model_dump(mode="json", exclude_none=True)
    raw["walls"]["x_min"] = "no_slip"
    from solver.simulation import Simulation

    sim = Simulation(parse_scene(raw, "box.toml"))
    sim.step()
    ps, ctx = sim.particles, sim.ctx
    src, sign, _ = ctx.image_tables()
    first = ps.n_local
    rows = first + np.arange(len(src))
    from solver.materials import Phase

    soil = sim.plan.materials.phase[ps["material"][src]] == Phase.SOIL
    assert np.array_equal(ps["bed_normal"][rows[soil]], sign[soil] * ps["bed_normal"][src[soil]])
    # across the no-slip wall: a surface particle's normal has a vertical part, which -n would flip
    up = soil & (sign[:, 0] < 0) & (sign[:, 1] > 0) & (np.abs(ps["bed_normal"][src, 1]) > 0.5)
    assert up.any() and (ps["bed_normal"][rows[up], 1] * ps["bed_normal"][src[up], 1] > 0).all()
