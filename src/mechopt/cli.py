"""The `mechopt` command: list, run, validate, sweep, report and benchmark the registry's scenes."""
import argparse
import json
import sys
from pathlib import Path

from mechopt import registry
from mechopt.benchmarks import STUDIES, study
from mechopt.models.errors import MechoptError
from mechopt.scene import parse_overrides
from mechopt.solvers.result import Status


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="mechopt", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("cases", help="list scene ids and titles")
    run = sub.add_parser("run", help="solve one scene and check it against its source")
    run.add_argument("case")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a parameter or solver setting (what-if); repeatable")
    run.add_argument("--json", type=Path, metavar="FILE", help="write the result as JSON")
    run.add_argument("--plot", type=Path, metavar="DIR", help="write figures into DIR")
    validate = sub.add_parser("validate", help="run every scene; non-zero exit when any expectation fails")
    validate.add_argument("--json", type=Path, metavar="FILE")
    bench = sub.add_parser("bench", help="accuracy against time for a mechanism's solvers")
    bench.add_argument("study", choices=list(STUDIES), help="a registered study (benchmarks/__init__.py)")
    bench.add_argument("--repeats", type=int, default=5, help="runs per point; medians are reported")
    bench.add_argument("--plot", type=Path, default=Path("out/bench"), metavar="DIR")
    fit = sub.add_parser("fit-force", help="fit a polynomial force law to load-travel data (paper 001, eq. (1))")
    fit.add_argument("csv", type=Path, help="header names columns and units, e.g. travel_mm,load_N")
    fit.add_argument("--degree", type=int, default=4, help="1 to 6 (the paper: 4)")
    fit.add_argument("--segments", type=int, default=2, help="spans of travel on which errors are reported")
    fit.add_argument("--with-intercept", action="store_true", help="allow a constant term (default: F(0) = 0)")
    sweep = sub.add_parser("sweep", help="what-if study: every variant of a scene, one Parquet table")
    sweep.add_argument("case")
    sweep.add_argument("--grid", action="append", default=[], metavar="KEY=START:STOP:NUM",
                       help="NUM evenly spaced values from START to STOP; repeatable (all combinations)")
    sweep.add_argument("--random", action="append", default=[], metavar="KEY=LOW:HIGH",
                       help="uniform draws (with --samples); repeatable")
    sweep.add_argument("--samples", type=int, default=0, metavar="N", help="random draws per grid point")
    sweep.add_argument("--seed", type=int, default=0, help="seed of the random draws")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786 (default: this process)")
    sweep.add_argument("--workers", type=int, default=1, metavar="N",
                       help="local processes without --scheduler (1: this process)")
    sweep.add_argument("--chunk", type=int, default=100, metavar="N", help="variants per task")
    sweep.add_argument("--out", type=Path, metavar="FILE", help="Parquet table (default out/sweep/<case>.parquet)")
    sweep.add_argument("--plot", type=Path, metavar="DIR", help="write the sweep's figures into DIR")
    report = sub.add_parser("report", help="one static HTML page: validation table, figures, bench plots")
    report.add_argument("--out", type=Path, default=Path("out/report"), metavar="DIR")
    report.add_argument("--bench", type=Path, default=Path("out/bench"), metavar="DIR",
                        help="folder of `mechopt bench` outputs to include (not re-run)")
    report.add_argument("--case", action="append", default=[], metavar="ID", help="only these scenes; repeatable")
    report.add_argument("--sweep", action="append", default=[], type=Path, metavar="FILE",
                        help="a `mechopt sweep --out` table whose maps to include; repeatable")
    args = parser.parse_args(argv)
    try:
        return {"cases": _cases, "run": _run, "validate": _validate, "bench": _bench,
                "fit-force": _fit_force, "sweep": _sweep, "report": _report}[args.command](args)
    except MechoptError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


def _cases(args) -> int:
    scenes = registry.all_scenes()
    width = max(len(s.id) for s in scenes)
    for scene in scenes:
        print(f"{scene.id:<{width}}  {scene.spec.title}")
    return 0


def _run(args) -> int:
    scene = registry.find(args.case)
    result = registry.run(scene, parse_overrides(args.set))
    _print_run(result)
    if args.json:
        _write_json(args.json, result.as_dict())
    if args.plot:
        from mechopt.plots import plot_run
        for path in plot_run(result, args.plot):
            print(f"plot: {path}")
    return 0 if result.ok and result.result.status is not Status.FAILED else 1


