"""Where a number comes from: the one rule for a scene's parameters and a loom table's entries.

given       printed in the source (`where` says where)
assumed     not printed: chosen, with the reasoning in `why`
calibrated  fitted to a published value (`on` names it; a check of that value is no reproduction)
"""
MARKS = ("given", "assumed", "calibrated")


def provenance_problem(mark, why="", on=None) -> str:
    """What is wrong with a provenance note, '' when nothing. `on` is checked when the entry can
    carry one (a scene's parameter); a loom table's entry cannot."""
    if mark not in MARKS:
        return f"mark={mark!r}: allowed {', '.join(MARKS)}"
    if mark != "given" and not str(why).strip():
        return f"marked '{mark}' needs a 'why' (the reasoning or the figure fitted)"
    if on is not None and (mark == "calibrated") != bool(str(on).strip()):
        return "'on' (the value a parameter was fitted to) goes with mark = 'calibrated', and only there"
    return ""
