"""The plan: from a scene, in plain Python, the passes, terms, fields, halo traffic and
time-step constraints that exist. Nothing outside the plan is allocated, compiled or run.

A missing piece of physics is simply absent here (Oceananigans' `nothing`): no field, no
pass, no exchanged field, no time-step limit. `scoursph run SCENE --explain` prints it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .materials import PHASE_SOIL, PHASE_WATER, YIELD_ELASTIC, MaterialTable, build_material_table
from .particles import FieldSpec
from .scene import Scene
from .tensors import N_SYM
from .timestep import Constraint

PHASE_NAMES = {PHASE_WATER: "water", PHASE_SOIL: "soil"}


@dataclass(frozen=True)
class Term:
    name: str
    equation: str


@dataclass(frozen=True)
class Pass:
    name: str
    targets: str  # phase whose particles get rates
    neighbours: str  # phase of the neighbours summed over
    terms: tuple[Term, ...]
    reads: tuple[str, ...]  # fields read from neighbours (ghosts/images must hold them)
    writes: tuple[str, ...]


@dataclass
class Plan:
    dim: int
    fields: dict[str, FieldSpec]
    passes: list[Pass]
    integrated: list[tuple[str, str, str]]  # (value, half-step value, rate)
    constraints: list[Constraint]
    image_vectors: tuple[str, ...]  # mirrored with sign s (x, v)
    image_scalars: tuple[str, ...]  # copied each step
    image_tensors: tuple[str, ...]  # mirrored with s_a s_b (eq. 23)
    halo_fields: dict[str, tuple[str, ...]]  # when -> fields other ranks must send
    materials: MaterialTable
    options: dict = field(default_factory=dict)
    post_drift_passes: list = field(default_factory=list)  # passes run after the drift (x_{n+1}, v_{n+1/2})

    def has_pass(self, name):
        return any(p.name == name for p in self.passes)

    def bytes_per_particle(self):
        return sum(spec.nbytes_per_particle() for spec in self.fields.values())


def build_plan(scene: Scene) -> Plan:
    dim = scene.dim
    num = scene.numerics
    mats = build_material_table(scene)
    fields = {
        "x": FieldSpec(dim, np.float64, "position"),
        "v": FieldSpec(dim, np.float64, "velocity at step n (predicted)"),
        "v_half": FieldSpec(dim, np.float64, "leap-frog velocity at n+1/2 (eq. 25)"),
        "acc": FieldSpec(dim, np.float64, "momentum rate (eq. 7)"),
        "rho": FieldSpec(0, np.float64, "density at step n (predicted)"),
        "rho_half": FieldSpec(0, np.float64, "leap-frog density at n+1/2 (eq. 24)"),
        "drho": FieldSpec(0, np.float64, "continuity rate (eq. 6)"),
        "mass": FieldSpec(0, np.float64, "particle mass"),
        "material": FieldSpec(0, np.int32, "material id"),
        "id": FieldSpec(0, np.int64, "global particle id"),
        "x_ref": FieldSpec(dim, np.float64, "position at the last neighbour rebuild (skin check)"),
    }
    passes: list[Pass] = []
    constraints = [
        Constraint("force", "seed eq. (29)", None),
    ]
    water_ids = mats.ids_of_phase(PHASE_WATER)
    options = {"viscous": False, "artificial_viscosity": False, "xsph": False}
    image_tensors: list[str] = []
    halo = {"every step, before the passes": ("x", "v", "rho"), "at rebuild": ("mass", "material", "id")}
    if water_ids:
        fields["p"] = FieldSpec(0, np.float64, "pressure, Tait EOS (eq. 9)")
        options["mixed_water"] = len(water_ids) > 1  # per-pair material look-ups only if needed
        c_max = float(mats.sound_speed[water_ids].max())
        constraints.insert(0, Constraint("sound", "seed eq. (28)", num.cfl.sound * scene.h / c_max))
        terms = [Term("continuity", "seed eq. (6)"), Term("pressure gradient", "seed eqs. (7)-(9)")]
        reads = ["x", "v", "rho", "p", "mass"]
        nu_max = max(mats.viscosity[k] / mats.rho0[k] for k in water_ids)
        if num.viscous_stress and nu_max > 0:
            options["viscous"] = True
            fields["tau"] = FieldSpec(N_SYM, np.float64, "viscous stress (eqs. 10-11), symmetric")
            image_tensors.append("tau")
            halo["every step, after viscous_stress"] = ("tau",)
            passes.append(
                Pass(
                    "viscous_stress",
                    "water",
                    "water",
                    (Term("Newtonian viscous stress", "seed eqs. (10)-(11)"),),
                    ("x", "v", "rho", "mass"),
                    ("tau",),
                )
            )
            terms.append(Term("viscous stress divergence", "seed eqs. (7), (8), (10)"))
            reads.append("tau")
            constraints.append(Constraint("viscous", "seed eq. (30)", num.cfl.viscous * scene.h**2 / nu_max))
        if any(mats.av_alpha[k] > 0 or mats.av_beta[k] > 0 for k in water_ids):
            options["artificial_viscosity"] = True
            terms.append(Term("Monaghan artificial viscosity", "seed eq. (19), erratum: + beta phi^2"))
        if num.xsph_epsilon > 0:
            options["xsph"] = True
            fields["xsph"] = FieldSpec(dim, np.float64, "XSPH correction (eq. 22)")
            terms.append(Term("XSPH", "seed eq. (22)"))
        passes.append(
            Pass(
                "fluid_rates",
                "water",
                "water",
                tuple(terms),
                tuple(reads),
                ("drho", "acc") + (("xsph",) if options["xsph"] else ()),
            )
        )
    integrated = [("v", "v_half", "acc"), ("rho", "rho_half", "drho")]
    post_drift = []
    options["symplectic_density"] = num.leapfrog == "symplectic_density" and bool(water_ids)
    options["hydrostatic_images"] = num.image_pressure == "hydrostatic" and bool(water_ids)
    if options["symplectic_density"]:
        # rho at whole steps like x, from v_{n+1/2} after the drift: a symplectic leap-frog for
        # the acoustic (rho, v) pair (verification/leapfrog_stability.py); no rho_half
        integrated.remove(("rho", "rho_half", "drho"))
        del fields["rho_half"]
        fluid_pass = passes[-1]
        passes[-1] = Pass(
            fluid_pass.name,
            fluid_pass.targets,
            fluid_pass.neighbours,
            tuple(t for t in fluid_pass.terms if t.name != "continuity"),
            fluid_pass.reads,
            tuple(w for w in fluid_pass.writes if w != "drho"),
        )
        post_drift.append(
            Pass(
                "fluid_continuity",
                "water",
                "water",
                (Term("continuity with v at n+1/2, rho at whole steps", "seed eq. (6)"),),
                ("x", "v_half", "mass"),
                ("drho",),
            )
        )
        halo["every step, after the drift"] = ("x", "v_half")
    image_scalars = ["rho"]
    options["soil"] = False
    if mats.ids_of_phase(PHASE_SOIL):
        _plan_soil(
            scene, mats, fields, passes, constraints, integrated, image_scalars, image_tensors, halo, options
        )
    if any(b.fixed for b in scene.blocks):
        fields["fixed"] = FieldSpec(0, np.bool_, "wall particles of fixed blocks: never moved")
        halo["at rebuild"] = halo["at rebuild"] + ("fixed",)
    return Plan(
        dim=dim,
        fields=fields,
        passes=passes,
        integrated=integrated,
        constraints=constraints,
        image_vectors=("x", "v"),
        image_scalars=tuple(image_scalars),
        image_tensors=tuple(image_tensors),
        halo_fields=halo,
        materials=mats,
        options=options,
        post_drift_passes=post_drift,
    )


def _plan_soil(
    scene, mats, fields, passes, constraints, integrated, image_scalars, image_tensors, halo, options
):
    """Soil terms (seed sec. 2.2, 2.4; Bui et al. 2008): present only with a soil material."""
    num = scene.numerics
    soil_ids = mats.ids_of_phase(PHASE_SOIL)
    options["equilibrium_soil_images"] = num.image_pressure == "hydrostatic" and bool(soil_ids)
    options["soil"] = True
    fields["stress_dev"] = FieldSpec(N_SYM, np.float64, "soil deviatoric stress s at step n (eqs. 12-13)")
    fields["stress_dev_half"] = FieldSpec(N_SYM, np.float64, "leap-frog s at n+1/2 (eq. 27)")
    fields["dstress"] = FieldSpec(N_SYM, np.float64, "Hooke-Jaumann rate of s (eqs. 13-15)")
    fields["mean_stress"] = FieldSpec(0, np.float64, "soil mean stress p, compression positive (eq. 17)")
    integrated.append(("stress_dev", "stress_dev_half", "dstress"))
    image_tensors.append("stress_dev")
    image_scalars.append("mean_stress")
    plastic = [k for k in soil_ids if mats.soil.yield_model[k] != YIELD_ELASTIC]
    options["plastic_dilation"] = bool(plastic)
    if plastic:
        fields["eps_vp"] = FieldSpec(
            0, np.float64, "plastic volumetric strain (tension cracking, dilatancy psi)"
        )
    stress_terms = [
        Term("mean stress", "seed eq. (17)"),
        Term("return mapping", "seed eq. (16) Mohr-Coulomb / Bui et al. (2008) Drucker-Prager"),
    ]
    options["artificial_stress"] = num.artificial_stress > 0
    if options["artificial_stress"]:
        fields["art_stress"] = FieldSpec(N_SYM, np.float64, "artificial stress R (Gray et al. 2001)")
        image_tensors.append("art_stress")
        stress_terms.append(Term("artificial stress", "Gray, Monaghan & Swift (2001)"))
    halo["every step, after soil_stress"] = ("mean_stress", "stress_dev") + (
        ("art_stress",) if options["artificial_stress"] else ()
    )
    passes.append(Pass("soil_stress", "soil", "soil", tuple(stress_terms), (), ("mean_stress", "stress_dev")))
    terms = [
        Term("continuity", "seed eq. (6)"),
        Term("stress divergence", "seed eqs. (12), (20) without seepage"),
        Term("Hooke-Jaumann deviatoric rate", "seed eqs. (13)-(15)"),
    ]
    options["soil_artificial_viscosity"] = any(mats.av_alpha[k] > 0 or mats.av_beta[k] > 0 for k in soil_ids)
    if options["soil_artificial_viscosity"]:
        terms.append(Term("Monaghan artificial viscosity", "seed eq. (19), alpha = beta = 1 for soil"))
    passes.append(
        Pass(
            "soil_rates",
            "soil",
            "soil",
            tuple(terms),
            ("x", "v", "rho", "mass", "mean_stress", "stress_dev"),
            ("drho", "acc", "dstress"),
        )
    )
    c_max = float(mats.sound_speed[soil_ids].max())
    constraints.append(
        Constraint(
            "soil sound", "seed eq. (28), c = sqrt((K + 4G/3) / rho0)", num.cfl.sound * scene.h / c_max
        )
    )


def explain(plan: Plan, scene: Scene) -> str:
    """Human-readable plan: what will be computed, and what will not."""
    lines = [
        f"Plan for scene '{scene.scene.name}' ({plan.dim}D, dx = {scene.scene.spacing:g} m, h = {scene.h:g} "
        "m)",
        "",
    ]
    lines.append("Materials:")
    for k, name in enumerate(plan.materials.names):
        lines.append(
            f"  [{k}] {name}: phase {PHASE_NAMES[int(plan.materials.phase[k])]}, rho0 = "
            f"{plan.materials.rho0[k]:g}, "
            f"c = {plan.materials.sound_speed[k]:g} m/s, mu = {plan.materials.viscosity[k]:g} Pa s, "
            f"AV alpha = {plan.materials.av_alpha[k]:g}, beta = {plan.materials.av_beta[k]:g}"
        )
    lines.append("")
    lines.append("Passes per step (after predict, image/halo refresh and EOS):")
    for k, p in enumerate(plan.passes, 1):
        lines.append(f"  {k}. {p.name}: {p.targets} <- {p.neighbours}")
        for t in p.terms:
            lines.append(f"       - {t.name} [{t.equation}]")
        lines.append(
            f"       reads from neighbours: {', '.join(p.reads) or 'nothing'}; writes: {', '.join(p.writes)}"
        )
    for p in plan.post_drift_passes:
        lines.append(
            f"  after the drift: {p.name}: {p.targets} <- {p.neighbours}: "
            + "; ".join(f"{t.name} [{t.equation}]" for t in p.terms)
        )
    lines.append(
        "  then gravity, and the leap-frog kick/drift (seed eqs. 24-27) of: "
        + ", ".join(v for v, _, _ in plan.integrated)
        + ", x"
    )
    lines.append("")
    lines.append("Time-step constraints (dt = min):")
    for c in plan.constraints:
        value = "depends on the state" if c.constant_dt is None else f"{c.constant_dt:.3g} s"
        lines.append(f"  - {c.name} [{c.equation}]: {value}")
    lines.append("")
    lines.append(f"Particle fields ({plan.bytes_per_particle()} bytes per particle):")
    for name, spec in plan.fields.items():
        comps = "scalar" if spec.components == 0 else f"{spec.components} components"
        lines.append(f"  {name:16s} {np.dtype(spec.dtype).name:8s} {comps:14s} {spec.reason}")
    lines.append("")
    lines.append(
        "Image particles (walls): vectors "
        + ", ".join(plan.image_vectors)
        + "; scalars "
        + ", ".join(plan.image_scalars)
        + ("; tensors " + ", ".join(plan.image_tensors) if plan.image_tensors else "")
    )
    if plan.options.get("hydrostatic_images"):
        lines.append(
            "  image pressure: source pressure + rho g . (x_image - x_source) (numerics.image_pressure = "
            "hydrostatic)"
        )
    if plan.options.get("equilibrium_soil_images"):
        lines.append(
            "  soil image stress: source stress + static increment rho g . (x_image - x_source) of the "
            "normal "
            "stress along gravity (numerics.image_pressure = hydrostatic)"
        )
    lines.append("Halo exchange (MPI):")
    for when, names in plan.halo_fields.items():
        lines.append(f"  {when}: {', '.join(names)}")
    absent = [
        name
        for name, on in plan.options.items()
        if not on and not name.startswith(("mixed", "symplectic", "hydrostatic", "equilibrium"))
    ]
    if absent:
        lines.append("")
        lines.append(
            "Not in this plan (not compiled, allocated or run): "
            + ", ".join(absent)
            + ("" if any(plan.materials.phase != PHASE_WATER) else ", soil stress, seepage")
        )
    return "\n".join(lines)
