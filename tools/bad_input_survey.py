"""Issue 21's hostile and careless inputs, each run as a user would, its outcome classified.

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
* wrong: another exit code, or a file outside the named outputs changed.

A survey, not a test (tests/test_hardening_*.py pin each item). Issue 21's counts, 42 probes:
before (main at 6bfc3fa) 8 clear, 3 unclear, 20 traceback, 4 hang, 7 wrong; after (branch harden)
41 clear, 1 wrong (damping_one: stop-impact's solver turns a roller leaving its cam into bad input;
its owner's fix). The deleted_lock probe was rewritten after the first run to a second writer that
holds the new lock (before, with the second run to completion: a traceback).
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
    klass: str                      # the section
    name: str
    setup: object                   # f(folder) -> argv (after python), or (argv, check(folder) -> problem)
    codes: tuple = (2,)             # exit codes a user was promised
    timeout: float = 60.0
    sigint_after: float | None = None
    must_say: str = ""              # a clear message names this (the key or file at fault)
    must_not_say: str = ""          # ... and does not say this (a wrong reading of the input)


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
        return None if path_.is_file() and path_.read_text() == text else f"{path} was changed or removed"
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
from mechopt.errors import MechoptError
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
]


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (6 << 30, 6 << 30))
    os.setsid()


def classify(probe: Probe) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        made = probe.setup(folder)
        argv, check = made if isinstance(made, tuple) else (made, None)
        start = time.monotonic()
        proc = subprocess.Popen([PY, *argv], cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, errors="replace", preexec_fn=_limit_memory)
        if probe.sigint_after:
            time.sleep(probe.sigint_after)
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
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
        if "Traceback" in err or proc.returncode < 0 or proc.returncode not in (0, 1, 2, 3, 130):
            outcome = "traceback"
        elif problem or proc.returncode not in probe.codes:
            outcome = "wrong"
        elif (len(err) > MAX_MESSAGE or SECRET in err + out or (proc.returncode == 2 and not said)
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
