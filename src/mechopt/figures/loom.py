"""Figures for the loom cyclogram scenes (models/loom.py): the cyclogram as a Gantt chart, and
for a repaired LP (loom.repair_cyclogram) each exact limit's excess over the rounds."""
from mechopt.figures.registry import new_figure, register
from mechopt.models.loom import Cyclogram


@register(Cyclogram)
def gantt(run):
    """One bar per operation from p(from) to p(to) over the machine angle, a row per operation,
    labelled by the mechanism whose event starts it (or the operation's name) and sorted by it;
    the critical chain in red, every other operation's total float as a light tail."""
    values = run.result.values
    if "span_deg" not in values:
        return {}             # infeasible or unbounded: there are no event times to draw

    task = run.task
    diag = run.result.diagnostics
    critical = set(diag.get("critical_ops", []))
    floats = diag.get("float_deg", {}) if isinstance(diag.get("float_deg"), dict) else {}
    mechanism = dict(task.graph.nodes(data="mechanism"))
    label = {(x, y): d["name"] or mechanism[x] or "-" for x, y, d in task.graph.edges(data=True)}
    arcs = sorted(task.arcs, key=lambda a: (label[a], values[f"p_{a[0]}_deg"]))

    end = task.cycle_deg or values["span_deg"]
    fig = new_figure(figsize=(11, 0.35 * len(arcs) + 1.8))
    ax = fig.subplots()
    for row, (x, y) in enumerate(arcs):
        start, angle = values[f"p_{x}_deg"], values[f"t_{x}_{y}_deg"]
        key = f"{x}->{y}"
        hot = key in critical
        ax.barh(row, angle, left=start, height=0.6, color="tab:red" if hot else "tab:blue",
                edgecolor="black", linewidth=0.5)
        slack = floats.get(key, 0.0)
        if slack > 1e-9 and not hot:
            ax.barh(row, slack, left=start + angle, height=0.25, color="tab:blue", alpha=0.25)
        inside = angle > 0.06 * max(end, 1e-9)          # a narrow bar gets its label beside it
        ax.text(start + angle / 2 if inside else start + angle + 0.005 * end, row, f"{x}-{y}",
                ha="center" if inside else "left", va="center", fontsize=7,
                color="white" if inside else "black")
    ax.set_yticks(range(len(arcs)))
    ax.set_yticklabels([f"{label[x, y]} ({x}-{y})" for x, y in arcs], fontsize=7)
    ax.invert_yaxis()
    from matplotlib.patches import Patch
    ax.legend(handles=[Patch(color="tab:red", label="critical operation (no float)"),
                       Patch(color="tab:blue", label="operation, at its event times"),
                       Patch(color="tab:blue", alpha=0.25, label="its total float")],
              loc="lower right", fontsize=8)
    ax.set_xlim(0, end * 1.02 if end > 0 else 1.0)
    ax.set_xlabel("main shaft angle [deg]")
    chain = diag.get("critical_chain") or []
    headline = (f"max speed {values['max_speed_rpm']:.2f} rpm" if "max_speed_rpm" in values
                else f"limiting op {values['limiting_op_deg']:.2f} deg" if "limiting_op_deg" in values
                else f"span {values['span_deg']:.2f} deg")
    ax.set_title(f"{run.scene.id}: {headline}; critical chain (red) {' - '.join(chain)}", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    rounds = diag.get("rounds")
    return {"cyclogram": fig} | ({"repair_rounds": _repair_rounds(run, rounds)} if rounds else {})


def _repair_rounds(run, rounds):
    """|exact - limit| / limit of every limit that was ever exceeded, per round (log scale): the
    sequential LP's Newton steps square it; a round whose next cut was the exact bound (the wavy
    rebound: scan and brentq, no tangent trusted) is marked with a square."""
    fig = new_figure(figsize=(7, 4.5))
    ax = fig.subplots()
    limits = {row["limit"] for rnd in rounds for row in rnd["limits"] if row["excess"] > 0}
    for name in sorted(limits):
        rows = [next(r for r in rnd["limits"] if r["limit"] == name) for rnd in rounds]
        value = rows[0].get("exact_mm", rows[0].get("exact_MPa")) - rows[0]["excess"]     # the limit
        excess = [max(abs(r["excess"]) / value, 1e-17) for r in rows]
        line, = ax.semilogy([rnd["round"] for rnd in rounds], excess, marker="o", label=name)
        exact = [(rnd["round"], e) for rnd, r, e in zip(rounds, rows, excess) if r.get("cut") == "exact"]
        if exact:
            ax.semilogy(*zip(*exact), linestyle="none", marker="s", markersize=11, markerfacecolor="none",
                        color=line.get_color(), label=f"{name}: next cut at the exact bound")
    ax.set(xlabel="LP round", ylabel="|exact - limit| / limit at the round's optimum",
           title=f"{run.scene.id}: exact laws at each round's optimum")
    ax.set_xticks([rnd["round"] for rnd in rounds])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig
