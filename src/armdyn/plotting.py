"""Figures of simulated runs, laid out as the book's Chapter 4 figures; the arm as a stick figure, and
animations of a run.

The arm is read by duck typing (its ``link_transforms``, ``tool_pose``, ``links``, ``base``, ``tool_link``):
this module imports Robot for type checking only, so armdyn.robot can draw itself through it.
"""

from __future__ import annotations

import io
import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from armdyn import inputs
from armdyn.errors import ArgumentError, ModelError
from armdyn.files import atomic_path
from armdyn.model.arm import ArmModel

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.text import Text
    from mpl_toolkits.mplot3d import Axes3D  # type: ignore[import-untyped]  # mplot3d ships no type hints
    from mpl_toolkits.mplot3d.art3d import Line3D, Text3D  # type: ignore[import-untyped]

    from armdyn.actuators.packing import DriveRecord
    from armdyn.control.task import Tracking
    from armdyn.robot import Robot
    from armdyn.simulation import Ensemble, Result
    from armdyn.study import StudyResult

TITLE_WIDTH = 100  # characters per title line: a 9 inch figure at 10 points holds about 110
SEPARATORS = (": ", "; ", ", ")  # where a title may break, the first the strongest


def wrap(title: str, width: int = TITLE_WIDTH) -> str:
    """``title`` in lines of at most ``width`` characters, each broken after a ": ", "; " or ", " rather
    than mid-phrase: the break outside parentheses and the strongest separator preferred, among those
    that fill at least half a line; between words when there is none."""
    lines, rest = [], title.strip()
    while len(rest) > width:
        cut = _break(rest, width)
        lines.append(rest[:cut].rstrip())
        rest = rest[cut:].lstrip()
    return "\n".join([*lines, rest])


def _break(text: str, width: int) -> int:
    """Where the first line of ``text`` ends: after the best separator in its second half (the least
    parenthesised, the strongest, the latest), else after its last space, else at ``width``."""
    depth, candidates = 0, []  # (depth, strength, -end)
    for k, character in enumerate(text[: width + 1]):
        depth += (character in "([{") - (character in ")]}")
        for strength, separator in enumerate(SEPARATORS):
            end = k + len(separator)
            if text.startswith(separator, k) and width // 2 <= end - 1 <= width:
                candidates.append((depth, strength, -end))
    if candidates:
        return -min(candidates)[2]
    space = text.rfind(" ", 1, width + 1)
    return space + 1 if space > 0 else width


def units(kinds: list[str], revolute: str, prismatic: str) -> str:
    """The unit of a quantity over joints of these kinds: one unit, or both when the arm mixes kinds."""
    found = {revolute if kind == "revolute" else prismatic for kind in kinds}
    return found.pop() if len(found) == 1 else f"{revolute} or {prismatic}"


def plot_result(result: Result, path: str | Path | None = None, title: str | None = None) -> Figure:
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
    error = result.error  # None when q_d is
    for i in range(n):
        colour = colours[i % len(colours)]
        axes[0].plot(result.t, result.q[:, i], color=colour)
        if result.q_d is not None and error is not None:
            axes[0].plot(result.t, result.q_d[:, i], color=colour, linestyle="--", linewidth=1.0)
            axes[1].plot(result.t, error[:, i], color=colour)
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
    fig.suptitle(wrap(title or _title(result)), fontsize=10)
    if path is not None:
        save_figure(fig, path)
        plt.close(fig)
    return fig


def _drive_panels(result: Result) -> list[tuple[str, list[int], np.ndarray]]:
    """The drives' extra plots of a run with its actuators: (label, joint of each column, values) for the
    inputs, the armature currents and the load pressures."""
    record = cast("DriveRecord | None", getattr(result, "drives", None))
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
        assert record.pressure is not None  # recorded for every arm with hydraulic drives
        panels.append(("load pressure (MPa)", hydraulic, record.pressure / 1e6))
    return panels


def _title(result: Result) -> str:
    info = result.info
    parts = [result.arm.name]
    if "controller" in info:
        parts.append(info["controller"])
    if result.q_d is not None and "trajectory" in info:
        parts.append(f"tracking a {info['trajectory']}")
    step = f", {info['method']}, dt = {info['dt'] * 1e3:g} ms" if "method" in info and "dt" in info else ""
    return ": ".join(parts[:2]) + (f", {parts[2]}" if len(parts) > 2 else "") + step


