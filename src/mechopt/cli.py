"""The `mechopt` command: list, describe, run, validate, sweep, report and benchmark scenes, the
registry's or the user's own (a scene is named by its id or by its file's path).

Exit codes: 0 solved (and every check passed), 1 a check or a target failed, 2 bad input (the
message names the file, key and allowed range; nothing was computed or written), 3 not solved
(INFEASIBLE, LIMIT, INACCURATE, FAILED), 130 interrupted.
"""
import argparse
import atexit
import csv
import errno
import inspect
import io
import json
import os
import re
import shlex
import signal
import sys
import threading
import warnings
from pathlib import Path

from mechopt import registry, verdicts
from mechopt.benchmarks import studies, study
from mechopt.drivers import set_mostly_by, steps_of
from mechopt.files import NotWritten, name_problem, output_problem, write_text_atomic
from mechopt.kit import interrupt
from mechopt.kit.errors import MechoptError, SceneError, SolverError
from mechopt.kit.result import Status, shown
from mechopt.mechanisms import templates
from mechopt.scene import parse_overrides

OK, CHECK_FAILED, BAD_INPUT, NOT_SOLVED, INTERRUPTED = 0, 1, 2, 3, 130

def main(argv=None) -> int:
    as_command = argv is None            # the process is this command (not a test or a caller's script)
    try:
        with interrupt.honoured():      # from the first step: Ctrl-C while parsing exits 130 too
            argv = sys.argv[1:] if argv is None else list(argv)
            args = _parser().parse_args(argv)
            args.argv = argv
            for folder in args.cases:
                registry.add_cases(folder)
            code = COMMANDS[args.command](args)
            interrupt.check()
            return code
    except MechoptError as exc:
        if interrupt.pending():         # a back end turned Ctrl-C into an error of its own
            return _interrupted()
        if isinstance(exc, SolverError):        # the input was valid; the back end failed on it
            print(f"error: not solved: {short(exc)}", file=sys.stderr)
            return NOT_SOLVED
        print(f"error: {short(exc)}", file=sys.stderr)
        return BAD_INPUT
    except KeyboardInterrupt:
        return _interrupted()
    except BrokenPipeError:             # `mechopt cases | head`: the reader left, not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return OK
    except OSError as exc:
        if exc.errno not in WRITE_FAILURES and not isinstance(exc, NotWritten):
            raise
        done = ("nothing was run and nothing written" if args.command == "new"
                else "the run itself finished: its result was computed but not written")
        todo = "free some space or choose another place" if exc.errno in WRITE_FAILURES else "choose another place"
        print(f"error: cannot write {exc.filename or 'an output'}: {exc.strerror} ({done}; {todo} and run it again)",
              file=sys.stderr)
        return CHECK_FAILED
    finally:
        if as_command:
            _exit_on_interrupt()


def _interrupted():
    print("interrupted (a sweep keeps its finished chunks: re-run the same command to resume)", file=sys.stderr)
    return INTERRUPTED


def _leave(code):
    """End the process now with `code`, the standard streams flushed."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


def _exit_on_interrupt():
    """From here on (the interpreter shutting down: Dask's and the pool's threads joined), Ctrl-C
    ends the process with 130 at once, not with a traceback and death by SIGINT (-2). From the
    exit hooks on, SIGINT is ignored: the interpreter then resets a Python-level handler to the
    default (death by SIGINT) before it tears the modules down, but leaves an ignored one ignored."""
    if threading.current_thread() is not threading.main_thread():
        return
    if interrupt.abandoned():       # a solver thread left in C code by Ctrl-C (a large LP's presolve):
        _leave(INTERRUPTED)         # the interpreter's clean-up must not run beside it
    signal.signal(signal.SIGINT, lambda signum, frame: _leave(INTERRUPTED))
    atexit.register(signal.signal, signal.SIGINT, signal.SIG_IGN)     # registered last: the first hook run


# a disk that filled up or turned read-only after the outputs were checked (before the work)
WRITE_FAILURES = {errno.ENOSPC, errno.EROFS, errno.EDQUOT, errno.EFBIG}


MAX_MESSAGE = 1000          # characters of an error line; the rest is counted, not printed


def short(message) -> str:
    """An error message of at most MAX_MESSAGE characters (a model listing every bad row of a table
    of millions would print megabytes)."""
    text = str(message)
    if len(text) <= MAX_MESSAGE:
        return text
    return f"{text[:MAX_MESSAGE]}... (and {len(text) - MAX_MESSAGE:,} more characters)"


class _Version(argparse.Action):
    """--version, the installed version looked up when asked (importlib.metadata: ~30 ms a run)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):
        super().__init__(option_strings, dest=dest, default=argparse.SUPPRESS, nargs=0,
                         help="show program's version number and exit")

    def __call__(self, parser, namespace, values, option_string=None):
        import mechopt
        print(f"mechopt {mechopt.__version__}")
        parser.exit()


