"""The static HTML report: the validation table as `registry.run` computes it, calibrations and
assumptions marked, figures and bench plots linked to files that exist beside the page."""
import html
import re

import matplotlib
import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.plots import save_figure
from mechopt.report import write_report

matplotlib.use("Agg")
SCENES = ("loom/group1", "stop-impact/frequencies")


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    root = tmp_path_factory.mktemp("report")
    bench = root / "bench_out"
    bench.mkdir()
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots()
    ax.loglog([1e-3, 1e-2], [1e-2, 1e-6])
    save_figure(fig, bench / "demo_work_precision.png")
    path = write_report(root / "site", scenes=[registry.find(s) for s in SCENES], bench_dir=bench)
    return path, path.read_text(encoding="utf-8")


def _rows(text):
    return [[re.sub("<[^>]+>", "", cell) for cell in re.findall(r"<td>(.*?)</td>", row)]
            for row in re.findall(r"<tr>(.*?)</tr>", text) if "<td>" in row]


def test_validation_table_holds_each_check_as_computed(page):
    _, text = page
    rows = {(r[0], r[1]): r for r in _rows(text) if len(r) == 8}
    for case in SCENES:
        run = registry.run(registry.find(case))
        assert run.checks
        for c in run.checks:
            row = rows[(case, c.name)]
            assert html.unescape(row[3]) == c.expected
            got = row[4]
            assert (got == c.got) if isinstance(c.got, str) else float(got) == pytest.approx(c.got, rel=1e-5)
            assert row[5] == (("ok (calibrated)" if c.calibrated else "ok") if c.ok else "FAIL")


def test_calibrations_are_marked_and_not_counted_as_reproductions(page):
    _, text = page
    checks = [c for s in SCENES for c in registry.run(registry.find(s)).checks]
    fitted = sum(c.ok and c.calibrated for c in checks)
    assert fitted >= 1                                     # stop-impact/frequencies is fitted to its figures
    assert f"{len(checks) - fitted} reproduced, {fitted} calibrated" in text
    scene = registry.find("stop-impact/frequencies")
    for key, param in scene.spec.params.items():
        if param.mark != "given":
            assert f"<td>{html.escape(key)}</td><td>{param.mark}</td>" in text


def test_figures_and_bench_plots_are_linked_files(page):
    path, text = page
    sources = re.findall(r"<img src='([^']+)'", text)
    assert "bench/demo_work_precision.png" in sources
    assert any(s.startswith("figures/loom_group1/") for s in sources)
    assert all((path.parent / s).is_file() for s in sources)


def test_report_without_bench_output_says_so(tmp_path):
    path = write_report(tmp_path, scenes=[registry.find("loom/group1")], bench_dir=tmp_path / "none")
    assert "no `mechopt bench` output found in" in path.read_text(encoding="utf-8")


def test_cli_report_and_unknown_case(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--case", "loom/group1", "--bench", str(tmp_path / "b")]) == 0
    assert (tmp_path / "index.html").is_file()
    assert main(["report", "--out", str(tmp_path / "x"), "--case", "loom/grup1"]) == 2
    assert "unknown case 'loom/grup1'" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
