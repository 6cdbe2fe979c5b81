"""Which assumed or calibrated input sets each headline value, and which inputs are steps.

A scene names its headline values (`headline = ["max_speed_rpm"]`): the numbers its README row or
report shows. Their elasticities e = (x / y) dy/dx to every input the scene marks assumed or
calibrated (params, and numeric fields of structure entries that carry such a mark: an operation's
flight time, a stress model's reference, a lever table's params) come from re-solves at
x (1 +- REL_STEP), the other inputs as the scene has them. Generic, so no solver needs its own AD
for it. The backward and forward differences are compared: where they agree their mean is the
elasticity; where they do not, the value is not smooth in that input (a wavy rebound that starts
or stops crossing its limit moves a bound by degrees) and the input is reported as a step, with
both slopes and a bracket of the jump, not as an elasticity. The cost is a count of re-solves
(MAX_RESOLVES), never seconds: the answer does not depend on how busy the machine is.
"""
import math
from dataclasses import dataclass

REL_STEP = 0.01          # +-1 % of each input
MAX_INPUTS = 60
MAX_RESOLVES = 2 * MAX_INPUTS + 40   # the budget: every input's pair, and bisections of the steps found
BISECTIONS = 5           # re-solves per step: its bracket 1/32 of the step REL_STEP
STEP_RTOL = 0.5          # one-sided elasticities further apart than this (relative) ...
STEP_ATOL = 0.02         # ... and than this (absolute) make the input a step
TOP = 5                  # the largest elasticities kept per headline value
MARKS = ("assumed", "calibrated")


@dataclass(frozen=True)
class Input:
    key: str             # a --set key: a param, or a structure path ("operations[from=a,to=b].min_ms")
    value: float
    mark: str


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value != 0


def uncertain_inputs(scene) -> list[Input]:
    """Every numeric input the scene marks assumed or calibrated, as a key `--set` reaches, but
    those its `headline_fixed` holds (a count such as one turn per cycle, not a quantity to vary).
    Order: params, then entries of structure lists, then of tables, then tables of another scene's
    params (`lever.E_GPa.value`): the cheap re-solves first, as the count budget may end the list."""
    out = [Input(k, float(p.value), p.mark) for k, p in scene.spec.params.items()
           if p.mark in MARKS and _number(p.value) and k not in scene.spec.derive]
    found = [i for name, node in scene.spec.structure.items() for i in _structure_inputs(name, node)]
    found.sort(key=lambda i: (i.key.endswith(".value"), "[" not in i.key, i.mark == "calibrated"))
    return [i for i in out + found if i.key not in scene.spec.headline_fixed]


def _structure_inputs(path, node) -> list[Input]:
    if isinstance(node, list):
        return [i for entry in node for i in _list_entry_inputs(path, node, entry)]
    if not isinstance(node, dict):
        return []
    if node.get("mark") in MARKS:
        if _number(node.get("value")) and set(node) <= {"value", "mark", "why", "on", "where"}:
            return [Input(f"{path}.value", float(node["value"]), node["mark"])]
        return [Input(f"{path}.{k}", float(v), node["mark"]) for k, v in node.items() if _number(v)]
    return [i for k, v in node.items() for i in _structure_inputs(f"{path}.{k}", v)]


def _list_entry_inputs(path, node, entry) -> list[Input]:
    """A marked table of a list, named by its from/to (else its name) as `--set` paths select it."""
    if not (isinstance(entry, dict) and entry.get("mark") in MARKS):
        return []
    ends = {k: entry[k] for k in ("from", "to") if isinstance(entry.get(k), str)}
    picks = ends or ({"name": entry["name"]} if isinstance(entry.get("name"), str) else {})
    same = [e for e in node if isinstance(e, dict) and all(e.get(k) == v for k, v in picks.items())]
    if not picks or len(same) != 1:
        return []                  # no path names this entry alone
    selector = ",".join(f"{k}={v}" for k, v in picks.items())
    return [Input(f"{path}[{selector}].{k}", float(v), entry["mark"]) for k, v in entry.items() if _number(v)]


