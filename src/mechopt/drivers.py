"""Which assumed or calibrated input sets each headline value (issue 26, part 3).

A scene names its headline values (`headline = ["max_speed_rpm"]`): the numbers its README row or
report shows. Their elasticities e = (x / y) dy/dx to every input the scene marks assumed or
calibrated (params, and numeric fields of structure entries that carry such a mark: an operation's
flight time, a stress model's reference, a lever table's params) come from central differences of
re-solves at x (1 +- REL_STEP), the other inputs as the scene has them. Generic, so no solver needs
its own AD for it; the cost is bounded (MAX_INPUTS inputs, a time budget), and an input not reached
within it is listed as such.
"""
import math
import time
from dataclasses import dataclass

REL_STEP = 0.01          # +-1 % of each input
MAX_INPUTS = 60
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
    params (`lever.E_GPa.value`): the cheap re-solves first, as the time budget may end the list."""
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


def elasticities(solve, inputs, headline, values, *, budget_s: float = 60.0) -> dict:
    """`solve(overrides) -> Result` for each input at x (1 +- REL_STEP); the headline values'
    largest elasticities, each with its derivative, and the inputs that could not be used."""
    start = time.perf_counter()
    per_value = {name: [] for name in headline if name in values}
    skipped = {name: "not a value of this result" for name in headline if name not in values}
    for item in inputs[:MAX_INPUTS]:
        if time.perf_counter() - start > budget_s:
            skipped[item.key] = f"not reached within the {budget_s:g} s budget"
            continue
        step = REL_STEP * item.value
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
            derivative = (pair[0] - pair[1]) / (2 * step)
            per_value[name].append({"input": item.key, "mark": item.mark, "value": item.value,
                                    "elasticity": derivative * item.value / values[name], "derivative": derivative})
    for item in inputs[MAX_INPUTS:]:
        skipped[item.key] = f"beyond the first {MAX_INPUTS} inputs"
    ranked = {name: {mark: sorted((r for r in rows if r["mark"] == mark), key=lambda r: -abs(r["elasticity"]))[:TOP]
                     for mark in MARKS} for name, rows in per_value.items()}
    # an assumption is the doubt a reader weighs; a calibrated input is pinned by the figure it was fitted to
    mostly = {name: by_mark["assumed"][0] for name, by_mark in ranked.items() if by_mark["assumed"]}
    return {"method": f"central differences of re-solves, +-{REL_STEP:.0%} of each assumed or calibrated input",
            "set_mostly_by": mostly, "values": ranked, "inputs": len(inputs), "skipped": skipped,
            "seconds": round(time.perf_counter() - start, 3)}


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