def plot_task(result: Result, path: str | Path | None = None, title: str | None = None) -> Figure:
    """The task-space path drawn over the desired one, beside the task error y_d - y per coordinate
    against time and its size |y_d - y| on a log scale.

    The path is in 3-D for an output with three or more coordinates (a tool or link point, a pose's
    position), with axes named by them (x, y, z in m); in 2-D for two (a PlanarPosition's world axes,
    a camera's u, v in px); against time for one. A pose's error is in two panels, its position (x, y,
    z in m) and its orientation (rx, ry, rz in rad: the rotation vector of R_d R^T), and its size
    in each part apart.
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    task = cast("Tracking", result.task)
    coordinates = _task_coordinates(task.output, task.y.shape[1])
    series = _time_values(result)
    fig = plt.figure(figsize=(12, 2.3 * (len(series) + 1) + 0.8), layout="constrained")
    grid = fig.add_gridspec(len(series) + 1, 3, width_ratios=[1.0, 0.06, 1.1])  # a gap for a 3-D axes' labels
    shown = min(3, len(coordinates))
    plane = fig.add_subplot(grid[:, 0], projection="3d" if shown == 3 else None)
    axes_names = [f"{name} ({unit})" for name, unit in coordinates[:shown]]
    if shown == 1:  # one coordinate: its path is its value against time
        plane.plot(result.t, task.y_d[:, 0], "k--", lw=1, label="desired")
        plane.plot(result.t, task.y[:, 0], color="C0", label="actual")
        plane.plot(result.t[0], task.y[0, 0], "o", color="C1", label="start")
        plane.set(xlabel="time (s)", ylabel=axes_names[0])
    else:
        plane.plot(*task.y[:, :shown].T, color="C0", label="actual", gid="path")
        plane.plot(*task.y_d[:, :shown].T, "k--", lw=1, label="desired", gid="desired path")  # over the actual
        plane.plot(*task.y[:1, :shown].T, "o", color="C1", label="start")
        plane.set_xlabel(axes_names[0])
        plane.set_ylabel(axes_names[1])
        if shown == 3:
            _equal_box(plane, np.vstack([task.y[:, :3], task.y_d[:, :3]]))
            cast("Axes3D", plane).set_zlabel(axes_names[2])
            _fewer_ticks(plane)
        else:
            plane.set_aspect("equal", adjustable="datalim")  # a straight path keeps a readable box
            plane.grid(True, alpha=0.3)
    plane.set_title(f"path of {task.output}", fontsize=10)
    plane.legend(loc="upper left", bbox_to_anchor=(0.0, -0.06 if shown == 3 else -0.12), ncols=3, frameon=False,
                 fontsize=8)  # fmt: skip
    panels = [fig.add_subplot(grid[k, 2]) for k in range(len(series) + 1)]
    for ax, (values, names, label, _) in zip(panels, series, strict=False):
        for i, name in enumerate(names):
            ax.plot(result.t, values[:, i], color=f"C{i % 10}", label=name)
        ax.axhline(0.0, color="0.6", linewidth=0.8)
        ax.set_ylabel(label)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, fontsize=8)
    panels[0].set_title(f"task error of {task.output}", fontsize=10)
    size = panels[-1]
    for values, _, label, _ in series:
        norm = np.linalg.norm(values, axis=1)
        unit = label[label.rindex("(") + 1 : -1]
        part = "orientation" if label.startswith("orientation") else "position" if len(series) > 1 else "size"
        size.semilogy(result.t, np.where(norm > 0, norm, np.nan), label=f"{part} ({unit})")  # 0 has no place on it
    size.set_ylabel("|y_d - y|" + (f" ({series[0][2][series[0][2].rindex('(') + 1 : -1]})" if len(series) == 1 else ""))
    size.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, fontsize=8)
    sizes = np.linalg.norm(task.error, axis=1)
    if np.any(sizes > 0):  # eight decades below the largest error: a start on the path is not a scale
        size.set_ylim(bottom=max(sizes[sizes > 0].min() * 0.5, sizes.max() * 1e-8))
    for ax in panels:
        ax.grid(True, alpha=0.3)
        ax.set_xlim(result.t[0], result.t[-1])
    for ax in panels[:-1]:
        ax.tick_params(labelbottom=False)
    size.set_xlabel("time (s)")
    fig.suptitle(wrap(title or _title(result)), fontsize=10)
    if path is not None:
        save_figure(fig, path)
        plt.close(fig)
    return fig


def _equal_box(ax: Axes, points: np.ndarray) -> None:
    """Equal scales on 3-D axes around ``points`` (a path undistorted), a tenth of its extent to spare."""
    low, high = points.min(axis=0), points.max(axis=0)
    centre, half = 0.5 * (low + high), 0.55 * float((high - low).max()) or 0.05
    space = cast("Axes3D", ax)
    for setter, middle in zip((space.set_xlim, space.set_ylim, space.set_zlim), centre, strict=True):
        setter(middle - half, middle + half)
    space.set_box_aspect((1.0, 1.0, 1.0))


def plot_ensemble(ensemble: Ensemble, path: str | Path | None, quantity: str, row: int) -> Figure:
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
    fig.suptitle(wrap(title), fontsize=10)
    if path is not None:
        save_figure(fig, path)
        plt.close(fig)
    return fig


def plot_study(result: StudyResult, path: str | Path | None = None) -> Figure:
    """A study's runs: a histogram per clause of its spec (the bound marked, runs that fail in a second
    colour), titled with the estimate of P(spec holds) and its interval."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    clauses = result.spec.clauses
    fig, axes = plt.subplots(1, len(clauses), figsize=(4.5 * len(clauses) + 1, 3.6), layout="constrained",
                             squeeze=False)  # fmt: skip
    table: Any = result.table  # a pandas DataFrame (pandas has no type stubs here)
    holds = np.asarray(table["holds"], dtype=bool)
    for axis, (column, op, bound) in zip(axes[0], clauses, strict=True):
        values = np.asarray(table[column], dtype=float)
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
    fig.suptitle(wrap(f"{result.spec.text}: {result.estimate}", width), fontsize=10)
    if path is not None:
        save_figure(fig, path)
        plt.close(fig)
    return fig


# ----- the arm as a stick figure (its forward kinematics, Appendix A) ------------------------------------
FRAME_COLOURS = ("tab:red", "tab:green", "tab:blue")  # x, y, z of a frame
LINK_STYLE: dict[str, Any] = {"color": "0.25", "linewidth": 5.0, "solid_capstyle": "round", "solid_joinstyle": "round"}
JOINT_STYLES: dict[str, dict[str, Any]] = {
    "revolute": {"color": "tab:orange", "linewidth": 4.0, "marker": "o", "markersize": 9, "markevery": [1],
                 "markerfacecolor": "white", "markeredgewidth": 2.0, "solid_capstyle": "butt"},
    "prismatic": {"color": "tab:purple", "linewidth": 2.5, "linestyle": (0, (3, 1.5)), "marker": "s",
                  "markersize": 8, "markevery": [1], "markerfacecolor": "white", "markeredgewidth": 2.0},
}  # fmt: skip
DESIRED_PATH_STYLE: dict[str, Any] = {"color": "0.45", "linestyle": "--", "linewidth": 1.2}
ACTUAL_PATH_STYLE: dict[str, Any] = {"color": "tab:cyan", "linewidth": 1.8}
PLANE_TOLERANCE = 1e-9  # m, and for the cosines between joint axes
MAX_FRAMES = 200  # an animation's default most frames
GIF_TICK = 0.01  # s: a GIF's frame delays are whole hundredths of a second
FASTEST, SLOWEST = 0.04, 0.1  # s per frame of a real-time playback by default: 25 to 10 frames per second
FEWEST_FRAMES = 25  # a short run is slowed down to this many frames rather than shown in a few
ANIMATION_FORMATS = (".gif", ".mp4")


