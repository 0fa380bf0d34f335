"""Figures of task-space runs and the playback of animations: plot_task draws the path in the output's
coordinates (3-D for a point, named x, y, z in m) and the task error per coordinate; an animation of a
task-space run shows the task error and the desired path y_d; GIFs play in real time (or say their speed);
titles break between phrases; the frames' names stay clear of their axes."""

from __future__ import annotations

import warnings
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.ticker import MaxNLocator
from PIL import Image

import armdyn as ad
from armdyn import task_space as ts
from armdyn.control import ComputedTorque, OperationalSpaceControl, TaskComputedTorque
from armdyn.plotting import _animation_figure, _frame_indices, _scene, wrap
from armdyn.trajectories import Circle, Line, PoseLine, Sinusoid


@pytest.fixture(autouse=True)
def _agg() -> None:
    matplotlib.use("Agg")
    yield
    plt.close("all")


def _quiet(*args: object, **options: object) -> ad.simulation.Result:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the task-space laws run in the Python loop
        return ad.simulate(*args, **options)


@pytest.fixture(scope="module")
def position_run() -> ad.simulation.Result:
    """The PUMA 560's tool along a 3-D line (ToolPosition, m = 3 < n = 6)."""
    puma = ad.models.puma560().without_friction()
    q0 = np.array([0.1, 0.6, -2.6, 0.3, 0.7, 0.2])
    y0 = ts.ToolPosition().value(puma, q0)
    law = OperationalSpaceControl(ts.ToolPosition(), Line(y0, y0 + [0.1, 0.0, 0.05], 0.3), 400.0, 40.0, posture=q0,
                                  kp0=25.0, kv0=10.0)  # fmt: skip
    return _quiet(puma, law, None, t_final=0.4, dt=2e-3, q0=q0 + 0.02)


@pytest.fixture(scope="module")
def pose_run() -> ad.simulation.Result:
    puma = ad.models.puma560().without_friction()
    q0, q1 = np.array([0.1, 0.6, -2.6, 0.3, 0.7, 0.2]), np.array([0.4, 0.5, -2.4, 0.5, 0.9, 0.6])
    path = PoseLine(puma.tool_pose(q0), puma.tool_pose(q1), duration=0.3)
    return _quiet(puma, TaskComputedTorque(ts.ToolPose(), path, 400.0, 40.0), None, t_final=0.4, dt=2e-3, q0=q0)


def _gif(path: Path) -> tuple[int, list[int]]:
    """A GIF's frame count and each frame's delay (ms), read back."""
    with Image.open(path) as image:
        delays = []
        for k in range(image.n_frames):
            image.seek(k)
            delays.append(image.info["duration"])
        return image.n_frames, delays


def test_plot_task_of_a_tool_position_is_a_3d_path_named_x_y_z(position_run) -> None:
    figure = position_run.plot_task()
    path = figure.axes[0]
    assert path.name == "3d"
    assert (path.get_xlabel(), path.get_ylabel(), path.get_zlabel()) == ("x (m)", "y (m)", "z (m)")
    lines = {line.get_gid(): np.array(line.get_data_3d()).T for line in path.lines if line.get_gid()}
    np.testing.assert_array_equal(lines["desired path"], position_run.task.y_d)
    np.testing.assert_array_equal(lines["path"], position_run.task.y)
    error, size = figure.axes[1], figure.axes[2]
    assert error.get_ylabel() == "task error y_d - y (m)"
    assert [text.get_text() for text in error.get_legend().get_texts()] == ["x", "y", "z"]
    for k, line in enumerate(error.lines[:3]):
        np.testing.assert_array_equal(line.get_ydata(), position_run.task.error[:, k])
    assert size.get_yscale() == "log" and size.get_ylabel() == "|y_d - y| (m)"
    # fewer ticks and small labels on the 3-D axes
    figure.canvas.draw()
    for axis in (path.xaxis, path.yaxis, path.zaxis):
        low, high = sorted(axis.get_view_interval())
        ticks = [tick for tick in axis.get_major_locator()() if low <= tick <= high]
        assert isinstance(axis.get_major_locator(), MaxNLocator) and len(ticks) <= 5
        assert all(label.get_fontsize() <= 7 for label in axis.get_ticklabels())


