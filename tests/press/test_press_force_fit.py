"""Polynomial force law from load-travel data (paper 001, eq. (1)).

The data here are a TEST FIXTURE generated from eq. (1) with seeded noise, not the paper's
Instron experiment (its 60 readings are not published).
"""
import numpy as np
import pytest

from mechopt.force_data import read_force_csv
from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Status
from mechopt.models.press_laws import cutting_force_N
from mechopt.solvers.press.force_fit import fit_force

EQ1 = {"c1_N_per_mm1": 1075.68, "c2_N_per_mm2": -406.8, "c3_N_per_mm3": -4.0, "c4_N_per_mm4": 90.93}


def _fixture(points=60, noise=0.0, seed=5):
    """60 readings on X in (0, 3] mm from eq. (1), with relative Gaussian noise: a fixture, not the experiment."""
    x = np.linspace(0.05, 3.0, points)
    f = cutting_force_N(x, *EQ1.values())
    return x, f * (1 + noise * np.random.default_rng(seed).standard_normal(points))


def test_quartic_recovers_eq1_from_clean_data():
    r = fit_force(*_fixture(), 4)
    assert r.status is Status.SOLVED
    for key, value in EQ1.items():
        assert r.values[key] == pytest.approx(value, rel=1e-9)
    assert r.values["max_rel_error"] < 1e-10


def test_quartic_on_noisy_data_is_close_and_lower_degrees_err_more():
    x, f = _fixture(noise=0.01)
    quartic = fit_force(x, f, 4)
    assert quartic.values["c1_N_per_mm1"] == pytest.approx(1075.68, rel=0.05)
    assert quartic.values["max_rel_error"] < 0.05                 # 1 % noise, 60 points: a few per cent at worst
    assert {"max_rel_error_seg1", "max_rel_error_seg2"} <= quartic.values.keys()
    linear = fit_force(x, f, 1)
    assert linear.values["max_rel_error"] > 3 * quartic.values["max_rel_error"]


def test_fit_with_intercept_matches_numpy_polyfit():
    x, f = _fixture(noise=0.02)
    r = fit_force(x, f, 3, through_origin=False)
    ref = np.polynomial.polynomial.polyfit(x, f, 3)
    got = [r.values["c0_N"]] + [r.values[f"c{k}_N_per_mm{k}"] for k in (1, 2, 3)]
    assert np.allclose(got, ref, rtol=1e-9, atol=1e-9)


def test_errors_per_segment_are_the_largest_relative_misfits_inside_each():
    x = np.array([1.0, 2.0, 3.0, 4.0])
    f = np.array([1.0, 2.0, 3.0, 5.0])
    r = fit_force(x, f, 1, segments=2)
    c = r.values["c1_N_per_mm1"]
    assert c == pytest.approx(np.dot(x, f) / np.dot(x, x))       # least squares through the origin
    rel = np.abs(c * x - f) / f
    assert r.values["max_rel_error_seg1"] == pytest.approx(rel[:2].max())   # edges 1, 2.5, 4
    assert r.values["max_rel_error_seg2"] == pytest.approx(rel[2:].max())


def test_csv_with_units_in_the_header(tmp_path):
    x, f = _fixture(noise=0.01)
    mm = tmp_path / "mm.csv"
    mm.write_text("travel_mm,load_N\n" + "".join(f"{a},{b}\n" for a, b in zip(x, f)))
    si = tmp_path / "si.csv"
    si.write_text("load_kN,travel_m\n" + "".join(f"{float(b) / 1000!r},{float(a) / 1000!r}\n" for a, b in zip(x, f)))
    a, b = fit_force(*read_force_csv(mm), 4), fit_force(*read_force_csv(si), 4)
    for key in EQ1:
        assert a.values[key] == pytest.approx(b.values[key], rel=1e-9)
    assert a.values["c4_N_per_mm4"] == pytest.approx(fit_force(x, f, 4).values["c4_N_per_mm4"], rel=1e-12)


def test_too_few_distinct_travels_is_inaccurate_not_a_fit():
    r = fit_force([1.0, 1.0, 1.0], [2.0, 2.1, 1.9], 2)
    assert r.status is Status.INACCURATE and "rank 1 < 2" in r.message


@pytest.mark.parametrize("args, kwargs, match", [
    (([1.0, 2.0], [1.0], 1), {}, r"travel_mm has 2 values but load_N has 1"),
    (([1.0, 2.0], [1.0, np.nan], 1), {}, r"must be finite numbers"),
    (([1.0, 2.0], [0.0, 0.0], 1), {}, r"load_N is zero everywhere: there is no force law to fit"),
    (([1.0, 2.0], [1.0, 2.0], 4), {}, r"2 points cannot fix 4 coefficients of degree 4; give at least 4"),
])
def test_bad_fit_input_is_refused(args, kwargs, match):
    with pytest.raises(ModelError, match=match):
        fit_force(*args, **kwargs)


