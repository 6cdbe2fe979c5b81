"""The one table of mechanisms: each row names a mechanism's files, and the spine reads it.

`mechopt new` offers the rows' templates (registry scenes, copied with the files they read),
`mechopt bench` their benchmarks (`mechopt.benchmarks.studies`), and `mechopt.figures` imports
their figure modules (which register their functions by solver). A fifth mechanism is one row
here plus its own files (docs/new-mechanism.md walks one through):

    cases/<name>/*.toml            its scenes (found by the registry: no list); `cases` names
                                   another row's folder where a wing's scenes live there
    models/<module>.py             its physics (a scene's `task = "<module>.<Class>"`): declared
                                   ranges on its fields, its own `warnings(values)`
    solvers/<package>/             its solvers (a scene's `solver = "<package>.<function>"`)
    src/mechopt/figures/<m>.py     its figures, `@figure(solver, ...)`, and any DXF writer,
                                   `@shop_drawing(solver, ...)` (mechopt.dxf)
    benchmarks/<module>.py         its accuracy-against-time study, `cli(repeats, out_dir, progress=None)`

setup.py discovers the packages, so none of them can drop out of a wheel. This module imports
nothing: the rows are names, imported by the readers (a missing module is an import error there).
"""
from dataclasses import dataclass


@dataclass(frozen=True)
class Mechanism:
    """One mechanism: its name (the cases folder and the benchmark's name), a title for the docs and
    its modules by full dotted name."""
    name: str
    title: str
    models: tuple[str, ...]            # the model module first, then its part files
    solvers: str                       # the solver package
    figures: tuple[str, ...]           # figure modules (they register by solver)
    benchmark: str                     # the `mechopt bench <name>` study
    templates: tuple[tuple[str, str], ...]    # (`mechopt new` name, the registry scene it copies)
    cases: str = ""                    # the cases folder of its scenes, when not its name

    @property
    def folder(self) -> str:
        """The cases folder (and scene-id prefix) of its scenes."""
        return self.cases or self.name


MECHANISMS = (
    Mechanism("cam-cutter", "Torch-guiding linkage (paper 000)",
              ("mechopt.models.cam_cutter", "mechopt.models.cam_profile"), "mechopt.solvers.cam_cutter",
              ("mechopt.figures.cam_cutter",), "mechopt.benchmarks.cam_cutter",
              (("cam-cutter", "cam-cutter/minimax"), ("cam-table", "cam-cutter/table-profile"))),
    Mechanism("press", "Crank press (paper 001)",
              ("mechopt.models.press", "mechopt.models.press_laws", "mechopt.models.press_energy",
               "mechopt.models.press_equations", "mechopt.models.press_design", "mechopt.models.press_loads"), "mechopt.solvers.press",
              ("mechopt.figures.press",), "mechopt.benchmarks.press",
              (("press", "press/kd2322"), ("press-design", "press/flywheel-design"))),
    # the engine of any cyclic machine; its scenes keep their loom/ ids (cases/loom) for one release
    Mechanism("cyclogram", "Cyclogram of a cyclic machine (paper 004's network)",
              ("mechopt.models.cyclogram", "mechopt.models.cyclogram_network", "mechopt.models.cyclogram_views",
               "mechopt.models.cyclogram_bounds", "mechopt.models.cyclogram_tables", "mechopt.models.cyclogram_motions",
               "mechopt.models.cyclogram_columns"),
              "mechopt.solvers.cyclogram",
              ("mechopt.figures.cyclogram",), "mechopt.benchmarks.loom", (("cyclogram", "loom/packaging"),), cases="loom"),
    # the STB loom, the cyclogram's case: its own limits and solvers (models/loom*.py also keep the
    # cyclogram's old paths for one release)
    Mechanism("loom", "STB loom: the cyclogram's case (paper 004)",
              ("mechopt.models.loom_limits", "mechopt.models.loom", "mechopt.models.loom_motions"), "mechopt.solvers.loom",
              ("mechopt.figures.loom",), "mechopt.benchmarks.loom", (("loom", "loom/group1"),)),
    Mechanism("stop-impact", "Lift lever at its stop (paper 004)",
              ("mechopt.models.stop_impact", "mechopt.models.cam_follower", "mechopt.models.cam_shape",
               "mechopt.models.cam_law", "mechopt.models.cam_laws", "mechopt.models.cam_motion"),
              "mechopt.solvers.stop_impact", ("mechopt.figures.stop_impact", "mechopt.figures.cam_shape",
                                              "mechopt.figures.law_synthesis"), "mechopt.benchmarks.stop_impact",
              (("stop-impact", "stop-impact/rebound-177rpm"),)),
    Mechanism("cam", "Disc cams with any follower (textbook cams)",
              ("mechopt.models.cam_followers", "mechopt.models.cam_geometry", "mechopt.models.cam_forces"),
              "mechopt.solvers.cam", ("mechopt.figures.cam",), "mechopt.benchmarks.cam",
              (("cam", "cam/translating-roller"),)),
)


def mechanisms() -> tuple[Mechanism, ...]:
    """The rows (read at call time, so a reader sees the table as it is)."""
    return MECHANISMS


def templates() -> dict[str, str]:
    """`mechopt new` name -> the registry scene it starts from, over every row."""
    return {name: scene for m in mechanisms() for name, scene in m.templates}