@dataclass(frozen=True)
class _Scene:
    """The arm at one configuration, in world coordinates (m): what the stick figure draws.

    ``links[i]`` runs from the parent's link-frame origin (the base's for a root) through joint i's
    origin, the origin moved by a prismatic joint, to link i's frame origin (Appendix A:
    T_i = T_parent placement motion(q_i) frame_offset).
    """

    links: tuple[np.ndarray, ...]  # each (4, 3)
    joints: np.ndarray  # (n, 3) origin of each joint frame, where the joint's axis passes
    axes: np.ndarray  # (n, 3) the joints' unit axes in the world
    kinds: tuple[str, ...]
    base: np.ndarray  # (4, 4)
    tool: np.ndarray  # (4, 4)
    tool_link: int

    def points(self) -> np.ndarray:
        """Every point drawn, (k, 3): the links' vertices, the base and the tool."""
        return np.vstack([*self.links, self.base[None, :3, 3], self.tool[None, :3, 3]])


def _scene(arm: Robot, q: np.ndarray) -> _Scene:
    """The stick figure of ``arm`` at q from the compiled forward kinematics (link_transforms, tool_pose)."""
    transforms = arm.link_transforms(q)
    base = np.asarray(arm.base, dtype=float)
    links, joints, axes = [], [], []
    for i, link in enumerate(arm.links):
        parent = base if link.parent < 0 else transforms[link.parent]
        frame = parent @ np.asarray(link.joint.placement, dtype=float)
        axis = frame[:3, :3] @ np.asarray(link.joint.axis, dtype=float)
        moved = frame[:3, 3] + (q[i] * axis if link.kind == "prismatic" else 0.0)
        links.append(np.array([parent[:3, 3], frame[:3, 3], moved, transforms[i, :3, 3]]))
        joints.append(frame[:3, 3])
        axes.append(axis)
    return _Scene(tuple(links), np.array(joints), np.array(axes), tuple(arm.kinds), base,
                  np.asarray(arm.tool_pose(q), dtype=float), arm.tool_link)  # fmt: skip


def _plane(scene: _Scene) -> tuple[np.ndarray, tuple[str, str]] | None:
    """The plane of a planar arm, as two orthonormal rows spanning it and their axis labels; None for a
    spatial arm. Planar: the revolute axes parallel (to the plane's normal), the prismatic ones
    perpendicular to it, every point of the figure in one plane perpendicular to the normal."""
    revolute = scene.axes[[kind == "revolute" for kind in scene.kinds]]
    prismatic = scene.axes[[kind == "prismatic" for kind in scene.kinds]]
    if len(revolute):
        normal = revolute[0]
    else:
        cross = np.cross(prismatic[0], prismatic[1:]) if len(prismatic) > 1 else np.zeros((1, 3))
        longest = cross[np.argmax(np.linalg.norm(cross, axis=1))]
        if np.linalg.norm(longest) < PLANE_TOLERANCE:
            return None
        normal = longest / np.linalg.norm(longest)
    points = scene.points()
    scale = max(1.0, float(np.ptp(points, axis=0).max()))
    if (
        np.abs(np.cross(normal, revolute)).max(initial=0.0) > PLANE_TOLERANCE
        or np.abs(prismatic @ normal).max(initial=0.0) > PLANE_TOLERANCE
        or np.ptp(points @ normal) > PLANE_TOLERANCE * scale
    ):
        return None
    return _plane_basis(normal)


def _plane_basis(normal: np.ndarray) -> tuple[np.ndarray, tuple[str, str]]:
    """Two orthonormal rows spanning the plane normal to ``normal``: world axes when the normal is one
    (x, y for z; x, z for y, so that a vertical arm stands up; y, z for x), else the world x (or y)
    projected on the plane and the normal's cross product with it."""
    closest = int(np.argmax(np.abs(normal)))
    if abs(abs(normal[closest]) - 1.0) < PLANE_TOLERANCE:
        first_axis, second_axis = (axis for axis in range(3) if axis != closest)
        return np.eye(3)[[first_axis, second_axis]], (f"{'xyz'[first_axis]} (m)", f"{'xyz'[second_axis]} (m)")
    first = np.eye(3)[0] if abs(normal[0]) < 0.9 else np.eye(3)[1]
    first = first - (first @ normal) * normal
    first /= np.linalg.norm(first)
    basis = np.array([first, np.cross(normal, first)])
    first_name, second_name = (f"along ({', '.join(f'{v:.3g}' for v in row)}) (m)" for row in basis)
    return basis, (first_name, second_name)