def _parser():
    parser = argparse.ArgumentParser(prog="mechopt", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action=_Version)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--cases", action="append", default=[], type=Path, metavar="DIR",
                        help="a folder of your own scenes (*.toml, searched recursively) added to the registry; "
                             "repeatable; also the MECHOPT_CASES variable")
    common.add_argument("--quiet", action="store_true", help="no progress on stderr (bars only show on a terminal)")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("cases", parents=[common], help="list scene ids and titles")
    describe = sub.add_parser("describe", parents=[common],
                              help="every key --set reaches: unit, mark, allowed range, current value")
    describe.add_argument("case", help="a scene id or a scene file's path")
    new = sub.add_parser("new", parents=[common], help="write a commented scene to start from")
    new.add_argument("mechanism", choices=list(templates()),
                     help="cam-table: a cam given as a point table (a CSV written beside the scene); "
                          "press-design: the drive found by optimisation; cyclogram: a machine's timing "
                          "diagram from its table of operations (a CSV written beside the scene)")
    new.add_argument("file", type=Path, help="the scene file to write (not overwritten if it exists)")
    run = sub.add_parser("run", parents=[common], help="solve one scene and check it against its source")
    run.add_argument("case", help="a scene id or a scene file's path")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a parameter, solver setting or structure path (what-if); repeatable")
    run.add_argument("--json", type=Path, metavar="FILE", help="write the result as JSON (with the drivers, see --drivers)")
    run.add_argument("--drivers", action="store_true",
                     help="the headline values' largest elasticities to the assumed inputs (re-solves; always with --json)")
    run.add_argument("--plot", type=Path, metavar="DIR", help="write figures into DIR")
    run.add_argument("--dxf", type=Path, metavar="DIR",
                     help="write the cam profile or torch path as DXF (mm, closed polylines on named layers) into DIR")
    run.add_argument("--csv", type=Path, metavar="FILE",
                     help="write the run's arrays (trajectories: t_s, states, loads ...) as CSV columns")
    validate = sub.add_parser("validate", parents=[common],
                              help="run scenes and check them; exit 1 when any expectation fails")
    validate.add_argument("refs", nargs="*", metavar="CASE",
                          help="scene ids, files or folders (default: every scene in the registry)")
    validate.add_argument("--json", type=Path, metavar="FILE")
    bench = sub.add_parser("bench", parents=[common], help="accuracy against time for a mechanism's solvers")
    bench.add_argument("study", choices=list(studies()), help="a mechanism's study (mechopt/mechanisms.py) or sweep")
    bench.add_argument("--repeats", type=_positive_int, default=5, help="runs per point (>= 1); medians reported")
    bench.add_argument("--plot", type=Path, default=Path("out/bench"), metavar="DIR")
    bench.add_argument("--quick", action="store_true",
                       help="a short version where the study offers one (sweep: 900 variants a study, not 10^4)")
    fit = sub.add_parser("fit-force", parents=[common],
                         help="fit a polynomial force law to load-travel data (paper 001, eq. (1))")
    fit.add_argument("csv", type=Path, help="header names columns and units, e.g. travel_mm,load_N")
    fit.add_argument("--degree", type=int, default=4, help="1 to 6 (the paper: 4)")
    fit.add_argument("--segments", type=int, default=2, help="spans of travel on which errors are reported")
    fit.add_argument("--with-intercept", action="store_true", help="allow a constant term (default: F(0) = 0)")
    fit.add_argument("--json", type=Path, metavar="FILE", help="write the fitted coefficients and errors as JSON")
    sweep = sub.add_parser("sweep", parents=[common], help="what-if study: every variant of a scene, one Parquet table")
    sweep.add_argument("case", help="a scene id or a scene file's path")
    sweep.add_argument("--grid", action="append", default=[], metavar="KEY=START:STOP:NUM",
                       help="NUM evenly spaced values from START to STOP, or KEY=V1,V2,...: those values; "
                            "repeatable (all combinations)")
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
    sweep.add_argument("--max-variants", type=_positive_int, default=1_000_000, metavar="N",
                       help="refuse a sweep of more variants than this before any work (default 1,000,000)")
    report = sub.add_parser("report", parents=[common],
                            help="one static HTML page: validation table, figures, maps, bench plots")
    report.add_argument("--out", type=Path, default=Path("out/report"), metavar="DIR")
    report.add_argument("--bench", type=Path, default=Path("out/bench"), metavar="DIR",
                        help="folder of `mechopt bench` outputs to include (not re-run)")
    report.add_argument("--case", action="append", default=[], metavar="CASE",
                        help="only these scenes (ids, files or folders); repeatable")
    report.add_argument("--sweep", action="append", default=[], type=Path, metavar="FILE",
                        help="a `mechopt sweep --out` table whose maps to include; repeatable")
    return parser


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value}: expected a whole number >= 1")
    return value


