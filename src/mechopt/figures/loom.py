"""Figures of the STB loom's own solvers (the cyclogram wing's case): a repaired LP
(loom.repair_cyclogram) as its cyclogram and each exact limit's excess over the rounds. The
cyclogram's charts live in mechopt.figures.cyclogram; their names answer here too, the same
functions, for one release."""
from mechopt.figures.cyclogram import gantt, gantt_at_speed, motions, periodic_schedule, timing_diagram
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.solvers.loom import repair_cyclogram

__all__ = ["gantt", "gantt_at_speed", "motions", "periodic_schedule", "repaired", "timing_diagram"]


@figure(repair_cyclogram)
def repaired(run):
    """The repaired cyclogram, and each exact limit's excess over the LP rounds."""
    figures, rounds = gantt(run), run.result.diagnostics.get("rounds")
    return figures | ({"repair_rounds": _repair_rounds(run, rounds)} if figures and rounds else {})


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
        line, = ax.semilogy([rnd["round"] for rnd in rounds], excess, marker="o", label=literal(name))
        exact = [(rnd["round"], e) for rnd, r, e in zip(rounds, rows, excess) if r.get("cut") == "exact"]
        if exact:
            ax.semilogy(*zip(*exact), linestyle="none", marker="s", markersize=11, markerfacecolor="none",
                        color=line.get_color(), label=f"{literal(name)}: next cut at the exact bound")
    ax.set(xlabel="LP round", ylabel="|exact - limit| / limit at the round's optimum",
           title=f"{literal(run.scene.id)}: exact laws at each round's optimum")
    ax.set_xticks([rnd["round"] for rnd in rounds])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig
