"""Accuracy-vs-time studies, run by `mechopt bench <study>` (timings are measured here, never
asserted in tests). Each study is registered here by name and has
`cli(repeats, out_dir, progress=None) -> str` (the printed table; figures into out_dir).
A study that is missing or fails to import is an error, not a silently shorter list."""
import importlib

STUDIES = {
    "cam-cutter": "mechopt.benchmarks.cam_cutter",
    "press": "mechopt.benchmarks.press",
    "loom": "mechopt.benchmarks.loom",
    "stop-impact": "mechopt.benchmarks.stop_impact",
    "sweep": "mechopt.benchmarks.sweep",
}


def study(name: str):
    """The module of a registered study (imported now: its import errors propagate)."""
    return importlib.import_module(STUDIES[name])