class _ArmDrawing:
    """The artists of the stick figure on one axes (2-D in a planar arm's plane, else 3-D), made once
    and moved by ``show``: plot_arm draws one configuration with it, animate every frame."""

    def __init__(self, ax: Axes, scene: _Scene, basis: np.ndarray | None, size: float) -> None:
        self.ax, self.basis, self.size = ax, basis, size
        self.links = [self._line(gid=f"link {i}", zorder=3, **LINK_STYLE) for i in range(len(scene.links))]
        self.joints = [self._line(gid=f"joint {i}", zorder=4, **JOINT_STYLES[kind]) for i, kind in
                       enumerate(scene.kinds)]  # fmt: skip
        self.tool_line = self._line(gid="tool", zorder=3, color="0.25", linewidth=2.0)
        self.frames = {name: [self._line(gid=f"{name} {'xyz'[k]}", zorder=5, color=FRAME_COLOURS[k], linewidth=2.0)
                              for k in range(3)] for name in ("base", "tool")}  # fmt: skip
        self.labels = {name: self._label(name) for name in ("base", "tool")}
        self.show(scene)

    def _screen(self) -> np.ndarray:
        """The world directions of the picture's right and up, (2, 3): the plane's basis, or the 3-D
        axes' view (its azimuth and elevation)."""
        if self.basis is not None:
            return self.basis
        space = cast("Axes3D", self.ax)
        azimuth, elevation = np.radians(space.azim), np.radians(space.elev)
        return np.array([[-np.sin(azimuth), np.cos(azimuth), 0.0],
                         [-np.sin(elevation) * np.cos(azimuth), -np.sin(elevation) * np.sin(azimuth),
                          np.cos(elevation)]])  # fmt: skip

    def _place_label(self, label: Text, origin: np.ndarray, directions: np.ndarray) -> None:
        """A frame's name beside its origin, in the widest free angle between the lines drawn from it
        (its axes, its links) as the picture shows them: never over its axes."""
        screen = self._screen()
        shown = directions @ screen.T  # (k, 2)
        length = np.linalg.norm(shown, axis=1)
        keep = length > 0.2 * np.linalg.norm(directions, axis=1)  # a line towards the viewer hides nothing
        angles = np.sort(np.arctan2(shown[keep, 1], shown[keep, 0]))
        if len(angles):
            gaps = np.diff(np.append(angles, angles[0] + 2 * np.pi))
            widest = int(np.argmax(gaps))
            angle = angles[widest] + 0.5 * gaps[widest]
        else:
            angle = -0.5 * np.pi  # below
        right, up = np.cos(angle), np.sin(angle)
        corner = origin + 0.3 * self.size * (right * screen[0] + up * screen[1])
        label.set_horizontalalignment("left" if right > 0.4 else "right" if right < -0.4 else "center")
        label.set_verticalalignment("bottom" if up > 0.4 else "top" if up < -0.4 else "center")
        if self.basis is not None:
            x, y = self._coordinates(corner[None])[:, 0]
            label.set_position((x, y))
        else:
            cast("Text3D", label).set_position_3d(corner)

    def _coordinates(self, points: np.ndarray) -> np.ndarray:
        """Points (k, 3) as the axes' coordinates: (2, k) in the plane, else (3, k)."""
        return (points @ self.basis.T).T if self.basis is not None else points.T

    def _label(self, name: str) -> Text:
        """A frame's name, at the origin until ``show`` moves it."""
        origin = self._coordinates(np.zeros((1, 3)))[:, 0]
        if self.basis is not None:
            return self.ax.text(origin[0], origin[1], name, fontsize=8, zorder=6, ha="right", va="top")
        return cast("Axes3D", self.ax).text(*origin, name, fontsize=8, zorder=6, ha="right", va="top")

    def _line(self, **style: Any) -> Line2D:
        (line,) = self.ax.plot(*np.zeros((2 if self.basis is not None else 3, 2)), **style)
        return line

    def _put(self, artist: Line2D, points: np.ndarray) -> None:
        coordinates = self._coordinates(points)
        if self.basis is not None:
            artist.set_data(*coordinates)
        else:
            cast("Line3D", artist).set_data_3d(*coordinates)

    def show(self, scene: _Scene) -> None:
        """Move every artist to the arm at ``scene``."""
        half = 0.8 * self.size  # a joint's axis a little longer than a frame's
        for line, points in zip(self.links, scene.links, strict=True):
            self._put(line, points)
        for line, joint, axis, kind in zip(self.joints, scene.joints, scene.axes, scene.kinds, strict=True):
            start = joint - half * axis if kind == "revolute" else joint  # a prismatic joint's sleeve: from its origin
            self._put(line, start + np.outer([0.0, half, 2.0 * half], axis))
        self._put(self.tool_line, np.array([scene.links[scene.tool_link][-1], scene.tool[:3, 3]]))
        for name, pose in (("base", scene.base), ("tool", scene.tool)):
            for k, line in enumerate(self.frames[name]):
                self._put(line, np.array([pose[:3, 3], pose[:3, 3] + self.size * pose[:3, k]]))
            self._place_label(
                self.labels[name], pose[:3, 3], np.vstack([pose[:3, :3].T, _lines_from(scene, pose[:3, 3])])
            )

    def artists(self) -> list[Any]:
        """Every artist of the figure (for an animation's frame)."""
        frames = [line for lines in self.frames.values() for line in lines]
        return [*self.links, *self.joints, self.tool_line, *frames, *self.labels.values()]


def _lines_from(scene: _Scene, point: np.ndarray) -> np.ndarray:
    """The directions (k, 3) of the figure's lines that leave ``point``: each link's and the tool's, from
    a vertex at ``point`` to the next vertex elsewhere, and the axes of the joints at ``point``."""
    tolerance = 1e-9 * max(1.0, float(np.abs(point).max()))
    directions = []
    polylines = [*scene.links, np.array([scene.links[scene.tool_link][-1], scene.tool[:3, 3]])]
    for vertices in polylines:
        away = np.linalg.norm(vertices - point, axis=1) > tolerance
        for k in np.flatnonzero(~away):
            for step in (-1, 1):
                others = [j for j in range(k + step, -1 if step < 0 else len(vertices), step) if away[j]]
                if others:
                    directions.append(vertices[others[0]] - point)
    for joint, axis, kind in zip(scene.joints, scene.axes, scene.kinds, strict=True):
        if np.linalg.norm(joint - point) <= tolerance:  # a joint's axis drawn through the point
            directions += [axis, -axis] if kind == "revolute" else [axis]
    return np.array(directions).reshape(-1, 3)


def _legend_handles(scene: _Scene, basis: np.ndarray | None) -> list[Line2D]:
    """The legend's entries: links, the kinds of joint the arm has, and the frames' axes that show
    (in a plane, an axis along its normal is a point)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], label="link", **LINK_STYLE)]
    for kind in ("revolute", "prismatic"):
        if kind in scene.kinds:
            handles.append(Line2D([], [], label=f"{kind} joint, along its axis", **JOINT_STYLES[kind]))
    for k, colour in enumerate(FRAME_COLOURS):
        shown = basis is None or any(np.linalg.norm(basis @ pose[:3, k]) > 1e-6 for pose in (scene.base, scene.tool))
        if shown:
            handles.append(Line2D([], [], color=colour, linewidth=2.0, label=f"frame {'xyz'[k]} axis"))
    return handles


def _legend(ax: Axes, scene: _Scene, basis: np.ndarray | None) -> None:
    """The legend of the stick figure, below its axes (the arm moves everywhere inside them)."""
    ax.legend(handles=_legend_handles(scene, basis), loc="upper center", bbox_to_anchor=(0.5, -0.08), ncols=3,
              fontsize=8, frameon=False)  # fmt: skip


def _figure_size(scene: _Scene) -> float:
    """The length of a frame's axes and of a joint's axis: a tenth of the figure's extent, at least 5 cm."""
    return max(0.05, 0.12 * float(np.ptp(scene.points(), axis=0).max()))


def _set_limits(ax: Axes, points: np.ndarray, basis: np.ndarray | None, pad: float) -> None:
    """Equal scales on every axis (an undistorted arm), the points inside with ``pad`` (m) to spare."""
    coordinates = (points @ basis.T) if basis is not None else points
    low, high = coordinates.min(axis=0), coordinates.max(axis=0)
    centre, half = 0.5 * (low + high), 0.5 * float((high - low).max()) + pad
    if basis is not None:
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_aspect("equal", adjustable="box")
    else:
        space = cast("Axes3D", ax)
        space.set_xlim(centre[0] - half, centre[0] + half)
        space.set_ylim(centre[1] - half, centre[1] + half)
        space.set_zlim(centre[2] - half, centre[2] + half)
        space.set_box_aspect((1.0, 1.0, 1.0), zoom=1.1)


