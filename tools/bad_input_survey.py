"""Hostile and careless inputs (two rounds of hardening), each run as a user would, its outcome classified.

    python tools/bad_input_survey.py [--only NAME ...] [--json FILE]

Each probe runs `python -m mechopt ...` (or a short Python snippet) in a scratch folder, memory
capped at 6 GB, with a wall-clock limit, and is classified:

* clear: the exit code a user was promised (2 bad input, 130 interrupted, ...), one short line
  naming what is wrong, nothing outside the outputs named touched, no content of a referenced
  file echoed;
* unclear: the right exit code but a message that is long (> 600 characters), echoes content or
  says nothing useful;
* traceback: a Python traceback, or death by a signal;
* hang: still running at the time limit;
* wrong: another exit code, a file outside the named outputs changed, more output than a probe's
  bound (`max_output`), or Ctrl-C honoured later than a probe allows (`exit_within_s`).

A probe's `echo_of` names a file (/etc/passwd) whose lines must not show in what the command says.

A survey, not a test (tests/test_hardening_*.py pin each item). The first round's counts, 42 probes:
before (main at 6bfc3fa) 8 clear, 3 unclear, 20 traceback, 4 hang, 7 wrong; after (branch harden)
41 clear, 1 wrong (damping_one: stop-impact's solver turns a roller leaving its cam into bad input;
its owner's fix). The deleted_lock probe was rewritten after the first run to a second writer that
holds the new lock (before, with the second run to completion: a traceback).

The second round's probes (classes "35.1 tmp" to "35.11 nonsense", one or more per defect it lists), 45:
before (main at ebb99eb, the probes as they are now) 3 clear, 3 unclear, 18 traceback, 1 hang, 20 wrong;
after (the merged branches files35, input35, signals35 and the follow-ups) 42 clear, 2 unclear, 0 traceback,
0 hang, 0 wrong (one full run, then the four probes mended after it re-run). The two unclear are the
front door's: press_too_much_work exits 3 with the right status but CasADi prints its inputs' dump (2 kB) on
stderr; workers_1000 says the cap in one line, after the HiGHS banner twice and a progress bar (606 characters).
Planting a link at `<output>.<pid>.tmp` needs the writer's pid: the probes guess the next 400 pids
(/proc/sys/kernel/ns_last_pid), or run the sweep in-process where its pid is its own.
"""
import argparse
import json
import os
import resource
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

PY = sys.executable
ROOT = Path(__file__).resolve().parents[1]
SECRET = "root:x:0:0:root:/root:/bin/bash:SECRET-TAIL-0123456789"    # a short prefix may show, not all
MAX_MESSAGE = 600

SCENE = """id = "mine/probe"
title = "a probe"
source = "a test"
task = "cam_profile.ProfileFit"
solver = "cam_cutter.minimax"
[params]
err_width_mm = {{ value = 0.4, mark = "assumed", why = "a test" }}
[solver_settings]
count = 200
[structure]
points_mm = {points}
"""


@dataclass
class Probe:
    klass: str                      # the hardening round's section
    name: str
    setup: object                   # f(folder) -> argv (after python), or (argv, check(folder) -> problem)
    codes: tuple = (2,)             # exit codes a user was promised
    timeout: float = 60.0
    sigint_after: float | None = None
    must_say: str = ""              # a clear message names this (the key or file at fault)
    must_not_say: str = ""          # ... and does not say this (a wrong reading of the input)
    echo_of: str = ""               # a file whose lines must not show in the output (a secret it names)
    exit_within_s: float | None = None   # after Ctrl-C the command ends this soon, else "wrong"
    max_output: int | None = None   # stdout + stderr + files written in the folder, in bytes, else "wrong"


def mechopt(*args):
    return ["-m", "mechopt", *map(str, args)]


def write(folder, name, text):
    path = Path(folder) / name
    path.write_text(text, encoding="utf-8")
    return path


def victim(folder):
    return write(folder, "victim.txt", "precious\n")


def intact(path, text="precious\n"):
    def check(folder):
        path_ = Path(path)
        same = path_.is_file() and path_.read_bytes() == text.encode()     # a victim may now hold binary data
        return None if same else f"{path} was changed or removed"
    return check


# --- section 1: files outside the outputs named ----------------------------------------------------

def lock_symlink(folder):
    v = victim(folder)
    os.symlink(v, Path(folder) / "o.parquet.lock")
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:2", "--out",
                   Path(folder) / "o.parquet"), intact(v)


def parts_symlink(folder):
    other = Path(folder) / "elsewhere"
    other.mkdir()
    keep = write(other, "data.parquet", "precious\n")
    os.symlink(other, Path(folder) / "o.parquet.parts")
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:2", "--out",
                   Path(folder) / "o.parquet"), intact(keep)


def lock_is_folder(folder):
    (Path(folder) / "o.parquet.lock").mkdir()
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:2", "--out",
                   Path(folder) / "o.parquet")


def no_fcntl(folder):
    return ["-c", "import sys; sys.modules['fcntl'] = None; import mechopt.sweep, mechopt.report, mechopt.cli; "
                  "print('ok')"]


def plot_into_file_parent(folder):
    write(folder, "afile", "x")
    return mechopt("run", "loom/group1", "--plot", Path(folder) / "afile" / "figs")


def full_disk_json(folder):
    # /dev/full: every write fails with ENOSPC, as on a full disk
    snippet = ("import errno, mechopt.files as f, mechopt.cli as c\n"
               "def full(path, data): raise OSError(errno.ENOSPC, 'No space left on device', str(path))\n"
               "f.write_bytes_atomic = full\nc.write_text_atomic = lambda p, t: full(p, t)\n"
               "import sys; sys.exit(c.main(['run', 'loom/group1', '--json', sys.argv[1]]))")
    return ["-c", snippet, str(Path(folder) / "r.json")]


