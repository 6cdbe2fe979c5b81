"""Hostile or careless input, the spine's part: a hostile or careless file cannot leak,
execute or exhaust, no request hangs, and legal input is read as meant. Each a clear exit-2 line
naming the file and key, or the right answer."""
import json
import os
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from mechopt import cli, registry
from mechopt import sweep as sw
from mechopt.files import read_regular
from mechopt.kit.errors import ModelError, SceneError, quote
from mechopt.scene import load, loads, parse_overrides
from mechopt.tables import read_rows

SECRET = "root:x:0:0:root:/root:/bin/bash:SECRET-TAIL-0123456789"
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
CSV = '{{ csv = "{}", columns = ["x_mm", "y_mm"] }}'


def _scene(tmp_path, points, name="s.toml", text=SCENE):
    path = tmp_path / name
    path.write_text(text.format(points=points), encoding="utf-8")
    return path


def _secret(tmp_path):
    path = tmp_path / "passwd"
    path.write_text((SECRET + "\n") * 3)
    return path


# --- references: no content echoed, regular files only, reads bounded ---------------------------

def test_a_table_reference_to_a_private_file_echoes_nothing_of_it(tmp_path):
    path = _scene(tmp_path, CSV.format(_secret(tmp_path)))
    with pytest.raises(SceneError, match=r"passwd: not a CSV table with columns x_mm, y_mm \(its first line is no "
                                         r"header of column names\)") as exc:
        load(path)
    assert "root" not in str(exc.value).replace(str(tmp_path), "")


def test_a_base_that_is_a_private_file_is_named_not_quoted(tmp_path):
    path = _scene(tmp_path, "[[0, 0], [1, 1]]", text=f'base = {{{{ scene = "{_secret(tmp_path)}" }}}}\n' + SCENE)
    with pytest.raises(SceneError, match=r"passwd: not valid TOML") as exc:
        load(path)
    assert "SECRET" not in str(exc.value)


@pytest.mark.parametrize("reference", ["scene", "base", "csv"])
def test_a_device_as_a_reference_is_refused_at_once(tmp_path, reference):
    path = {"scene": lambda: "/dev/zero",
            "base": lambda: _scene(tmp_path, "[]", text='base = {{ scene = "/dev/zero" }}\n' + SCENE),
            "csv": lambda: _scene(tmp_path, CSV.format("/dev/zero"))}[reference]()
    with pytest.raises(SceneError, match=r"/dev/zero: a device, not a (scene file|point table) \(references must name "
                                         r"regular files\)"):
        load(path)


def test_a_fifo_as_a_scene_or_table_is_refused_without_blocking(tmp_path, monkeypatch):
    fifo = tmp_path / "p.csv"
    os.mkfifo(fifo)
    opened, real_open = [], os.open

    def spy(path, flags, *args, **kwargs):       # a FIFO opened without O_NONBLOCK waits for a writer for ever
        if Path(path) == fifo:
            opened.append(flags)
        return real_open(path, flags, *args, **kwargs)
    monkeypatch.setattr(os, "open", spy)
    with pytest.raises(SceneError, match=r"p.csv: a FIFO, not a scene file"):
        load(fifo)
    with pytest.raises(SceneError, match=r"p.csv: a FIFO, not a point table"):
        load(_scene(tmp_path, CSV.format(fifo)))
    assert opened and all(flags & os.O_NONBLOCK for flags in opened)


def test_a_file_growing_past_its_limit_is_refused_by_the_bytes_read(tmp_path, monkeypatch):
    path = tmp_path / "grows.csv"
    path.write_bytes(b"x" * 100)
    real_fstat = os.fstat
    monkeypatch.setattr(os, "fstat", lambda fd: os.stat_result((*real_fstat(fd)[:6], 0, *real_fstat(fd)[7:])))
    with pytest.raises(ValueError, match=r"grows.csv: more than 5e-05 MB; a table is at most 5e-05 MB"):
        read_regular(path, max_bytes=50, what="a table")       # st_size says 0, as /proc files do