def _cases(args) -> int:
    catalogue = registry.catalogue()
    width = max(len(s.id) for s in catalogue.scenes)
    for scene in catalogue.scenes:
        where = "" if scene.path.is_relative_to(registry.cases_dir()) else f"  [{scene.path}]"
        print(f"{scene.id:<{width}}  {scene.spec.title}{where}")
    _warn(catalogue.problems)
    return OK


def _describe(args) -> int:
    scene = registry.find(args.case)
    print(f"{scene.id}: {scene.spec.title}\nfile: {scene.path}\n"
          f"task {scene.spec.task}, solver {scene.spec.solver}, effects {', '.join(scene.spec.effects) or 'none'}")
    rows = scene.describe()
    params = scene.spec.params
    why = {k: (p.why + (f" (fitted to {p.on})" if p.on else "") if p.mark != "given" else p.where)
           for k, p in params.items()}
    _print_table(("key", "kind", "unit", "mark", "allowed", "value", "why / where"),
                 [(r["key"], r["kind"], r["unit"] or "-", r["mark"], r["range"], r["value"], why.get(r["key"], ""))
                  for r in rows])
    print("\nchange any of them with --set KEY=VALUE (structure: --set 'PATH=VALUE', a TOML value)")
    return OK


def _new(args) -> int:
    """Write a scene to start from, and every file it reads (its CSV tables, base and other
    scenes), each renamed with it: every name and content checked first (the scene loads with
    them), then all written, none over an existing file; a failure removes what this call wrote."""
    from mechopt.scene import id_problem
    template = registry.find(templates()[args.mechanism])
    new_id = f"my/{args.file.stem}"
    if id_problem(new_id):
        raise SceneError(f"{args.file}: the new scene's id would be {new_id!r}: {id_problem(new_id)}; name the file "
                         "with such characters, e.g. my-press.toml (nothing was written)", key="id")
    contents = {}
    _starting_files(template, args.file, contents, {})
    _check_new(contents)
    from mechopt.files import shipped
    from mechopt.scene import loads
    with shipped({str(p.resolve()): c.encode("utf-8") for p, c in contents.items()}):
        loads(contents[args.file], args.file)       # what we write must load (what it reads taken from `contents`)
    _write_new(contents)
    print(f"scene: {args.file} (from {template.id})" + "".join(f", with {p}" for p in contents if p != args.file)
          + f"; try: mechopt run {args.file}")
    return OK