def deleted_lock(folder):
    """After the first chunk the lock is deleted and a second writer takes a new one (and holds
    it, still running): the first must not go on writing beside it (exit 2, its parts kept)."""
    snippet = f"""
import fcntl, os, sys
from pathlib import Path
from mechopt import registry, sweep
out = Path({str(folder)!r}) / "o.parquet"
held = []
def second_writer(rows):
    if held: return
    os.unlink(str(out) + ".lock")
    fd = os.open(str(out) + ".lock", os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    held.append(fd)
from mechopt.kit.errors import MechoptError
try:
    sweep.sweep(registry.find("loom/group1"), [sweep.parse_grid("amplitude_limit_mm=0.1:0.12:4")], out=out,
                chunk=1, progress=False, on_chunk=second_writer)
except MechoptError as exc:
    print("error:", exc, file=sys.stderr)
    sys.exit(2)
"""
    return ["-c", snippet]


# --- section 2: hostile files ------------------------------------------------------------------------

def secret(folder):
    return write(folder, "passwd", "\n".join([SECRET] * 5) + "\n")


def csv_secret(folder):
    s = secret(folder)
    scene = write(folder, "s.toml", SCENE.format(points=f'{{ csv = "{s}", columns = ["x_mm", "y_mm"] }}'))
    return mechopt("run", scene)


def base_secret(folder):
    s = secret(folder)
    scene = write(folder, "s.toml", f'base = {{ scene = "{s}" }}\n' + SCENE.format(points="[[0, 0], [1, 1]]"))
    return mechopt("run", scene)


def lever_secret(folder):
    s = write(folder, "lever.toml", f'id = "x"\ntitle = "{SECRET}"\nsource = 3\n')
    scene = write(folder, "s.toml", SCENE.format(points=f'{{ scene = "{s}" }}'))
    return mechopt("run", scene)


def scene_dev_zero(folder):
    return mechopt("run", "/dev/zero")


def base_dev_zero(folder):
    return mechopt("run", write(folder, "s.toml", 'base = { scene = "/dev/zero" }\n' + SCENE.format(points="[]")))


def csv_dev_zero(folder):
    points = '{ csv = "/dev/zero", columns = ["x_mm", "y_mm"] }'
    return mechopt("run", write(folder, "s.toml", SCENE.format(points=points)))


def force_dev_zero(folder):
    return mechopt("fit-force", "/dev/zero")


def scene_fifo(folder):
    fifo = Path(folder) / "s.toml"
    os.mkfifo(fifo)
    return mechopt("run", fifo)


def csv_fifo(folder):
    fifo = Path(folder) / "p.csv"
    os.mkfifo(fifo)
    points = f'{{ csv = "{fifo}", columns = ["x_mm", "y_mm"] }}'
    return mechopt("run", write(folder, "s.toml", SCENE.format(points=points)))


def csv_many_rows(folder):
    path = Path(folder) / "big.csv"
    with open(path, "w") as f:
        f.write("travel_mm,load_N\n")
        f.write("1,x\n" * 2_000_000)
    return mechopt("fit-force", path)


def hostile_meta(folder, text='{"case": "<script>alert(1)</script>", "spec": "<b>x</b>", "scene_sha256": 3}'):
    import pyarrow as pa
    import pyarrow.parquet as pq
    path = Path(folder) / "h.parquet"
    table = pa.table({"variant": [0], "status": ["SOLVED"], "message": ["<script>alert(2)</script>"],
                      "x": [1.0]}).replace_schema_metadata({b"mechopt.sweep": text.encode()})
    pq.write_table(table, path)
    return path


def no_script(folder):
    page = Path(folder) / "rep" / "index.html"
    return "<script>alert" in page.read_text() and "script in the page" if page.exists() else None


def report_hostile_meta(folder):
    path = hostile_meta(folder)
    return mechopt("report", "--case", "loom/group1", "--sweep", path, "--out", Path(folder) / "rep"), no_script


