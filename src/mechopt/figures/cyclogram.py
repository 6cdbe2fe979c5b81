"""Figures of the cyclogram wing's scenes (models/cyclogram.py): the cyclogram as a Gantt chart (a
plan, a machine at its highest speed, a plan of motions), the timing diagram designers draw, and a
recurrent machine's periodic schedule at its least cycle time."""
import textwrap

import numpy as np

from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.kit.errors import some_of
from mechopt.solvers.cyclogram import least_cycle_time, max_machine_speed, plan_cyclogram, plan_motions

ROW_IN = 0.35              # inches per operation row on a small network ...
DENSE_ROWS = 40           # ... past which rows narrow to DENSE_ROW_IN and bars lose their own labels
DENSE_ROW_IN = 0.17
TITLE_CHARS = 130         # a title line's width before it wraps
CHAIN_SHOWN = 12          # events of the critical chain named in the title before it is shortened


@figure(plan_cyclogram)
def gantt(run, headline=None):
    """One bar per operation from p(from) to p(to) over the machine angle, a row per operation:
    rows grouped by the operation's group (its own, else its first event's), groups in the order
    they start, and inside a group by start angle, so the chain reads as a staircase; the
    critical chain in red, every other operation's total float as a light tail; where the plan
    names its binding rows (plan_motions' binding_rows), the operations they bound (a floor, a
    window on the operation, either side of a clearance) edged in orange, a window between other
    events as an orange line over its span, the objective's operations at the optimum hatched. Past DENSE_ROWS
    operations (a machine's whole timing table) rows narrow and bars lose their own labels.
    `headline` heads the title (by default the LP's objective: the limiting operation on a machine,
    else the span)."""
    values = run.result.values
    if "span_deg" not in values:
        return {}             # infeasible or unbounded: there are no event times to draw

    task = run.task
    diag = run.result.diagnostics
    critical = set(diag.get("critical_ops", []))
    floats = diag.get("float_deg", {}) if isinstance(diag.get("float_deg"), dict) else {}
    nodes = task.graph.nodes
    label, group = {}, {}
    for x, y, d in task.graph.edges(data=True):
        label[x, y] = d["name"] or nodes[x]["mechanism"] or "-"
        group[x, y] = d.get("group") or nodes[x]["group"] or nodes[y]["group"]
    start = {a: values[f"p_{a[0]}_deg"] for a in task.arcs}
    first = {}
    for a in task.arcs:
        first[group[a]] = min(first.get(group[a], start[a]), start[a])
    # a link row (a zero-angle operation that joins events, at zero angle in the plan) is no operation to draw
    shown = [a for a in task.arcs if values[f"t_{a[0]}_{a[1]}_deg"] > 0 or task.graph.edges[a]["min_deg"] > 0
             or task.graph.edges[a]["min_ms"] is not None or f"{a[0]}->{a[1]}" in critical] or task.arcs
    arcs = sorted(shown, key=lambda a: (first[group[a]], group[a], start[a], values[f"p_{a[1]}_deg"], label[a]))

    dense = len(arcs) > DENSE_ROWS
    end = task.cycle_deg or values["span_deg"]
    if not task.span_within_cycle:      # one cycle's events spread past a turn (loom.plan_motions)
        end = max(end, values["span_deg"])
    fig = new_figure(figsize=(11, (DENSE_ROW_IN if dense else ROW_IN) * len(arcs) + 1.8))
    ax = fig.subplots()
    bound, windows, at_objective = _bound_ops(diag, {f"{x}->{y}" for x, y in arcs})
    for row, (x, y) in enumerate(arcs):
        angle = values[f"t_{x}_{y}_deg"]
        hot, op = f"{x}->{y}" in critical, f"{x}->{y}"
        ax.barh(row, angle, left=start[x, y], height=0.7 if dense else 0.6, color="tab:red" if hot else "tab:blue",
                edgecolor=BOUND_COLOUR if op in bound else "black",
                linewidth=BOUND_WIDTH if op in bound else 0.3 if dense else 0.5,
                hatch="//" if op in at_objective else None,
                gid=" ".join(["operation", op] + ["binding"] * (op in bound) + ["objective"] * (op in at_objective)))
        slack = floats.get(f"{x}->{y}", 0.0)
        if slack > 1e-9 and not hot:
            ax.barh(row, slack, left=start[x, y] + angle, height=0.25, color="tab:blue", alpha=0.25)
        if not dense:
            text = literal(f"{x}-{y}")
            inside = angle > max(0.06, 0.011 * len(text)) * max(end, 1e-9)   # a narrow bar: its label beside it
            ax.text(start[x, y] + angle / 2 if inside else start[x, y] + angle + 0.005 * end, row, text,
                    ha="center" if inside else "left", va="center", fontsize=7,
                    color="white" if inside else "black")
    _group_bands(ax, [group[a] for a in arcs])
    for a, b in windows:     # a binding window between events no drawn operation joins
        ax.plot([values[f"p_{a}_deg"], values[f"p_{b}_deg"]], [-0.4, -0.4], color=BOUND_COLOUR,
                linewidth=BOUND_WIDTH, solid_capstyle="butt", gid=f"window {a}->{b} binding")
    ax.set_yticks(range(len(arcs)))
    ax.set_yticklabels([literal(f"{label[x, y]} ({x}-{y})") for x, y in arcs], fontsize=6 if dense else 7)
    ax.set_ylim(len(arcs) - 0.5, -0.5)
    from matplotlib.patches import Patch
    handles = [Patch(color="tab:red", label="critical operation (no float)"),
               Patch(color="tab:blue", label="operation, at its event times"),
               Patch(color="tab:blue", alpha=0.25, label="its total float")]
    if "binding_rows" in diag:
        handles[0] = Patch(facecolor="tab:blue", edgecolor=BOUND_COLOUR, linewidth=BOUND_WIDTH,
                                      label="bound at the answer")
        handles.append(Patch(facecolor="tab:blue", hatch="//", label="the objective's, at its optimum"))
    ax.legend(handles=handles,
              loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=len(handles), fontsize=8, frameon=False)
    ax.set_xlim(0, end * 1.02 if end > 0 else 1.0)
    ax.set_xlabel("main shaft angle [deg]")
    chain = diag.get("critical_chain") or []
    if len(chain) > CHAIN_SHOWN:
        chain = chain[:CHAIN_SHOWN // 2] + [f"... ({len(chain) - CHAIN_SHOWN} more)"] + chain[-CHAIN_SHOWN // 2:]
    if headline is None:            # the objective the plan's LP minimised (a machine's limiting operation)
        headline = (f"limiting op {values['limiting_op_deg']:.2f} deg" if "limiting_op_deg" in values
                    else f"span {values['span_deg']:.2f} deg")
    ax.set_title(f"{literal(run.scene.id)}: {headline}, {len(arcs)} operations"
                 + (f" ({len(task.arcs) - len(arcs)} zero-angle link{'s' if len(task.arcs) - len(arcs) > 1 else ''} not drawn)" if len(arcs) < len(task.arcs) else "")
                 + "\n"
                 + ("\n".join(textwrap.wrap(f"bound (orange): {literal(some_of((r['constraint'] for r in diag['binding_rows']), sep='; '))}", TITLE_CHARS))
                    if "binding_rows" in diag else f"critical chain (red) {literal(' - '.join(chain))}"),
                 fontsize=9, pad=22)
    ax.grid(True, axis="x", alpha=0.3)
    return {"cyclogram": fig}


@figure(max_machine_speed)
def gantt_at_speed(run):
    """The cyclogram at the machine's largest speed, headed by that speed."""
    speed = run.result.values.get("max_speed_rpm")
    figures = gantt(run, headline=None if speed is None else f"max speed {speed:.2f} rpm")
    return figures | ({"timing_diagram": timing_diagram(run)} if figures and run.task.motion_arcs else {})


@figure(plan_motions)
def motions(run):
    """The plan of a machine's motions: its cyclogram, and the timing diagram designers draw."""
    values = run.result.values
    if "span_deg" not in values:
        return {}
    scaled = next((k for k in values if k.startswith("highest_peak_accel_")), None)
    headline = (f"least angle {values['least_angle_deg']:.2f} deg" if "least_angle_deg" in values
                else f"largest peak acceleration {values[scaled]:.4g} {scaled.split('_')[-2]}/s^2" if scaled
                else f"span {values['span_deg']:.2f} deg")
    figures = gantt(run, headline=headline)
    return figures | ({"timing_diagram": timing_diagram(run)} if run.task.motion_arcs else {})


CHART_POINTS = 721          # samples of the shaft angle over one cycle
CHART_CYCLES = (-2, -1, 0, 1)   # a motion's copies of earlier and later cycles drawn into this one


def timing_diagram(run):
    """Displacement against shaft angle, one panel per group (mechanism), over one cycle: every
    motion of the group by its law (cam law S over its angle, stroke in mm, + out, - back; an
    oscillating output's swing in deg on a panel of its own, not a second axis: a panel's curve is
    the sum of its motions, meaningful in one unit, and a clearance's level is read on it), its
    copies of the cycles before and after folded in, so a stroke that runs into the next index shows
    where it overlaps; each clearance's two instants as dotted lines (the turret stopped before the
    die is 0.6 down, ...), and where a clearance names a displacement inside a stroke, its level
    (dashed) and the interference region it guards (the motion past it: the die inside the turret's
    space) shaded."""
    task, values = run.task, run.result.values
    cycle = task.cycle_deg or values["span_deg"]
    theta = np.linspace(0.0, cycle, CHART_POINTS)
    # a panel per group and stroke unit: an oscillating output's swing [deg] is not added to a
    # slide's travel [mm], so a group with both gets two panels, each with one ordinate
    group_of = {k: (task.arc_data(k)["group"] or task.graph.nodes[task.arcs[k][0]]["group"] or "-",
                    m.units[0] if m.stroke is not None else "of stroke") for k, m in task.motion_arcs.items()}
    groups = list(dict.fromkeys(group_of.values()))
    fig = new_figure(figsize=(10, 2.2 * len(groups) + 1.2))
    axes = np.atleast_1d(fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0])
    panels = {}
    for ax, group in zip(axes, groups):
        total, names = np.zeros_like(theta), []
        for k, motion in task.motion_arcs.items():
            if group_of[k] != group:
                continue
            x, y = task.arcs[k]
            start, angle = values[f"p_{x}_deg"], max(values[f"t_{x}_{y}_deg"], 1e-12)
            total += sum(motion.displacement((theta - start - m * cycle) / angle) for m in CHART_CYCLES)
            names.append(((start + angle / 2) % cycle, task.arc_data(k)["name"] or f"{x}-{y}", angle))
        total -= total.min()
        panels[group] = (ax, total)
        ax.plot(theta, total, color="black", linewidth=1.5)
        for mid, name, angle in names:      # each motion named at its middle, its angle beside the name
            ax.annotate(literal(f"{name} {angle:.1f} deg"), (mid, np.interp(mid, theta, total)), fontsize=7,
                        xytext=(4, 4), textcoords="offset points", color="tab:blue")
        ax.set_ylabel(f"{literal(group[0])} [{group[1]}]", fontsize=8)
        ax.grid(True, alpha=0.3)
    for j, c in enumerate(task.clearance_rows):
        for side, (k, xi, shift) in enumerate(((c.a, c.x_a, 0), (c.b, c.x_b, c.cycles))):
            x, y = task.arcs[k]
            at = (values[f"p_{x}_deg"] + xi * values[f"t_{x}_{y}_deg"] + shift * cycle) % cycle
            for ax in axes:
                ax.axvline(at, color="tab:red", linestyle=":", linewidth=1)
            if side == 0:
                axes[0].text(at, 1.0, f"c{j}", transform=axes[0].get_xaxis_transform(), color="tab:red",
                             fontsize=7, ha="center", va="bottom")
            if not 0.0 < xi < 1.0 or k not in task.motion_arcs:
                continue
            # the interference region this clearance guards: the motion past its threshold (before it on
            # the `operation` side of a "before" row, after it on the `other` side; "after" the reverse)
            ax, total = panels[group_of[k]]
            sign = 1.0 if task.motion_arcs[k].direction == "out" else -1.0
            sign *= (-1.0 if side == 0 else 1.0) * c.sign
            level = float(np.interp(at, theta, total))
            ax.axhline(level, color="tab:red", linestyle="--", linewidth=0.8)
            for every in axes:      # on every panel: what else moves there moves into the region
                every.fill_between(theta, 0, 1, where=sign * (total - level) >= 0, color="tab:red", alpha=0.08,
                                   transform=every.get_xaxis_transform(), linewidth=0)
    axes[-1].set_xlim(0, cycle)
    axes[-1].set_xlabel("main shaft angle [deg] (one cycle; strokes of the next cycle folded in)")
    axes[0].set_title(f"{literal(run.scene.id)}: displacement against shaft angle\nclearances c0..: dotted their "
                      f"instants, dashed and shaded the displacement each guards", fontsize=9, pad=14)
    return fig