_TABLE = re.compile(r'\bcsv = "([^"/\\]+)"')      # a table read from a CSV beside the scene


def _starting_files(scene, path, contents, sources) -> None:
    """Into `contents` ({path: text}): `scene` as the user's, at `path`, and every file its own
    file reads, copied beside it and named after it (`packaging-ops.csv` of `packaging.toml`
    becomes `mine-ops.csv` of `mine.toml`; its base `kd2322.toml` becomes `mine-kd2322.toml`,
    itself a scene of the user's with what it reads). `sources`: each copied scene's original."""
    from mechopt.scene import load
    own = scene.path.read_text(encoding="utf-8")
    sources[path] = scene.path.resolve()
    refs = {}
    for name in dict.fromkeys(_OTHER_SCENE.findall(own)):       # base = { scene = ... }, [structure.x] scene = ...
        other = load((scene.path.parent / name).resolve())
        mine = path.with_name(f"{path.stem}-{other.path.stem}.toml")
        refs[name] = mine.name
        if mine not in sources:
            _starting_files(other, mine, contents, sources)
        elif sources[mine] != other.path.resolve():     # two scenes of one name in different folders
            raise SceneError(f"{scene.path}: reads {sources[mine]} and {other.path}, which would both be copied "
                             f"as {mine}; name the new scene differently or copy them by hand (nothing was written)")
    text = scene_template(scene, f"my/{path.stem}", refs)
    for name in dict.fromkeys(_TABLE.findall(own)):             # { csv = "...", columns = [...] }
        mine = path.with_name(_renamed(name, scene.path.stem, path.stem))
        text = text.replace(f'csv = "{name}"', f'csv = "{mine.name}"')
        contents[mine] = (scene.path.parent / name).read_text(encoding="utf-8")
    contents[path] = text


def _renamed(name: str, old_stem: str, new_stem: str) -> str:
    """A companion file's name for the new scene: `<old stem>-rest` becomes `<new stem>-rest`;
    another name is prefixed with the new stem."""
    return f"{new_stem}-{name.removeprefix(f'{old_stem}-')}"


def _check_new(contents):
    """Refuse, before anything is written, a file of `new` that exists or cannot be created."""
    for path in contents:
        if path.exists() or path.is_symlink():
            raise SceneError(f"{path}: exists; name a new file (nothing was written)")
        problem = output_problem(path)
        if problem:
            raise SceneError(f"{path}: {problem} (nothing was written)")
        _writable_folder("new", path.parent)


def _write_new(contents):
    """Write every file of `contents`, none over an existing file; on any failure remove what was written."""
    written = []
    try:
        for path, text in contents.items():
            write_text_atomic(path, text, replace=False)
            written.append(path)
    except FileExistsError:
        _remove(written)
        raise SceneError(f"{path}: exists (made while `new` ran); name a new file (nothing was written)") from None
    except BaseException:
        _remove(written)
        raise


def _remove(paths):
    for path in paths:
        path.unlink(missing_ok=True)


_OTHER_SCENE = re.compile(r'scene = "([^"]+)"')      # a reference to another scene, relative to its file


