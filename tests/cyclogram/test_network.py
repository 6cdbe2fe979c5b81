"""The cyclogram's network as the model builds and checks it (models/cyclogram.py and its parts):
a bad network refused naming its key, an isolated event kept apart, the lower bounds of a chain."""
import pytest

from mechopt.kit.errors import ModelError
from mechopt.models.cyclogram import Cyclogram


def chain(*angles, **kw):
    """Events 1..n+1 in a row, operation k -> k+1 with min angle angles[k-1]."""
    events = {str(k): {"mechanism": "m"} for k in range(1, len(angles) + 2)}
    ops = [{"from": str(k), "to": str(k + 1), "min_deg": a} for k, a in enumerate(angles, start=1)]
    return Cyclogram(events=events, operations=ops, **kw)


EVENTS = {"1": {}, "2": {}, "3": {}}


OPS = [{"from": "1", "to": "2", "min_deg": 10.0}, {"from": "2", "to": "3", "min_deg": 5.0}]


@pytest.mark.parametrize("change, match", [
    (dict(operations=[{"from": "1", "to": "9", "min_deg": 1.0}]), r"operations\[1->9\]: unknown event '9'; events: 1, 2, 3"),
    (dict(operations=OPS + [{"from": "3", "to": "1", "min_deg": 1.0}]), r"operations: precedence cycle 1 -> 2 -> 3 -> 1"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": -5.0}, OPS[1]]),
     r"operations\[1->2\]\.min_deg=-5\.0: a minimum phase angle must be >= 0"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1e300}, OPS[1]]),
     r"operations\[1->2\]\.min_deg=1e\+300: a minimum phase angle must be <= 1e\+06 deg"),
    (dict(operations=OPS, sigma_H_limit_MPa=1e300), r"sigma_H_limit_MPa=1e\+300: allowed > 0 \.\.\. 1e\+06"),
    (dict(operations=OPS, cycle_deg=float("inf")), r"cycle_deg=inf: expected a finite number"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=1e-300,
          stress_models={"cam": {"sigma_ref_MPa": 900.0, "t_ref_deg": 30.0}}),
     r"operations\[1->2\]: its contact_stress bound 2\.7e\+304 deg \(exact form\), set by stress_models\.cam and "
     r"sigma_H_limit_MPa, is outside the allowed \+-1e\+06 deg"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "amplitude": "linear"}, OPS[1]],
          amplitude_slope_mm_per_deg=-0.003, amplitude_intercept_mm=1e300, amplitude_limit_mm=0.1),
     r"operations\[1->2\]: its amplitude bound 3\.33333e\+302 deg \(exact form\), set by amplitude_slope_mm_per_deg, "
     r"amplitude_intercept_mm and amplitude_limit_mm"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0,
          stress_models={"cam": {"sigma_ref_MPa": 900.0, "t_ref_deg": 1e300}}),
     r"stress_models\.cam\.t_ref_deg=1e\+300 must be in \(0, 1e\+06\]"),
    (dict(operations=OPS, windows=[{"from": "1", "to": "3", "max_deg": 1e300}]),
     r"windows\[0\]\.max_deg=1e\+300: allowed within \+-1e\+06 deg"),
    (dict(operations=OPS, windows=1.0), r"windows: expected a list of tables, got 1\.0"),
    (dict(operations=OPS, syncs="2,3"), r"syncs: expected a list of tables, got '2,3'"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": "ten"}, OPS[1]]), r"operations\[1->2\]\.min_deg='ten': expected a finite number"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0),
     r"operations\[1->2\]\.stress='cam': no such stress model; defined: none"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]],
          stress_models={"cam": {"sigma_ref_MPa": 900.0, "t_ref_deg": 30.0}}),
     r"operations\[1->2\]\.stress='cam' needs sigma_H_limit_MPa \(effect contact_stress\)"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0,
          stress_models={"cam": {"sigma_ref_MPa": -900.0, "t_ref_deg": 30.0}}),
     r"stress_models\.cam\.sigma_ref_MPa=-900\.0 must be in \(0, 1e\+06\]"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0,
          stress_models={"cam": {"sigma_ref_MPa": 900.0}}), r"stress_models\.cam: missing t_ref_deg"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "amplitude": "cubic"}, OPS[1]]),
     r"operations\[1->2\]\.amplitude='cubic': no such amplitude model; known: linear"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "amplitude": "linear"}, OPS[1]]),
     r"amplitude='linear' needs amplitude_slope_mm_per_deg, amplitude_intercept_mm, amplitude_limit_mm"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "colour": "red"}, OPS[1]]),
     r"operations\[0\]: unknown colour; allowed: amplitude, cycles, direction, from, group, law, mark, max_accel_m_s2, max_accel_rad_s2, max_deg, max_velocity_m_s, max_velocity_rad_s, mechanism, min_deg, min_ms, name, stress, stroke_deg, stroke_mm, to, what, where, why"),
    (dict(operations=[{"from": "1", "min_deg": 1.0}]), r"operations\[0\]: missing to"),
    (dict(operations=OPS + [dict(OPS[0])]), r"operations\[1->2\]: given twice"),
    (dict(operations=[{"from": "1", "to": "1", "min_deg": 1.0}]), r"operations\[1->1\]: an operation must join two different events"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "mark": "assumed"}, OPS[1]]),
     r"operations\[0\]: marked 'assumed' needs a 'why'"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "mark": "guessed", "why": "x"}, OPS[1]]),
     r"operations\[0\]\.mark='guessed': allowed given, assumed, calibrated"),
    (dict(operations=OPS + [{"from": "1", "to": "3", "min_deg": 1.0}]), None),      # fine: a second chain
    (dict(operations=[OPS[0], {"from": "3", "to": "2", "min_deg": 1.0}]),
     r"a cyclogram needs one first and one last event; found first \['1', '3'\] and last \['2'\]"),
    (dict(operations=OPS, windows=[{"from": "1", "to": "7", "max_deg": 3.0}]), r"windows\[0\]: unknown event '7'"),
    (dict(events=EVENTS | {"spare": {}}, operations=OPS, syncs=[{"events": ["1", "spare"]}]),
     r"syncs\[0\]: event 'spare' has no operation; a window or sync needs events of the network"),
    (dict(operations=OPS, syncs=[{"events": ["1"]}]), r"syncs\[0\]\.events=\['1'\]: give a list of two or more events"),
    (dict(operations=OPS, limiting_op=["1", "3"]), r"limiting_op=\['1', '3'\]: must name an operation \[from, to\]"),
    (dict(operations=OPS, cycle_deg=-360.0), r"cycle_deg=-360\.0: allowed > 0 \.\.\. 1e\+06"),
    (dict(operations=OPS, amplitude_slope_mm_per_deg=0.003), r"amplitude_slope_mm_per_deg=0\.003: allowed < 0"),
    (dict(operations=OPS, amplitude_intercept_mm=float("nan")), r"amplitude_intercept_mm=nan: expected a finite number"),
    # formerly -1 mm gave a -1.09 mm amplitude reported as SOLVED
    (dict(operations=OPS, amplitude_intercept_mm=-1.0), r"amplitude_intercept_mm=-1\.0: allowed > 0"),
    (dict(events=[1, 2], operations=OPS), r"events: expected a table, got \[1, 2\]"),
    (dict(operations={"a": 1}), r"operations: expected a list of tables"),
    (dict(events={"1": "lift", "2": {}, "3": {}}, operations=OPS), r"events\.1: expected a table, got 'lift'"),
])
def test_bad_network_is_refused_naming_the_key(change, match):
    kwargs = {"events": EVENTS, "operations": OPS} | change
    if match is None:
        Cyclogram(**kwargs)
        return
    with pytest.raises(ModelError, match=match):
        Cyclogram(**kwargs)


def test_isolated_event_is_kept_apart_and_not_a_first_event():
    task = Cyclogram(events=EVENTS | {"spare": {}}, operations=OPS)
    assert task.isolated_events == ["spare"] and task.first_event == "1" and task.last_event == "3"


def test_chain_helper_lower_bounds_are_the_min_angles():
    lb, why = chain(3.0, 0.0, 7.5).lower_bounds_deg()
    assert list(lb) == [3.0, 0.0, 7.5] and why == ["min_angle"] * 3