def report_hostile_message(folder):
    """A well-formed sweep whose rows carry script: escaped in the page."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    meta = {"case": "loom/group1", "scene_sha256": "0" * 64,
            "spec": {"case": "loom/group1", "grid": [{"key": "<script>alert(3)</script>", "low": 0, "high": 1,
                                                      "num": 2}], "random": [], "samples": 0, "seed": 0}}
    path = Path(folder) / "h.parquet"
    table = pa.table({"<script>alert(3)</script>": [0.0, 1.0], "variant": [0, 1], "status": ["SOLVED", "FAILED"],
                      "message": ["<script>alert(4)</script>"] * 2, "x": [1.0, 2.0]})
    pq.write_table(table.replace_schema_metadata({b"mechopt.sweep": json.dumps(meta).encode()}), path)
    return mechopt("report", "--case", "loom/group1", "--sweep", path, "--out", Path(folder) / "rep"), no_script


def out_meta_not_json(folder):
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:2", "--out",
                   hostile_meta(folder, "not json{"))


def out_meta_wrong_types(folder):
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:2", "--out",
                   hostile_meta(folder, '{"case": 1, "spec": [1], "scene_sha256": null}'))


def report_meta_deep(folder):
    return mechopt("report", "--case", "loom/group1", "--sweep", hostile_meta(folder, "[" * 100_000 + "]" * 100_000),
                   "--out", Path(folder) / "rep")


def toml_nesting(folder):
    return mechopt("run", write(folder, "s.toml", SCENE.format(points="[" * 5000 + "]" * 5000)))


def expression_nesting(folder):
    return mechopt("run", "cam-cutter/other-profile", "--set", "x_expr=" + "(" * 3000 + "t" + ")" * 3000)


def long_literal_set(folder):
    return mechopt("run", "loom/group1", "--set", "amplitude_limit_mm=1" + "0" * 5000)


def long_literal_scene(folder):
    return mechopt("run", write(folder, "s.toml", SCENE.format(points="[[0, 1" + "0" * 5000 + "], [1, 1]]")))


def long_float_scene(folder):
    return mechopt("run", write(folder, "s.toml", SCENE.format(points="[[0, 1" + "0" * 400 + ".0], [1, 1]]")))


def task_not_class(folder):
    text = SCENE.format(points="[[0, 0], [1, 1]]").replace('task = "cam_profile.ProfileFit"', 'task = "cam_profile.np"')
    return mechopt("run", write(folder, "s.toml", text))


def solver_not_function(folder):
    text = SCENE.format(points="[[0, 0], [1, 1]]").replace('"cam_cutter.minimax"', '"cam_cutter.METHODS"')
    return mechopt("run", write(folder, "s.toml", text))


def csv_huge_values(folder):
    rows = "x_mm,y_mm\n" + "".join(f"{1e300 * (k % 2)},{k}\n" for k in range(20))
    write(folder, "p.csv", rows)
    return mechopt("run", write(folder, "s.toml", SCENE.format(points='{ csv = "p.csv", columns = ["x_mm", "y_mm"] }')))


def seed_negative(folder):
    return mechopt("sweep", "loom/group1", "--random", "amplitude_limit_mm=0.1:0.12", "--samples", "2", "--seed", "-1",
                   "--out", Path(folder) / "o.parquet")


def cases_root(folder):
    return mechopt("cases", "--cases", "/")


# --- section 3: no hang ------------------------------------------------------------------------------

def speeds_500(folder):
    return mechopt("run", "stop-impact/rebound-177rpm", "--set", "speeds_rpm=[" + ", ".join(["177"] * 500) + "]")


def silent_server():
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held = []

    def accept():
        while True:
            try:
                held.append(server.accept())     # accepted, never answered: not a Dask scheduler
            except OSError:
                return
    threading.Thread(target=accept, daemon=True).start()
    return server


def scheduler_not_dask(folder):
    server = silent_server()
    port = server.getsockname()[1]
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:2", "--scheduler",
                   f"tcp://127.0.0.1:{port}", "--out", Path(folder) / "o.parquet")


# --- section 4: Ctrl-C ---------------------------------------------------------------------------------

def ctrl_c_loom_repaired(folder):
    return mechopt("run", "loom/group1-repaired")


def ctrl_c_validate(folder):
    return mechopt("validate", "stop-impact/amplitude-law", "loom/group1-repaired")


def ctrl_c_stop_sweep(folder):
    return mechopt("sweep", "stop-impact/amplitude-law", "--grid", "damping_ratio=0.04:0.06:40", "--chunk", "1",
                   "--out", Path(folder) / "o.parquet")


# --- section 5: legal input ----------------------------------------------------------------------------

def missing_structure_table(folder):
    return mechopt("run", "loom/group1", "--set", "windows=[]")


def grid_selector(folder):
    return mechopt("sweep", "loom/group1", "--grid", "operations[from=3,to=7].min_deg=10:40:4", "--out",
                   Path(folder) / "o.parquet")


def bom_scene(folder):
    text = (ROOT / "cases" / "cam-cutter" / "minimax.toml").read_text(encoding="utf-8").replace(
        'id = "cam-cutter/minimax"', 'id = "mine/bom"').replace("count = 1000", "count = 100")
    path = Path(folder) / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    return mechopt("run", path), None


def derive_missing(folder):
    text = SCENE.format(points="[[0, 0], [1, 1]]") + '[derive]\nt0_rad = "no/such-scene:x"\n'
    return mechopt("run", write(folder, "s.toml", text))


def damping_one(folder):
    return mechopt("run", "stop-impact/amplitude-law", "--set", "damping_ratio=1")


# --- the second round: temporary names, foreign files, bounded everything, no traceback ----------------------

PACKAGING = ROOT / "cases" / "loom" / "packaging.toml"
LIFT_CAM = ROOT / "cases" / "stop-impact" / "lift-cam-profile.toml"
GRID = ("--grid", "amplitude_limit_mm=0.1:0.12:2")


def packaging(folder, rows=None, id_="mine/packaging", extra=""):
    """The packaging machine as a user's scene in `folder`: its timing table's rows edited by `rows`
    (a function of the list of CSV rows), its id `id_`."""
    import csv as csv_
    with open(PACKAGING.with_name("packaging-ops.csv"), encoding="utf-8", newline="") as f:
        table = list(csv_.reader(f))
    table = rows(table) if rows else table
    with open(Path(folder) / "packaging-ops.csv", "w", encoding="utf-8", newline="") as f:
        csv_.writer(f).writerows(table)
    text = PACKAGING.read_text(encoding="utf-8").replace('id = "loom/packaging"', f"id = {json.dumps(id_)}")
    return write(folder, "s.toml", text + extra)


def renamed(*names):
    """A `rows` edit: the first operations take these names."""
    def edit(table):
        for row, name in zip(table[1:], names):
            row[2] = name
        return table
    return edit


def snippet(code):
    """argv running `code` (mechopt imported as m, cli as cli; `folder` the probe's folder)."""
    return ["-c", "import os, sys\nfrom pathlib import Path\nfrom mechopt import cli\n" + code]


def planted(folder, names):
    """Symlinks to a victim at each of `names` (temporary names a writer might use); its check."""
    v = victim(folder)
    for name in names:
        path = Path(folder) / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() and not path.is_symlink():
            os.symlink(v, path)
    return intact(v)


def next_pids(count=400):
    """The process ids the next processes are likely to get (a writer naming its temporary by pid)."""
    try:
        last = int(Path("/proc/sys/kernel/ns_last_pid").read_text())
    except OSError:
        return []
    return range(last + 1, last + 1 + count)


def tmp_link_json(folder):
    check = planted(folder, [f"r.json.{pid}.tmp" for pid in next_pids()])
    return mechopt("run", "loom/group1", "--json", Path(folder) / "r.json"), check


def tmp_link_dxf(folder):
    check = planted(folder, [f"d/stop-impact_lift-cam-profile.dxf.{pid}.tmp" for pid in next_pids()])
    return mechopt("run", "stop-impact/lift-cam-profile", "--dxf", Path(folder) / "d"), check


def tmp_link_new(folder):
    check = planted(folder, [f"{name}.{pid}.tmp" for pid in next_pids() for name in ("m.toml", "m-ops.csv")])
    return mechopt("new", "cyclogram", Path(folder) / "m.toml"), check


def tmp_link_sweep(folder):
    """The sweep's pid is in its lock: links planted at its merge's and parts' temporary names as
    soon as the first chunk is in (the sweep run in-process, so that its pid is known)."""
    check = planted(folder, [])
    code = f"""
from mechopt import registry, sweep
folder = Path({str(folder)!r})
out = folder / "o.parquet"
def plant(rows):
    pid = os.getpid()
    names = [f"o.parquet.{{pid}}.tmp"] + [f"o.parquet.parts/part-{{k}}.parquet{{s}}.{{pid}}.tmp"
                                          for k in range(4) for s in ("", ".sha256")]
    for name in names:
        if not (folder / name).exists():
            os.symlink(folder / "victim.txt", folder / name)
sweep.sweep(registry.find("loom/group1"), [sweep.parse_grid("amplitude_limit_mm=0.1:0.12:3")], out=out, chunk=1,
            progress=False, on_chunk=plant)
"""
    return snippet(code), check


def foreign_tmp_glob(folder):
    keep = write(folder, "results.parquet.12345.tmp", "precious\n")
    return mechopt("sweep", "loom/group1", *GRID, "--out", Path(folder) / "*.parquet"), intact(keep)


def foreign_tmp_backup(folder):
    keep = write(folder, "o.parquet.backup.tmp", "precious\n")
    return mechopt("sweep", "loom/group1", *GRID, "--out", Path(folder) / "o.parquet"), intact(keep)


def lock_hardlink(folder):
    v = victim(folder)
    os.link(v, Path(folder) / "o.parquet.lock")
    return mechopt("sweep", "loom/group1", *GRID, "--out", Path(folder) / "o.parquet"), intact(v)


def first_sweep(folder):
    """An interrupted sweep in `folder`: its parts folder with the first chunk's part and sha256
    (the sweep run in-process, stopped after its first chunk as Ctrl-C would)."""
    code = f"""
from mechopt import registry, sweep
def stop(rows):
    raise KeyboardInterrupt
try:
    sweep.sweep(registry.find("loom/group1"), [sweep.parse_grid("amplitude_limit_mm=0.1:0.12:3")],
                out=Path({str(Path(folder) / "o.parquet")!r}), chunk=1, progress=False, on_chunk=stop)
except BaseException:
    pass
"""
    subprocess.run([PY, *snippet(code)], cwd=folder, capture_output=True, timeout=300)
    return Path(folder) / "o.parquet.parts"


def resume_args(folder):
    return mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:3", "--chunk", "1", "--out",
                   Path(folder) / "o.parquet")


