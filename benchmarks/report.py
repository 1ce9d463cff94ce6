"""Markdown table of a pytest-benchmark JSON (for the README):

.venv/bin/python -m pytest benchmarks/bench_step.py --benchmark-only -o addopts="" --benchmark-json=bench.json
.venv/bin/python benchmarks/report.py bench.json
"""

import json
import sys


def main(path):
    data = json.load(open(path))
    print(f"machine: {data['machine_info'].get('cpu', {}).get('brand_raw', '?')}, {data['datetime']}")
    print("| benchmark | median | figures |")
    print("|---|---|---|")
    for b in data["benchmarks"]:
        info = ", ".join(
            f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in b["extra_info"].items()
        )
        print(f"| {b['name']} | {b['stats']['median'] * 1e3:.2f} ms | {info} |")


if __name__ == "__main__":
    main(sys.argv[1])