def elasticities(solve, inputs, headline, values, *, max_resolves: int = MAX_RESOLVES) -> dict:
    """`solve(overrides) -> Result` for each input at x (1 +- REL_STEP); per headline value, the
    largest elasticities (each with its derivative), the inputs that are steps, and the inputs that
    could not be used.

    The budget is a count of re-solves, never seconds, so the answer is the same on a busy machine:
    every input's pair of re-solves comes first (in `uncertain_inputs` order, an input past the
    budget is listed as such), then the steps' brackets with what is left. An input whose forward
    and backward differences disagree (`is_step`) is a step, not an elasticity: both slopes and a
    bracket [lo, hi] of the jump, narrowed by bisection re-solves.
    """
    per_value = {name: [] for name in headline if name in values}
    steps = {name: [] for name in per_value}
    skipped = {name: "not a value of this result" for name in headline if name not in values}
    spent = 0
    for item in inputs[:MAX_INPUTS]:
        if spent + 2 > max_resolves:
            skipped[item.key] = f"beyond the count budget of {max_resolves} re-solves"
            continue
        if item.value == 0:             # an input set to 0: +-1 % of it is no step, and (x / y) dy/dx is 0 there
            skipped[item.key] = f"at 0: a step of +-{REL_STEP:.0%} of it is no step (its elasticity is 0 there)"
            continue
        step = REL_STEP * item.value
        spent += 2
        try:
            up, down = (solve({item.key: item.value + sign * step}) for sign in (1, -1))
        except Exception as exc:        # noqa: BLE001 -- a refused or failed variant skips one input only
            skipped[item.key] = f"{type(exc).__name__}: {exc}"
            continue
        for name in per_value:
            pair = [r.values.get(name) for r in (up, down) if r.status.value == "SOLVED"]
            if len(pair) < 2 or values[name] == 0:
                skipped[f"{item.key} -> {name}"] = "a perturbed solve did not give it"
                continue
            row = _slopes(item, step, values[name], *pair)
            (steps if row["kind"] == "step" else per_value)[name].append(row)
    for item in inputs[MAX_INPUTS:]:
        skipped[item.key] = f"beyond the first {MAX_INPUTS} inputs"
    for name, rows in steps.items():
        for row in rows:
            spent += _bracket_the_jump(solve, name, row, max(0, max_resolves - spent))
    ranked = {name: {mark: sorted((r for r in rows if r["mark"] == mark), key=lambda r: -abs(r["elasticity"]))[:TOP]
                     for mark in MARKS} for name, rows in per_value.items()}
    # an assumption is the doubt a reader weighs; a calibrated input is pinned by the figure it was fitted to
    mostly = {name: by_mark["assumed"][0] for name, by_mark in ranked.items() if by_mark["assumed"]}
    return {"method": f"one-sided differences of re-solves, +-{REL_STEP:.0%} of each assumed or calibrated input: "
                      f"their mean the elasticity, a step where they differ by more than {STEP_RTOL:.0%} (and "
                      f"{STEP_ATOL:g} in elasticity); at most {max_resolves} re-solves",
            "set_mostly_by": mostly, "values": ranked, "steps": steps, "inputs": len(inputs), "skipped": skipped,
            "resolves": spent, "max_resolves": max_resolves}


def is_step(e_below: float, e_above: float) -> bool:
    """Whether the backward and forward elasticities disagree beyond what curvature explains: a
    smooth y = x^k gives slopes within ~k% of each other at +-1 %, a jump one far from the other."""
    gap = abs(e_above - e_below)
    return gap > STEP_ATOL and gap > STEP_RTOL * max(abs(e_above), abs(e_below))


