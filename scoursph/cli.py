"""The command line: `scoursph run SCENE`, `scoursph verify CASE`, `scoursph report`,
`scoursph study scour ...` (the scouring study, verification/scour_study.py).

Exit status: 0 success, 1 numerical blow-up (outputs so far are kept) or a failed
verification check, 2 bad input (scene file, option, output directory or restart; nothing
written), 130 / 143 stopped by SIGINT / SIGTERM after writing a checkpoint (128 + the signal).
Every error is one line on standard error, starting "scoursph: error:".
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from solver.errors import BlowUpError, SceneError
from solver.output.run_dir import RunDirError


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (the usage itself is in --help)."""

    def error(self, message):
        self.exit(2, f"scoursph: error: {self.prog}: {message} (see {self.prog} --help)\n")


def _at_least_one(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _parser():
    p = _Parser(prog="scoursph", description="ScourSPH: SPH for soil-water interaction")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a scene file")
    r.add_argument(
        "scene", type=Path, help="a scene file, or the name of a shipped scene (e.g. dam_break_2d)"
    )
    r.add_argument("--out", type=Path, help="output directory (default runs/<scene name>)")
    r.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an earlier run in the output directory (only the files a run writes are removed)",
    )
    r.add_argument(
        "--restart",
        type=Path,
        metavar="RUN_DIR",
        help="continue the run in RUN_DIR from its newest readable checkpoint (or the one --checkpoint "
        "names); outputs continue in RUN_DIR. SCENE must be the run's scene (scene.end_time, output.* and "
        "parallel.* may change)",
    )
    r.add_argument(
        "--checkpoint",
        metavar="NAME",
        help="with --restart: the checkpoint to continue from, by file name in RUN_DIR/checkpoints/ "
        "(000001234.h5) or step number (1234); later checkpoints of that run are removed",
    )
    r.add_argument("--explain", action="store_true", help="print the plan (passes, terms, fields) and exit")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--threads", type=_at_least_one, help="Numba threads per process (at least 1)")
    r.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene key before validation, e.g. --set numerics.xsph_epsilon=0 (repeatable)",
    )
    r.add_argument(
        "--rebalance-every", type=int, metavar="N", help="MPI: rebalance the domain cuts every N steps"
    )
    r.add_argument(
        "--imbalance-threshold",
        type=float,
        metavar="X",
        help="MPI: rebalance when the largest rank holds more than X times the mean count",
    )
    v = sub.add_parser("verify", help="run a verification case and check it against its references")
    v.add_argument("case", help="case name, or 'all'")
    v.add_argument(
        "--resolution", type=int, help="particles across the reference length (case default if omitted)"
    )
    v.add_argument(
        "--study", action="store_true", help="resolution study: error and wall time at 3+ spacings"
    )
    v.add_argument("--out", type=Path, default=Path("runs/verification"))
    v.add_argument("--quiet", action="store_true")
    from verification.nightly.options import add_arguments as add_report_arguments

    add_report_arguments(sub.add_parser("report", help="nightly verification report: HTML page + JSON"))
    st = sub.add_parser(
        "study",
        help="a parameter study: 'scour' runs verification/scour_study.py (issue 11), e.g. "
        "'scoursph study scour report' or 'scoursph study scour run saturated 0.11 --end 0.5'",
    )
    st.add_argument("study", choices=("scour",))
    st.add_argument("study_args", nargs=argparse.REMAINDER, help="its arguments (default: report)")
    return p


def _fail(message, status):
    print(f"scoursph: error: {message}", file=sys.stderr)
    return status


def main(argv=None):
    args = _parser().parse_args(argv)
    if getattr(args, "threads", None) is not None:
        import numba

        most = numba.config.NUMBA_NUM_THREADS
        if args.threads > most:
            return _fail(
                f"--threads: at most {most} here (NUMBA_NUM_THREADS or the core count), got {args.threads}", 2
            )
        numba.set_num_threads(args.threads)
    if args.command == "run":
        return _run(args)
    if args.command == "report":
        from verification.nightly.report import main as report

        return report(args)
    if args.command == "study":
        from verification.scour_study import main as scour_study

        return scour_study(args.study_args or ["report"])
    return _verify(args)


