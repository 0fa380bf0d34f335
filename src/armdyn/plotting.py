"""Figures of simulated runs, laid out as the book's Chapter 4 figures."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

TITLE_WIDTH = 100  # characters per title line: a 9 inch figure at 10 points holds about 110


def units(kinds: list[str], revolute: str, prismatic: str) -> str:
    """The unit of a quantity over joints of these kinds: one unit, or both when the arm mixes kinds."""
    found = {revolute if kind == "revolute" else prismatic for kind in kinds}
    return found.pop() if len(found) == 1 else f"{revolute} or {prismatic}"


def plot_result(result: object, path: str | Path | None = None, title: str | None = None) -> object:
    """Joint values (solid) with their desired values (dashed), tracking errors, and torques.

    One colour per joint, named in a legend beside the plots (never over the data); the title
    names the arm, the controller with its gains and the trajectory; axes carry the units of
    the arm's joints (rad and N m for revolute joints, m and N for prismatic ones).
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    n = result.q.shape[1]
    kinds = result.arm.kinds
    position, force = units(kinds, "rad", "m"), units(kinds, "N m", "N")
    drives = _drive_panels(result)
    rows = (3 if result.q_d is not None else 2) + len(drives)
    fig, axes = plt.subplots(rows, 1, figsize=(9, 2.5 * rows + 0.6), sharex=True, layout="constrained")
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    names = result.arm.joint_names
    torque_axis = axes[rows - 1 - len(drives)]
    for i in range(n):
        colour = colours[i % len(colours)]
        axes[0].plot(result.t, result.q[:, i], color=colour)
        if result.q_d is not None:
            axes[0].plot(result.t, result.q_d[:, i], color=colour, linestyle="--", linewidth=1.0)
            axes[1].plot(result.t, result.error[:, i], color=colour)
        torque_axis.plot(result.t, result.tau[:, i], color=colour)
    axes[0].set_ylabel(f"joint position ({position})")
    if result.q_d is not None:
        axes[1].set_ylabel(f"error q_d - q ({position})")
        axes[1].axhline(0.0, color="0.6", linewidth=0.8)
    torque_axis.set_ylabel(f"torque ({force})")
    for axis, (label, joints, values) in zip(axes[rows - len(drives) :], drives, strict=True):
        for column, joint in enumerate(joints):
            axis.plot(result.t, values[:, column], color=colours[joint % len(colours)])
        axis.set_ylabel(label)
    axes[-1].set_xlabel("time (s)")
    for axis in axes:
        axis.grid(True, alpha=0.3)
    axes[-1].set_xlim(result.t[0], result.t[-1])
    handles = [Line2D([], [], color=colours[i % len(colours)], label=names[i]) for i in range(n)]
    if result.q_d is not None:
        handles += [Line2D([], [], color="0.3", label="actual"), Line2D([], [], color="0.3", ls="--", label="desired")]
    # an axes legend anchored outside the top plot: constrained layout makes room for it beside the
    # data, and it stays below the title (a figure legend shares the title's top edge)
    axes[0].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.suptitle(textwrap.fill(title or _title(result), TITLE_WIDTH), fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig


def _drive_panels(result: object) -> list[tuple[str, list[int], object]]:
    """The drives' extra plots of a run with its actuators: (label, joint of each column, values) for the
    inputs, the armature currents and the load pressures."""
    record = getattr(result, "drives", None)
    if record is None:
        return []
    joints = result.arm.joint_names

    def columns(prefix: str) -> list[int]:
        return [joints.index(name[len(prefix) :]) for name in record.names if name.startswith(prefix)]

    dc, hydraulic = columns("i "), columns("PL ")
    unit = "V" if not hydraulic else "A" if not dc else "V; valves A"
    panels = [(f"drive input ({unit})", list(range(len(joints))), record.v)]
    if dc:
        panels.append(("armature current (A)", dc, record.i))
    if hydraulic:
        panels.append(("load pressure (MPa)", hydraulic, record.pressure / 1e6))
    return panels


def _title(result: object) -> str:
    info = result.info
    parts = [result.arm.name]
    if "controller" in info:
        parts.append(info["controller"])
    if result.q_d is not None and "trajectory" in info:
        parts.append(f"tracking a {info['trajectory']}")
    step = f", {info['method']}, dt = {info['dt'] * 1e3:g} ms" if "method" in info and "dt" in info else ""
    return ": ".join(parts[:2]) + (f", {parts[2]}" if len(parts) > 2 else "") + step


def _task_units(output: str) -> str:
    """The unit of a task output's coordinates, from its description."""
    if output.startswith("Camera"):
        return "px"
    return "output units" if output.startswith("Output") else "m"


def plot_task(result: object, path: str | Path | None = None, title: str | None = None) -> object:
    """The task-space path drawn over the desired one (the first two coordinates), and the size of
    the task error over time on a log scale (a pose task: its position and orientation parts apart)."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    task = result.task
    unit = _task_units(task.output)
    fig, (plane, error) = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    plane.plot(task.y_d[:, 0], task.y_d[:, 1], "k--", lw=1, label="desired")
    plane.plot(task.y[:, 0], task.y[:, 1], color="C0", label="actual")
    plane.plot(task.y[0, 0], task.y[0, 1], "o", color="C1", label="start")
    plane.set(xlabel=f"y1 ({unit})", ylabel=f"y2 ({unit})", title=f"path of {task.output}")
    plane.set_aspect("equal", adjustable="datalim")  # a straight path keeps a readable box
    plane.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False, fontsize=8)

    def size(e: np.ndarray) -> np.ndarray:  # a zero error (a start on the path) has no place on a log scale
        norm = np.linalg.norm(e, axis=1)
        return np.where(norm > 0, norm, np.nan)

    if task.output.startswith("ToolPose"):
        error.semilogy(result.t, size(task.error[:, :3]), label="position (m)")
        error.semilogy(result.t, size(task.error[:, 3:]), label="orientation (rad)")
        error.legend(frameon=False, fontsize=8)
        error.set_ylabel("task error |e|")
    else:
        error.semilogy(result.t, size(task.error), color="C0")
        error.set_ylabel(f"task error |y_d - y| ({unit})")
    error.set(xlabel="time (s)", title="task error", xlim=(result.t[0], result.t[-1]))
    sizes = np.linalg.norm(task.error, axis=1)
    if np.any(sizes > 0):  # eight decades below the largest error: a start on the path is not a scale
        error.set_ylim(bottom=max(sizes[sizes > 0].min() * 0.5, sizes.max() * 1e-8))
    error.grid(True, alpha=0.3)
    fig.suptitle(textwrap.fill(title or _title(result), TITLE_WIDTH), fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig


def plot_ensemble(ensemble: object, path: str | Path | None, quantity: str, row: int) -> object:
    """Many runs at once: the tracking error's envelope over time (median, 25-75 % and 5-95 % bands of
    |q_d - q| per joint, when samples were kept) above histograms of one summary (``quantity``, row
    ``row`` of the summaries) per joint."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    arm, n = ensemble.arm, ensemble.arm.n
    position = units(arm.kinds, "rad", "m")
    envelope = bool(ensemble.samples)
    fig = plt.figure(figsize=(9, 6.5 if envelope else 3.5), layout="constrained")
    grid = fig.add_gridspec(2 if envelope else 1, n)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    if envelope:
        top = fig.add_subplot(grid[0, :])
        error = np.abs(ensemble.samples["q_d"] - ensemble.samples["q"])
        for j in range(n):
            colour = colours[j % len(colours)]
            low, quarter, median, upper, high = np.percentile(error[:, :, j], [5, 25, 50, 75, 95], axis=0)
            top.fill_between(ensemble.t, low, high, color=colour, alpha=0.15, linewidth=0)
            top.fill_between(ensemble.t, quarter, upper, color=colour, alpha=0.3, linewidth=0)
            top.plot(ensemble.t, median, color=colour, label=arm.joint_names[j])
        top.set_yscale("log")
        top.set_xlabel("time (s)")
        top.set_ylabel(f"|q_d - q| ({position})")
        top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
        top.grid(True, alpha=0.3)
    values = ensemble.summaries[:, row]
    for j in range(n):
        axis = fig.add_subplot(grid[-1, j])
        axis.hist(np.abs(values[:, j]) if quantity != "final_q" else values[:, j], bins=30,
                  color=colours[j % len(colours)])  # fmt: skip
        axis.set_title(arm.joint_names[j], fontsize=8)
        axis.xaxis.set_major_locator(MaxNLocator(3))
        axis.ticklabel_format(axis="x", style="sci", scilimits=(-2, 3), useOffset=False)
        axis.tick_params(labelsize=7)
        axis.tick_params(axis="x", labelrotation=30)
        if j == 0:
            axis.set_ylabel("runs")
    fig.supxlabel(f"{quantity.replace('_', ' ')} ({position})", fontsize=9)
    title = (f"{arm.name}: {ensemble.runs} runs, {ensemble.info['controller']}, error after "
             f"{ensemble.info['after']:g} s")  # fmt: skip
    fig.suptitle(textwrap.fill(title, TITLE_WIDTH), fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig


def plot_study(result: object, path: str | Path | None = None) -> object:
    """A study's runs: a histogram per clause of its spec (the bound marked, runs that fail in a second
    colour), titled with the estimate of P(spec holds) and its interval."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    clauses = result.spec.clauses
    fig, axes = plt.subplots(1, len(clauses), figsize=(4.5 * len(clauses) + 1, 3.6), layout="constrained",
                             squeeze=False)  # fmt: skip
    holds = np.asarray(result.table["holds"], dtype=bool)
    for axis, (column, op, bound) in zip(axes[0], clauses, strict=True):
        values = np.asarray(result.table[column], dtype=float)
        finite = np.isfinite(values)
        bins = np.histogram_bin_edges(values[finite], bins=40) if finite.any() else 10
        axis.hist([values[finite & holds], values[finite & ~holds]], bins=bins, stacked=True,
                  color=["tab:green", "tab:red"], label=["spec holds", "spec fails"])  # fmt: skip
        axis.axvline(bound, color="0.2", linestyle="--", linewidth=1.0, label=f"{op} {bound:g}")
        unit = {"payload": "kg", "max_tau": "N m or N"}.get(column.split()[0], "rad or m")
        unit = "" if column.split()[0] in ("mass_scale", "friction_scale") else f" ({unit})"
        axis.set_xlabel(column.replace("_", " ") + unit)
        axis.set_ylabel("runs")
        axis.legend(fontsize=8, frameon=False)
        axis.grid(True, alpha=0.3)
    width = min(TITLE_WIDTH, int(12 * fig.get_figwidth()))
    fig.suptitle(textwrap.fill(f"{result.spec.text}: {result.estimate}", width), fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig
