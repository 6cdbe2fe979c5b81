"""Units read from names: every value and parameter carries its unit as a suffix (`H_mm`,
`peak_belt_torque_Nm`, `sens_sigma_H_deg_per_MPa`); this reads the suffix by a small grammar.

    name      := words unit [ "_" tag ]        tag: a number naming a case (`rebound_mm_280`: at 280 rpm)
    unit      := quotient [ "_per_" quotient ]
    quotient  := atom { "_" atom }             `rad_s2` is rad/s², `Nms_rad` N m s/rad
    atom      := symbol [ power ]              `mm4` is mm⁴, `mm1` mm; `N_m` is the torque N m
    derivative:  d_<name>_d_<name>            unit of the first over the unit of the second
                 d_<name>                     a column of a sensitivity table, one row per parameter:
                                              the name's unit over the row's parameter's
    elasticity:  a name with `elasticity`     (p/y) dy/dp: no unit

The first word of a name is never read as a unit (`N_N` is a normal force in N, `J_x_mm4` a
second moment in mm⁴).
"""
import re

SYMBOLS = {"mm": "mm", "m": "m", "um": "µm", "s": "s", "ms": "ms", "deg": "deg", "rad": "rad", "N": "N",
           "Nm": "N m", "Nms": "N m s", "Ns": "N s", "kg": "kg", "kgm2": "kg m²", "Pa": "Pa", "MPa": "MPa",
           "GPa": "GPa", "Hz": "Hz", "rpm": "rpm", "J": "J", "W": "W"}
POWERS = {"1": "", "2": "²", "3": "³", "4": "⁴"}
_ATOM = re.compile(rf"({'|'.join(sorted(SYMBOLS, key=len, reverse=True))})([1-4]?)")
_TAG = re.compile(r"\d+(p\d+)?")      # a speed tag (models.stop_impact.speed_tag: 177.5 -> 177p5)


def _atom(token: str) -> str | None:
    found = _ATOM.fullmatch(token)
    if found is None or (found[2] and found[1] in ("kgm2", "Nm", "Nms", "Ns", "rpm", "Hz", "J", "W")):
        return None
    return SYMBOLS[found[1]] + POWERS.get(found[2], "")


def _quotient(tokens: list[str]) -> tuple[int, str]:
    """How many tokens at the end of `tokens` form a quotient of atoms, and its text."""
    atoms = []
    i = len(tokens)
    while i > 1:                                   # the first word is never a unit
        if tokens[i - 2:i] == ["N", "m"] and i > 2:
            atoms.insert(0, "N m")
            i -= 2
            continue
        atom = _atom(tokens[i - 1])
        if atom is None:
            break
        atoms.insert(0, atom)
        i -= 1
    if not atoms:
        return 0, ""
    return len(tokens) - i, atoms[0] + "".join(f"/{a}" for a in atoms[1:])


def parse(name: str) -> tuple[str, str]:
    """(words, unit) of a name: `sens_sigma_H_deg_per_MPa` -> ("sens sigma H", "deg/MPa")."""
    if "elasticity" in name:
        return _plain(name)[0], ""
    derivative = re.fullmatch(r"d_(.+)_d_(.+)", name)
    if derivative:
        (top_words, top), (bottom_words, bottom) = parse(derivative[1]), parse(derivative[2])
        unit = top if not bottom else f"{top or '1'}/{_grouped(bottom)}"
        return f"d {top_words} / d {bottom_words}", unit
    if name.startswith("d_"):
        words, unit = parse(name[2:])
        return f"d {words}", f"{unit or '1'}/(parameter)"
    return _plain(name)


def _plain(name: str) -> tuple[str, str]:
    """(words, unit) of a name that is neither a derivative nor an elasticity."""
    tokens = name.split("_")
    tag = []
    if len(tokens) > 2 and _TAG.fullmatch(tokens[-1]) and _quotient(tokens[:-1])[0]:
        tag = tokens[-1:]
        tokens = tokens[:-1]
    taken, unit = _quotient(tokens)
    if taken and len(tokens) - taken > 2 and tokens[-taken - 1] == "per":
        before, numerator = _quotient(tokens[:-taken - 1])
        if before:
            taken, unit = taken + 1 + before, f"{numerator}/{_grouped(unit)}"
    words = " ".join(tokens[:len(tokens) - taken] + tag)
    return words, unit


def _grouped(unit: str) -> str:
    """A unit as a divisor: in brackets when it is itself a quotient or product (`N m/(rad/s)`)."""
    return f"({unit})" if "/" in unit or " " in unit else unit


def unit_of(name: str) -> str:
    """The unit a name's suffix states ('' when it states none: a ratio, a count, an elasticity)."""
    return parse(name)[1]


def label(name: str) -> str:
    """A name as an axis label: words and unit, `err_width_mm` -> "err width [mm]"."""
    words, unit = parse(name)
    return f"{words} [{unit}]" if unit else words