def sidecar_fifo(folder):
    parts = first_sweep(folder)
    for sidecar in parts.glob("part-*.parquet.sha256"):
        sidecar.unlink()
        os.mkfifo(sidecar)
    return resume_args(folder)


def sidecar_dev_zero(folder):
    parts = first_sweep(folder)
    for sidecar in parts.glob("part-*.parquet.sha256"):
        sidecar.unlink()
        os.symlink("/dev/zero", sidecar)
    return resume_args(folder)


def infeasible_chain(folder, operations=200_000):
    """A chain of 200,000 1-degree operations in a 10-degree cycle: INFEASIBLE, its conflict as
    long (a million once printed 87 MB; 20,000 print 1.5 MB and write a 2 MB --json on main):
    what is printed and written must stay bounded."""
    with open(Path(folder) / "ops.csv", "w", encoding="utf-8") as f:
        f.write("from,to,min_deg\n")
        f.writelines(f"e{k},e{k + 1},1\n" for k in range(operations))
    scene = write(folder, "s.toml", 'id = "mine/chain"\ntitle = "a long chain"\nsource = "a test"\n'
                  'task = "loom.Cyclogram"\nsolver = "loom.plan_cyclogram"\n'
                  '[params]\ncycle_deg = { value = 10.0, mark = "assumed", why = "a test" }\n'
                  '[structure]\noperations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n')
    return mechopt("run", scene, "--json", Path(folder) / "r.json")


def points_csv(folder, text):
    """A cam point table `p.csv` holding `text`, and the scene that reads it."""
    write(folder, "p.csv", text)
    return mechopt("run", write(folder, "s.toml", SCENE.format(points='{ csv = "p.csv", columns = ["x_mm", "y_mm"] }')))


def csv_wide_header(folder):
    return points_csv(folder, ",".join(f"c{k}" for k in range(100_000)) + "\n1,2\n")