def _label_axes(ax: Axes, basis: np.ndarray | None, names: tuple[str, str] | None) -> None:
    if basis is not None:
        assert names is not None  # a plane comes with its axes' names
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        ax.grid(True, alpha=0.3)
    else:
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        cast("Axes3D", ax).set_zlabel("z (m)")


def _configuration(arm: Robot, q: object) -> tuple[np.ndarray, str | None]:
    """q checked as one configuration of the arm (a name of one of its configurations, or n numbers),
    with its name; None gives the arm's qn, else its qz, else zeros."""
    named = getattr(arm, "configurations", {})
    if q is None:
        q = next((key for key in ("qn", "qz") if key in named), None)
        if q is None:
            return np.zeros(arm.n), None
    if isinstance(q, str):
        if q not in named:
            raise ModelError(f"robot '{arm.name}' has no configuration '{q}' (it has {sorted(named) or 'none'})")
        return np.asarray(named[q], dtype=float), q
    array = inputs.state(q, arm.n, "q", f" for '{arm.name}'")
    if array.ndim != 1:
        raise ModelError(f"q must be one configuration, {arm.n} joint values for '{arm.name}', got shape {array.shape}")
    return array, None


def _checked_arm(arm: object) -> None:
    """An arm that can be drawn, else an ArgumentError: a Robot (told by its compiled kinematics, as this module
    cannot import Robot, which draws itself through it) with numeric parameters."""
    if not all(hasattr(arm, name) for name in ("link_transforms", "tool_pose", "links", "base", "kinds")):
        raise ArgumentError(f"arm must be an armdyn Robot, got {type(arm).__name__}")
    inputs.arm_argument(arm, ArmModel, numeric=True, why=" to draw it")


def _checked_path(path: str | Path, suffixes: Sequence[str], what: str) -> Path:
    """An output file in an existing folder, ending in one of ``suffixes``; a ModelError otherwise."""
    target = Path(path)
    if not target.parent.is_dir():
        raise ModelError(f"{path}: the folder {target.parent} does not exist")
    if target.is_dir():
        raise ModelError(f"{path} is a folder; give a file name")
    if target.suffix.lower() not in suffixes:
        raise ModelError(f"{path}: {what} must end in {', '.join(suffixes[:-1])} or {suffixes[-1]}")
    return target


def check_picture_path(path: str | Path) -> Path:
    """A picture's file checked before any work: in an existing folder, its suffix an image format
    matplotlib writes (.png, .pdf, .svg, ...).

    Parameters
    ----------
    path : str or Path
        The file to write.

    Returns
    -------
    Path
        The file.

    Raises
    ------
    armdyn.ModelError
        When the folder does not exist, the path is a folder, or the suffix is no image format.
    """
    from matplotlib.backend_bases import FigureCanvasBase

    formats = tuple(f".{suffix}" for suffix in FigureCanvasBase.get_supported_filetypes())
    return _checked_path(path, formats, "a picture")


def _q_title(arm: Robot, q: np.ndarray, name: str | None) -> str:
    values = ", ".join(f"{value:.4g}" if abs(value) >= 5e-5 else "0" for value in q)
    unit = units(list(arm.kinds), "rad", "m") if len(set(arm.kinds)) == 1 else "(rad for R, m for P)"
    return f"{arm.name} at {name or 'q'} = ({values}) {unit}"


def plot_arm(
    arm: Robot, q: object = None, ax: Axes | None = None, path: str | Path | None = None, title: str | None = None
) -> Figure:
    """The arm at one configuration as a stick figure: its forward kinematics (Appendix A) drawn.

    Each link is a thick line from its parent's link-frame origin (the base's for a root link)
    through its joint's origin to its own frame origin, so a tree draws each branch from its
    parent; each joint's axis is a short segment through its origin (revolute: solid, with a
    circle; prismatic: dashed, with a square); the base and tool frames are triads (x red,
    y green, z blue). An arm whose revolute axes are parallel and whose joints lie in one plane
    perpendicular to them is drawn in 2-D in that plane's coordinates; any other in 3-D.
    Scales are equal on every axis, in metres.

    Parameters
    ----------
    arm : Robot
        The arm (numeric parameters).
    q : array_like or str, optional
        Joint positions (n,), rad or m, or the name of one of the arm's configurations
        (e.g. "qr"); default its "qn", else its "qz", else zeros.
    ax : matplotlib.axes.Axes, optional
        Draw on these axes (3-D axes for a spatial arm); default a new figure's.
    path : str or Path, optional
        Also write the figure to this file (its format by the suffix, e.g. .png, .pdf, .svg).
    title : str, optional
        The title; default the arm's name and q.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn on.

    Raises
    ------
    armdyn.ModelError
        When q is not n finite numbers or a configuration of the arm, the folder of ``path`` does
        not exist, its suffix is no image format, or ``ax`` is 2-D for a spatial arm.
    armdyn.ArgumentError
        When ``arm`` is not an armdyn Robot, or has symbolic parameters (a ModelError and a TypeError).
    """
    _checked_arm(arm)
    q, name = _configuration(arm, q)
    target = check_picture_path(path) if path is not None else None
    import matplotlib

    if target is not None and ax is None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = _scene(arm, q)
    plane = _plane(scene)
    basis, names = plane if plane is not None else (None, None)
    own = ax is None
    if ax is None:
        fig = plt.figure(figsize=(7.0, 6.4), layout="constrained")
        ax = fig.add_subplot(projection=None if basis is not None else "3d")
    elif basis is None and getattr(ax, "name", "") != "3d":
        raise ModelError(f"robot '{arm.name}' is spatial: draw it on 3-D axes (projection='3d'), or give no ax")
    size = _figure_size(scene)
    _ArmDrawing(ax, scene, basis, size)
    _set_limits(ax, np.vstack([scene.points(), _frame_tips(scene, size)]), basis, 0.6 * size)
    _label_axes(ax, basis, names)
    if basis is None:
        _fewer_ticks(ax)
    _legend(ax, scene, basis)
    ax.set_title(wrap(title or _q_title(arm, q, name), 70), fontsize=10)
    fig = cast("Figure", ax.figure)  # the axes of a figure (a subfigure's cannot save)
    if target is not None:
        save_figure(fig, target)
        if own:
            plt.close(fig)
    return fig


