"""What a user waits for: `mechopt run big.toml --json F` on a generated CSV timing table (a DAG,
method "graph"), the whole fresh process, against a plain script that reads the same CSV into
networkx and runs `dag_longest_path_length`. Interleaved runs, medians of `repeats`, peak RSS of
each from `/usr/bin/time -f %M` (KiB). Run: `python -m mechopt.benchmarks.cyclogram_cli [operations ...]`.

Targets (a ratio in the same run, so the machine's load cancels to first order): at 10^5
operations the CLI at least 2x faster than the networkx script and its peak memory no more; at
10^6 operations the CLI under 10 s and under 1 GB on a quiet 2-core machine (the load is printed).
A scene's CSV holds at most 10^6 rows (tables.MAX_ROWS): the 10^6 case is `990000` operations asked,
996,260 written (`layered` adds the leaves' arcs to the last event)."""
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from mechopt.benchmarks.loom import layered

ARCS_PER_EVENT = 3              # `layered`'s in-degree: operations ~ 3 x events
NETWORKX_SCRIPT = """\
import csv, sys
import networkx as nx
g = nx.DiGraph()
with open(sys.argv[1], newline="", encoding="utf-8") as f:
    rows = csv.reader(f)
    next(rows)
    g.add_weighted_edges_from((a, b, float(w)) for a, b, w, *_ in rows)
print(nx.dag_longest_path_length(g))
"""
SCENE = """\
id = "bench/cli-machine"
title = "generated DAG read from a CSV timing table"
source = "benchmarks/cyclogram_cli.py"
task = "cyclogram.Cyclogram"
solver = "cyclogram.plan_cyclogram"
[params]
[solver_settings]
method = "graph"
[structure]
operations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }
"""


def write_scene(folder: Path, operations: int, seed=0) -> int:
    """A layered DAG of about `operations` operations as ops.csv (text event names, a group
    column) and big.toml beside it; returns the number of operations written."""
    tails, heads, angles = layered(max(operations // ARCS_PER_EVENT, 3), seed=seed)
    n = int(heads.max()) + 1
    with open(folder / "ops.csv", "w", encoding="utf-8") as f:
        f.write("from,to,min_deg,group\n")
        f.writelines(f"e{a},e{b},{w:.9f},g{a * 4 // n}\n"
                     for a, b, w in zip(tails.tolist(), heads.tolist(), angles.tolist()))
    (folder / "big.toml").write_text(SCENE, encoding="utf-8")
    return len(tails)


def _timed(argv, env=None) -> tuple[float, int, str]:
    """(wall s, peak RSS MiB, stdout) of one fresh process under /usr/bin/time."""
    out = subprocess.run(["/usr/bin/time", "-f", "%e %M", *argv], capture_output=True, text=True, env=env)
    if out.returncode:
        raise RuntimeError(f"{argv[0]}: exit {out.returncode}: {out.stderr[-2000:]}")
    wall, rss_kib = out.stderr.strip().splitlines()[-1].split()
    return float(wall), int(rss_kib) // 1024, out.stdout


def user_env(folder: Path) -> dict:
    """The environment of a user's process: Python's bytecode cached (an installed package's is;
    here in a temporary folder, not the checkout), whatever the calling session said
    (PYTHONDONTWRITEBYTECODE would have every mechopt module compiled in every timed run)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return env | {"PYTHONPYCACHEPREFIX": str(folder / "pycache")}


def compare(operations: int, repeats=3, progress=print) -> dict:
    """The CLI and the networkx script on the same generated CSV, interleaved after one untimed run
    of each (which writes the bytecode caches); medians and peaks."""
    mechopt = shutil.which("mechopt", path=os.path.dirname(sys.executable)) or "mechopt"
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        arcs = write_scene(folder, operations)
        (folder / "nx_script.py").write_text(NETWORKX_SCRIPT, encoding="utf-8")
        env = user_env(folder)
        cli_argv = [mechopt, "run", str(folder / "big.toml"), "--json", str(folder / "out.json")]
        nx_argv = [sys.executable, str(folder / "nx_script.py"), str(folder / "ops.csv")]
        for argv in (cli_argv, nx_argv):
            _timed(argv, env)
        runs = {"cli": [], "networkx": []}
        span = {}
        for _ in range(repeats):
            wall, rss, _out = _timed(cli_argv, env)
            runs["cli"].append((wall, rss))
            span["cli"] = json.loads((folder / "out.json").read_text())
            wall, rss, out = _timed(nx_argv, env)
            runs["networkx"].append((wall, rss))
            span["networkx"] = float(out.split()[-1])
            if progress:
                progress(f"{arcs:,} operations: cli {runs['cli'][-1]}, networkx {runs['networkx'][-1]}")
    row = {"operations": arcs, "load": os.getloadavg()[0]}
    for who, got in runs.items():
        row[f"{who}_s"] = statistics.median(w for w, _ in got)
        row[f"{who}_mib"] = max(r for _, r in got)
    row["ratio"] = row["networkx_s"] / row["cli_s"]
    row["cli_span_deg"] = _span(span["cli"])
    row["networkx_span_deg"] = span["networkx"]
    return row


def _span(report) -> float | None:
    """span_deg from the CLI's JSON report, wherever it sits."""
    if isinstance(report, dict):
        if "span_deg" in report and isinstance(report["span_deg"], (int, float)):
            return float(report["span_deg"])
        for v in report.values():
            got = _span(v)
            if got is not None:
                return got
    if isinstance(report, list):
        for v in report:
            got = _span(v)
            if got is not None:
                return got
    return None


def line(row) -> str:
    return (f"{row['operations']:,} operations (load {row['load']:.1f}): cli {row['cli_s']:.2f} s {row['cli_mib']} MiB, "
            f"networkx script {row['networkx_s']:.2f} s {row['networkx_mib']} MiB, networkx / cli = "
            f"{row['ratio']:.2f}x; span {row['cli_span_deg']} vs {row['networkx_span_deg']}")


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """`mechopt bench cyclogram_cli`: 10^5 operations, medians of `repeats` (quick: 10^4, one run each)."""
    size, reps = (10_000, 1) if quick else (100_000, max(1, min(repeats, 3)))
    return line(compare(size, repeats=reps, progress=progress))


if __name__ == "__main__":
    for size in [int(float(a)) for a in sys.argv[1:]] or [100_000]:
        print(line(compare(size)), flush=True)