def test_plot_task_of_a_pose_shows_position_and_orientation_errors_with_units(pose_run) -> None:
    figure = pose_run.plot_task()
    assert len(figure.axes) == 4 and figure.axes[0].name == "3d"
    position, orientation = figure.axes[1], figure.axes[2]
    assert position.get_ylabel() == "task error y_d - y (m)"
    assert orientation.get_ylabel() == "orientation error y_d - y (rad)"
    assert [text.get_text() for text in orientation.get_legend().get_texts()] == ["rx", "ry", "rz"]
    np.testing.assert_array_equal(orientation.lines[1].get_ydata(), pose_run.task.error[:, 4])
    lines = {line.get_gid(): np.array(line.get_data_3d()).T for line in figure.axes[0].lines if line.get_gid()}
    np.testing.assert_array_equal(lines["desired path"], pose_run.task.y_d[:, :3])  # the pose's position


def test_plot_task_of_a_planar_output_names_its_world_axes() -> None:
    arm = ad.models.two_link_planar(1.0, 1.0, 2.0, 2.0, g=9.8)
    output = ts.PlanarPosition()
    start = np.array([0.3, 1.2])
    law = TaskComputedTorque(output, Circle(output.value(arm, start) - [0.2, 0.0], 0.2, 2.0), 400.0, 40.0)
    figure = _quiet(arm, law, None, t_final=0.1, q0=start).plot_task()
    assert figure.axes[0].name != "3d"
    assert (figure.axes[0].get_xlabel(), figure.axes[0].get_ylabel()) == ("x (m)", "y (m)")


def test_an_animation_of_a_task_run_shows_the_task_error_and_the_desired_path(position_run) -> None:
    indices = _frame_indices(len(position_run.t), 5)
    scenes = [_scene(position_run.arm, position_run.q[k]) for k in indices]
    samples = _frame_indices(len(position_run.t), 2000)
    figure, _ = _animation_figure(position_run, scenes, samples, None, 50)
    arm, error = figure.axes[0], figure.axes[1]
    target = next(line for line in arm.lines if line.get_gid() == "desired tool path")
    np.testing.assert_allclose(np.array(target.get_data_3d()).T, position_run.task.y_d[samples], rtol=0, atol=0)
    assert error.get_title() == "task error of ToolPosition()" and error.get_ylabel() == "task error y_d - y (m)"
    for k in range(3):
        np.testing.assert_array_equal(error.lines[k].get_ydata(), position_run.task.error[:, k])
    assert "no desired trajectory" not in error.get_title()


def test_an_animation_of_a_pose_run_has_two_error_panels(pose_run, tmp_path: Path) -> None:
    pose_run.animate(tmp_path / "pose.gif", dpi=40)
    indices = _frame_indices(len(pose_run.t), 3)
    figure, _ = _animation_figure(pose_run, [_scene(pose_run.arm, pose_run.q[k]) for k in indices],
                                  indices, None, 40)  # fmt: skip
    assert [ax.get_ylabel() for ax in figure.axes[1:]] == ["task error y_d - y (m)", "orientation error y_d - y (rad)"]


def _two_link(t_final: float, dt: float = 1e-2) -> ad.simulation.Result:
    arm = ad.models.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
    desired = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])
    return ad.simulate(arm, ComputedTorque(100.0, 20.0), desired, t_final=t_final, dt=dt)


@pytest.mark.parametrize("t_final", [2.0, 6.0])
def test_a_gif_plays_in_real_time_by_default(t_final: float, tmp_path: Path) -> None:
    run = _two_link(t_final)
    run.animate(tmp_path / "run.gif", dpi=30)
    count, delays = _gif(tmp_path / "run.gif")
    assert count <= 200 and set(delays) == {40}  # 25 frames a second
    assert abs((count - 1) * delays[0] / 1000 - t_final) <= delays[0] / 1000  # the run's length, within a frame
    assert count == round(t_final / 0.04) + 1