def _frame_tips(scene: _Scene, size: float) -> np.ndarray:
    """The ends of the base's and the tool's axes, (6, 3): inside the limits too."""
    return np.vstack([pose[:3, 3] + size * pose[:3, :3].T for pose in (scene.base, scene.tool)])


# ----- animations of a run ------------------------------------------------------------------------------
def check_animation_path(path: str | Path) -> Path:
    """An animation's file checked before any work: in an existing folder, a .gif (written with Pillow)
    or an .mp4 (written with ffmpeg, which must be installed).

    Parameters
    ----------
    path : str or Path
        The file to write.

    Returns
    -------
    Path
        The file.

    Raises
    ------
    armdyn.ModelError
        When the folder does not exist, the path is a folder, the suffix is neither .gif nor .mp4,
        or it is .mp4 and ffmpeg is not on the PATH.
    """
    target = _checked_path(path, ANIMATION_FORMATS, "an animation")
    if target.suffix.lower() == ".mp4":
        from matplotlib import animation

        if not animation.writers.is_available("ffmpeg"):
            raise ModelError(f"{path}: writing an .mp4 needs ffmpeg, which is not installed (not on the PATH); "
                             "install it, or write a .gif")  # fmt: skip
    return target


def _frame_indices(samples: int, frames: int) -> np.ndarray:
    """At most ``frames`` sample indices evenly spread from the first sample to the last."""
    return np.unique(np.linspace(0, samples - 1, min(frames, samples)).round().astype(int))


def _positive(value: object, name: str, integer: bool = False) -> float:
    """A positive finite number (a whole one when ``integer``), or a ModelError naming it."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(f"{name} must be a positive {'whole ' if integer else ''}number, got {value!r}")
    if not math.isfinite(value) or value <= 0 or (integer and value != int(value)):
        raise ModelError(f"{name} must be a positive {'whole ' if integer else ''}number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Playback:
    """How an animation plays a run: ``frames`` frames, each shown ``delay`` seconds, the run's time
    passing ``speed`` times as fast as the viewer's (1: real time)."""

    frames: int
    delay: float
    speed: float

    @property
    def label(self) -> str:
        """The speed as the animation says it: "" in real time (within 5 %), else e.g. "x4 speed"."""
        return "" if abs(self.speed - 1.0) <= 0.05 else f"x{self.speed:.2g} speed"


def _playback(duration: float, samples: int, fps: object, frames: object) -> Playback:
    """Frames and their delay: real time by default (a frame every 40 ms, up to every 100 ms for a run
    longer than MAX_FRAMES such frames, within the run's samples), a longer run sped up and a run
    shorter than FEWEST_FRAMES frames slowed down; ``fps`` and ``frames`` checked and kept when given.
    Delays are whole GIF ticks (10 ms), what a GIF can hold."""
    most = min(samples, MAX_FRAMES if frames is None else int(_positive(frames, "frames", integer=True)))
    if fps is not None:
        rate = _positive(fps, "fps")
        if rate > 50:
            raise ModelError(f"fps must be at most 50 (GIF viewers slow faster frames down), got {fps!r}")
        delay = max(GIF_TICK, round(1.0 / rate / GIF_TICK) * GIF_TICK)
        count = most if frames is not None else min(most, round(duration / delay) + 1)
    elif frames is not None:
        count = most
        delay = min(0.5, max(FASTEST, round(duration / max(count - 1, 1) / GIF_TICK) * GIF_TICK))
    else:
        slowest = SLOWEST if samples > MAX_FRAMES else 1.0  # a run of few samples: each its own time
        delay = min(slowest, max(FASTEST, math.ceil(duration / max(most - 1, 1) / GIF_TICK - 1e-9) * GIF_TICK))
        count = min(most, max(round(duration / delay) + 1, FEWEST_FRAMES))
    count = max(count, 1)
    speed = duration / ((count - 1) * delay) if count > 1 and duration > 0 else 1.0
    return Playback(count, delay, speed)


@dataclass
class _Panels:
    """What moves in an animation: the stick figure, the tool's path so far, a time cursor and the
    values' dots on each time panel, with the run's numbers they are moved to."""

    drawing: _ArmDrawing
    path: Line2D  # the tool's (or the task point's) path so far
    cursors: list[Line2D]
    dots: list[Line2D]
    times: np.ndarray
    values: list[np.ndarray]  # (samples, k) each: what each time panel plots
    actual: np.ndarray  # (k, 3): the path's points at ``samples``
    samples: np.ndarray
    speed: str = ""  # the playback's speed when not real time, e.g. "x4 speed"

    def show(self, scene: _Scene, index: int) -> list[Any]:
        """Move everything to sample ``index`` (the arm at ``scene``); the artists moved."""
        self.drawing.show(scene)
        shown = self.actual[self.samples <= index]
        self.drawing._put(self.path, shown if len(shown) else self.actual[:1])
        t = self.times[index]
        for cursor, dots, values in zip(self.cursors, self.dots, self.values, strict=True):
            cursor.set_xdata([t, t])
            dots.set_data(np.full(values.shape[1], t), values[index])
        self.drawing.ax.title.set_text(f"t = {t:.2f} s" + (f" (played at {self.speed})" if self.speed else ""))
        return [*self.drawing.artists(), self.path, *self.cursors, *self.dots, self.drawing.ax.title]


def _task_coordinates(output: str, count: int) -> list[tuple[str, str]]:
    """The names and units of a task output's ``count`` coordinates, from its description (Tracking.output):
    x, y, z (m) of a point, then rx, ry, rz (rad) of a pose's orientation (the rotation vector); the world
    axes a PlanarPosition keeps; u, v (px) of a camera; y1, y2, ... of any other output."""
    if output.startswith(("ToolPosition", "ToolPose", "LinkPoint")):
        names = [("x", "m"), ("y", "m"), ("z", "m"), ("rx", "rad"), ("ry", "rad"), ("rz", "rad")]
    elif output.startswith("PlanarPosition"):
        axes = [int(a) for a in re.findall(r"\d", output)] or [0, 1]
        names = [("xyz"[a], "m") for a in axes]
    elif output.startswith("Camera"):
        names = [("u", "px"), ("v", "px")]
    else:
        names = []
    return (names + [(f"y{i + 1}", "output units") for i in range(len(names), count)])[:count]


