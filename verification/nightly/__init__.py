"""The nightly verification report (`scoursph report`, `make nightly`).

Every case of verification/registry.py runs in its own process (a crash or a hang stops only
that case) at its nightly resolution, then its resolution study where the case affords one;
the results, the accuracy-against-cost data, the benchmark gate and the trend over the
previous nights become one static HTML page and one JSON file. The interface a case offers
the report is in docs/nightly_report.md.

    run_case.py   the child process: one case, its checks, figures, study rows, timings
    collect.py    runs the children (two side by side), with a CPU-time limit and a wall timeout each
    history.py    the history file (one JSON line per night) and the regression flags
    plots.py      accuracy against wall and CPU time; trends over the nights
    page.py       the HTML page (no script, images embedded as base64 PNG)
    report.py     `scoursph report`: all of the above, results folder, exit status
"""
