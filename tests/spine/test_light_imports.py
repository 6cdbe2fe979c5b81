"""A light front door: what a command or a plan needs imports no back end it does not use
(CasADi, numba, cvxpy load in seconds under load). Each check runs in a fresh interpreter."""
import json
import subprocess
import sys

import pytest

HEAVY = ("casadi", "numba", "cvxpy")


def _imported_after(code: str) -> list[str]:
    """The heavy modules imported by a fresh interpreter that ran `code`."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=600, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_the_command_line_and_its_version_import_no_back_end():
    assert _imported_after("import mechopt.cli") == []
    assert _imported_after("from mechopt.cli import main\ntry:\n    main(['--version'])\nexcept SystemExit:\n"
                           "    pass") == []


def test_a_loom_plan_imports_no_casadi_and_no_numba():
    """The scene's own model and solver (models/loom.py, solvers/loom/plan.py) reach the lever's
    laws (models/cam_follower.py, cam_law.py), whose CasADi forms are imported where used."""
    code = ("from mechopt.registry import cases_dir, run\nfrom mechopt.scene import load\n"
            "assert run(load(cases_dir() / 'loom' / 'group1.toml')).success")
    assert [m for m in _imported_after(code) if m != "cvxpy"] == []


def test_solving_a_loom_scene_by_its_id_imports_no_casadi_and_no_numba():
    code = "import mechopt\nassert mechopt.solve('loom/group1').success"
    assert [m for m in _imported_after(code) if m != "cvxpy"] == []


def test_the_lazy_solver_doors_give_the_same_functions_as_their_modules():
    from mechopt.solvers import loom, stop_impact
    from mechopt.solvers.loom.plan import plan_cyclogram
    from mechopt.solvers.stop_impact.entry_points import rebound
    assert loom.plan_cyclogram is plan_cyclogram and stop_impact.rebound is rebound
    for door in (loom, stop_impact):
        assert set(door.__all__) <= set(dir(door))
        assert all(callable(getattr(door, name)) for name in door.__all__)
    with pytest.raises(AttributeError, match="has no attribute 'no_such_solver'"):
        loom.no_such_solver                     # noqa: B018


def test_a_graph_only_plan_imports_no_lp_modeller():
    """`method = "graph"` with no LP certificate asked for (`check = False`) needs no cvxpy (seconds to
    import, the cost a CLI run from a CSV waited for ahead of a 0.2 s solve)."""
    code = ("from mechopt.registry import cases_dir\nfrom mechopt.scene import load\n"
            "from mechopt.solvers.loom import plan_cyclogram\n"
            "task = load(cases_dir() / 'loom' / 'group1.toml').build()[0]\n"
            "assert plan_cyclogram(task, method='graph', check=False).success")
    assert _imported_after(code) == []
