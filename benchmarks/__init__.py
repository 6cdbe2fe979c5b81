"""Accuracy-vs-time studies, run by `mechopt bench <study>` (timings are measured here, never
asserted in tests): each mechanism's, named by its row in `mechopt.mechanisms`, and the sweep's.
A study has `cli(repeats, out_dir, progress=None) -> str` (the printed table; figures into out_dir).
A study that is missing or fails to import is an error, not a silently shorter list."""

if __name__ != "mechopt.benchmarks":      # `import benchmarks` from the repository root: a second, different copy
    raise ImportError(f"{__name__}: this folder is the package mechopt.benchmarks; import mechopt.benchmarks "
                      "(installed by `pip install -e .`), not benchmarks from the repository root")
import importlib

from mechopt.mechanisms import mechanisms

SPINE_STUDIES = {"sweep": "mechopt.benchmarks.sweep"}      # of the spine, not of one mechanism
# a mechanism's further studies (stop-impact's window LP, also run within its first: mechopt bench synthesis;
# the loom's exact-bound walk and the co-design's whole command: mechopt bench walk; the groove's rise: mechopt
# bench groove; a big CSV timing table's whole command against a networkx script: mechopt bench cyclogram_cli;
# the least cycle time of a 10^5-event recurrent network against its LP: mechopt bench cycle_time)
MORE_STUDIES = {"synthesis": "mechopt.benchmarks.synthesis", "walk": "mechopt.benchmarks.walk",
                "groove": "mechopt.benchmarks.groove", "cyclogram_cli": "mechopt.benchmarks.cyclogram_cli",
                "cycle_time": "mechopt.benchmarks.cycle_time"}


def studies() -> dict[str, str]:
    """Study name -> its module: one per mechanism, then the spine's."""
    return {m.name: m.benchmark for m in mechanisms()} | MORE_STUDIES | SPINE_STUDIES


STUDIES = studies()


def study(name: str):
    """The module of a registered study (imported now: its import errors propagate)."""
    return importlib.import_module(studies()[name])