def csv_big_cell(folder):
    return points_csv(folder, "x_mm,y_mm\n" + "1" * 200_000 + ",2\n")


def csv_million_rows(folder):
    """Exactly 10^6 data rows and a trailing newline: within the limit, not "1,000,002 lines"."""
    with open(Path(folder) / "f.csv", "w") as f:
        f.write("travel_mm,load_N\n")
        f.writelines(f"{k * 1e-6:.6f},{k * 1e-3:.3f}\n" for k in range(1_000_000))
    return mechopt("fit-force", Path(folder) / "f.csv")


def csv_etc_passwd(folder):
    points = '{ csv = "/etc/passwd", columns = ["x_mm", "y_mm"] }'
    return mechopt("run", write(folder, "s.toml", SCENE.format(points=points)))


def ops_csv_etc_passwd(folder):
    scene = packaging(folder)
    scene.write_text(scene.read_text(encoding="utf-8").replace('csv = "packaging-ops.csv"', 'csv = "/etc/passwd"'),
                     encoding="utf-8")
    return mechopt("run", scene)


DOLLARS = renamed("$x^$ feed", r"$\frac{ push", "a_b return", "100% fold")


def dollar_plot(folder):
    return mechopt("run", packaging(folder, DOLLARS), "--plot", Path(folder) / "figs")


def dollar_report(folder):
    return mechopt("report", "--case", packaging(folder, DOLLARS), "--out", Path(folder) / "rep")


def dollar_report_sweep(folder):
    scene = packaging(folder, DOLLARS)
    subprocess.run([PY, *mechopt("sweep", scene, "--grid", "speed_rpm=50:60:2", "--out", Path(folder) / "o.parquet")],
                   cwd=folder, capture_output=True, timeout=300)
    return mechopt("report", "--case", scene, "--sweep", Path(folder) / "o.parquet", "--out", Path(folder) / "rep")


LONG_ID = "mine/" + "x" * 300


def long_id_dxf(folder):
    return mechopt("run", lift_cam(folder, LONG_ID), "--dxf", Path(folder) / "d")


def long_id_plot(folder):
    return mechopt("run", packaging(folder, id_=LONG_ID), "--plot", Path(folder) / "figs")


def long_id_sweep(folder):
    return mechopt("sweep", packaging(folder, id_=LONG_ID), "--grid", "speed_rpm=50:60:2")


def dxf_dangling(folder):
    os.symlink(Path(folder) / "nowhere" / "d", Path(folder) / "d")
    return mechopt("run", "stop-impact/lift-cam-profile", "--dxf", Path(folder) / "d")


def dxf_proc(folder):
    return mechopt("run", "stop-impact/lift-cam-profile", "--dxf", "/proc/d")


def dxf_name_is_folder(folder):
    (Path(folder) / "d" / "stop-impact_lift-cam-profile.dxf").mkdir(parents=True)
    return mechopt("run", "stop-impact/lift-cam-profile", "--dxf", Path(folder) / "d")


def json_proc(folder):
    return mechopt("run", "loom/group1", "--json", "/proc/r.json")


def sweep_out_proc(folder):
    return mechopt("sweep", "loom/group1", *GRID, "--out", "/proc/o.parquet")


def stale_tmp_folder(folder):
    """Folders named as a sweep's temporaries beside its output (not its own: never removed)."""
    stale = [Path(folder) / f"o.parquet.{pid}.tmp" for pid in (1, *next_pids(50))]
    for path in stale:
        path.mkdir()

    def check(folder):
        gone = [p.name for p in stale if not p.is_dir()]
        return f"removed {len(gone)} folders not its own, e.g. {gone[0]}" if gone else None
    return mechopt("sweep", "loom/group1", *GRID, "--out", Path(folder) / "o.parquet"), check


def sweep_out_dot(folder):
    return snippet("from mechopt import registry, sweep\nfrom mechopt.kit.errors import MechoptError\ntry:\n"
                   "    sweep.sweep(registry.find('loom/group1'), [sweep.parse_grid('amplitude_limit_mm=0.1:0.12:2')],"
                   " out='.', progress=False)\nexcept MechoptError as exc:\n"
                   "    print('error:', exc, file=sys.stderr)\n    sys.exit(2)\n")


def scene_symlink_loop(folder):
    os.symlink("loop.toml", Path(folder) / "loop.toml")
    return mechopt("run", Path(folder) / "loop.toml")


def base_chain_300(folder):
    write(folder, "s0.toml", SCENE.format(points="[[0, 0], [1, 1]]"))
    for k in range(1, 301):
        write(folder, f"s{k}.toml", f'base = {{ scene = "s{k - 1}.toml" }}\n')
    return mechopt("run", Path(folder) / "s300.toml")


def unary_minus_1990(folder):
    return mechopt("run", "cam-cutter/other-profile", "--set", "x_expr=" + "-" * 1990 + "t")


def literal_1999_digits(folder):
    return mechopt("run", "cam-cutter/other-profile", "--set", "x_expr=" + "9" * 1999)


def press_too_much_work(folder):
    return mechopt("run", "press/sensitivity", "--set", "flywheel_inertia_kgm2=0.01")


def events_renamed(names):
    """A `rows` edit: events renamed by `names` (old: new) wherever an operation names them."""
    def edit(table):
        for row in table[1:]:
            row[:2] = [names.get(event, event) for event in row[:2]]
        return table
    return edit


