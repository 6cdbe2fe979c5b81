"""A sweep touches no file outside the outputs named (a symbolic link at its
lock or parts folder is refused, never followed; it removes only what it wrote), its lock holds
when deleted under it, figures are written atomically, a full disk or a read-only target is one
clear line, and the package imports where `fcntl` does not exist."""
import errno
import json
import os
import subprocess
import sys

import pytest

from mechopt import cli, files, registry
from mechopt import sweep as sw
from mechopt.kit.errors import SceneError

LOOM = "loom/group1"


def _axes():
    return [sw.parse_grid("amplitude_limit_mm=0.1:0.12:3")]


def test_a_lock_that_is_a_symbolic_link_is_refused_and_its_target_kept(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    (tmp_path / "o.parquet.lock").symlink_to(victim)
    with pytest.raises(SceneError, match=r"o.parquet.lock: a symbolic link where a lock file belongs"):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", progress=False)
    assert victim.read_text() == "precious" and not (tmp_path / "o.parquet").exists()


@pytest.mark.parametrize("make", [os.mkdir, os.mkfifo], ids=["folder", "fifo"])
def test_a_lock_that_is_not_a_regular_file_is_refused(tmp_path, make):
    make(tmp_path / "o.parquet.lock")
    with pytest.raises(SceneError, match=r"o.parquet.lock: not a regular file"):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", progress=False)


def test_a_parts_folder_that_is_a_symbolic_link_is_refused_and_not_followed(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "data.parquet").write_text("precious")          # no checksum: once deleted as "damaged"
    (tmp_path / "o.parquet.parts").symlink_to(elsewhere)
    with pytest.raises(SceneError, match=r"o.parquet.parts: not this sweep's folder of parts \(a symbolic link"):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", progress=False)
    assert (elsewhere / "data.parquet").read_text() == "precious"


def test_files_in_the_parts_folder_that_are_not_parts_are_left_alone(tmp_path):
    parts = tmp_path / "o.parquet.parts"
    parts.mkdir()
    (parts / "notes.parquet").write_text("mine")
    (parts / "part-1.parquet").write_text("not a part's name either")
    table = sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", progress=False)
    assert table.num_rows == 3
    assert sorted(p.name for p in parts.iterdir()) == ["notes.parquet", "part-1.parquet"]
    assert not (tmp_path / "o.parquet.lock").exists()


def test_a_lock_deleted_under_a_running_sweep_is_taken_again(tmp_path):
    out = tmp_path / "o.parquet"
    lock = tmp_path / "o.parquet.lock"
    seen = []

    def delete_once(rows):
        if not seen:
            lock.unlink()
        seen.append(lock.exists())
    table = sw.sweep(registry.find(LOOM), _axes(), out=out, chunk=1, progress=False, on_chunk=delete_once)
    assert table.num_rows == 3 and seen == [False, True, True]    # re-taken at the next chunk


def test_a_sweep_whose_lock_another_writer_took_stops_with_its_parts_kept(tmp_path):
    out = tmp_path / "o.parquet"
    lock = tmp_path / "o.parquet.lock"
    other = []

    def second_writer_gets_in(rows):
        if not other:
            lock.unlink()
            other.append(files.take_lock(lock))      # another sweep takes the new lock file
    try:
        with pytest.raises(SceneError, match=r"o.parquet.lock was removed while this sweep ran, and .* is being "
                                             r"written by another sweep .*; this sweep stops \(its finished parts "
                                             r"are kept in .*o.parquet.parts\)"):
            sw.sweep(registry.find(LOOM), _axes(), out=out, chunk=1, progress=False, on_chunk=second_writer_gets_in)
    finally:
        os.close(other[0])
    assert lock.exists() and len(list((tmp_path / "o.parquet.parts").glob("part-*.parquet"))) == 1


def test_the_package_imports_where_fcntl_does_not_exist():
    code = ("import importlib, pkgutil, sys; sys.modules['fcntl'] = None\n"
            "import mechopt\n"
            "for m in pkgutil.walk_packages(mechopt.__path__, 'mechopt.'):\n"
            "    if not m.name.endswith('__main__'): importlib.import_module(m.name)\n"
            "assert mechopt.files.fcntl is None and 'mechopt.sweep' in sys.modules\nprint('ok')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


def test_a_figure_is_written_whole_or_not_at_all(tmp_path, monkeypatch):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mechopt.figures import save_figure
    fig = plt.figure()
    target = tmp_path / "f.png"
    target.write_bytes(b"the old figure")

    def interrupted(self, *args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(type(fig), "savefig", interrupted)
    with pytest.raises(KeyboardInterrupt):
        save_figure(fig, target)
    assert target.read_bytes() == b"the old figure" and [p.name for p in tmp_path.iterdir()] == ["f.png"]


def test_a_long_label_is_never_cut_at_the_figures_edge(tmp_path):
    """A y label longer than the figure is wide (a long operation name on a timing diagram): the PNG grows
    to hold it (its whole text inside the image), not cut at the figure's 4 in."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.image import imread

    from mechopt.figures import save_figure
    from mechopt.figures.registry import new_figure
    fig = new_figure(figsize=(4, 2))
    ax = fig.add_subplot()
    ax.set_yticks([0])
    ax.set_yticklabels(["the die's descent to the turret face, station 3 of the indexing table " * 2])
    fig.canvas.draw()
    label = ax.get_yticklabels()[0].get_window_extent()
    assert label.x0 < 0                              # drawn past the figure's left edge: the case in question
    height, width = imread(save_figure(fig, tmp_path / "long.png", dpi=50)).shape[:2]
    assert width >= label.width * 50 / fig.dpi        # the whole label is in the image


def test_a_full_disk_is_one_clear_line(tmp_path, monkeypatch, capsys):
    def full(path, data):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))
    monkeypatch.setattr(cli, "write_text_atomic", full)
    code = cli.main(["run", LOOM, "--json", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 1 and err.strip().splitlines()[-1] == (
        f"error: cannot write {tmp_path / 'r.json'}: No space left on device (the run itself finished: its result "
        "was computed but not written; "
        "free some space or choose another place and run it again)")


def test_a_read_only_output_folder_is_refused_before_the_work(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(cli.os, "access", lambda path, mode: False)
    monkeypatch.setattr(registry, "run", lambda *a, **k: pytest.fail("ran before the output was checked"))
    assert cli.main(["run", LOOM, "--plot", str(tmp_path / "figs")]) == 2
    assert "is not writable" in capsys.readouterr().err


# --- Temporary names, foreign files, bounded reads, output paths, `new`, ids ----------

CARDIOID = "cam-cutter/pure-cardioid"          # solves in well under a second; draws, exports DXF


class _Kill(BaseException):
    """A kill at a chosen point (BaseException: nothing catches it as an error)."""


def _plant(targets, victim):
    """At every name a temporary of each target had (`<name>.<pid>.tmp`) or might have: a link to
    `victim`, or a folder (a stale temporary folder)."""
    for target in targets:
        target.parent.mkdir(parents=True, exist_ok=True)
        name = target.name
        target.with_name(f"{name}.{os.getpid()}.tmp").symlink_to(victim)
        target.with_name(f"{name}.{os.getpid() + 1}.tmp").mkdir()
        for guess in ("0" * 16, "f" * 16, "0123456789abcdef"):
            target.with_name(f".{name}.{guess}.tmp").symlink_to(victim)


def _victim(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    return victim


def test_an_atomic_write_never_follows_a_link_at_a_temporary_name(tmp_path):
    victim, target = _victim(tmp_path), tmp_path / "out" / "r.json"
    _plant([target], victim)
    files.write_text_atomic(target, "new")
    assert victim.read_text() == "precious" and target.read_text() == "new" and not target.is_symlink()


def test_run_outputs_never_follow_links_or_folders_at_temporary_names(tmp_path, capsys):
    victim, out = _victim(tmp_path), tmp_path / "out"
    targets = [out / "r.json", out / "dxf" / "cam-cutter_pure-cardioid.dxf",
               out / "plot" / "cam-cutter_pure-cardioid_paths.png"]
    _plant(targets, victim)
    code = cli.main(["run", CARDIOID, "--json", str(targets[0]), "--dxf", str(out / "dxf"),
                     "--plot", str(out / "plot")])
    assert code == 0, capsys.readouterr().err
    assert victim.read_text() == "precious" and all(t.is_file() and not t.is_symlink() for t in targets)


def test_new_and_a_sweep_never_follow_links_at_temporary_names(tmp_path, capsys):
    victim, scene, out = _victim(tmp_path), tmp_path / "mine.toml", tmp_path / "o.parquet"
    parts = [tmp_path / "o.parquet.parts" / f"part-{i:09d}.parquet{s}" for i in range(3) for s in ("", ".sha256")]
    _plant([scene, tmp_path / "mine-ops.csv", out, *parts], victim)
    assert cli.main(["new", "cyclogram", str(scene)]) == 0, capsys.readouterr().err
    assert sw.sweep(registry.find(LOOM), _axes(), out=out, chunk=1, progress=False).num_rows == 3
    assert victim.read_text() == "precious"
    assert all(p.is_file() and not p.is_symlink() for p in (scene, tmp_path / "mine-ops.csv", out))


def test_a_sweep_removes_no_file_that_only_looks_like_its_temporary(tmp_path):
    mine = [tmp_path / "results.parquet.12345.tmp", tmp_path / "o.parquet.backup.tmp",
            tmp_path / ".o.parquet.0123456789abcdef.tmp"]       # the last named as its temporaries are, not recorded
    for path in mine:
        path.write_text("mine")
    for out in ("*.parquet", "o.parquet"):                       # --out taken literally, never as a pattern
        assert sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / out, progress=False).num_rows == 3
    assert all(p.read_text() == "mine" for p in mine) and (tmp_path / "*.parquet").is_file()


def test_a_sweeps_temporary_is_recorded_in_its_lock_and_removed_after_a_kill(tmp_path, monkeypatch):
    out, lock = tmp_path / "o.parquet", tmp_path / "o.parquet.lock"
    seen, real = [], sw.write_bytes_atomic

    def watched(path, data, *, on_temporary):
        def note(tmp):
            on_temporary(tmp)
            seen.append((tmp, lock.read_text()))
        return real(path, data, on_temporary=note)
    monkeypatch.setattr(sw, "write_bytes_atomic", watched)
    sw.sweep(registry.find(LOOM), _axes(), out=out, progress=False)
    assert len(seen) == 3 and all(text == f"{os.getpid()}\n{tmp.relative_to(tmp_path).as_posix()}\n"
                                  for tmp, text in seen)      # part, its checksum, the merge
    monkeypatch.undo()
    # what a sweep killed (kill -9) during its merge leaves: its lock naming the temporary in flight
    killed = tmp_path / ".o.parquet.00000000000000aa.tmp"
    killed.write_bytes(b"half a merge")
    lookalike = tmp_path / ".o.parquet.00000000000000bb.tmp"
    lookalike.write_bytes(b"not recorded")
    lock.write_text(f"4242\n{killed.name}\n")
    assert sw.sweep(registry.find(LOOM), _axes(), out=out, progress=False).num_rows == 3
    assert not killed.exists() and lookalike.read_bytes() == b"not recorded" and not lock.exists()


def test_a_lock_with_another_name_or_foreign_text_is_refused_and_kept(tmp_path):
    victim = _victim(tmp_path)
    os.link(victim, tmp_path / "o.parquet.lock")
    with pytest.raises(SceneError, match=r"o.parquet.lock: a file with 1 other name\(s\) \(a hard link\)"):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", progress=False)
    assert victim.read_text() == "precious"
    (tmp_path / "p.parquet.lock").write_text("my notes\n")
    with pytest.raises(SceneError, match=r"p.parquet.lock: holds text no sweep writes"):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "p.parquet", progress=False)
    assert (tmp_path / "p.parquet.lock").read_text() == "my notes\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.parquet.lock", "p.parquet.lock", "victim.txt"]


def _one_part(tmp_path):
    """A sweep stopped after its first chunk: one part and its checksum in o.parquet.parts."""
    def stop(rows):
        raise _Kill
    with pytest.raises(_Kill):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", chunk=1, progress=False, on_chunk=stop)
    return tmp_path / "o.parquet.parts" / "part-000000000.parquet.sha256"


def _fifo(path):
    path.unlink(missing_ok=True)
    os.mkfifo(path)


def _zeros(path):
    path.unlink(missing_ok=True)
    path.symlink_to("/dev/zero")


@pytest.mark.parametrize("make", [_fifo, _zeros], ids=["fifo", "dev-zero"])
def test_a_checksum_file_that_is_not_a_regular_file_is_refused_at_once(tmp_path, make):
    check = _one_part(tmp_path)
    make(check)
    with pytest.raises(SceneError, match=r"part-000000000.parquet.sha256: not a file this sweep wrote"):
        sw.sweep(registry.find(LOOM), _axes(), out=tmp_path / "o.parquet", progress=False)
    assert check.is_symlink() or check.exists()           # left as it is


@pytest.mark.parametrize("make", [_fifo, _zeros], ids=["fifo", "dev-zero"])
def test_a_table_that_is_not_a_regular_file_is_refused_at_once(tmp_path, make):
    out = tmp_path / "o.parquet"
    make(out)
    with pytest.raises(SceneError, match=r"o.parquet: a (FIFO|device), not a sweep's table"):
        sw.sweep(registry.find(LOOM), _axes(), out=out, progress=False)
    with pytest.raises(SceneError, match=r"o.parquet: a (FIFO|device), not a sweep's table"):
        sw.read_table(out)


def _long_id_scene(tmp_path):
    text = (registry.cases_dir() / "cam-cutter" / "pure-cardioid.toml").read_text(encoding="utf-8")
    path = tmp_path / "long.toml"
    path.write_text(text.replace('id = "cam-cutter/pure-cardioid"', f'id = "my/{"a" * 300}"'), encoding="utf-8")
    return path


def _dangling(tmp_path):
    (tmp_path / "d").symlink_to(tmp_path / "nowhere")
    return ["run", CARDIOID, "--dxf", str(tmp_path / "d")], "is a symbolic link to nothing"


def _dxf_is_a_folder(tmp_path):
    (tmp_path / "d" / "cam-cutter_pure-cardioid.dxf").mkdir(parents=True)
    return ["run", CARDIOID, "--dxf", str(tmp_path / "d")], "cam-cutter_pure-cardioid.dxf: a folder"


OUTPUT_PATHS = {
    "long-id-dxf": lambda t: (["run", str(_long_id_scene(t)), "--dxf", str(t / "d")], "an id has at most 100"),
    "long-id-plot": lambda t: (["run", str(_long_id_scene(t)), "--plot", str(t / "p")], "an id has at most 100"),
    "long-id-sweep": lambda t: (["sweep", str(_long_id_scene(t)), "--grid", "a_mm=24:26:2"], "an id has at most 100"),
    "long-json-name": lambda t: (["run", CARDIOID, "--json", str(t / ("r" * 300 + ".json"))],
                                 "is 305 characters; a file name has at most 255"),
    "dangling-dxf": _dangling,
    "dxf-is-a-folder": _dxf_is_a_folder,
    "proc-dxf": lambda t: (["run", CARDIOID, "--dxf", "/proc/d"], "no file can be created in /proc"),
    "proc-json": lambda t: (["run", CARDIOID, "--json", "/proc/r.json"], "no file can be created in /proc"),
    "proc-sweep-out": lambda t: (["sweep", LOOM, "--grid", "amplitude_limit_mm=0.1:0.12:3", "--out", "/proc/o.parquet"],
                                 "no file can be created in /proc"),
}


@pytest.mark.parametrize("case", list(OUTPUT_PATHS))
def test_an_output_path_that_cannot_be_written_is_refused_before_the_solve(tmp_path, monkeypatch, capsys, case):
    argv, said = OUTPUT_PATHS[case](tmp_path)
    before = sorted(tmp_path.rglob("*"))
    monkeypatch.setattr(registry, "run", lambda *a, **k: pytest.fail("solved before the output was checked"))
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0] and "Traceback" not in err[0]
    assert sorted(tmp_path.rglob("*")) == before


def test_an_output_that_fails_after_the_solve_is_one_line_saying_it_was_computed(tmp_path, capsys):
    (tmp_path / "p" / "cam-cutter_pure-cardioid_paths.png").mkdir(parents=True)     # where the figure goes
    assert cli.main(["run", CARDIOID, "--plot", str(tmp_path / "p")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"error: cannot write {tmp_path / 'p' / 'cam-cutter_pure-cardioid_paths.png'}: ")
    assert "the run itself finished: its result was computed but not written" in err[-1]
    assert [p.name for p in (tmp_path / "p").iterdir()] == ["cam-cutter_pure-cardioid_paths.png"]


@pytest.mark.parametrize("out", [".", "", ".."])
def test_a_sweep_out_that_names_a_folder_is_refused(tmp_path, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError, match=r"a folder; --out names the table's file"):
        sw.sweep(registry.find(LOOM), _axes(), out=out, progress=False)
    assert not list(tmp_path.iterdir())


def test_new_with_a_name_that_makes_no_id_writes_nothing(tmp_path, capsys):
    assert cli.main(["new", "cyclogram", str(tmp_path / 'a"b.toml')]) == 2
    assert "the new scene's id would be 'my/a\"b'" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_new_removes_what_it_wrote_when_a_later_file_fails(tmp_path, monkeypatch, capsys):
    real = cli.write_text_atomic

    def scene_refused(path, text, **how):
        if str(path).endswith(".toml"):
            raise files.NotWritten(errno.EROFS, "Read-only file system", str(path))
        return real(path, text, **how)
    monkeypatch.setattr(cli, "write_text_atomic", scene_refused)
    assert cli.main(["new", "cyclogram", str(tmp_path / "mine.toml")]) == 1
    err = capsys.readouterr().err
    assert "Read-only file system (nothing was run and nothing written" in err and "run itself finished" not in err
    assert not list(tmp_path.iterdir())


def test_new_into_a_read_only_folder_is_refused_before_writing(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(cli.os, "access", lambda path, mode: False)
    assert cli.main(["new", "cyclogram", str(tmp_path / "mine.toml")]) == 2
    assert "is not writable" in capsys.readouterr().err and not list(tmp_path.iterdir())


@pytest.mark.parametrize("bad", ["", ".", "..", "my/..", "/abs", "a b", "my/", 'a"b', "x" * 101])
def test_an_id_that_cannot_name_files_is_refused_with_the_allowed_form(tmp_path, bad):
    from mechopt.scene import loads
    text = (registry.cases_dir() / "cam-cutter" / "pure-cardioid.toml").read_text(encoding="utf-8")
    with pytest.raises(SceneError, match=r"id: .*(letters, digits, '\.', '_' and '-'|an id has at most 100)"):
        loads(text.replace('id = "cam-cutter/pure-cardioid"', f"id = {json.dumps(bad)}"), tmp_path / "s.toml")


def test_the_report_draws_a_scene_only_inside_its_scratch_folder(tmp_path):
    import dataclasses

    from mechopt import report
    run = registry.run(registry.find(CARDIOID))
    dotted = dataclasses.replace(run.scene, spec=run.scene.spec.model_copy(update={"id": ".."}))
    folder = tmp_path / "scratch" / "scene_0"
    report._scene_section(dataclasses.replace(run, scene=dotted), folder)
    assert [p.relative_to(tmp_path).parts[:2] for p in tmp_path.rglob("*.png")] == [("scratch", "scene_0")]


def test_local_workers_are_capped_at_the_cores_and_it_is_said(monkeypatch):
    seen, scene = [], registry.find(LOOM)

    def pool(workers, source, chunks):
        seen.append(workers)
        return (sw._solve_rows(scene, c) for c in chunks)
    monkeypatch.setattr(sw.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(sw, "_on_pool", pool)
    with pytest.warns(sw.SweepWarning, match=r"workers = 1000: this machine has 2 cores, so 2 processes are used"):
        assert sw.sweep(scene, _axes(), workers=1000, chunk=1, progress=False).num_rows == 3
    assert seen == [2]


@pytest.mark.parametrize("out", ["/proc/o.parquet", "/proc/x/o.parquet"])
def test_a_sweep_out_where_no_file_can_be_made_is_one_error_before_any_work(monkeypatch, out):
    monkeypatch.setattr(registry, "run", lambda *a, **k: pytest.fail("solved before the output was checked"))
    with pytest.raises(SceneError, match=r"/proc.*: cannot (make the folder of --out|create the sweep's lock file)"):
        sw.sweep(registry.find(LOOM), _axes(), out=out, progress=False)