def scene_template(scene, new_id: str, refs: dict[str, str] | None = None) -> str:
    """A scene's file as a user's starting point: a new id, its source's expectations dropped
    (they hold for the source's numbers only), references to other scenes renamed by `refs`
    (reference as written -> the copy's name) or else made absolute (the copy lives elsewhere),
    every parameter (a base scene's too) restated as `assumed` with why = "your value" (the
    source's provenance in a comment above it: a figure of the source describes the source's
    machine, not yours), and a header saying what to edit."""
    lines, out, skipping = scene.path.read_text(encoding="utf-8").splitlines(), [], False
    for line in lines:
        stripped = line.strip()
        if stripped.startswith("["):
            skipping = stripped.startswith(("[expect", "[params"))
            if stripped.startswith("[params"):
                out += ["[params]", *_your_params(scene)]
        if skipping:
            continue
        if stripped.startswith("id ="):
            line = f'id = "{new_id}"'
        out.append(_OTHER_SCENE.sub(lambda m: f'scene = "{_reference(scene, m[1], refs)}"', line))
    if "[params]" not in out and scene.spec.params:
        out += ["", "[params]", *_your_params(scene)]
    header = [f"# A scene of your own, started from {scene.id} ({scene.path.name}).",
              "# Edit [params] (the unit is in every name; say why you chose a value), [structure] and",
              "# [solver_settings]; `mechopt describe THIS_FILE` lists every key with its allowed range.",
              "# Add [expect.NAME] tables (value with abs or rel, or max/min, kind, where) for figures you",
              "# know: `mechopt run THIS_FILE` checks them.", ""]
    return "\n".join(header + out).rstrip() + "\n"


def _reference(scene, name, refs) -> str:
    return refs[name] if refs and name in refs else (scene.path.parent / name).resolve().as_posix()


def _your_params(scene) -> list[str]:
    """The scene's parameters as the user's: `assumed`, why = "your value"; a calibrated one says
    that it must be fitted again when what it was fitted with changes."""
    lines = []
    for key, p in scene.spec.params.items():
        said = {"given": f"given by the source ({p.where or scene.spec.source})", "assumed": f"assumed: {p.why}",
                "calibrated": f"calibrated on {p.on}: {p.why}"}[p.mark]
        why = "your value" + ("; calibrated in " + scene.id + " against " + p.on + ": re-derive it when its "
                              "inputs change" if p.mark == "calibrated" else "")
        lines += [f"# {scene.id}: {' '.join(said.split())}",
                  f"{key} = {{ value = {json.dumps(p.value)}, mark = \"assumed\", why = {json.dumps(why)} }}"]
    return lines


def _run(args) -> int:
    overrides = parse_overrides(args.set)
    _check_outputs(json_file=args.json, plot_dir=args.plot, table_file=args.csv)
    if args.dxf is not None:
        _short_names("--dxf", args.dxf)
        if args.dxf.exists() and not args.dxf.is_dir():
            raise SceneError(f"--dxf {args.dxf}: an existing file, not a folder")
        _writable_folder("--dxf", args.dxf)
        _probe("--dxf", args.dxf, folder=True)
        from mechopt.dxf import ezdxf_module
        ezdxf_module()                      # a missing extra is said before the solve, not after
    scene = registry.find(args.case)
    if args.dxf is not None:
        from mechopt.dxf import NothingToExport, dxf_path, refuse_before_solve
        try:                                # a scene that cannot be drawn is said before the solve, not after
            refuse_before_solve(scene, lambda: registry.pose(scene, overrides)[0])
        except NothingToExport as exc:
            print(f"dxf: {exc}; nothing was solved", file=sys.stderr)
            return CHECK_FAILED
        _check_outputs(table_file=dxf_path(scene, args.dxf), table_flag="--dxf", table_suffix=len(".lock"))
    result = registry.run(scene, overrides, drivers=args.drivers or args.json is not None)
    _print_run(result)
    if args.json:
        _write_json(args.json, result.as_dict())
    if args.csv:
        _write_text(args.csv, arrays_csv(result.arrays, args.csv))
        print(f"csv: {args.csv}")
    if args.plot:
        from mechopt.figures import plot_run
        paths = plot_run(result, args.plot)
        for path in paths:
            print(f"plot: {path}")
        if not paths:
            why = (f"status {result.status.value}: no solution to draw" if not result.success
                   else "its figures found nothing to draw in this result")
            print(f"plot: nothing drawn into {args.plot} ({why})", file=sys.stderr)
    if args.dxf is not None:
        return _write_dxf(result, args.dxf) or run_exit_code(result)
    return run_exit_code(result)