def _task_paths(result: Result, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray, str] | None:
    """The task point's actual and desired world positions at ``samples`` ((k, 3) each: y and y_d of a
    point, a pose's position, a PlanarPosition's two axes with the tool's third) and its name; None for
    an output that is no point of the arm (a camera's image, any other output)."""
    task = cast("Tracking", result.task)
    output = task.output
    if output.startswith(("ToolPosition", "ToolPose", "LinkPoint")):
        name = f"link {output[len('LinkPoint(') : -1]}" if output.startswith("LinkPoint") else "tool"
        return task.y[samples, :3], task.y_d[samples, :3], name
    if output.startswith("PlanarPosition"):
        axes = [int(a) for a in re.findall(r"\d", output)]
        actual = result.arm.tool_pose(result.q[samples])[:, :3, 3]
        desired = actual.copy()
        desired[:, axes] = task.y_d[samples][:, : len(axes)]
        actual[:, axes] = task.y[samples][:, : len(axes)]
        return actual, desired, "tool"
    return None


def _tool_paths(result: Result, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, str]:
    """The actual and desired path at ``samples``, (k, 3) each, and whose: the task point's y and y_d under
    a task-space law, else the tool's (forward kinematics of q and q_d; no desired path without q_d)."""
    if result.task is not None:
        paths = _task_paths(result, samples)
        if paths is not None:
            return paths
    actual = result.arm.tool_pose(result.q[samples])[:, :3, 3]
    desired = None if result.q_d is None else result.arm.tool_pose(result.q_d[samples])[:, :3, 3]
    return actual, desired, "tool"


def _time_values(result: Result) -> list[tuple[np.ndarray, list[str], str, str]]:
    """What the time panels plot: (values, names, y label, title) per panel. The task error y_d - y per
    coordinate of a task-space run (a pose's position and orientation apart: their units differ); else
    the tracking error per joint, or the joint positions of a run without a desired trajectory."""
    if result.task is not None:
        task = result.task
        coordinates = _task_coordinates(task.output, task.error.shape[1])
        panels = []
        for unit in dict.fromkeys(unit for _, unit in coordinates):
            columns = [k for k, (_, u) in enumerate(coordinates) if u == unit]
            part = "orientation " if unit == "rad" and len(columns) < len(coordinates) else ""
            panels.append((task.error[:, columns], [coordinates[k][0] for k in columns],
                           f"{part or 'task '}error y_d - y ({unit})", f"task error of {task.output}"))  # fmt: skip
        return panels
    position = units(list(result.arm.kinds), "rad", "m")
    names = list(result.arm.joint_names)
    error = result.error
    if error is None:
        return [(result.q, names, f"joint position ({position})", "joint positions (no desired trajectory)")]
    return [(error, names, f"error q_d - q ({position})", "tracking error")]


def _time_panel(ax: Axes, t: np.ndarray, values: np.ndarray, names: list[str], label: str) -> tuple[Line2D, Line2D]:
    """``values`` against time, one line per name, with a time cursor and a dot per line that animate moves."""
    for i, name in enumerate(names):
        ax.plot(t, values[:, i], color=f"C{i % 10}", label=name)
    (dots,) = ax.plot(t[:1].repeat(values.shape[1]), values[0], "o", color="0.2", markersize=4, zorder=5,
                      clip_on=False)  # fmt: skip
    cursor = ax.axvline(t[0], color="0.3", linewidth=1.0)
    ax.axhline(0.0, color="0.6", linewidth=0.8)
    ax.set(ylabel=label, xlim=(t[0], t[-1]))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8, ncols=2 if values.shape[1] > 3 else 1)
    return cursor, dots