def csv_output(folder, name):
    """`run --csv` of the packaging machine whose event feed.start is called `name` (the operations'
    label column reads "from->to"): every row as wide as the header, no cell a spreadsheet runs."""
    scene = packaging(folder, events_renamed({"feed.start": name}))
    out = Path(folder) / "t.csv"

    def check(folder):
        import csv as csv_
        if not out.exists():
            return None
        with open(out, encoding="utf-8", newline="") as f:
            rows = list(csv_.reader(f))
        widths = {len(r) for r in rows}
        formulas = [c for r in rows for c in r if c[:1] in "=+-@" and not _number(c)]
        return (f"rows of {sorted(widths)} cells" if len(widths) > 1 else
                f"a cell a spreadsheet runs: {formulas[0][:40]}" if formulas else None)
    return mechopt("run", scene, "--csv", out), check


def _number(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def csv_comma_name(folder):
    return csv_output(folder, "feed, start")


def csv_formula_name(folder):
    return csv_output(folder, '=HYPERLINK("http://example.invalid")')


def new_bad_name(folder):
    def check(folder):
        left = sorted(p.name for p in Path(folder).iterdir())
        return f"left behind: {left}" if left else None
    return mechopt("new", "cyclogram", Path(folder) / 'a"b.toml'), check


def new_read_only(folder):
    locked = Path(folder) / "ro"
    locked.mkdir()
    locked.chmod(0o555)                 # root writes there anyway: then exit 0 is the outcome
    return mechopt("new", "cyclogram", locked / "m.toml")


def ctrl_c_large_lp(folder, events=20000):
    """A cyclogram of 20,000 events planned by cvxpy's HiGHS LP (some 120,000 rows: tens of seconds of
    presolve); Ctrl-C 8 s in, inside the LP on a quiet machine."""
    import numpy as np
    rng = np.random.default_rng(1)
    tails = rng.integers(0, events - 1, 4 * events)
    heads = np.minimum(tails + rng.integers(1, 50, 4 * events), events - 1)
    tails = np.r_[np.zeros(events - 1, int), tails, np.arange(1, events - 1)]
    heads = np.r_[np.arange(1, events), heads, np.full(events - 2, events - 1)]
    arcs = {(a, b): d for a, b, d in zip(tails, heads, rng.uniform(1, 5, len(tails))) if a != b}
    write(folder, "ops.csv", "from,to,min_deg\n" + "".join(f"e{a},e{b},{d:.3f}\n" for (a, b), d in arcs.items()))
    scene = write(folder, "s.toml", 'id = "mine/large-lp"\ntitle = "a large LP"\nsource = "a test"\n'
                  'task = "loom.Cyclogram"\nsolver = "loom.plan_cyclogram"\n[params]\n[solver_settings]\n'
                  'method = "lp"\n[structure]\noperations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n')
    out = Path(folder) / "r.json"
    return mechopt("run", scene, "--json", out), lambda folder: f"{out} written" if out.exists() else None


def min_deg_of_second_operation(text):
    """A `rows` edit: the second operation's min_deg cell reads `text`."""
    def edit(table):
        table[2][5] = text
        return table
    return edit


def csv_nul_cell(folder):
    return mechopt("run", packaging(folder, renamed("feed:\x00wait")))


def csv_underscore_number(folder):
    return mechopt("run", packaging(folder, min_deg_of_second_operation("7_0")))


def csv_line_break_name(folder):
    return mechopt("run", packaging(folder, renamed("feed:\nwait")))


def lift_cam(folder, id_):
    """The lift cam's profile scene as a user's file with id `id_`."""
    text = LIFT_CAM.read_text(encoding="utf-8")
    return write(folder, "s.toml", text.replace('id = "stop-impact/lift-cam-profile"', f"id = {json.dumps(id_)}"))


def id_empty(folder):
    return mechopt("run", lift_cam(folder, ""), "--dxf", Path(folder) / "d")


def id_dot_dot(folder):
    """id ".." and `report`: its figures must not land beside the report's scratch folder."""
    before = set(Path(tempfile.gettempdir()).glob(".._*"))

    def check(folder):
        left = sorted(set(Path(tempfile.gettempdir()).glob(".._*")) - before)
        for path in left:           # the probe's own litter: cleared, so that the next run sees its own
            path.unlink()
        return f"left in the temporary folder: {left[0]}" if left else None
    return mechopt("report", "--case", packaging(folder, id_=".."), "--out", Path(folder) / "rep"), check


def samples_fraction(folder):
    """A solver setting that counts (press samples per piece) swept at 2.5: refused, not run as 2
    (a scene file or --set with 2.5 is refused already)."""
    return mechopt("sweep", "press/loads", "--grid", "samples=2.5:2.5:1", "--out", Path(folder) / "o.parquet")


def workers_1000(folder):
    code = """
import concurrent.futures as cf, multiprocessing
started = []
real = cf.ProcessPoolExecutor.__init__
def init(self, max_workers=None, *args, **kwargs):
    started.append(max_workers)     # what the sweep asked for; one process is started (a probe, not a load test)
    real(self, 1, *args, **kwargs)
cf.ProcessPoolExecutor.__init__ = init
code = cli.main(["sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.1:0.12:4", "--workers", "1000",
                 "--chunk", "1", "--out", str(Path.cwd() / "o.parquet")])
cores = len(os.sched_getaffinity(0))
if any(n and n > cores for n in started):
    print(f"error: {max(started)} worker processes on {cores} cores", file=sys.stderr)
    sys.exit(1)
sys.exit(code)
"""
    return snippet(code)


PROBES = [
    Probe("1 files", "lock_symlink", lock_symlink),
    Probe("1 files", "parts_symlink", parts_symlink),
    Probe("1 files", "lock_is_folder", lock_is_folder),
    Probe("1 files", "deleted_lock", deleted_lock, codes=(2,)),
    Probe("1 files", "no_fcntl", no_fcntl, codes=(0,)),
    Probe("1 files", "plot_into_file_parent", plot_into_file_parent),
    Probe("1 files", "full_disk_json", full_disk_json, codes=(1, 2)),
    Probe("2 hostile", "csv_secret", csv_secret),
    Probe("2 hostile", "base_secret", base_secret),
    Probe("2 hostile", "lever_secret", lever_secret),
    Probe("2 hostile", "scene_dev_zero", scene_dev_zero, timeout=30),
    Probe("2 hostile", "base_dev_zero", base_dev_zero, timeout=30),
    Probe("2 hostile", "csv_dev_zero", csv_dev_zero, timeout=30),
    Probe("2 hostile", "force_dev_zero", force_dev_zero, timeout=30),
    Probe("2 hostile", "scene_fifo", scene_fifo, timeout=15),
    Probe("2 hostile", "csv_fifo", csv_fifo, timeout=15),
    Probe("2 hostile", "csv_many_rows", csv_many_rows, timeout=60),
    Probe("2 hostile", "report_hostile_meta", report_hostile_meta),
    Probe("2 hostile", "report_hostile_message", report_hostile_message, codes=(0,)),
    Probe("2 hostile", "out_meta_not_json", out_meta_not_json),
    Probe("2 hostile", "out_meta_wrong_types", out_meta_wrong_types),
    Probe("2 hostile", "report_meta_deep", report_meta_deep),
    Probe("2 hostile", "toml_nesting", toml_nesting),
    Probe("2 hostile", "expression_nesting", expression_nesting),
    Probe("2 hostile", "long_literal_set", long_literal_set),
    Probe("2 hostile", "long_literal_scene", long_literal_scene),
    Probe("2 hostile", "long_float_scene", long_float_scene),
    Probe("2 hostile", "task_not_class", task_not_class),
    Probe("2 hostile", "solver_not_function", solver_not_function),
    Probe("2 hostile", "csv_huge_values", csv_huge_values),
    Probe("2 hostile", "seed_negative", seed_negative),
    Probe("2 hostile", "cases_root", cases_root, timeout=30),
    Probe("3 hang", "speeds_500", speeds_500, timeout=30),
    Probe("3 hang", "scheduler_not_dask", scheduler_not_dask, timeout=30),
    Probe("4 ctrl-c", "ctrl_c_loom_repaired", ctrl_c_loom_repaired, codes=(130,), sigint_after=4.0),
    Probe("4 ctrl-c", "ctrl_c_validate", ctrl_c_validate, codes=(130,), sigint_after=6.0),
    Probe("4 ctrl-c", "ctrl_c_stop_sweep", ctrl_c_stop_sweep, codes=(130,), sigint_after=8.0),
    Probe("5 legal", "missing_structure_table", missing_structure_table, codes=(0,)),
    Probe("5 legal", "grid_selector", grid_selector, codes=(0,), timeout=120),
    Probe("5 legal", "bom_scene", bom_scene, codes=(0,)),
    Probe("5 legal", "derive_missing", derive_missing, must_say="derive.t0_rad"),
    Probe("5 legal", "damping_one", damping_one, codes=(3,)),
    # the second round (its items 1-11)
    Probe("35.1 tmp", "tmp_link_json", tmp_link_json, codes=(0,)),
    Probe("35.1 tmp", "tmp_link_dxf", tmp_link_dxf, codes=(0,)),
    Probe("35.1 tmp", "tmp_link_new", tmp_link_new, codes=(0,)),
    Probe("35.1 tmp", "tmp_link_sweep", tmp_link_sweep, codes=(0,), timeout=120),
    Probe("35.2 foreign", "foreign_tmp_glob", foreign_tmp_glob, codes=(0, 2)),
    Probe("35.2 foreign", "foreign_tmp_backup", foreign_tmp_backup, codes=(0,)),
    Probe("35.3 lock", "lock_hardlink", lock_hardlink),
    Probe("35.4 bounds", "sidecar_fifo", sidecar_fifo, codes=(0, 2), timeout=60),
    Probe("35.4 bounds", "sidecar_dev_zero", sidecar_dev_zero, codes=(0, 2), timeout=60),
    Probe("35.4 bounds", "infeasible_chain", infeasible_chain, codes=(3,), timeout=900, max_output=1_000_000),
    Probe("35.4 bounds", "csv_wide_header", csv_wide_header, timeout=30),
    Probe("35.4 bounds", "csv_big_cell", csv_big_cell),
    Probe("35.4 bounds", "csv_million_rows", csv_million_rows, codes=(0,), timeout=600, must_not_say="1,000,002"),
    Probe("35.5 echo", "csv_etc_passwd", csv_etc_passwd, echo_of="/etc/passwd"),
    Probe("35.5 echo", "ops_csv_etc_passwd", ops_csv_etc_passwd, echo_of="/etc/passwd"),
    Probe("35.6 after solve", "dollar_plot", dollar_plot, codes=(0,)),
    Probe("35.6 after solve", "dollar_report", dollar_report, codes=(0,), timeout=120),
    Probe("35.6 after solve", "dollar_report_sweep", dollar_report_sweep, codes=(0,), timeout=180),
    Probe("35.6 after solve", "long_id_dxf", long_id_dxf, codes=(0, 2)),
    Probe("35.6 after solve", "long_id_plot", long_id_plot, codes=(0, 2)),
    Probe("35.6 after solve", "long_id_sweep", long_id_sweep, codes=(0, 2)),
    Probe("35.6 after solve", "dxf_dangling", dxf_dangling, codes=(0, 2)),
    Probe("35.6 after solve", "dxf_proc", dxf_proc),
    Probe("35.6 after solve", "dxf_name_is_folder", dxf_name_is_folder),
    Probe("35.6 after solve", "json_proc", json_proc),
    Probe("35.6 after solve", "sweep_out_proc", sweep_out_proc),
    Probe("35.6 after solve", "stale_tmp_folder", stale_tmp_folder, codes=(0, 2)),
    Probe("35.6 after solve", "sweep_out_dot", sweep_out_dot),
    Probe("35.7 traceback", "scene_symlink_loop", scene_symlink_loop),
    Probe("35.7 traceback", "base_chain_300", base_chain_300, codes=(0, 2)),
    Probe("35.7 traceback", "unary_minus_1990", unary_minus_1990, codes=(0, 2, 3)),
    Probe("35.7 traceback", "literal_1999_digits", literal_1999_digits, codes=(2, 3)),
    Probe("35.7 traceback", "press_too_much_work", press_too_much_work, codes=(3,), timeout=300),
    Probe("35.8 csv out", "csv_comma_name", csv_comma_name, codes=(0,)),
    Probe("35.8 csv out", "csv_formula_name", csv_formula_name, codes=(0,)),
    Probe("35.9 new", "new_bad_name", new_bad_name),
    Probe("35.9 new", "new_read_only", new_read_only, codes=(0, 2) if os.geteuid() == 0 else (2,),
          must_not_say="the run itself finished"),
    Probe("35.10 ctrl-c", "ctrl_c_large_lp", ctrl_c_large_lp, codes=(130,), sigint_after=8.0, exit_within_s=5.0,
          timeout=300),
    Probe("35.11 nonsense", "csv_nul_cell", csv_nul_cell),
    Probe("35.11 nonsense", "csv_underscore_number", csv_underscore_number),
    Probe("35.11 nonsense", "csv_line_break_name", csv_line_break_name),
    Probe("35.11 nonsense", "id_empty", id_empty),
    Probe("35.11 nonsense", "id_dot_dot", id_dot_dot, timeout=120),
    Probe("35.11 nonsense", "samples_fraction", samples_fraction, timeout=300),
    Probe("35.11 nonsense", "workers_1000", workers_1000, codes=(0,), timeout=120),
]


def echoes(path, text) -> bool:
    """Whether `text` shows the start of any of the first lines of the file at `path` (16 characters
    of a line of 16 or more is content, not a file name)."""
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = [f.readline().strip() for _ in range(5)]
    return any(len(line) >= 16 and line[:16] in text for line in lines)


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (6 << 30, 6 << 30))
    os.setsid()


