"""Numerical variants of the interFoam Lobovsky tank: what makes the no-slip run's corner eddy (corner.py)?

    python -m reference_cases.openfoam_lobovsky_impact.variants --cells-per-H N --walls noSlip|slip
        [--nu-water NU] [--div-U SCHEME] [--turbulence laminar|kOmegaSST] [--no-slip-only PATCH] [--nice 10]

Each variant is the reference case (run.py, open top) with one change: the water's kinematic viscosity
(default 1e-6 m^2/s) or the convection scheme of the momentum equation (default "Gauss linearUpwind
grad(U)", the reference's; "Gauss upwind" uses no reconstruction gradient, so the wall's velocity
enters the momentum equation only through the viscous term), or the turbulence closure ("laminar", the
reference's; "kOmegaSST": Menter's k-omega SST RANS model with standard wall functions on the three walls,
a modelled turbulent wall shear and eddy viscosity in place of the laminar wall layer; TURBULENCE below).
With --no-slip-only floor|rightWall the no-slip condition is kept on that wall alone, the other two walls
slip (which wall's layer starts the corner eddy). Its fields go to work/<label> (not in
git), its sensor metrics (the impact case's functions, as run.py) and corner numbers (corner.py) to
one row of data/variants.csv, with the command.
"""

from __future__ import annotations

import argparse
import csv
import os
import re
import shlex
import sys
import time
from pathlib import Path

from reference_cases import _common as C

from . import corner
from . import run as R

OUT = R.DATA_DIR / "variants.csv"
DEFAULT_DIV_U = "Gauss linearUpwind grad(U)"
FIELDS = ("label", "cells_per_H", "walls", "nu_water", "div_U", "turbulence", "impact_s2", "plateau_mean_s1",
          "plateau_mean_s2", "plateau_mean_s3", "plateau_mean_s4", "backflow_u", "reversed_fraction",
          "downflow_v", "wall_shear_Pa", "cpu_s", "load", "command")  # fmt: skip
# RANS variant: Menter's k-omega SST (OpenFOAM "kOmegaSST") with the standard wall functions
# (kqRWallFunction, omegaWallFunction, nutkWallFunction) on leftWall, rightWall and floor. Water at rest
# at t = 0, so a quiet start: k0 = 1e-5 m^2/s^2 (u' ~ 3 mm/s) and omega0 = sqrt(k0) / (Cmu^0.25 l0) with a
# mixing length l0 = 1 mm (5.8 1/s), i.e. nut0 = k0 / omega0 ~ 1.7e-6 m^2/s, of the order of the water's nu.
# The first cell centre at H/20 is 7.5 mm from the wall: y+ ~ 580-730 for the log-law u* = 0.078-0.097 m/s
# of the first row's 1.6-2.1 m/s over the floor (t* 3.4-5.2), at the top of the log-law range.
K0, OMEGA0 = 1e-5, 5.8
TURB_WALLS = "(leftWall|rightWall|floor)"


PATCHES = ("leftWall", "rightWall", "floor")


def label_of(n: int, walls: str, nu: float, div_u: str, turbulence: str = "laminar", only: str = "") -> str:
    tag = f"h{n}_var_{walls}" + (f"_only{only}" if only else "") + f"_nu{nu:.0e}"
    tag += "" if div_u == DEFAULT_DIV_U else "_" + re.sub(r"[^A-Za-z0-9]+", "", div_u.split()[1])
    return tag + ("" if turbulence == "laminar" else "_" + turbulence)


def _field(name: str, cls: str, dims: str, value: str, wall: str, top: str) -> str:
    return (
        f'FoamFile\n{{\n    version 2.0;\n    format ascii;\n    class {cls};\n    location "0";\n'
        f"    object {name};\n}}\ndimensions {dims};\ninternalField uniform {value};\nboundaryField\n{{\n"
        f'    "{TURB_WALLS}"\n    {{\n        type {wall};\n        value uniform {value};\n    }}\n'
        f"    atmosphere\n    {{\n{top}\n    }}\n    frontAndBack\n    {{\n        type empty;\n    }}\n}}\n"
    )


def write_rans(work: Path) -> None:
    """Switch the case to k-omega SST with wall functions (TURB_WALLS; K0, OMEGA0 above)."""
    (work / "constant" / "turbulenceProperties").write_text(
        "FoamFile\n{\n    version 2.0;\n    format ascii;\n    class dictionary;\n"
        '    location "constant";\n    object turbulenceProperties;\n}\nsimulationType RAS;\n'
        "RAS\n{\n    RASModel kOmegaSST;\n    turbulence on;\n    printCoeffs on;\n}\n"
    )
    inout = "        type inletOutlet;\n        inletValue uniform {v};\n        value uniform {v};"
    zero = "0 0 0 0"
    (work / "0" / "k").write_text(
        _field("k", "volScalarField", f"[0 2 -2 {zero}]", f"{K0:g}", "kqRWallFunction",
               inout.format(v=f"{K0:g}"))
    )  # fmt: skip
    (work / "0" / "omega").write_text(
        _field("omega", "volScalarField", f"[0 0 -1 {zero}]", f"{OMEGA0:g}", "omegaWallFunction",
               inout.format(v=f"{OMEGA0:g}"))
    )  # fmt: skip
    (work / "0" / "nut").write_text(
        _field("nut", "volScalarField", f"[0 2 -1 {zero}]", "0", "nutkWallFunction",
               "        type calculated;\n        value uniform 0;")
    )  # fmt: skip
    fs = work / "system" / "fvSchemes"
    text = fs.read_text()
    rans_div = "    div(phi,k)      Gauss upwind;\n    div(phi,omega)  Gauss upwind;\n"
    text = text.replace("    div(phi,alpha)", rans_div + "    div(phi,alpha)", 1)
    fs.write_text(text + "\nwallDist\n{\n    method meshWave;\n}\n")
    fv = work / "system" / "fvSolution"
    text = fv.read_text()
    solver = (
        '    "(k|omega).*"\n    {\n        solver smoothSolver;\n        smoother symGaussSeidel;\n'
        "        tolerance 1e-7;\n        relTol 0;\n        minIter 1;\n    }\n"
    )
    head = text.index("solvers")
    brace = text.index("{", head)
    fv.write_text(text[: brace + 2] + solver + text[brace + 2 :])