def _run(args):
    from solver.parallel.launch import communicator
    from solver.plan import build_plan, explain
    from solver.scene import load_scene, resolve_scene_path

    comm = communicator()
    if comm.size > 1:
        _share_cores_among_ranks(comm, explicit=args.threads)
    overrides = list(args.set)
    if args.rebalance_every is not None:
        overrides.append(f"parallel.rebalance_every={args.rebalance_every}")
    if args.imbalance_threshold is not None:
        overrides.append(f"parallel.imbalance_threshold={args.imbalance_threshold}")
    try:
        scene = load_scene(resolve_scene_path(args.scene), overrides)
        _check_memory(scene, comm.size, args.scene)
    except SceneError as exc:
        if comm.is_root():
            _fail(str(exc), 2)
        return 2
    if args.explain:
        if comm.is_root():
            print(explain(build_plan(scene), scene))
        return 0
    from solver.interrupt import Interrupted
    from solver.output.checkpoint import CheckpointError
    from solver.run import run_scene

    out = args.out or Path("runs") / scene.scene.name
    if args.restart is not None and (args.overwrite or args.out is not None):
        if comm.is_root():
            _fail("--restart continues in the run's own directory: it takes no --out or --overwrite", 2)
        return 2
    run_dir = out
    if args.restart is not None:  # the run directory, also when --restart names a checkpoint file
        run_dir = args.restart.parent.parent if args.restart.is_file() else args.restart
    if args.checkpoint is not None and args.restart is None:
        if comm.is_root():
            _fail(
                f"--checkpoint {args.checkpoint}: it names a checkpoint of --restart RUN_DIR, "
                "which is missing",
                2,
            )
        return 2
    try:
        result = run_scene(
            scene,
            out,
            comm=comm,
            quiet=args.quiet,
            overwrite=args.overwrite,
            restart=args.restart,
            checkpoint=args.checkpoint,
        )
    except RunDirError as exc:
        if comm.is_root():
            _fail(f"--out {exc}", 2)
        return 2
    except CheckpointError as exc:
        if comm.is_root():
            _fail(f"--restart {exc}", 2)
        return 2
    except Interrupted as exc:
        if comm.is_root():
            _interrupted(exc, args, run_dir)
        return exc.status
    except KeyboardInterrupt:  # a second SIGINT, serial (interrupt.py; MPI aborts): no checkpoint
        _fail("stopped at once by a second SIGINT: no checkpoint written (earlier ones remain)", 130)
        return 130
    except BlowUpError as exc:
        if comm.is_root():
            _fail(f"{exc}; outputs written so far are kept in {run_dir}/", 1)
        return 1
    if comm.is_root():
        # three significant digits: a small or slow run read "0.00 M" with two decimals
        print(
            f"run completed: {result.steps} steps, {result.particles} particles, {result.wall_time:.1f} s "
            "wall, "
            f"{result.particle_steps_per_second / 1e6:.3g} M particle-steps/s"
        )
        out = result.out_dir  # a restart's is the run directory it continues
        print(
            f"outputs in {out}/: particles.h5 (HDF5 series), particles.pvd (ParaView), final.png, "
            "scene.toml, run.json"
        )
        if (out / "scour.csv").is_file():
            print(
                f"scour: {out}/scour.csv (depth, deepest point, eroded area per output time), "
                f"{out}/scour_profiles.csv (surface z_s(x, t)), {out}/scour.png (surfaces and depth d(t))"
                + (f", {out}/scour_hole.png (the hole)" if (out / "scour_hole.png").is_file() else "")
            )
            last = _last_scour_row(out / "scour.csv")
            if last is not None:
                print(
                    f"scour depth at t = {float(last['t_s']):.4g} s: {1000 * float(last['depth_m']):.1f} mm "
                    f"(deepest at x = {float(last['x_deepest_m']):.3f} m)"
                )
    return 0


def _last_scour_row(path):
    """The last row of a run's scour.csv as a dict, or None if it has none."""
    import csv

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return rows[-1] if rows else None


def _interrupted(exc, args, run_dir):
    """The one line a stopped run leaves on standard error (with the command that resumes it)."""
    if exc.checkpoint is not None:
        sets = "".join(f" --set {shlex.quote(s)}" for s in args.set)
        resume = f"scoursph run {shlex.quote(str(args.scene))}{sets} --restart {shlex.quote(str(run_dir))}"
        how = f"checkpoint written to {exc.checkpoint}; resume with {resume}"
    elif exc.error is not None:
        how = f"no checkpoint written ({exc.error}); the earlier ones in {run_dir} remain"
    else:
        how = "no checkpoint (outputs not written)"
    at = f"at t = {exc.t:.6g} s (step {exc.step})"
    print(f"scoursph: interrupted by {exc.signame} {at}; {how}", file=sys.stderr)


# Resident memory per particle measured for the 2D dam break (README "Speed"): a lower bound,
# so a scene is refused only when it certainly does not fit.
BYTES_PER_PARTICLE = 391


def _check_memory(scene, ranks, path):
    """Bad input (exit 2) if the particles alone would not fit in this machine's memory."""
    import os

    from solver.geometry import estimated_particles

    try:
        memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return
    n = estimated_particles(scene)
    need = n * BYTES_PER_PARTICLE / max(ranks, 1)
    if need > memory:
        raise SceneError(
            path,
            "scene.spacing",
            f"about {n:.3g} particles need at least {need / 2**30:.1f} GiB per process, "
            f"more than this machine's {memory / 2**30:.1f} GiB",
        )


def _share_cores_among_ranks(comm, explicit):
    """Under MPI each rank gets cores / (ranks on this node) Numba threads, at least one,
    unless --threads or NUMBA_NUM_THREADS says otherwise: ranks x threads above the core
    count made 2 ranks x 2 threads 28x slower than serial on this 2-core machine."""
    import os

    import numba

    if explicit or "NUMBA_NUM_THREADS" in os.environ:
        return
    local = next(
        (
            int(os.environ[k])
            for k in ("MPI_LOCALNRANKS", "OMPI_COMM_WORLD_LOCAL_SIZE", "MV2_COMM_WORLD_LOCAL_SIZE")
            if os.environ.get(k, "").isdigit()
        ),
        comm.size,
    )
    numba.set_num_threads(max(1, min(numba.config.NUMBA_NUM_THREADS, (os.cpu_count() or 1) // max(local, 1))))


def _verify(args):
    from verification.registry import run_cases

    return run_cases(args.case, args.out, resolution=args.resolution, study=args.study, quiet=args.quiet)


if __name__ == "__main__":
    sys.exit(main())