@figure(least_cycle_time)
def periodic_schedule(run):
    """Every operation of a recurrent machine as a bar from p(from) to p(to) + k T (its end k cycles
    on) in a schedule repeating every least cycle time T (dotted lines at its multiples); the
    critical circuits' operations in red."""
    values, diag = run.result.values, run.result.diagnostics
    unit = diag.get("unit", "ms")
    T = values.get("cycle_time_ms", values.get("cycle_deg"))
    if T is None or not all(f"p_{v}_{unit}" in values for v in run.task.graph.nodes):
        return {}             # infeasible, or too large to name every event
    task, critical = run.task, set(diag.get("critical_ops", []))
    rows = [(x, y, 0, f"{x}->{y}") for x, y in task.arcs]
    rows += [(r["from"], r["to"], r["cycles"], f"{r['from']}->{r['to']}[+{r['cycles']}]") for r in task.recurrences]
    fig = new_figure(figsize=(10, ROW_IN * len(rows) + 1.8))
    ax = fig.subplots()
    for row, (x, y, k, label) in enumerate(rows):
        start = values[f"p_{x}_{unit}"]
        ax.barh(row, values[f"p_{y}_{unit}"] + k * T - start, left=start, height=0.6, edgecolor="black", linewidth=0.5,
                color="tab:red" if label in critical else "tab:blue")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels([literal(label) for *_, label in rows], fontsize=7)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    for m in range(1, 1 + max((k for _, _, k, _ in rows), default=0)):
        ax.axvline(m * T, color="0.4", linestyle=":", linewidth=1)
    ax.set_xlabel(f"time [{unit}]" if unit == "ms" else "main shaft angle [deg]")
    ax.set_title(f"{literal(run.scene.id)}: least cycle time {T:.4g} {unit}; critical circuits in red", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    return {"periodic_schedule": fig}


BOUND_COLOUR, BOUND_WIDTH = "tab:orange", 2.5     # a bar a binding row bounds


def _bound_ops(diag, drawn) -> tuple[dict, list, set]:
    """The operations ("from->to") the plan's binding rows bound (op -> the rows' names), the
    binding windows between events no drawn operation joins ((a, b) each), and the objective's
    operations whose rows bind at the optimum."""
    bound, windows = {}, []
    for row in diag.get("binding_rows", []):
        ops = row.get("ops") or []
        if row.get("kind") == "window" and "->".join(row["events"]) in drawn:
            ops = ["->".join(row["events"])]         # a max_deg window on the operation itself
        elif row.get("kind") == "window":
            windows.append(tuple(row["events"]))
        for op in ops:
            bound.setdefault(op, []).append(row["constraint"])
    return bound, windows, set(diag.get("objective_binds", []))


def _group_bands(ax, groups):
    """Every other group's rows shaded and each group named at the right edge (with two or more)."""
    if len(set(groups)) < 2:
        return
    top, band = 0, 0
    for row in range(1, len(groups) + 1):
        if row < len(groups) and groups[row] == groups[top]:
            continue
        if band % 2:
            ax.axhspan(top - 0.5, row - 0.5, color="0.92", zorder=0)
        ax.text(1.005, (top + row - 1) / 2, literal(groups[top] or "(no group)"), transform=ax.get_yaxis_transform(),
                rotation=90, ha="left", va="center", fontsize=8)
        top, band = row, band + 1