def no_slip_only(work: Path, patch: str) -> None:
    """0/U: noSlip on `patch`, slip on the other two walls (the top is left as it is)."""
    u = work / "0" / "U"
    entries = "".join(
        f"    {name}\n    {{\n        type            {'noSlip' if name == patch else 'slip'};\n    }}\n"
        for name in PATCHES
    )
    text, count = re.subn(r'    "\(leftWall\|rightWall\|floor\)"\s*\{[^}]*\}\n', entries, u.read_text())
    if count != 1:
        raise RuntimeError(f"{u}: the walls' entry was not found")
    u.write_text(text)


def write_variant(
    work: Path, n: int, walls: str, nu: float, div_u: str, turbulence: str = "laminar", only: str = ""
) -> None:
    R.write_case(work, R.case_values(n, R.T_END_STAR * R.TIME_SCALE, walls=walls))
    if only:
        no_slip_only(work, only)
    tp = work / "constant" / "transportProperties"
    text = tp.read_text()
    water = text.index("water")
    text = text[:water] + re.sub(r"nu\s+[0-9.eE+-]+;", f"nu              {nu:g};", text[water:], count=1)
    tp.write_text(text)
    fs = work / "system" / "fvSchemes"
    fs.write_text(fs.read_text().replace(f"div(rhoPhi,U)   {DEFAULT_DIV_U};", f"div(rhoPhi,U)   {div_u};"))
    if div_u not in fs.read_text():
        raise RuntimeError(f"{fs}: could not set div(rhoPhi,U) to {div_u}")
    if turbulence == "kOmegaSST":
        write_rans(work)


def run_variant(
    n: int, walls: str, nu: float, div_u: str, turbulence: str = "laminar", only: str = ""
) -> dict:
    C.require("blockMesh", "setFields", "interFoam", "postProcess")
    label = label_of(n, walls, nu, div_u, turbulence, only)
    work = R.WORK_DIR / label
    write_variant(work, n, walls, nu, div_u, turbulence, only)
    logs = work / "logs"
    logs.mkdir()
    cpu0 = os.times()
    for cmd in (["blockMesh"], ["setFields"], ["interFoam"]):
        C.run(cmd, work, logs / f"{cmd[0]}.log", R.FOAM_ENV)
    cpu1 = os.times()
    C.run(["postProcess", "-func", "writeCellCentres", "-time", "0"], work, logs / "cc.log", R.FOAM_ENV)
    red = R.reduce_probes(work, n)
    m = R.impact_metrics(red["t"] / R.TIME_SCALE, red["p_star"])
    cm = corner.corner_metrics(corner.grid_fields(label, work, n), mu=nu * R.RHO_W)
    row = {
        "label": label,
        "cells_per_H": n,
        "walls": f"noSlip on {only} only, slip elsewhere" if only else walls,
        "nu_water": nu,
        "div_U": div_u,
        "turbulence": turbulence,
        **{k: round(m.get(k, float("nan")), 4) for k in FIELDS[6:11]},
        **{k: round(cm[k], 3) for k in ("backflow_u", "reversed_fraction", "downflow_v", "wall_shear_Pa")},
        "cpu_s": round(
            cpu1.children_user - cpu0.children_user + cpu1.children_system - cpu0.children_system, 1
        ),  # fmt: skip
        "load": round(os.getloadavg()[0], 2),
        "command": "python -m reference_cases.openfoam_lobovsky_impact.variants "
        + shlex.join(["--cells-per-H", str(n), "--walls", walls, "--nu-water", f"{nu:g}"])
        + " "
        + shlex.join(
            ["--div-U", div_u, "--turbulence", turbulence] + (["--no-slip-only", only] if only else [])
        ),
    }
    new = not OUT.is_file()
    with open(OUT, "a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        if new:
            w.writeheader()
        w.writerow(row)
    return row


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cells-per-H", type=int, default=20)
    p.add_argument("--walls", choices=R.WALLS, default="noSlip")
    p.add_argument("--nu-water", type=float, default=1e-6)
    p.add_argument("--div-U", default=DEFAULT_DIV_U)
    p.add_argument("--turbulence", choices=("laminar", "kOmegaSST"), default="laminar")
    p.add_argument("--no-slip-only", choices=("floor", "rightWall"), default="")
    p.add_argument("--nice", type=int, default=0)
    a = p.parse_args(argv)
    if a.nu_water < 0:
        print("--nu-water: must be >= 0", file=sys.stderr)
        return 2
    if a.no_slip_only and a.walls != "noSlip":
        print("--no-slip-only: needs --walls noSlip", file=sys.stderr)
        return 2
    if a.nice:
        os.nice(a.nice)
    t0 = time.perf_counter()
    row = run_variant(a.cells_per_H, a.walls, a.nu_water, a.div_U, a.turbulence, a.no_slip_only)
    print({k: v for k, v in row.items() if k != "command"}, f"wall {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