def test_a_csv_of_too_many_rows_is_refused_before_it_is_parsed(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text("travel_mm,load_N\n" + "1,2\n" * 2001)
    with pytest.raises(ModelError, match=r"big.csv: 2,001 rows; a load-travel record has at most 2,000 rows"):
        read_rows(path, what="a load-travel record", example="travel_mm,load_N", max_rows=2000)


def test_csv_values_of_1e300_are_refused_with_their_line(tmp_path):
    (tmp_path / "p.csv").write_text("x_mm,y_mm\n0,0\n1e300,1\n2,0\n3,1\n")
    with pytest.raises(SceneError, match=r"p.csv: line 3: expected finite numbers within ±1e\+09"):
        load(_scene(tmp_path, CSV.format("p.csv")))


def test_every_cli_error_is_capped_in_length(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(registry, "find", lambda ref: (_ for _ in ()).throw(SceneError("row 1, " * 10_000)))
    assert cli.main(["run", "x"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err) < cli.MAX_MESSAGE + 80 and err.endswith("more characters)")


def test_quote_shows_a_short_escaped_prefix():
    text = "a\x1b[31m" + "b" * 100
    assert quote(text, 10) == f"'a\\x1b[31m... ({len(repr(text))} characters)"


# --- TOML, literals, names -----------------------------------------------------------------------

@pytest.mark.parametrize("points, match", [
    ("[" * 5000 + "]" * 5000, r"s.toml: not a scene: arrays or tables nested too deeply"),
    ("[[0, 1" + "0" * 5000 + "], [1, 1]]", r"s.toml: not a scene: Exceeds the limit \(4300 digits\)"),
], ids=["nesting", "digits"])
def test_hostile_toml_is_one_clear_line(tmp_path, points, match):
    with pytest.raises(SceneError, match=match):
        load(_scene(tmp_path, points))


@pytest.mark.parametrize("value, match", [
    ("1" + "0" * 5000, r"--set a_mm: the value \(5,001 characters\) is no number or table a mechanism takes"),
    ("[" * 3000 + "]" * 3000, r"--set a_mm: the value \(6,000 characters\) is no number"),
], ids=["digits", "nesting"])
def test_hostile_set_values_are_one_clear_line(value, match):
    with pytest.raises(SceneError, match=match):
        parse_overrides([f"a_mm={value}"])


def test_an_integer_no_float_holds_is_refused_naming_the_key():
    with pytest.raises(SceneError, match=r"params.amplitude_limit_mm=1000.*\(401 characters\): expected a finite"):
        registry.find("loom/group1").build({"amplitude_limit_mm": 10**400})


@pytest.mark.parametrize("line, match", [
    ('task = "cam_profile.np"', r"task = 'cam_profile.np' names a module, not a model's task class"),
    ('solver = "cam_cutter.METHODS"', r"solver = 'cam_cutter.METHODS' names a dict, not a solver function"),
])
def test_a_task_or_solver_name_that_is_no_class_or_function_is_refused(tmp_path, line, match):
    key = line.split(" =")[0]
    text = "\n".join(line if row.startswith(key + " =") else row for row in SCENE.splitlines())
    with pytest.raises(SceneError, match=match):
        load(_scene(tmp_path, "[[0, 0], [1, 1]]", text=text))


def test_a_negative_seed_is_refused():
    with pytest.raises(SceneError, match=r"--seed -1: expected a whole number from 0 to 2\*\*63 - 1"):
        sw.plan(registry.find("loom/group1"), random=[sw.parse_random("amplitude_limit_mm=0.1:0.2")], samples=2,
                seed=-1)


def test_cases_at_the_root_of_the_disk_is_refused_after_a_bounded_walk(monkeypatch, tmp_path):
    from mechopt import scene as scene_mod
    for k in range(30):
        (tmp_path / f"d{k}").mkdir()
    monkeypatch.setattr(scene_mod, "MAX_WALK_ENTRIES", 20)
    with pytest.raises(SceneError, match=r"more than 20 files and folders below it; a folder of scenes is smaller"):
        scene_mod.scene_files(tmp_path)


# --- hostile sweep tables ------------------------------------------------------------------------

def _table(path, meta_text, key="amplitude_limit_mm", message="ok"):
    table = pa.table({key: [0.1, 0.2], "variant": [0, 1], "status": ["SOLVED", "FAILED"],
                      "message": [message] * 2, "x_mm": [1.0, 2.0]})
    pq.write_table(table.replace_schema_metadata({b"mechopt.sweep": meta_text.encode()}), path)
    return path


def _meta(case="loom/group1", key="amplitude_limit_mm"):
    return {"case": case, "scene_sha256": "0" * 64,
            "spec": {"case": case, "grid": [{"key": key, "low": 0.1, "high": 0.2, "num": 2}], "random": [],
                     "samples": 0, "seed": 0}}


@pytest.mark.parametrize("meta, match", [
    ("not json{", r"not JSON \(starts 'not json\{'\)"),
    ('{"case": 1, "spec": [1], "scene_sha256": null}', r"case must be text and scene_sha256 64 hex digits"),
    ("[" * 60_000 + "]" * 60_000, r"120,000 bytes, more than a sweep's spec ever needs"),
    ("[" * 20_000 + "]" * 20_000, r"not JSON"),
    (json.dumps(_meta() | {"spec": {"case": "x", "grid": [{"key": 1}], "random": [], "samples": 0, "seed": 0}}),
     r"spec.grid must be a list of axes"),
], ids=["not-json", "wrong-types", "oversize", "deep", "bad-axis"])
def test_hostile_sweep_metadata_is_refused_naming_the_file(tmp_path, meta, match):
    path = _table(tmp_path / "h.parquet", meta)
    with pytest.raises(SceneError, match=r"h.parquet: its mechopt.sweep metadata is not a sweep's: " + match):
        sw.read_table(path)
    with pytest.raises(SceneError, match=r"h.parquet: its mechopt.sweep metadata is not a sweep's"):
        sw.sweep(registry.find("loom/group1"), [sw.parse_grid("amplitude_limit_mm=0.1:0.2:2")], out=path,
                 progress=False)


def test_a_sweep_table_lacking_its_columns_is_refused(tmp_path):
    path = _table(tmp_path / "h.parquet", json.dumps(_meta(key="other_key")))
    with pytest.raises(SceneError, match=r"h.parquet: not a sweep's table: column 'other_key' is missing"):
        sw.read_table(path)


def test_the_report_escapes_every_value_of_a_hostile_sweep_table(tmp_path):
    from mechopt.report import write_report
    script = "<script>alert(1)</script>"
    path = _table(tmp_path / "h.parquet", json.dumps(_meta(case=script, key=script)), key=script, message=script)
    page = write_report(tmp_path / "rep", scenes=[], sweeps=[path]).read_text()
    assert "<script>alert" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page


# --- section 3: no hang --------------------------------------------------------------------------

def test_a_list_of_500_speeds_is_refused_before_any_work():
    with pytest.raises(SceneError, match=r"rebound-177rpm.toml: speeds_rpm: 500 entries; a list given here holds "
                                         r"at most 100"):
        registry.run("stop-impact/rebound-177rpm", {"speeds_rpm": [177] * 500})


def test_a_scheduler_address_where_a_silent_server_answers_is_refused_within_the_timeout(monkeypatch):
    import distributed

    def client(*args, **kwargs):                 # its handshake with a silent server is what would hang
        raise AssertionError("a Dask client was made for a silent server")
    monkeypatch.setattr(distributed, "Client", client)
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    held = []
    threading.Thread(target=lambda: held.append(server.accept()), daemon=True).start()
    try:
        with pytest.raises(SceneError, match=r"a server answers there but said nothing within 0.5 s: not a Dask"):
            sw._connect(f"tcp://127.0.0.1:{server.getsockname()[1]}", 0.5)
    finally:
        server.close()
        for conn, _ in held:
            conn.close()


# --- section 5: legal input read as meant ---------------------------------------------------------

def test_a_scene_with_a_byte_order_mark_loads(tmp_path):
    path = _scene(tmp_path, "[[0, 0], [1, 1]]")
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    with pytest.raises(SceneError, match=r"points_mm: expected two columns"):   # read as TOML: the model speaks
        load(path)


def test_a_whole_structure_entry_the_scene_lacks_is_structure_not_a_parameter():
    scene = registry.find("loom/group1")
    assert "windows" not in scene.spec.structure
    window = [{"from": "3", "to": "7", "max_deg": 1.0}]
    task, _ = scene.build({"windows": window})
    assert task.windows == window


def test_a_grid_over_a_structure_path_with_a_selector_is_parsed_and_swept():
    axis = sw.parse_grid("operations[from=3,to=7].min_deg=10:40:4")
    assert axis == sw.Axis("operations[from=3,to=7].min_deg", 10.0, 40.0, 4)
    spec, variants = sw.plan(registry.find("loom/group1"), [axis])
    assert [v["operations[from=3,to=7].min_deg"] for v in variants] == [10.0, 20.0, 30.0, 40.0]
    with pytest.raises(SceneError, match=r"\[from=3,to=9\] matches 0 entries of 'operations', not one"):
        sw.plan(registry.find("loom/group1"), [sw.parse_grid("operations[from=3,to=9].min_deg=10:40:4")])


def test_derive_naming_a_missing_scene_names_the_file_and_the_key(tmp_path):
    text = SCENE.format(points="[[0, 0], [1, 1]]") + '[derive]\nt0_rad = "no/such-scene:x"\n'
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"s.toml: derive.t0_rad = 'no/such-scene:x': unknown case 'no/such-scene'"):
        registry.run(path)


def test_a_solver_error_is_not_solved_not_bad_input(monkeypatch, capsys):
    from mechopt.kit.errors import SolverError
    monkeypatch.setattr(registry, "run", lambda *a, **k: (_ for _ in ()).throw(SolverError("CVODES gave up")))
    assert cli.main(["run", "loom/group1"]) == cli.NOT_SOLVED
    assert capsys.readouterr().err.strip() == "error: not solved: CVODES gave up"


def test_a_sweep_sends_the_csv_table_its_scene_references_to_the_workers(tmp_path):
    table = tmp_path / "tables" / "cam.csv"
    table.parent.mkdir()
    table.write_text((Path(__file__).parents[2] / "examples" / "cam-profile-table.csv").read_text())
    path = _scene(tmp_path, CSV.format("tables/cam.csv"))
    source = sw.SceneText.of(load(path))
    assert [p for p, _ in source.files] == [str(table.resolve())]
    table.unlink()                       # a worker on another machine has no copy of it
    rows = sw.run_chunk(source, [(0, {"err_width_mm": 0.5})])
    assert rows[0]["status"] == "SOLVED", rows[0]["message"]
    with pytest.raises(SceneError, match=r"cam.csv: cannot read: No such file"):
        loads(source.text, path)         # without what was sent, the table is not there


def test_threads_loading_scenes_at_once_see_no_false_loop(tmp_path, monkeypatch):
    """While one thread reads the base of s.toml, another loads t.toml whose base is s.toml: each
    thread's chain of scenes being read is its own (a shared one made the second a false loop)."""
    import mechopt.scene as scene_module
    kd2322 = Path(registry.find("press/kd2322").path)
    (tmp_path / "s.toml").write_text(f'id = "mine/s"\ntitle = "s"\nsource = "t"\ntask = "press.PressDrive"\n'
                                     f'solver = "press.steady_state"\nbase = {{ scene = "{kd2322}" }}\n', encoding="utf-8")
    (tmp_path / "t.toml").write_text('id = "mine/t"\ntitle = "t"\nsource = "t"\ntask = "press.PressDrive"\n'
                                     'solver = "press.steady_state"\nbase = { scene = "s.toml" }\n', encoding="utf-8")
    inside, done = threading.Event(), threading.Event()
    real = scene_module.read_regular

    def slow_base(path, **kw):              # the first thread pauses inside s.toml's base
        if Path(path).resolve() == kd2322.resolve() and threading.current_thread().name == "first":
            inside.set()
            done.wait(30)
        return real(path, **kw)

    monkeypatch.setattr(scene_module, "read_regular", slow_base)
    errors = []
    first = threading.Thread(target=lambda: scene_module.load(tmp_path / "s.toml"), name="first")
    first.start()
    assert inside.wait(30)
    try:
        scene_module.load(tmp_path / "t.toml")
    except SceneError as exc:
        errors.append(str(exc))
    finally:
        done.set()
        first.join(60)
    assert errors == []


# --- no traceback from a link loop, a long chain of scenes, a deep expression, a solver's limit -----

def test_a_scene_that_is_a_symlink_loop_is_one_clear_line(tmp_path, capsys):
    loop = tmp_path / "loop.toml"
    loop.symlink_to("loop.toml")
    assert cli.main(["run", str(loop)]) == cli.BAD_INPUT
    assert capsys.readouterr().err.strip() == f"error: {loop}: cannot read: Too many levels of symbolic links"
    with pytest.raises(SceneError, match=r"loop.toml: cannot read: Too many levels of symbolic links"):
        load(_scene(tmp_path, "[]", text='base = {{ scene = "loop.toml" }}\n' + SCENE))


def test_a_chain_of_300_base_scenes_is_refused_naming_the_limit(tmp_path):
    from mechopt import scene as scene_mod
    MAX_CHAIN = getattr(scene_mod, "MAX_CHAIN", 32)
    _scene(tmp_path, "[[0, 0], [1, 1], [2, 0]]", name="s0.toml")
    head = ('base = {{ scene = "s{}.toml" }}\nid = "c/s{}"\ntitle = "t"\nsource = "s"\n'
            'task = "cam_profile.ProfileFit"\nsolver = "cam_cutter.minimax"\n[params]\n')
    for k in range(1, 301):
        (tmp_path / f"s{k}.toml").write_text(head.format(k - 1, k))
    with pytest.raises(SceneError, match=rf"s{300 - MAX_CHAIN}.toml: base: s{299 - MAX_CHAIN}.toml makes a chain of "
                                         rf"references \(base, scene = ...\) of more than {MAX_CHAIN} scenes; a chain "
                                         rf"holds at most {MAX_CHAIN}"):
        load(tmp_path / "s300.toml")


@pytest.mark.parametrize("expression, match", [
    ("-" * 1990 + "t", r"x_expr: operators nested more than 100 levels deep; at most 100"),
    ("1" * 1999, r"x_expr: a number of 1,999 digits beyond a float's range \(at most 1.8e308\)"),
], ids=["unary-minus", "digits"])
def test_a_deep_or_huge_expression_is_one_clear_line(expression, match):
    with pytest.raises(SceneError, match=r"other-profile.toml: structure.x_expr: " + match):
        registry.find("cam-cutter/other-profile").build({"x_expr": expression})


def test_the_press_sensitivity_at_its_step_limit_is_a_status_not_a_traceback(monkeypatch):
    import importlib
    sensitivity = importlib.import_module("mechopt.solvers.press.sensitivity")
    task, _ = registry.find("press/sensitivity").build()
    # CVODES stops as it does with a 0.01 kg m2 flywheel (`--set flywheel_inertia_kgm2=0.01`), in a fraction of its time
    monkeypatch.setattr(sensitivity, "MAX_STEPS", 20, raising=False)
    r = sensitivity.sensitivity(task, tol=1e-6)
    assert r.status.value == "LIMIT" and r.values == {}
    assert r.message.startswith("CVODES gave up (CV_TOO_MUCH_WORK: more steps than allowed")
    assert "Traceback" not in r.message and "\n" not in r.message


# --- bounded messages and checks, tables read as meant, nothing of a foreign file echoed ------------

def _chain(n, cycle_deg=10.0):
    from mechopt.models.loom import Cyclogram
    return Cyclogram(operations=[{"from": f"e{k}", "to": f"e{k + 1}", "min_deg": 1.0} for k in range(n)],
                     cycle_deg=cycle_deg)


@pytest.mark.parametrize("method", ["graph", "lp"])
def test_an_infeasible_chain_of_2000_operations_is_named_in_a_bounded_message(method):
    from mechopt.kit.errors import NAMED
    from mechopt.solvers.loom import plan_cyclogram
    r = plan_cyclogram(_chain(2000), method=method)
    assert r.status.value == "INFEASIBLE"
    assert r.message.startswith("infeasible: conflicting chain t(e0->e1) >= 1 deg (min_angle); ")
    assert f" ... and {2001 - NAMED:,} more (needs 1990 deg more than its limits allow)" in r.message
    assert len(r.message) < 2000 and len(r.violated) == NAMED
    assert len(r.diagnostics["conflict_events"]) == NAMED and r.diagnostics["conflict_length"] == 2001


def test_a_result_bounds_any_message_and_list_of_broken_limits():
    from mechopt.kit.result import MAX_MESSAGE, MAX_VIOLATED, Result, Status, Timing
    r = Result(Status.INFEASIBLE, {}, Timing(0, 0), message="x" * 10**6, violated=tuple(f"v{k}" for k in range(10**4)))
    assert len(r.violated) == MAX_VIOLATED and r.violated[-1] == f"v{MAX_VIOLATED - 1}"
    assert len(r.message) < MAX_MESSAGE + 120
    assert r.message.endswith(f"... (and {10**6 - MAX_MESSAGE:,} more characters) (violated names the first "
                              f"{MAX_VIOLATED} of 10,000 broken limits)")


def test_a_header_of_100000_columns_is_refused_at_once(tmp_path):
    path = tmp_path / "wide.csv"
    path.write_text(",".join(f"c{k}" for k in range(100_000)) + "\n" + ",".join(["1"] * 100_000) + "\n")
    start = time.process_time()
    with pytest.raises(ModelError, match=r"wide.csv: line 1: a header of 100,000 columns; a table of operations has at "
                                         r"most 100"):
        _operations(path)
    assert time.process_time() - start < 10        # CPU seconds, not wall-clock: 68.6 s before (quadratic)


def _operations(path):
    from mechopt.models.loom import OPERATION_COLUMNS
    from mechopt.tables import read_records
    return read_records(path, ("from", "to"), OPERATION_COLUMNS, required=("from", "to"), what="a table of operations",
                        example="from,to,min_deg")


@pytest.mark.parametrize("text, match", [
    ("from,to,min_deg\na,b,1\na," + "b" * 131_073 + ",1\n",
     r"t.csv: line 3: a cell longer than 131,072 characters, the most a cell may hold"),
    ("from,to,min_deg\na,b,1\na\x00x,b,1\n", r"t.csv: line 3, column from: a NUL character; a CSV table is text"),
    ("from,to,min_deg\na,b,1\na,c,1_0\n", r"t.csv: line 3, column min_deg: expected a number, got '1_0'"),
    ("from,to,min_deg\na,b,inf\n", r"t.csv: line 2, column min_deg: expected a number, got 'inf'"),
    ('from,to,min_deg,name\na,b,1,"feed\nstart"\nb,c,1,x\n',
     r"t.csv: line 2: a line break inside a quoted cell; every cell of a table of operations is one line"),
], ids=["long-cell", "nul", "underscore", "inf", "line-break"])
def test_a_timing_table_cell_that_is_no_plain_value_is_refused_naming_line_and_column(tmp_path, text, match):
    path = tmp_path / "t.csv"
    path.write_text(text, encoding="utf-8", newline="")
    with pytest.raises(ModelError, match=match):
        _operations(path)


def test_exactly_the_most_rows_with_a_last_line_break_are_read_and_one_more_is_refused(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text("travel_mm,load_N\n\n" + "1,2\n" * 2000 + "\n")
    header, rows, _ = read_rows(path, what="a load-travel record", example="travel_mm,load_N", max_rows=2000)
    assert len(rows) == 2000
    path.write_text("travel_mm,load_N\n" + "1,2\n" * 2001)
    with pytest.raises(ModelError, match=r"big.csv: 2,001 rows; a load-travel record has at most 2,000 rows"):
        read_rows(path, what="a load-travel record", example="travel_mm,load_N", max_rows=2000)


@pytest.mark.parametrize("reader", ["points", "operations", "force"])
def test_a_file_that_is_no_table_is_said_to_be_none_quoting_nothing_of_it(tmp_path, reader):
    from mechopt.force_data import read_force_csv
    secret = _secret(tmp_path)
    (tmp_path / "token").write_text("a3f9c2d18b7e4f60a3f9c2d18b7e4f60\nsecond-line-secret\n")
    for path in (secret, tmp_path / "token"):
        with pytest.raises((ModelError, SceneError), match=r"not a CSV table with columns") as exc:
            {"points": lambda: load(_scene(tmp_path, CSV.format(path))), "operations": lambda: _operations(path),
             "force": lambda: read_force_csv(path)}[reader]()
        said = str(exc.value).replace(str(tmp_path), "")
        assert not any(word in said for word in ("root", "a3f9", "second", "SECRET"))


LOOM_SCENE = """id = "mine/names"
title = "names a spreadsheet would misread"
source = "a test"
task = "loom.Cyclogram"
solver = "loom.plan_cyclogram"
[params]
cycle_deg = {{ value = 360.0, mark = "assumed", why = "a test" }}
[structure]
operations = [{{ from = "feed, start", to = '=HYPERLINK("http://x.test")', min_deg = 10.0 }},
              {{ from = '=HYPERLINK("http://x.test")', to = "@end", min_deg = 20.0 }}]
"""


def test_csv_output_quotes_text_and_defuses_formulas_numbers_stay_numbers(tmp_path, capsys):
    import csv as csv_module
    scene = tmp_path / "names.toml"
    scene.write_text(LOOM_SCENE.format(), encoding="utf-8")
    assert cli.main(["run", str(scene), "--csv", str(tmp_path / "plan.csv")]) == cli.OK
    with open(tmp_path / "plan.csv", newline="", encoding="utf-8") as f:
        rows = list(csv_module.reader(f))
    assert rows[0][:4] == ["operation", "start_deg", "end_deg", "duration_deg"]
    assert all(len(row) == len(rows[0]) for row in rows)          # "feed, start" shifts no cell
    assert [row[0] for row in rows[1:]] == ['feed, start->=HYPERLINK("http://x.test")',
                                            '\'=HYPERLINK("http://x.test")->@end']
    assert [row[1:4] for row in rows[1:]] == [["0", "10", "10"], ["10", "30", "20"]]
    negative = cli.arrays_csv({"name": np.array(["-x", "+y", "@z", "ok"]), "v_mm": np.array([-1.5, 2.0, 3.0, 4.0])},
                              "t")
    assert negative.splitlines() == ["name,v_mm", "'-x,-1.5", "'+y,2", "'@z,3", "ok,4"]


@pytest.mark.parametrize("samples", [2.5, 2.0, "2"])
def test_a_sweep_of_a_fractional_number_of_samples_is_refused_naming_its_type(samples):
    with pytest.raises(SceneError, match=rf"--samples {samples!r}: expected a whole number \(int\) of random draws, "
                                         rf"not {type(samples).__name__}"):
        sw.plan(registry.find("loom/group1"), random=[sw.parse_random("amplitude_limit_mm=0.1:0.2")], samples=samples)


@pytest.mark.parametrize("case, assignment, where", [
    ("stop-impact/rebound-177rpm", "speeds_rpm=[{}]", r"structure.speeds_rpm\[0\]"),
    ("loom/group1", "operations[from=3,to=7].min_deg={}", r"structure.operations\[\d+\].min_deg"),
    ("cam-cutter/other-profile", "constants.A_mm={}", r"structure.constants.A_mm"),
], ids=["list", "selector", "table"])
def test_a_1999_digit_integer_in_a_structure_is_refused_naming_its_path(case, assignment, where):
    with pytest.raises(SceneError, match=where + r": a number beyond a float's range \(at most 1.8e308\)"):
        registry.find(case).build(parse_overrides([assignment.format("1" * 1999)]))


@pytest.mark.parametrize("operations, match", [
    ([{"from": f"e{k}", "to": f"e{k + 1}", "min_deg": 1.0} for k in range(3000)]
     + [{"from": "e3000", "to": "e0", "min_deg": 1.0}],
     r"precedence cycle e\d+ -> .* \.\.\. and 2,98\d more: an event"),
    ([{"from": f"s{k}", "to": "end", "min_deg": 1.0} for k in range(3000)],
     r"found first \['s0', .* \.\.\. and 2,980 more\] and last \['end'\]"),
], ids=["cycle", "starts"])
def test_a_timing_network_error_names_a_bounded_part_of_a_large_network(operations, match):
    from mechopt.models.loom import Cyclogram
    with pytest.raises(ModelError, match=match) as exc:
        Cyclogram(operations=operations, cycle_deg=360.0)
    assert len(str(exc.value)) < 1000


def test_a_grid_of_a_whole_number_setting_must_hold_whole_numbers():
    """samples (per piece, an int setting) swept at 2.5 was run as 2 unsaid; whole grids still run."""
    scene = registry.find("press/loads")
    with pytest.raises(SceneError, match=r"--grid samples: samples is a whole-number solver setting, but the grid "
                                         r"holds 2.5"):
        sw.plan(scene, grid=[sw.parse_grid("samples=2.5:2.5:1")])
    _, variants = sw.plan(scene, grid=[sw.parse_grid("samples=8:16:3")])
    assert [v["samples"] for v in variants] == [8, 12, 16]


def test_an_expression_given_as_a_huge_number_is_named_not_echoed():
    """--set x_expr=<1999 digits> is no expression: the message says so and quotes a short prefix."""
    with pytest.raises(SceneError) as caught:
        registry.find("cam-cutter/other-profile").build(parse_overrides(["x_expr=" + "9" * 1999]))
    assert "expected an expression in t" in str(caught.value) and len(str(caught.value)) < 400