def _slopes(item, step, y, y_up, y_down) -> dict:
    """The elasticity row of one input, or its step row when the one-sided differences disagree."""
    below, above = (y - y_down) / step, (y_up - y) / step
    scale = item.value / y
    row = {"input": item.key, "mark": item.mark, "value": item.value}
    if not is_step(below * scale, above * scale):
        derivative = (y_up - y_down) / (2 * step)
        return row | {"kind": "smooth", "elasticity": derivative * scale, "derivative": derivative}
    # the jump is on the side whose difference is the steeper one; the other side is the smooth slope
    up_side = abs(above) > abs(below)
    lo, hi = (item.value, item.value + step) if up_side else (item.value - step, item.value)
    y_lo, y_hi = (y, y_up) if up_side else (y_down, y)
    return row | {"kind": "step", "slope_below": below, "slope_above": above, "elasticity_below": below * scale,
                  "elasticity_above": above * scale, "smooth_slope": below if up_side else above,
                  "jump_between": [lo, hi], "values_at_ends": [y_lo, y_hi], "bisections": 0, "bracket_note": ""}


def _bracket_the_jump(solve, name, row, allowed: int) -> int:
    """Narrow `row`'s bracket of the jump by bisection re-solves (at most BISECTIONS and `allowed`),
    in place; the re-solves spent. A midpoint whose value lies nearer the smooth line from the lower
    end than from the upper end's is below the jump."""
    (lo, hi), (y_lo, y_hi) = row["jump_between"], row["values_at_ends"]
    slope, spent = row["smooth_slope"], 0
    for _ in range(BISECTIONS):
        if spent >= allowed:
            row["bracket_note"] = "the count budget of re-solves was spent"
            break
        mid = 0.5 * (lo + hi)
        spent += 1
        try:
            r = solve({row["input"]: mid})
        except Exception as exc:        # noqa: BLE001 -- the bracket stays as it is, and says why
            row["bracket_note"] = f"{type(exc).__name__}: {exc}"
            break
        y_mid = r.values.get(name)
        if r.status.value != "SOLVED" or y_mid is None:
            row["bracket_note"] = f"the re-solve at {mid:.6g} gave {r.status.value}"
            break
        below_jump = abs(y_mid - (y_lo + slope * (mid - lo))) < abs(y_mid - (y_hi - slope * (hi - mid)))
        lo, hi, y_lo, y_hi = (mid, hi, y_mid, y_hi) if below_jump else (lo, mid, y_lo, y_mid)
        row["bisections"] += 1
    row["jump_between"], row["values_at_ends"] = [lo, hi], [y_lo, y_hi]
    row["jump"] = y_hi - y_lo
    return spent


def set_mostly_by(drivers: dict) -> list[str]:
    """One sentence per headline value: "max_speed_rpm: set mostly by <assumed input> (elasticity
    -0.676); then ...; of the calibrated inputs, <input> (-0.74)"."""
    out = []
    for name, by_mark in drivers.get("values", {}).items():
        assumed, calibrated = by_mark["assumed"], by_mark["calibrated"]
        words = [f"set mostly by {assumed[0]['input']} (assumed, elasticity {assumed[0]['elasticity']:+.3g})"
                 + "".join(f"; then {r['input']} ({r['elasticity']:+.3g})" for r in assumed[1:3])] if assumed else []
        if calibrated:
            words.append(f"of the calibrated inputs, {calibrated[0]['input']} ({calibrated[0]['elasticity']:+.3g})")
        if words:
            out.append(f"{name}: " + "; ".join(words))
    return out


def steps_of(drivers: dict) -> list[str]:
    """One sentence per step: "max_speed_rpm: a step in <input> (assumed): slope <below> below,
    <above> above 12.3; it jumps by +5.1 between 12.31 and 12.32"."""
    out = []
    for name, rows in drivers.get("steps", {}).items():
        for r in rows:
            lo, hi = r["jump_between"]
            out.append(f"{name}: a step in {r['input']} ({r['mark']}, {r['value']:.6g}): slope {r['slope_below']:+.4g} "
                       f"below, {r['slope_above']:+.4g} above; it jumps by {r['jump']:+.4g} between {lo:.6g} and "
                       f"{hi:.6g} (not an elasticity)" + (f"; bracket not narrowed further: {r['bracket_note']}"
                                                          if r["bracket_note"] else ""))
    return out
