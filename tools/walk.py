"""The walk a reader takes through the press's periodic orbit (the target: "the task
through steady_state visits fewer files with fewer returns").

    python tools/walk.py [--what-if] [--files]

Runs `mechopt.solve("press/kd2322")` in this process (cold: nothing built yet) and follows the
Python call chain from the entry of `solvers/press/periodic.py:steady_state` to its return with
`sys.setprofile`. At every call and return the position is the file of the innermost frame that
belongs to mechopt (src/mechopt, models, solvers: frames of numpy, CasADi or the standard library
leave it where it was). The walk is that sequence of files with repeats in a row merged:

* stops: its length (steady_state's own file is the first stop);
* returns: stops at a file already visited (stops - distinct files).

`--what-if` measures instead the re-solve `mechopt.solve("press/kd2322", belt_stiffness_Nm_rad=6e4)`
after a first solve (the orbit warm-started on the structure's build). Deterministic: one process,
one call chain, no timing. `--files` prints the walk itself.

The counts (this definition): before (main at 11dcd09) 99 stops, 94 returns (cold) and 95 / 90
(what-if), 5 files; after (branch press) 55 / 50 and 45 / 40, the same 5 files. What went: the task's
effect flags and state names, `Dynamics`' bound Functions and `Revolution.n` became attributes set
once (they were properties, each read a call into models/press.py and back); summarise reads the
outputs Function and the cut's angles it is handed instead of asking again; `stall_check`, physics
of the model, moved from solvers/press/problem.py to models/press.py beside the torques it compares.
"""
import argparse
import os
import sys

import mechopt
import mechopt.models
import mechopt.solvers

ROOTS = tuple(os.path.realpath(p) + os.sep for pkg in (mechopt, mechopt.models, mechopt.solvers)
              for p in pkg.__path__)
ENTRY = ("periodic.py", "steady_state")


def _ours(filename):
    """The file's path relative to the repository when it belongs to mechopt, else None."""
    path = os.path.realpath(filename)
    for root in ROOTS:
        if path.startswith(root):
            return os.path.relpath(path, os.path.dirname(root.rstrip(os.sep)))
    return None


def _position(frame):
    """The file of the innermost mechopt frame from `frame` outwards, or None."""
    while frame is not None:
        here = _ours(frame.f_code.co_filename)
        if here:
            return here
        frame = frame.f_back
    return None


def walk(**overrides) -> list[str]:
    """The files visited inside steady_state during `mechopt.solve("press/kd2322", **overrides)`,
    repeats in a row merged."""
    seen, depth = [], [0]

    def profile(frame, event, _arg):
        if event not in ("call", "return"):
            return
        code = frame.f_code
        entry = code.co_name == ENTRY[1] and code.co_filename.endswith(os.sep + ENTRY[0])
        if entry and event == "call":
            depth[0] += 1
        if entry and event == "return" and depth[0] == 1:       # the walk ends here, not at the caller
            depth[0] = 0
            return
        if depth[0]:
            here = _position(frame if event == "call" else frame.f_back)
            if here and (not seen or seen[-1] != here):
                seen.append(here)
        if entry and event == "return":
            depth[0] -= 1

    sys.setprofile(profile)
    try:
        run = mechopt.solve("press/kd2322", **overrides)
    finally:
        sys.setprofile(None)
    if run.status.name != "SOLVED":
        raise SystemExit(f"press/kd2322 ended {run.status.name}: {run.result.message}")
    return seen


def count(seen) -> tuple[int, int]:
    """(stops, returns) of a walk."""
    return len(seen), len(seen) - len(set(seen))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--what-if", action="store_true", help="the warm re-solve with belt_stiffness_Nm_rad=6e4")
    parser.add_argument("--files", action="store_true", help="print the walk, one stop a line")
    args = parser.parse_args(argv)
    if args.what_if:
        walk()
        seen, label = walk(belt_stiffness_Nm_rad=6e4), "what-if (belt_stiffness_Nm_rad=6e4 after a first solve)"
    else:
        seen, label = walk(), "cold solve"
    if args.files:
        print("\n".join(seen))
    stops, returns = count(seen)
    print(f"steady_state walk, {label}: {stops} stops, {returns} returns, {len(set(seen))} files")


if __name__ == "__main__":
    main()