def _write_dxf(run, folder) -> int:
    """`run --dxf DIR`: the scene's curves as DXF, each layer's chordal error printed; a scene with
    nothing to export says so on stderr (exit 1 when it solved: the file asked for is not there)."""
    from mechopt.dxf import NothingToExport, export_run, notes
    try:
        written = export_run(run, folder)
    except NothingToExport as exc:
        print(f"dxf: {exc}", file=sys.stderr)
        return CHECK_FAILED if run.success else 0
    for line in notes([item for _, item in written]):
        print(f"dxf: {written[0][0]} {line}")
    return 0


def run_exit_code(run) -> int:
    """0 solved and checked, 1 a check failed, 3 not solved (unless the scene expects that status)."""
    if not run.status_as_expected:
        return NOT_SOLVED
    return OK if run.ok else CHECK_FAILED


def _validate(args) -> int:
    _check_outputs(json_file=args.json)
    scenes, problems = registry.select(args.refs)
    rows, runs = [], []
    step = _progress(args, len(scenes))
    for scene in scenes:
        step(scene.id)
        result = registry.run(scene)
        runs.append(result)
        for c in result.checks:
            rows.append((verdicts.VERDICTS.index(c.verdict), scene.id, c.name, c.kind, c.expected, shown(c.got),
                         _verdict(c), f"{result.result.timing.build_s + result.result.timing.solve_s:.3f}"))
    step()
    rows.sort(key=lambda row: row[0] if row[0] < len(verdicts.MISSES) else len(verdicts.MISSES))  # misses first
    _print_table(("case", "quantity", "kind", "expected", "got", "verdict", "time [s]"), [r[1:] for r in rows])
    checks = [c for r in runs for c in r.checks]
    failed = [c for c in checks if not c.ok]
    print(f"\n{len(checks) - len(failed)} passed, {len(failed)} failed")
    print(verdicts.summary_line(checks))
    for c in checks:
        if c.verdict in verdicts.MISSES and c.reason:
            print(f"  {c.verdict.replace('_', ' ')}: {c.name}: {c.reason}")
        elif c.verdict == "reproduced" and c.readings_after_figure:
            print(f"  reproduced with readings chosen after the figure: {c.name}: {'; '.join(c.readings_after_figure)}")
        elif c.verdict == "alternative":
            print(f"  alternative reading, not counted as reproduced: {c.name}: matched here; the reading taken is "
                  f"{c.alternative_to}'s")
    unchecked = [r.scene.id for r in runs if not r.checks]
    if unchecked:
        print(f"scenes with no expectations (solved, nothing to check): {', '.join(unchecked)}")
    _warn(problems)
    if args.json:
        _write_json(args.json, [r.as_dict() for r in runs])
    return CHECK_FAILED if failed or problems else OK


def _bench(args) -> int:
    _check_outputs(plot_dir=args.plot)
    module = study(args.study)
    quick = {}
    if args.quick:
        if "quick" not in inspect.signature(module.cli).parameters:
            raise SceneError(f"bench {args.study}: no --quick version (it takes seconds to a few minutes as it is)")
        quick = {"quick": True}
    said = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    text = module.cli(args.repeats, args.plot, progress=said, **quick)
    print(text)
    return CHECK_FAILED if "MISSED" in text else OK


def _fit_force(args) -> int:
    _check_outputs(json_file=args.json)
    from mechopt.force_data import read_force_csv
    from mechopt.solvers.press.force_fit import fit_force
    result = fit_force(*read_force_csv(args.csv), args.degree, segments=args.segments,
                       through_origin=not args.with_intercept)
    print(f"{args.csv}: degree {args.degree}, status {result.status.value}" + (f" ({result.message})" if result.message else ""))
    _print_table(("value", "got"), [(k, shown(v)) for k, v in result.values.items()])
    if args.json:
        _write_json(args.json, {"file": str(args.csv), "degree": args.degree, "status": result.status.value,
                                "message": result.message, "values": result.values})
    return OK if result.status is Status.SOLVED else NOT_SOLVED


