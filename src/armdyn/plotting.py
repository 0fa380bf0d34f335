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
