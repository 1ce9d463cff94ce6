"""The option-combination table behind the defaults (issue 15 item 5): for each combination of
the numerics options, the errors on the dam break (a/20), the still tank (H/40), the impact
pressure (Lobovsky et al. 2014, H/20), the wall time of each, blow-ups and wall reflections.

    python -m verification.scheme_table [--out verification/results/scheme_table.md]

Every number is one run; the checks and their tolerances are those of each case's module
(dam_break.py, hydrostatic.py, impact_pressure.py). Wall times: stepping only, 1 Numba thread;
the 1-minute load average when each case ended is given with it, since this machine is shared.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import numba

from . import dam_break, hydrostatic, impact_pressure
from .common import RESULTS

SEED = {"scheme": "seed"}
COMBINATIONS = {
    "seed scheme": SEED,
    "seed + midpoint_density": {**SEED, "leapfrog": "midpoint_density"},
    "seed + hydrostatic images": {**SEED, "image_pressure": "hydrostatic"},
    "seed + Fourtakas diffusion": {**SEED, "density_diffusion": "fourtakas"},
    "seed + wall repulsion": {**SEED, "wall_repulsion": True},
    "midpoint + hydrostatic images": {
        **SEED,
        "leapfrog": "midpoint_density",
        "image_pressure": "hydrostatic",
    },
    "midpoint + Fourtakas + hydrostatic images": {
        **SEED,
        "leapfrog": "midpoint_density",
        "image_pressure": "hydrostatic",
        "density_diffusion": "fourtakas",
    },
    "midpoint + Molteni + hydrostatic images + repulsion": {"density_diffusion": "molteni"},
    "seed leap-frog + Fourtakas + hydrostatic images + repulsion (soil-scene default)": {"leapfrog": "seed"},
    "defaults (midpoint + Fourtakas + hydrostatic images + repulsion)": {},
}


def dotted(numerics):
    return {f"numerics.{k}": v for k, v in numerics.items()}


def load():
    return round(os.getloadavg()[0], 1)


def row(label, numerics):
    out = {"options": label}
    dam = dam_break.run(dam_break.DEFAULT_RESOLUTION, **dotted(numerics))
    out["dam"] = {c.metric: (round(c.value, 4), c.passed) for c in dam.checks}
    out["dam_wall"], out["dam_load"] = round(dam.wall_time, 1), load()
    tank = hydrostatic.run(40, **dotted(numerics))
    out["tank"] = {
        "p_err": round(float(tank.series["mean_pressure_error"]), 5),
        "mach_end": float(tank.series["mach"][-1]),
        "reflections": int(tank.sim_reflections),
        "passed": tank.passed,
    }
    out["tank_wall"], out["tank_load"] = round(tank.wall_time, 1), load()
    imp = impact_pressure.run(impact_pressure.DEFAULT_RESOLUTION, out_dir=None, **numerics)
    m = imp.series["metrics"]
    ref = imp.series["reference"]
    out["impact"] = {
        "status": m["status"],
        "reflections": m["reflections"],
        "impact_s2": m.get("impact_s2"),
        "plateau_mean_s2_minus_median": m.get("plateau_mean_s2", float("nan")) - ref["plateau_median"],
        "plateau_sd_s2": m.get("plateau_sd_s2"),
        "plateau_sd_1ms_s2": m.get("plateau_sd_1ms_s2"),
        "peak_s1": m.get("peak_s1"),
    }
    out["impact_wall"], out["impact_load"] = round(imp.wall_time, 1), load()
    return out


def num(value, spec):
    """A number for the table, or '-' where the run did not produce it (blew up before)."""
    if value is None or value != value:
        return "-"
    return format(value, spec)


def markdown(rows):
    head = (
        "| options | dam a/20: front speed / front vs exp. / height vs exp. / front vs OpenFOAM "
        "(tol. 0.074 / 0.166 / 0.037 / 0.144) | dam wall s (load) | tank H/40: p err / Mach end / "
        "reflections (tol. 0.0325 / 0.01 / 0) | tank wall s (load) | impact H/20: status, reflections | "
        "t*_imp s2 (exp. 2.44-2.49) | plateau s2 - median (band +-0.115) | plateau sd s2, 1 ms / acoustic "
        "filter 4H/c0 (exp. 0.050 / 0.051; tol. 0.115 + e) | "
        "peak s1, 1 ms (Table 2: 2.55-4.45) | impact wall s (load) |"
    )
    lines = [head, "|" + "---|" * 11]
    keys = ["front speed", "front vs Martin", "wall height vs Martin", "front vs OpenFOAM"]
    for r in rows:
        dam = []
        for k in keys:
            hit = [v for name, v in r["dam"].items() if name.startswith(k)]
            dam.append(f"{hit[0][0]:.4g}{'' if hit[0][1] else ' FAIL'}" if hit else "-")
        t, i = r["tank"], r["impact"]
        cells = [
            r["options"],
            " / ".join(dam),
            f"{r['dam_wall']} ({r['dam_load']})",
            f"{t['p_err']:.3g} / {t['mach_end']:.3g} / {t['reflections']}",
            f"{r['tank_wall']} ({r['tank_load']})",
            f"{i['status']}, {i['reflections']}",
            num(i["impact_s2"], ".3f"),
            num(i["plateau_mean_s2_minus_median"], "+.3f"),
            f"{num(i.get('plateau_sd_1ms_s2'), '.3f')} / {num(i['plateau_sd_s2'], '.3f')}",
            num(i["peak_s1"], ".1f"),
            f"{r['impact_wall']} ({r['impact_load']})",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


SOIL = {"seed scheme": "seed", "defaults": "default"}


def soil_rows():
    """The soil column collapse (column_collapse.py, dx = 5 mm) with the seed's scheme and with the
    defaults (for soil: equilibrium image stress and the wall repulsion; no water terms)."""
    from . import column_collapse

    rows = []
    for label, scheme in SOIL.items():
        res = column_collapse.run(20, overrides={"numerics": {"scheme": scheme}})
        s = res.series
        failed = [c.metric for c in res.checks if not c.passed]
        rows.append(
            f"| {label} | {s['runout']:.4f} | {s['wall_height']:.4f} | {s['wall_reflections']} | "
            f"{', '.join(failed) or 'none'} | {res.wall_time:.1f} ({load()}) |"
        )
    head = "| soil collapse, dx = 5 mm | runout (m; exp. 0.442) | height at wall (m; exp. 0.099) | "
    head += "wall reflections | failed checks | wall s (load) |\n|---|---|---|---|---|---|\n"
    return head + "\n".join(rows) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(RESULTS / "scheme_table.md"))
    parser.add_argument("--only", nargs="*", help="labels (substrings) of the combinations to run")
    parser.add_argument("--soil", action="store_true", help="also the soil collapse, seed scheme vs defaults")
    args = parser.parse_args(argv)
    numba.set_num_threads(1)
    jsonl = Path(args.out).with_suffix(".jsonl")
    done = {}
    if jsonl.exists():
        done = {
            json.loads(line)["options"]: json.loads(line) for line in jsonl.read_text().splitlines() if line
        }
    # the two ends first (the seed's scheme and the defaults), so a run cut short still has them
    order = sorted(COMBINATIONS, key=lambda k: (k != "seed scheme", not k.startswith("defaults")))
    for label in order:
        numerics = COMBINATIONS[label]
        if label in done or (args.only and not any(s in label for s in args.only)):
            continue
        done[label] = row(label, numerics)
        with open(jsonl, "a") as fh:
            fh.write(json.dumps(done[label], default=float) + "\n")
    rows = [done[k] for k in COMBINATIONS if k in done]
    text = markdown(rows)
    soil = Path(args.out).with_name("scheme_table_soil.md")
    if args.soil:
        soil.write_text(soil_rows())
    if soil.exists():
        text += "\n" + soil.read_text()
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
