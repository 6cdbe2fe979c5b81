"""The command's exit codes (0 solved, 1 a check or target failed, 2 bad input, 3 not solved)
and its refusal of outputs it cannot write before any work is done."""
import pytest

from mechopt import benchmarks, registry
from mechopt.cli import main, scene_template


def test_a_what_if_that_is_not_solved_exits_3(capsys):
    # a band of 1 um: no limaçon follows the offset cardioid that closely
    assert main(["run", "cam-cutter/minimax", "--set", "err_width_mm=0.001"]) == 3
    assert "status: INFEASIBLE" in capsys.readouterr().out


def test_a_scene_that_expects_its_infeasibility_exits_0():
    assert registry.find("loom/group1-window-conflict").spec.expect["status"].value == "INFEASIBLE"
    assert main(["run", "loom/group1-window-conflict"]) == 0


def test_a_failed_check_exits_1(tmp_path):
    text = scene_template(registry.find("cam-cutter/pure-cardioid"), "my/wrong")
    path = tmp_path / "wrong.toml"
    path.write_text(text + '\n[expect.L_mm]\nvalue = 49.0\nabs = 0.01\nkind = "derived"\nwhere = "a wrong guess"\n',
                    encoding="utf-8")
    assert main(["run", str(path)]) == 1


@pytest.mark.parametrize("args, match", [
    (["run", "loom/group1", "--json", "."], r"--json \.: a folder"),
    (["run", "loom/group1", "--set", "colour=1"], r"colour: unknown key"),
    (["run", "no/such-case"], r"unknown case 'no/such-case'"),
    (["run", "missing.toml"], r"missing\.toml: no such scene file"),
    (["validate", "nowhere-folder/"], r"no such scene file|unknown case"),
])
def test_bad_input_exits_2_with_one_line(args, match, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1
    assert __import__("re").search(match, err)


def test_an_output_that_cannot_be_written_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    ran = []
    monkeypatch.setattr(registry, "run", lambda *a, **k: ran.append(a))
    taken = tmp_path / "a-file"
    taken.write_text("x")
    assert main(["run", "loom/group1", "--plot", str(taken)]) == 2
    assert main(["run", "loom/group1", "--json", str(taken / "r.json")]) == 2
    assert main(["run", "loom/group1", "--json", str(tmp_path)]) == 2
    assert ran == [] and taken.read_text() == "x"
    assert "an existing file, not a folder" in capsys.readouterr().err


def test_bench_refuses_zero_repeats_and_exits_1_on_a_missed_target(monkeypatch, tmp_path):
    with pytest.raises(SystemExit) as exit_:
        main(["bench", "loom", "--repeats", "0"])
    assert exit_.value.code == 2

    class Study:
        @staticmethod
        def cli(repeats, out_dir, progress=None):
            return "target  0.5 s  MISSED"
    monkeypatch.setattr("mechopt.cli.study", lambda name: Study)
    assert main(["bench", "loom", "--plot", str(tmp_path)]) == 1
    assert set(benchmarks.STUDIES) >= {"cam-cutter", "press", "loom", "stop-impact", "sweep"}


def test_json_is_written_whole_or_not_at_all(tmp_path):
    out = tmp_path / "deep" / "r.json"
    assert main(["run", "stop-impact/frequencies", "--json", str(out)]) == 0
    import json
    assert json.loads(out.read_text())["case"] == "stop-impact/frequencies"
    assert [p.name for p in out.parent.iterdir()] == ["r.json"]       # no temporary file left beside it


def test_sweep_takes_a_scene_file_and_refuses_a_huge_grid_before_work(tmp_path, capsys):
    path = tmp_path / "mine.toml"
    assert main(["new", "loom", str(path)]) == 0
    out = tmp_path / "mine.parquet"
    assert main(["sweep", str(path), "--grid", "amplitude_limit_mm=0.08:0.14:3", "--out", str(out)]) == 0
    assert "my/mine: 3 variants (3 SOLVED)" in capsys.readouterr().out
    assert main(["sweep", str(path), "--grid", "amplitude_limit_mm=0.08:0.14:100000",
                 "--grid", "sigma_H_limit_MPa=600:1000:100000", "--out", str(tmp_path / "huge.parquet")]) == 2
    err = capsys.readouterr().err
    assert "10,000,000,000 variants" in err and "exceed the limit of 1,000,000" in err
    assert not (tmp_path / "huge.parquet").exists()


def test_run_writes_its_arrays_as_csv_columns(tmp_path):
    import numpy as np

    import mechopt
    out = tmp_path / "press.csv"
    assert main(["run", "press/kd2322", "--csv", str(out)]) == 0
    header = out.read_text().splitlines()[0].split(",")
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    arrays = mechopt.solve("press/kd2322").arrays
    assert header == list(arrays) and data.shape == (len(arrays["t_s"]), len(arrays))
    np.testing.assert_allclose(data[:, header.index("omega_rad_s")], arrays["omega_rad_s"], rtol=1e-11)


def test_the_shipped_sample_record_gives_back_the_scenes_force_law(tmp_path):
    import json
    from pathlib import Path

    import numpy as np

    from mechopt.models.press_laws import FORCE_KEYS, cutting_force_N
    sample = Path(__file__).resolve().parents[2] / "examples" / "instron-sample.csv"
    out = tmp_path / "fit.json"
    assert main(["fit-force", str(sample), "--degree", "4", "--json", str(out)]) == 0
    fit = json.loads(out.read_text())
    assert fit["status"] == "SOLVED"
    # the record is eq. (1) with the scene's coefficients plus 1 % noise: the fitted law follows it
    law = [registry.find("press/kd2322").params()[k] for k in FORCE_KEYS]
    got = [fit["values"][f"c{i}_N_per_mm{i}"] for i in range(1, 5)]
    x = np.linspace(0.0, 3.0, 31)
    assert np.max(np.abs(cutting_force_N(x, *got) - cutting_force_N(x, *law))) < 0.02 * np.max(cutting_force_N(x, *law))


def test_bench_quick_is_offered_where_a_study_has_it_and_the_long_one_says_its_time(capsys, monkeypatch, tmp_path):
    from mechopt.benchmarks import sweep as sweep_bench
    assert main(["bench", "press", "--quick"]) == 2
    assert "bench press: no --quick version" in capsys.readouterr().err
    # the full sweep study announces its expected time (from the budgets it measured) before anything runs,
    # and points to the shorter --quick
    full, quick = sweep_bench.expected_s(5), sweep_bench.expected_s(5, quick=True)
    assert full > 600 and full > 10 * quick
    said = []
    monkeypatch.setattr(sweep_bench, "in_process", lambda *a, **k: (_ for _ in ()).throw(KeyboardInterrupt))
    with pytest.raises(KeyboardInterrupt):
        sweep_bench.cli(5, tmp_path, progress=said.append)
    assert said and f"expect about {full / 60:.0f} min" in said[0] and "--quick" in said[0]


def test_a_reader_that_leaves_early_is_not_an_error(monkeypatch, capsys):
    """`mechopt cases | head -1`: the pipe is closed under the listing; exit 0, not a traceback."""
    import io
    import os
    read_end, write_end = os.pipe()
    os.close(read_end)                      # the reader has left before the first line
    closed_pipe = io.TextIOWrapper(open(write_end, "wb", buffering=0), write_through=True)
    with monkeypatch.context() as patch:
        patch.setattr("sys.stdout", closed_pipe)
        assert main(["cases"]) == 0
    closed_pipe.close()                     # main pointed the descriptor at /dev/null: closes cleanly