def _animation_figure(
    result: Result, scenes: list[_Scene], samples: np.ndarray, title: str | None, dpi: int
) -> tuple[Figure, _Panels]:
    """The figure of an animation at its first frame: the arm (left), the errors against time (right)."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    plane = _plane(scenes[0])
    basis, names = plane if plane is not None else (None, None)
    fig = plt.figure(figsize=(11.5, 5.4), dpi=dpi, layout="constrained")
    grid = fig.add_gridspec(1, 2, width_ratios=[1.0, 1.1])
    left = fig.add_subplot(grid[0], projection=None if basis is not None else "3d")
    series = _time_values(result)
    right = grid[1].subgridspec(len(series), 1).subplots(sharex=True, squeeze=False)[:, 0]
    actual, desired, whose = _tool_paths(result, samples)
    size = _figure_size(scenes[0])
    handles = _legend_handles(scenes[0], basis)
    styles = {f"desired {whose} path": DESIRED_PATH_STYLE, f"{whose} path so far": ACTUAL_PATH_STYLE}
    if desired is not None:
        left.plot(*(desired @ basis.T if basis is not None else desired).T, gid="desired tool path", zorder=2,
                  **DESIRED_PATH_STYLE)  # fmt: skip
    (path,) = left.plot(*np.zeros((2 if basis is not None else 3, 1)), gid="tool path", zorder=2, **ACTUAL_PATH_STYLE)
    handles += [Line2D([], [], label=label, **style) for label, style in styles.items()
                if desired is not None or style is ACTUAL_PATH_STYLE]  # fmt: skip
    drawing = _ArmDrawing(left, scenes[0], basis, size)
    reach = [scene.points() for scene in scenes] + [_frame_tips(scene, size) for scene in scenes] + [actual]
    _set_limits(left, np.vstack(reach + ([desired] if desired is not None else [])), basis, 0.6 * size)
    _label_axes(left, basis, names)
    if basis is None:
        _fewer_ticks(left)
    left.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncols=3, fontsize=7, frameon=False)
    moving = [_time_panel(ax, result.t, values, labels, label) for ax, (values, labels, label, _) in
              zip(right, series, strict=True)]  # fmt: skip
    right[0].set_title(series[0][3], fontsize=10)
    right[-1].set_xlabel("time (s)")
    fig.suptitle(wrap(title or _title(result)), fontsize=10)
    cursors, dots = [cursor for cursor, _ in moving], [dot for _, dot in moving]
    return fig, _Panels(drawing, path, cursors, dots, result.t, [values for values, *_ in series], actual, samples)


def _fewer_ticks(ax: Axes) -> None:
    """Four ticks a side and small labels on 3-D axes, whose tick labels crowd otherwise."""
    from matplotlib.ticker import MaxNLocator

    space = cast("Axes3D", ax)
    for axis in (space.xaxis, space.yaxis, space.zaxis):
        axis.set_major_locator(MaxNLocator(4))
    space.tick_params(labelsize=7)


def animate(
    result: Result,
    path: str | Path,
    fps: float | None = None,
    frames: int | None = None,
    dpi: int = 90,
    title: str | None = None,
) -> Path:
    """An animation of a simulated run (Chapter 4): the arm's stick figure moving (as plot_arm draws
    it) with the desired tool path (q_d through the forward kinematics, when the run has a desired
    trajectory) and the tool's path so far, beside the tracking error e = q_d - q of every joint
    against time with a moving time cursor. A run under a task-space law (``result.task``) shows its
    task point's desired path y_d and its path y so far, beside the task error y_d - y per coordinate
    (a pose's position, m, and orientation, rad, in two panels).

    It plays in real time by default: a frame every 40 ms (25 per second) for a run of at most 8 s,
    fewer and longer frames (up to 100 ms) for a longer one, at most 200 frames; a run longer than
    20 s plays faster, and one shorter than 1 s slower, and the arm's title then says how much
    (e.g. "t = 12.00 s (played at x4 speed)").

    Parameters
    ----------
    result : armdyn.simulation.Result
        The run.
    path : str or Path
        The file: .gif (Pillow) or .mp4 (ffmpeg, when installed).
    fps : float, optional
        Frames per second, at most 50 (a GIF holds delays in whole hundredths of a second); default
        real time as above.
    frames : int, optional
        The most frames, spread evenly over the run; default as above (at most 200, within the run's
        samples). Given alone, the frames' delay spreads them over the run's duration (40 ms to 0.5 s).
    dpi : int, optional
        Pixels per inch of the 11.5 x 5.4 inch figure (default 90).
    title : str, optional
        The title; default the arm, controller and trajectory, as Result.plot's.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    armdyn.ModelError
        When the folder of ``path`` does not exist, its suffix is neither .gif nor .mp4, an .mp4
        is asked for without ffmpeg, ``fps``, ``frames`` or ``dpi`` is not a positive number
        (a whole one for ``frames`` and ``dpi``), or the run has no samples.
    """
    target = check_animation_path(path)
    resolution = int(_positive(dpi, "dpi", integer=True))
    if len(result.t) == 0:
        raise ModelError("the run has no samples to animate")
    playback = _playback(float(result.t[-1] - result.t[0]), len(result.t), fps, frames)
    _checked_arm(result.arm)
    indices = _frame_indices(len(result.t), playback.frames)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = [_scene(result.arm, result.q[k]) for k in indices]
    fig, panels = _animation_figure(result, scenes, _frame_indices(len(result.t), 2000), title, resolution)
    panels.speed = playback.label
    try:
        with atomic_path(target) as temporary:  # whole or not at all
            if target.suffix.lower() == ".gif":
                _write_gif(temporary, _blitted_frames(fig, panels, scenes, indices), playback.delay)
            else:
                _write_mp4(temporary, fig, panels, scenes, indices, 1.0 / playback.delay)
    finally:
        plt.close(fig)
    return target


def _blitted_frames(fig: Figure, panels: _Panels, scenes: list[_Scene], indices: np.ndarray) -> Iterator[np.ndarray]:
    """The frames as RGBA arrays: the still parts (axes, ticks, legends, the error curves) drawn once,
    then per frame only the moving artists over them (blitting): a frame costs a few milliseconds."""
    canvas = cast("FigureCanvasAgg", fig.canvas)  # animate selects the Agg backend
    moving = panels.show(scenes[0], indices[0])
    canvas.draw()  # the layout once, with the first frame's labels; then kept, so that nothing jumps
    fig.set_layout_engine("none")
    for artist in moving:
        artist.set_animated(True)
    canvas.draw()
    still = canvas.copy_from_bbox(fig.bbox)
    for scene, index in zip(scenes, indices, strict=True):
        canvas.restore_region(still)
        for artist in panels.show(scene, index):
            fig.draw_artist(artist)
        yield np.asarray(canvas.buffer_rgba())


def _write_gif(target: Path, frames: Iterator[np.ndarray], delay: float) -> None:
    """A looping GIF of the frames, each reduced to one palette (made from the first frame, the
    figure's colours) so that colours do not flicker between frames."""
    from PIL import Image

    first = Image.fromarray(next(frames)).convert("RGB")
    palette = first.quantize(colors=256, method=Image.Quantize.MEDIANCUT)
    images = [palette] + [Image.fromarray(frame).convert("RGB").quantize(palette=palette, dither=Image.Dither.NONE)
                          for frame in frames]  # fmt: skip
    images[0].save(target, save_all=True, append_images=images[1:], duration=round(1000 * delay), loop=0)


def _write_mp4(target: Path, fig: Figure, panels: _Panels, scenes: list[_Scene], indices: np.ndarray,
               fps: float) -> None:  # fmt: skip
    """An MP4 through matplotlib's FFMpegWriter: every frame drawn in full."""
    from matplotlib import animation

    writer = animation.FFMpegWriter(fps=fps)  # type: ignore[arg-type]  # the stub says int; ffmpeg takes -r 12.5
    with writer.saving(fig, target, fig.dpi):
        for scene, index in zip(scenes, indices, strict=True):
            panels.show(scene, index)
            writer.grab_frame()


def save_figure(fig: Figure, path: str | Path) -> None:
    """Save ``fig`` (150 dpi) to ``path`` whole or not at all (armdyn.files.atomic_path: a ModelError names
    a missing folder or a failed write); a path without a suffix gets matplotlib's default format's."""
    import matplotlib

    target = Path(path)
    if not target.suffix:
        target = target.with_name(f"{target.name}.{matplotlib.rcParams['savefig.format']}")
    with atomic_path(target) as temporary:
        fig.savefig(temporary, dpi=150)


def png_bytes(fig: Figure) -> bytes:
    """A figure as PNG bytes (for Jupyter's display), the figure closed afterwards.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.

    Returns
    -------
    bytes
        The PNG file's bytes.
    """
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format="png", dpi=100)
    finally:
        plt.close(fig)
    return buffer.getvalue()
