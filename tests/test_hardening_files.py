"""Issue 21, section 1: a sweep touches no file outside the outputs named (a symbolic link at its
lock or parts folder is refused, never followed; it removes only what it wrote), its lock holds
when deleted under it, figures are written atomically, a full disk or a read-only target is one
clear line, and the package imports where `fcntl` does not exist."""
import errno
import os
import subprocess
import sys

import pytest

from mechopt import cli, files, registry
from mechopt import sweep as sw
from mechopt.errors import SceneError

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