def _sweep(args) -> int:
    from collections import Counter

    from mechopt import sweep
    grid = [sweep.parse_grid(g) for g in args.grid]
    random = [sweep.parse_random(r) for r in args.random]
    scene = registry.find(args.case)
    out = args.out or Path("out/sweep") / f"{scene.id.replace('/', '_')}.parquet"
    _check_outputs(table_file=out, plot_dir=args.plot, table_suffix=len(".parts"))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always", sweep.SweepWarning)
        try:
            table = sweep.sweep(scene, grid, random, samples=args.samples, seed=args.seed, out=out,
                                scheduler=args.scheduler, workers=args.workers, chunk=args.chunk,
                                max_variants=args.max_variants, progress=False if args.quiet else None)
        except sweep.SweepInterrupted as stop:
            print(f"interrupted: {stop}", file=sys.stderr)
            return INTERRUPTED
        finally:
            for warning in said:
                print(f"warning: {short(warning.message)}", file=sys.stderr)
    counts = Counter(table.column("status").to_pylist())
    print(f"{scene.id}: {table.num_rows} variants ({', '.join(f'{n} {s}' for s, n in sorted(counts.items()))})")
    print(f"table: {out}")
    if args.plot:
        from mechopt.figures.sweep import plot_sweep
        for path in plot_sweep(table, args.plot, scene=scene):
            print(f"plot: {path}")
    return OK


def _report(args) -> int:
    from mechopt.report import write_report
    _check_outputs(plot_dir=args.out)
    scenes, problems = registry.select(args.case)
    _warn(problems)
    step = _progress(args, len(scenes))
    path = write_report(args.out, scenes=scenes, bench_dir=args.bench, sweeps=args.sweep,
                        progress=lambda line: step(line.removeprefix("running ").removesuffix(" ...")),
                        command=shlex.join(["mechopt", *args.argv]))
    step()
    print(f"report: {path}")
    return OK


def arrays_csv(arrays, where) -> str:
    """A result's arrays as CSV columns (header: their names, with units); one row per sample."""
    if not arrays:
        raise SceneError(f"--csv {where}: this solver computes no arrays (only values); use --json")
    lengths = {len(a) for a in arrays.values()}
    if len(lengths) != 1:
        raise SceneError(f"--csv {where}: the arrays have different lengths {sorted(lengths)}; use --json")
    import numpy as np
    names = list(arrays)
    columns = [np.asarray(arrays[n]) for n in names]
    # a label column is text, the others numbers; each formatted a block of rows at a time, column by
    # column from Python values (tolist), not numpy scalars: ~3x faster at 10^5 rows, memory of a block
    cells = [text_cell if a.dtype.kind == "U" else "{:.12g}".format for a in columns]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")       # quotes a cell holding a comma, quote or line break
    writer.writerow(map(text_cell, names))
    for start in range(0, lengths.pop(), CSV_BLOCK):
        writer.writerows(zip(*(list(map(cell, a[start:start + CSV_BLOCK].tolist())) for a, cell in zip(columns, cells))))
    return out.getvalue()


CSV_BLOCK = 8192            # rows formatted at once by arrays_csv


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")     # a spreadsheet reads a cell starting so as a formula


def text_cell(text: str) -> str:
    """A text cell of a CSV made safe to open in a spreadsheet: one starting like a formula
    (=HYPERLINK(...), +, -, @) gets a leading ' (OWASP, CSV injection); numbers are written apart."""
    return "'" + text if text.startswith(FORMULA_START) else text


COMMANDS = {"cases": _cases, "describe": _describe, "new": _new, "run": _run, "validate": _validate,
            "bench": _bench, "fit-force": _fit_force, "sweep": _sweep, "report": _report}


