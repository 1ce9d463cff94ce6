"""Dry soil costs nothing of water, and soil walls mirror stress by seed eq. (23)."""

import numpy as np

from solver.materials import Phase
from solver.particles import Mirror
from solver.plan import build_plan
from solver.simulation import Simulation
from solver.term import Integrated
from verification.column_collapse import scene_at

WATER_FIELDS = ("p", "tau", "xsph")


def small_collapse(**kw):
    return scene_at(0.01, end_time=0.01, **kw)


def test_soil_only_plan_has_no_water_term_or_field():
    plan = build_plan(small_collapse())
    assert [t.name for t in plan.terms] == [
        "wall images",
        "soil stress state",
        "artificial stress",
        "gravity",
        "soil rates",
        "artificial stress force",
        "soil return mapping",
    ]
    assert plan.pairs == ((Phase.SOIL, Phase.SOIL),)
    assert not any(f in plan.fields for f in WATER_FIELDS)
    assert not any("seepage" in t.name for t in plan.terms)
    assert [c.name for c in plan.constraints] == ["force", "soil sound"]  # no water sound, no viscous limit
    assert Integrated("stress_dev", "stress_dev_half", "dstress") in plan.integrated
    tensors = [n for n in plan.halo_fields if plan.fields[n].mirror is Mirror.TENSOR]
    assert tensors == ["stress_dev", "art_stress"]
    sim = Simulation(small_collapse())
    assert not any(f in sim.particles for f in WATER_FIELDS)


def test_equilibrium_image_stress_option_is_planned_for_soil_only_and_explained():
    from solver.plan import explain

    scene = small_collapse(overrides={"numerics": {"image_pressure": "hydrostatic"}})
    on = build_plan(scene)
    assert on.has_term("equilibrium soil image stress")
    assert not on.has_term("hydrostatic image pressure")  # no water here
    assert not build_plan(small_collapse()).has_term("equilibrium soil image stress")
    assert "sigma_image = sigma_source - q g^ g^" in explain(on, scene)


def test_artificial_stress_off_removes_field_and_term():
    plan = build_plan(small_collapse(overrides={"numerics": {"artificial_stress": 0.0}}))
    assert "art_stress" not in plan.fields and "art_stress" not in plan.halo_fields
    assert "tension" not in plan.fields
    assert not any("artificial stress" in name for name, _ in plan.equations())
    assert not any("artificial stress" in t.name for t in plan.terms)


def test_soil_sound_speed_constraint_from_k_and_g():
    scene = small_collapse()
    mat = scene.materials["bars"]
    K, G = 0.84e6 / (3 * 0.4), 0.84e6 / 2.6
    c = np.sqrt((K + 4 * G / 3) / 2650)
    assert mat.sound_speed == np.float64(c) or abs(mat.sound_speed - c) < 1e-12 * c
    dt = [k.constant_dt for k in build_plan(scene).constraints if k.name == "soil sound"][0]
    assert abs(dt - 0.25 * scene.h / c) < 1e-15


def test_stress_images_mirror_by_eq23():
    """Images of soil particles carry T'_ab = s_a s_b T_ab (seed eq. 23) across the free-slip
    walls and T' = T across the no-slip floor (its shear traction; tests/test_soil_walls.py);
    at the no-slip floor the image velocity is reversed entirely, at the free-slip wall only
    its normal part."""
    sim = Simulation(small_collapse())
    for _ in range(30):
        sim.step()
    sim.compute_rates()  # images refreshed from the current sources
    ps = sim.particles
    src, sign, _ = sim.ctx.image_tables()
    first = ps.n_local
    s = ps["stress_dev"]
    assert len(src) > 0 and np.abs(s[src, 3]).max() > 0
    for k in range(len(src)):
        i, j = first + k, src[k]
        sx, sy = sign[k]
        np.testing.assert_array_equal(s[i, :3], s[j, :3])
        assert s[i, 3] == sx * s[j, 3]  # only the free-slip (x) wall reverses the shear
        assert ps["mean_stress"][i] == ps["mean_stress"][j]
        # composition over the walls crossed: the floor (no slip) flips both components,
        # the free-slip side wall flips only v_x
        flip = np.array([sx, 1.0]) * (np.array([-1.0, -1.0]) if sy < 0 else np.ones(2))
        expect_v = flip * ps["v"][j]
        np.testing.assert_array_equal(ps["v"][i], expect_v)