def _files(folder) -> dict:
    """path -> (size, mtime_ns) of every regular file under `folder` (links not followed)."""
    return {f: (f.stat().st_size, f.stat().st_mtime_ns) for f in Path(folder).rglob("*")
            if f.is_file() and not f.is_symlink()}


def classify(probe: Probe) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        made = probe.setup(folder)
        argv, check = made if isinstance(made, tuple) else (made, None)
        inputs = _files(folder)              # the probe's own input files: not the command's output
        start = time.monotonic()
        proc = subprocess.Popen([PY, *argv], cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, errors="replace", preexec_fn=_limit_memory)
        signalled = None
        if probe.sigint_after:
            time.sleep(probe.sigint_after)
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
                signalled = time.monotonic()
        try:
            out, err = proc.communicate(timeout=probe.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            return {"name": probe.name, "class": probe.klass, "outcome": "hang", "code": None,
                    "seconds": round(time.monotonic() - start, 1), "said": ""}
        seconds = round(time.monotonic() - start, 1)
        said = err.strip().splitlines()[-1] if err.strip() else ""
        problem = check(folder) if check else None
        if not problem and signalled and probe.exit_within_s and time.monotonic() - signalled > probe.exit_within_s:
            problem = f"Ctrl-C honoured only {time.monotonic() - signalled:.1f} s after it came"
        if not problem and probe.max_output is not None:
            written = len(out) + len(err) + sum(stamp[0] for path, stamp in _files(folder).items()
                                                if inputs.get(path) != stamp)
            problem = f"{written:,} bytes of output (bound {probe.max_output:,})" if written > probe.max_output \
                else None
        echoed = probe.echo_of and echoes(probe.echo_of, out + err)
        if "Traceback" in err or proc.returncode < 0 or proc.returncode not in (0, 1, 2, 3, 130):
            outcome = "traceback"
        elif problem or proc.returncode not in probe.codes:
            outcome = "wrong"
        elif (len(err) > MAX_MESSAGE or SECRET in err + out or echoed or (proc.returncode == 2 and not said)
              or probe.must_say not in err or (probe.must_not_say and probe.must_not_say in err)):
            outcome = "unclear"
        else:
            outcome = "clear"
        return {"name": probe.name, "class": probe.klass, "outcome": outcome, "code": proc.returncode,
                "seconds": seconds, "said": (problem or said)[:200], "stderr_chars": len(err)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="*", default=[])
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    rows = []
    for probe in PROBES:
        if args.only and probe.name not in args.only:
            continue
        row = classify(probe)
        rows.append(row)
        print(f"{row['class']:<10} {row['name']:<24} {row['outcome']:<9} exit {row['code']!s:<4} "
              f"{row['seconds']:>6.1f} s  {row['said'][:110]}", flush=True)
    counts = {k: sum(r["outcome"] == k for r in rows) for k in ("clear", "unclear", "traceback", "hang", "wrong")}
    print("\n" + ", ".join(f"{n} {k}" for k, n in counts.items()) + f" (of {len(rows)})")
    if args.json:
        args.json.write_text(json.dumps({"counts": counts, "probes": rows}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