def _validate(args) -> int:
    rows, runs = [], []
    for scene in registry.all_scenes():
        print(f"running {scene.id} ...", file=sys.stderr, flush=True)
        result = registry.run(scene)
        runs.append(result)
        for c in result.checks:
            rows.append((scene.id, c.name, c.kind, c.expected, _fmt(c.got), _verdict(c),
                         f"{result.result.timing.build_s + result.result.timing.solve_s:.3f}"))
    _print_table(("case", "quantity", "kind", "expected", "got", "check", "time [s]"), rows)
    counts = registry.tally(c for r in runs for c in r.checks)
    print(f"\n{sum(counts.values()) - counts['failed']} passed, {counts['failed']} failed")
    print(f"of the passed: {counts['reproduced']} reproduce a published value, {counts['calibrated']} are "
          f"calibrations (fitted, or following from a fit by construction), {counts['consistent']} are "
          "derived (independent computations, bounds, statuses)")
    if args.json:
        _write_json(args.json, [r.as_dict() for r in runs])
    return 1 if counts["failed"] else 0


def _bench(args) -> int:
    print(study(args.study).cli(args.repeats, args.plot, progress=lambda line: print(line, file=sys.stderr, flush=True)))
    return 0


def _fit_force(args) -> int:
    from mechopt.force_data import read_force_csv
    from mechopt.solvers.press.force_fit import fit_force
    result = fit_force(*read_force_csv(args.csv), args.degree, segments=args.segments,
                       through_origin=not args.with_intercept)
    print(f"{args.csv}: degree {args.degree}, status {result.status.value}" + (f" ({result.message})" if result.message else ""))
    _print_table(("value", "got"), [(k, _fmt(v)) for k, v in result.values.items()])
    return 0 if result.status is Status.SOLVED else 1


def _sweep(args) -> int:
    from collections import Counter

    from mechopt import sweep
    scene = registry.find(args.case)
    out = args.out or Path("out/sweep") / f"{scene.id.replace('/', '_')}.parquet"
    table = sweep.sweep(scene, [sweep.parse_grid(g) for g in args.grid],
                        [sweep.parse_random(r) for r in args.random], samples=args.samples, seed=args.seed,
                        out=out, scheduler=args.scheduler, workers=args.workers, chunk=args.chunk)
    counts = Counter(table.column("status").to_pylist())
    print(f"{scene.id}: {table.num_rows} variants ({', '.join(f'{n} {s}' for s, n in sorted(counts.items()))})")
    print(f"table: {out}")
    if args.plot:
        from mechopt.figures.sweep import plot_sweep
        for path in plot_sweep(table, args.plot, scene=scene):
            print(f"plot: {path}")
    return 0


def _report(args) -> int:
    from mechopt.report import write_report
    scenes = [registry.find(c) for c in args.case] if args.case else None
    path = write_report(args.out, scenes=scenes, bench_dir=args.bench, sweeps=args.sweep,
                        progress=lambda line: print(line, file=sys.stderr, flush=True))
    print(f"report: {path}")
    return 0


def _print_run(run):
    r = run.result
    print(f"{run.scene.id}: {run.scene.spec.title}")
    print(f"source: {run.scene.spec.source}")
    if run.overrides:
        print(f"what-if: {', '.join(f'{k}={v}' for k, v in run.overrides.items())}")
    print(f"status: {r.status.value}  ({r.message})" if r.message else f"status: {r.status.value}")
    if r.violated:
        print(f"violated: {', '.join(r.violated)}")
    _print_table(("value", "got"), [(k, _fmt(v)) for k, v in r.values.items()])
    if run.checks:
        _print_table(("check", "expected", "got", "kind", "where", ""),
                     [(c.name, c.expected, _fmt(c.got), c.kind, c.where, _verdict(c)) for c in run.checks])
    elif run.scene.spec.expect:
        print("checks: skipped (parameters overridden; the source's figures hold for its own parameters)")
    print(f"timing: build {r.timing.build_s:.4f} s, solve {r.timing.solve_s:.4f} s")


def _verdict(check):
    return ("ok (calibrated)" if check.calibrated else "ok") if check.ok else "FAIL"


def _print_table(header, rows):
    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    print()
    for row in (header, *rows):
        print("  ".join(str(x).ljust(w) for x, w in zip(row, widths)).rstrip())


def _fmt(value):
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _write_json(path, payload):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(payload, indent=2))
    print(f"json: {path}")


if __name__ == "__main__":
    sys.exit(main())