def test_a_long_run_plays_faster_and_says_so(tmp_path: Path) -> None:
    run = _two_link(60.0, dt=0.05)
    run.animate(tmp_path / "long.gif", dpi=30)
    count, delays = _gif(tmp_path / "long.gif")
    assert count == 200 and set(delays) == {100}  # the most frames at 10 a second: 20 s for 60 s, x3
    speed = 60.0 / ((count - 1) * 0.1)
    indices = _frame_indices(len(run.t), count)
    figure, panels = _animation_figure(run, [_scene(run.arm, run.q[k]) for k in indices[:2]], indices, None, 30)
    from armdyn.plotting import _playback

    playback = _playback(60.0, len(run.t), None, None)
    assert playback.frames == 200 and playback.delay == pytest.approx(0.1)
    assert playback.label == f"x{speed:.2g} speed" == "x3 speed"
    panels.speed = playback.label
    panels.show(_scene(run.arm, run.q[0]), 0)
    assert figure.axes[0].get_title() == "t = 0.00 s (played at x3 speed)"
    assert _playback(2.0, 201, None, None).label == ""  # real time says nothing


def test_given_frames_and_fps_are_kept(tmp_path: Path) -> None:
    run = _two_link(1.0)
    run.animate(tmp_path / "run.gif", frames=12, fps=20, dpi=30)
    count, delays = _gif(tmp_path / "run.gif")
    assert count == 12 and set(delays) == {50}


def test_titles_break_between_phrases() -> None:
    title = ("puma560: operational-space control on ToolPosition() (kp = 400, kv = 40; posture kp0 = 25, "
             "kv0 = 10), rk4 (Python), dt = 1 ms")  # fmt: skip
    lines = wrap(title, 100).split("\n")
    assert lines == ["puma560: operational-space control on ToolPosition() (kp = 400, kv = 40;",
                     "posture kp0 = 25, kv0 = 10), rk4 (Python), dt = 1 ms"]  # fmt: skip
    assert " ".join(lines) == title and all(len(line) <= 100 for line in lines)
    assert wrap("short: title") == "short: title"
    assert all(len(line) <= 40 for line in wrap("x" * 30 + " " + "y" * 30, 40).split("\n"))


@pytest.mark.parametrize(("name", "q"), [("two_link_planar", [0.3, 1.2]), ("two_link_planar", [0.0, 0.0]),
                                         ("puma560", None)])  # fmt: skip
def test_frame_names_do_not_sit_on_their_axes(name: str, q: list[float] | None) -> None:
    """The names "base" and "tool" are drawn where no frame axis or link leaves their origin: the text's
    box (in pixels) holds none of the axes' lines' points near the origin."""
    arm = getattr(ad.models, name)()
    figure = arm.plot(q)
    ax = figure.axes[0]
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    for text in ax.texts:
        box = text.get_window_extent(renderer)
        for line in ax.lines:
            if line.get_gid() is None or not line.get_gid().startswith(text.get_text()):
                continue
            if ax.name == "3d":
                from mpl_toolkits.mplot3d import proj3d

                xs, ys, zs = line.get_data_3d()
                x, y, _ = proj3d.proj_transform(np.asarray(xs), np.asarray(ys), np.asarray(zs), ax.get_proj())
                points = np.column_stack([x, y])
            else:
                points = np.column_stack(line.get_data())
            dense = points[0] + np.linspace(0, 1, 50)[:, None] * (points[-1] - points[0])  # the axis's length
            pixels = ax.transData.transform(dense)
            inside = (
                (box.x0 <= pixels[:, 0])
                & (pixels[:, 0] <= box.x1)
                & (box.y0 <= pixels[:, 1])
                & (pixels[:, 1] <= box.y1)
            )
            assert not inside.any(), (name, text.get_text(), line.get_gid())
