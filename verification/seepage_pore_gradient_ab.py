"""The seepage cases with one pore-water numerics option off and on (issue 10): should it become the
default? Each case's own `run(RESOLUTION)` (its checks, its tolerances) once per setting, set on every
scene the case builds (seepage_common.scene's numerics). The options (--key):
  * pore_pressure_gradient "symmetric" | "corrected" (docs/seepage.md, "The pore water's own pressure
    force"; the sheet pile is left out: it sets "corrected" itself);
  * pore_density_diffusion "none" | "antuono" (docs/seepage.md, "The pore water's odd-even mode").

    NUMBA_NUM_THREADS=1 python -m verification.seepage_pore_gradient_ab CASE|all SETTING [RESOLUTION]
        [--key KEY]

runs one case (or all four, one after the other) with one setting in this process (the CPU times are
each case's own timing of its stepping, compiles excluded) and writes
results/seepage_pore_gradient/CASE_SETTING.json (results/seepage_pore_diffusion/ for the other key);
`--table` writes the table of every JSON there (pore_gradient_ab.md, pore_diffusion_ab.md)."""

from __future__ import annotations

import importlib
import json
import os
import sys

from . import seepage_common as sc
from .common import RESULTS, script_parser

KEYS = {  # numerics key: (its settings, off first; the results' directory and table)
    "pore_pressure_gradient": (("symmetric", "corrected"), RESULTS / "seepage_pore_gradient",
                               "pore_gradient_ab.md"),
    "pore_density_diffusion": (("none", "antuono"), RESULTS / "seepage_pore_diffusion",
                               "pore_diffusion_ab.md"),
}  # fmt: skip
OUT = KEYS["pore_pressure_gradient"][1]
CASES = {  # the CI sizes (tests/test_seepage_verification.py), each the case's own run()
    "seepage_bed_at_rest": 10,
    "seepage_darcy": 10,
    "seepage_terzaghi": 10,
    "seepage_critical_gradient": 12,
}
SETTINGS = tuple(s for settings, _, _ in KEYS.values() for s in settings)


def cpu_of(runs):
    """Summed CPU seconds of a case's runs (dicts with "cpu", possibly nested in lists/dicts)."""
    if isinstance(runs, dict):
        return runs["cpu"] if "cpu" in runs else sum(cpu_of(r) for r in runs.values())
    if isinstance(runs, (list, tuple)):
        return sum(cpu_of(r) for r in runs)
    return 0.0


def key_of(setting):
    return next(k for k, (settings, _, _) in KEYS.items() if setting in settings)


def run_case(case, setting, resolution=None):
    original = sc.scene
    key = key_of(setting)

    def scene(*args, **numerics):
        numerics.setdefault(key, setting)
        return original(*args, **numerics)

    sc.scene = scene
    try:
        module = importlib.import_module(f"verification.{case}")
        res = module.run(resolution or CASES[case])
    finally:
        sc.scene = original
    out = {
        "case": case, "setting": setting, "resolution": res.resolution, "cpu_s": cpu_of(res.series),
        "wall_s": res.wall_time, "load": round(os.getloadavg()[0], 2),
        "threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
        "blow_ups": [n for n in res.notes if "BLEW UP" in n],
        "checks": [{"metric": c.metric, "value": float(c.value), "tolerance": float(c.tolerance),
                    "passed": bool(c.passed)} for c in res.checks],
    }  # fmt: skip
    out_dir = KEYS[key][1]
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / f"{case}_{setting}.json").write_text(json.dumps(out, indent=1))
    return out


def table(key="pore_pressure_gradient"):
    (off, on), out_dir, name = KEYS[key]
    lines = [
        f"| case (resolution) | check | tolerance | {off} | {on} | change |",
        "|---|---|---|---|---|---|",
    ]
    cpu = ["", f"| case | CPU {off} (s) | CPU {on} (s) | ratio | load |", "|---|---|---|---|---|"]
    for case in CASES:
        runs = {}
        for s in (off, on):
            path = out_dir / f"{case}_{s}.json"
            if path.exists():
                runs[s] = json.loads(path.read_text())
        if len(runs) < 2:
            continue
        sym, cor = runs[off], runs[on]
        by = {c["metric"]: c for c in cor["checks"]}
        for c in sym["checks"]:
            d = by.get(c["metric"])
            if d is None:
                continue
            mark = lambda x: f"{x['value']:+.4g}" + ("" if x["passed"] else " FAIL")  # noqa: E731
            change = abs(d["value"]) - abs(c["value"])
            head = f"| {case} ({sym['resolution']}) | {c['metric']} | {c['tolerance']:.4g}"
            lines.append(f"{head} | {mark(c)} | {mark(d)} | {change:+.2g} |")
        for r in (sym, cor):
            if r["checks"] and all(c["value"] != c["value"] for c in r["checks"]):  # all NaN
                blew = "; ".join(r.get("blow_ups", [])) or "every run raised BlowUpError (cpu 0, no gradient)"
                lines.append(f"| {case} ({r['resolution']}) | {r['setting']}: BLEW UP | | | | {blew} |")
        ratio = cor["cpu_s"] / sym["cpu_s"] if cor["cpu_s"] else float("nan")
        load = f"{sym['load']}; {cor['load']}"
        cpu.append(f"| {case} | {sym['cpu_s']:.1f} | {cor['cpu_s']:.1f} | {ratio:.2f} | {load} |")
    text = "\n".join(lines + cpu) + "\n"
    (out_dir / name).write_text(text)
    return text


def main(argv=None):
    parser = script_parser(sys.modules[__name__])
    parser.add_argument("case", nargs="?", choices=[*CASES, "all"], help="a seepage case, or all four")
    parser.add_argument("setting", nargs="?", choices=SETTINGS, help="a setting of one of the keys")
    parser.add_argument("resolution", nargs="?", type=int, help="the case's resolution (default: CI size)")
    parser.add_argument("--table", action="store_true", help="write the table of the results on disk")
    parser.add_argument("--key", choices=list(KEYS), default="pore_pressure_gradient", help="--table's key")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.table:
        print(table(args.key))
        return
    if args.case is None or args.setting is None:
        parser.error("case and setting: required without --table (e.g. all symmetric)")
    if args.resolution is not None and args.resolution <= 0:
        parser.error(f"resolution: a positive integer, got {args.resolution}")
    for case in list(CASES) if args.case == "all" else [args.case]:
        r = run_case(case, args.setting, args.resolution)
        print(json.dumps(r, indent=1), flush=True)


if __name__ == "__main__":
    main()