@pytest.mark.parametrize("degree, kwargs, match", [
    (0, {}, r"degree=0: allowed 1, 2, 3, 4, 5 or 6"),
    (7, {}, r"degree=7: allowed 1, 2, 3, 4, 5 or 6"),
    (2.5, {}, r"degree=2\.5: allowed"),
    (1, {"segments": 0}, r"segments=0: must be an integer >= 1"),
])
def test_a_bad_fit_setting_is_a_setting_error(degree, kwargs, match):
    with pytest.raises(SettingError, match=match):
        fit_force([1.0, 2.0], [1.0, 2.0], degree, **kwargs)


@pytest.mark.parametrize("text, match", [
    ("travel_in,load_N\n1,2\n", r"column 'travel_in': unit 'in' unknown; allowed travel_mm, travel_m, travel_um"),
    ("travel_mm,force_N\n1,2\n", r"no 'load_<unit>' column in header \['travel_mm', 'force_N'\]"),
    ("travel_mm,load_N\n1,abc\n", r"line 2: \['1', 'abc'\] is not a number in every column"),
    ("", r"empty file; expected a header such as travel_mm,load_N"),
])
def test_bad_csv_is_refused_naming_what_is_allowed(tmp_path, text, match):
    path = tmp_path / "d.csv"
    path.write_text(text)
    with pytest.raises(ModelError, match=match):
        read_force_csv(path)


def test_cli_fit_force_prints_the_coefficients_and_segment_errors(tmp_path, capsys):
    from mechopt.cli import main
    x, f = _fixture(noise=0.01)
    path = tmp_path / "instron.csv"
    path.write_text("travel_mm,load_N\n" + "".join(f"{a},{b}\n" for a, b in zip(x, f)))
    assert main(["fit-force", str(path), "--degree", "4"]) == 0
    out = capsys.readouterr().out
    expected = fit_force(x, f, 4)
    assert f"{expected.values['c4_N_per_mm4']:.6g}" in out and "max_rel_error_seg2" in out
    assert main(["fit-force", str(tmp_path / "missing.csv")]) == 2


def test_semicolon_decimal_comma_and_any_case_header_read_the_same_numbers(tmp_path):
    x, f = (a.tolist() for a in _fixture(points=7))
    plain = tmp_path / "plain.csv"
    plain.write_text("travel_mm,load_N\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(x, f)))
    european = tmp_path / "eu.csv"        # what a German testing machine exports: ';' and a decimal comma
    european.write_text("LOAD_KN;Travel_MM\n" + "".join(f"{float(b) / 1000!r};{float(a)!r}\n".replace(".", ",")
                                                      for a, b in zip(x, f)))
    upper = tmp_path / "upper.csv"
    upper.write_bytes(("\ufeffTRAVEL_mm,Load_n\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(x, f))).encode())
    for path in (plain, european, upper):
        tx, tf = read_force_csv(path)
        assert np.allclose(tx, x, rtol=1e-15) and np.allclose(tf, f, rtol=1e-12)


@pytest.mark.parametrize("content, match", [
    (b"travel_mm,load_N\n1,2\n\xe9\n", r"bad\.csv: not UTF-8 text \(byte 0xe9 at offset 21\); save it as UTF-8 CSV"),
    (b"travel_mm,load_N\n1,1e400\n", r"bad\.csv: line 2: '1e400' in column 2 is inf N, outside \[-1e\+12, 1e\+12\] N"),
    (b"travel_mm,load_N\n1e300,2\n", r"bad\.csv: line 2: '1e300' in column 1 is 1e\+300 mm, outside \[-1e\+06, 1e\+06\] mm"),
    (b"travel_m,load_N\n2000,2\n", r"bad\.csv: line 2: '2000' in column 1 is 2e\+06 mm, outside"),
    (b"travel_mm,load_N\nnan,2\n", r"bad\.csv: line 2: \['nan', '2'\] is not a number in every column"),
    (b"x;y\n1;2\n", r"bad\.csv: no 'travel_<unit>' column in header \['x', 'y'\]; expected travel_<mm\|m\|um>,"
                    r"load_<N\|kN>"),
])
def test_unreadable_csv_is_one_line_naming_the_file(tmp_path, content, match):
    path = tmp_path / "bad.csv"
    path.write_bytes(content)
    with pytest.raises(ModelError, match=match) as info:
        read_force_csv(path)
    assert "\n" not in str(info.value)


def test_cli_fit_force_on_a_non_utf8_file_is_exit_2_with_one_line(tmp_path, capsys):
    from mechopt.cli import main
    path = tmp_path / "latin1.csv"
    path.write_bytes("travel_mm,load_N\n1,2\n2,4\n# Prüfung\n".encode("latin-1"))
    assert main(["fit-force", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "latin1.csv: not UTF-8 text" in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_a_file_far_larger_than_a_test_record_is_refused_before_reading(tmp_path, monkeypatch):
    from mechopt import force_data
    path = tmp_path / "big.csv"
    path.write_text("travel_mm,load_N\n" + "1,2\n" * 1000)                # 4017 bytes
    monkeypatch.setattr(force_data, "MAX_BYTES", 4000)
    with pytest.raises(ModelError, match=r"big\.csv: 0\.00402 MB; a load-travel record is at most 0\.004 MB"):
        read_force_csv(path)