def _check_outputs(*, json_file=None, plot_dir=None, table_file=None, table_flag="--out/--csv", table_suffix=0):
    """Refuse an output that cannot be written before any work is done (`table_suffix`: the
    characters its writer adds to the table's name for files beside it: `.parts`, `.lock`)."""
    for flag, path, example in (("--json", json_file, "result.json"), (table_flag, table_file, "table.parquet")):
        if path is None:
            continue
        _short_names(flag, path, table_suffix if path is table_file else 0)
        if path.is_dir() or str(path).endswith(os.sep) or path.name in ("", ".", ".."):
            raise SceneError(f"{flag} {path}: a folder; give a file name, e.g. {path / example}")
        _writable_folder(flag, path.parent)
        _probe(flag, path, longest_suffix=table_suffix if path is table_file else 0)
    if plot_dir is not None:
        _short_names("--plot/--out", plot_dir)
        if plot_dir.exists() and not plot_dir.is_dir():
            raise SceneError(f"--plot/--out {plot_dir}: an existing file, not a folder")
        _writable_folder("--plot/--out", plot_dir)
        _probe("--plot/--out", plot_dir, folder=True)


def _short_names(flag, path, longest_suffix=0):
    """Refuse a name too long for a file system (first: even asking whether it exists fails)."""
    problem = name_problem(path, longest_suffix)
    if problem:
        raise SceneError(f"{flag} {path}: {problem}; nothing was run")


def _probe(flag, path, **how):
    """Refuse what `files.output_problem` finds (a name too long, a dangling link, no file creatable there)."""
    problem = output_problem(path, **how)
    if problem:
        raise SceneError(f"{flag} {path}: {problem}; nothing was run")


def _writable_folder(flag, folder):
    existing = next((p for p in (folder, *folder.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise SceneError(f"{flag}: {existing} is a file, so {folder} cannot be a folder")
    if not os.access(existing, os.W_OK):
        raise SceneError(f"{flag}: {existing} is not writable")


def _progress(args, total):
    """`step(scene_id)` as each scene's run starts, `step()` when all are done: a tqdm bar on a
    terminal's stderr, a line "running ID ..." per scene when stderr is a file or pipe, nothing
    with --quiet."""
    if args.quiet:
        return lambda scene_id=None: None
    if not sys.stderr.isatty():
        return lambda scene_id=None: scene_id and print(f"running {scene_id} ...", file=sys.stderr, flush=True)
    from tqdm import tqdm
    bar = tqdm(total=total, unit="scene", file=sys.stderr, dynamic_ncols=True, leave=False)

    def step(scene_id=None):
        if bar.desc:                           # the previous scene is done
            bar.update()
        if scene_id is None:
            bar.close()
        else:
            bar.set_description_str(scene_id)
    return step


def _warn(problems):
    for line in problems:
        print(f"warning: skipped {short(line)}", file=sys.stderr)


def _print_run(run):
    r = run.result
    print(f"{run.scene.id}: {run.scene.spec.title}")
    print(f"source: {run.scene.spec.source}")
    if run.overrides:
        print(f"what-if: {', '.join(f'{k}={v}' for k, v in run.overrides.items())}")
    print(f"status: {r.status.value}  ({r.message})" if r.message else f"status: {r.status.value}")
    if r.violated:
        print(f"violated: {', '.join(r.violated)}")
    for sentence in r.warnings:
        print(f"warning: {sentence}")
    drivers = r.diagnostics.get("drivers", {})
    for sentence in set_mostly_by(drivers) + steps_of(drivers):
        print(f"drivers: {sentence}")
    _print_table(("value", "got"), [(k, shown(v)) for k, v in r.values.items()])
    if run.checks:
        _print_table(("check", "expected", "got", "kind", "where", ""),
                     [(c.name, c.expected, shown(c.got), c.kind, c.where, _verdict(c)) for c in run.checks])
    elif run.scene.spec.expect:
        print("checks: skipped (parameters overridden; the source's figures hold for its own parameters)")
    print(f"timing: build {r.timing.build_s:.4f} s, solve {r.timing.solve_s:.4f} s")


def _verdict(check):
    return check.label if check.ok else f"FAIL ({check.label})"


def _print_table(header, rows):
    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    print()
    for row in (header, *rows):
        print("  ".join(str(x).ljust(w) for x, w in zip(row, widths)).rstrip())


def _write_json(path, payload):
    _write_text(path, json.dumps(payload, indent=2))
    print(f"json: {path}")


def _write_text(path, text):
    write_text_atomic(path, text)

if __name__ == "__main__":
    sys.exit(main())
