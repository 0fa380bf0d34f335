"""Pictures of the arm and animations of a run: the stick figure is the forward kinematics, planar arms
are drawn in 2-D and spatial ones in 3-D, animations are GIFs of the moving arm, and every bad
argument is one clear ModelError."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

import armdyn as ad
from armdyn.cli import app
from armdyn.control import ComputedTorque, PDGravity
from armdyn.model.joint import rot_x
from armdyn.plotting import animate, plot_arm
from armdyn.trajectories import Sinusoid
from tests.helpers import URDFS

LINK_GREY = np.array([64, 64, 64])  # the links' colour, "0.25"


@pytest.fixture(autouse=True)
def _agg() -> None:
    """Figures drawn off screen, and closed after each test."""
    matplotlib.use("Agg")
    yield
    plt.close("all")


def _panda() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its mimic joint
        return ad.load_urdf(URDFS["panda"])


def _lines(ax: object) -> dict[str, np.ndarray]:
    """The axes' lines by gid, each as its vertices (k, 2) or (k, 3)."""
    found = {}
    for line in ax.lines:
        if line.get_gid() is not None:
            found[line.get_gid()] = np.array(line.get_data_3d() if ax.name == "3d" else line.get_data()).T
    return found


def _assert_figure_is_the_kinematics(arm: ad.Robot, q: np.ndarray, fig: object, basis: np.ndarray) -> None:
    """Each link's line runs from its parent's frame origin to its own (link_transforms), the tool's
    to tool_pose, in the axes' coordinates (``basis`` rows: the world axes the axes show)."""
    lines = _lines(fig.axes[0])
    origins = arm.link_transforms(q)[:, :3, 3]
    for i, parent in enumerate(arm.parents):
        start = arm.base[:3, 3] if parent < 0 else origins[parent]
        np.testing.assert_allclose(lines[f"link {i}"][0], basis @ start, rtol=0, atol=1e-12)
        np.testing.assert_allclose(lines[f"link {i}"][-1], basis @ origins[i], rtol=0, atol=1e-12)
    np.testing.assert_allclose(lines["tool"][-1], basis @ arm.tool_pose(q)[:3, 3], rtol=0, atol=1e-12)
    assert {f"joint {i}" for i in range(arm.n)} <= set(lines)


@pytest.mark.parametrize("name", ["qz", "qr"])
def test_the_puma_is_drawn_at_its_forward_kinematics_in_3d(name: str) -> None:
    arm = ad.models.puma560()
    fig = plot_arm(arm, name)
    assert fig.axes[0].name == "3d"
    _assert_figure_is_the_kinematics(arm, arm.configuration(name), fig, np.eye(3))
    assert fig.axes[0].get_title().startswith(f"puma560 at {name} = (0, ")
    spans = [np.ptp(limits) for limits in (fig.axes[0].get_xlim(), fig.axes[0].get_ylim(), fig.axes[0].get_zlim())]
    np.testing.assert_allclose(spans, spans[0])  # equal scales: the arm is not distorted


def test_the_panda_tree_draws_each_branch_from_its_parent() -> None:
    arm = _panda()
    assert list(arm.parents[-2:]) == [6, 6]  # two fingers on the hand
    q = np.array([0.3, -0.785, 0.2, -2.356, 0.1, 1.571, 0.785, 0.02, 0.03])
    _assert_figure_is_the_kinematics(arm, q, plot_arm(arm, q), np.eye(3))


def test_the_rr_arm_is_drawn_in_2d_in_its_plane() -> None:
    arm = ad.models.two_link_planar()
    q = np.array([0.3, 1.2])
    fig = arm.plot(q)
    ax = fig.axes[0]
    assert ax.name == "rectilinear" and ax.get_aspect() == 1.0
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "y (m)")
    _assert_figure_is_the_kinematics(arm, q, fig, np.eye(3)[:2])


def test_an_arm_in_a_vertical_plane_is_drawn_in_its_x_z_coordinates() -> None:
    arm = ad.models.two_link_planar().replace(base=rot_x(np.pi / 2))  # joint axes along -y
    q = np.array([0.4, -0.9])
    fig = plot_arm(arm, q)
    assert fig.axes[0].name == "rectilinear" and fig.axes[0].get_ylabel() == "z (m)"
    _assert_figure_is_the_kinematics(arm, q, fig, np.eye(3)[[0, 2]])


def test_robot_plot_draws_the_named_configuration_by_default_and_writes_a_file(tmp_path: Path) -> None:
    arm = ad.models.puma560()
    assert arm.plot().axes[0].get_title().startswith("puma560 at qn = (0, 0.7854, -3.142")
    assert ad.models.two_link_planar().plot().axes[0].get_title().startswith("two_link_planar at qz = (0, 0)")
    fig = plot_arm(_panda())
    assert fig.axes[0].get_title().startswith("panda at q = (0, 0, 0")
    assert "(rad for R, m for P)" in fig.axes[0].get_title().replace("\n", " ")
    labels = [text.get_text() for text in fig.axes[0].get_legend().get_texts()]
    assert "revolute joint, along its axis" in labels and "prismatic joint, along its axis" in labels
    picture = arm.plot("qr", path=tmp_path / "puma.png")
    assert (tmp_path / "puma.png").read_bytes().startswith(b"\x89PNG") and picture.number not in plt.get_fignums()


def test_plot_arm_draws_on_given_axes() -> None:
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    assert plot_arm(ad.models.stanford(), ax=ax) is fig and len(ax.lines) > 6


@pytest.fixture(scope="module")
def rr_run() -> object:
    """Example 4.4-1 for one second."""
    arm = ad.models.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
    desired = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])
    return ad.simulate(arm, ComputedTorque(100.0, 20.0), desired, t_final=1.0, dt=1e-3)


def _frames(path: Path) -> list[np.ndarray]:
    with Image.open(path) as image:
        frames = []
        for k in range(image.n_frames):
            image.seek(k)
            frames.append(np.asarray(image.convert("RGB")))
        return frames


def _arm_pixels(frame: np.ndarray) -> int:
    return int(np.all(np.abs(frame.astype(int) - LINK_GREY) <= 8, axis=-1).sum())


def test_animate_writes_a_gif_of_the_moving_arm(rr_run: object, tmp_path: Path) -> None:
    written = rr_run.animate(tmp_path / "run.gif", frames=12)
    assert written == tmp_path / "run.gif"
    frames = _frames(written)
    assert len(frames) == 12 and frames[0].shape == (486, 1035, 3)  # 11.5 x 5.4 in at 90 dpi
    assert all(_arm_pixels(frame) > 500 for frame in frames)  # the links are there in every frame
    assert not np.array_equal(frames[0], frames[-1])  # and they move (with the cursor)
    with Image.open(written) as image:
        assert abs(image.info["duration"] - 1000 / 11) <= 10 and image.info["loop"] == 0  # real time, 11 steps in 1 s


def test_animate_a_spatial_arm_and_a_run_without_a_trajectory(tmp_path: Path) -> None:
    arm = ad.models.puma560()
    held = ad.simulate(arm, PDGravity(100.0, 20.0), t_final=0.2, q0=arm.qn, qd0=np.full(6, 0.5))
    assert held.q_d is None
    animate(held, tmp_path / "held.gif", frames=4, fps=5, dpi=50)
    frames = _frames(tmp_path / "held.gif")
    assert len(frames) == 4 and frames[0].shape == (270, 575, 3)
    assert _arm_pixels(frames[-1]) > 100


def test_a_result_shows_in_jupyter_as_its_figure(rr_run: object) -> None:
    before = plt.get_fignums()
    png = rr_run._repr_png_()
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and plt.get_fignums() == before


@pytest.mark.slow
def test_cli_simulate_animate_and_show_draw(tmp_path: Path) -> None:
    gif, picture = tmp_path / "run.gif", tmp_path / "arm.svg"
    args = ["simulate", "two_link_planar", "--t-final", "0.3", "--animate", str(gif)]
    result = CliRunner().invoke(app, args, prog_name="armdyn")
    assert result.exit_code == 0, result.output
    assert f"wrote {gif}" in result.output and len(_frames(gif)) > 1
    result = CliRunner().invoke(app, ["show", "scara", "--draw", str(picture), "--q", "qr"], prog_name="armdyn")
    assert result.exit_code == 0, result.output
    assert "scara at qr = (0, 0.7854, 0.1, 0)" in picture.read_text()


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["simulate", "two_link_planar", "--animate", "out.png"], "--animate out.png: an animation must end in .gif"),
        (["simulate", "two_link_planar", "--animate", "no/out.gif"], "--animate no/out.gif: the folder no does not"),
        (["show", "scara", "--draw", "arm.xyz"], "--draw arm.xyz: a picture must end in"),
        (["show", "scara", "--draw", "arm.png", "--q", "1,2"], "--q has 2 values, but the arm has 4 joints"),
        (["show", "scara", "--q", "qr"], "--q is the configuration of the picture: give --draw PATH too"),
    ],
)
def test_cli_picture_errors_are_one_line(args: list[str], fragment: str, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, args, prog_name="armdyn")
    assert result.exit_code == 2 and result.stderr.startswith("error: ") and fragment in result.stderr
    assert not list(tmp_path.iterdir())  # refused before anything was written


@pytest.mark.slow
def test_demo_writes_the_animation_of_example_4_4_1(demo_run: tuple) -> None:
    result, folder = demo_run
    assert result.exit_code == 0, result.output
    assert "demo.gif (the arm moving)" in " ".join(result.output.split())
    frames = _frames(folder / "demo.gif")
    assert len(frames) == 126 and all(_arm_pixels(frame) > 500 for frame in frames[::30])


def test_bad_configurations_arms_and_paths_are_model_errors(rr_run: object, tmp_path: Path) -> None:
    puma = ad.models.puma560()
    with pytest.raises(ad.ModelError, match=r"q must have shape \(6,\) or \(\.\.\., 6\) for 'puma560', got \(2,\)"):
        plot_arm(puma, [0.0, 1.0])
    with pytest.raises(ad.ModelError, match=r"q must be one configuration, 6 joint values for 'puma560'"):
        puma.plot(np.zeros((2, 6)))
    with pytest.raises(ad.ModelError, match="has no configuration 'qq'"):
        puma.plot("qq")
    with pytest.raises(ad.ModelError, match="must be finite"):
        puma.plot([0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ad.ModelError, match=r"the folder .*missing does not exist"):
        puma.plot(path=tmp_path / "missing" / "arm.png")
    with pytest.raises(ad.ModelError, match="draw it on 3-D axes"):
        puma.plot(ax=plt.figure().add_subplot())
    with pytest.raises(ad.ModelError, match="symbolic"):
        plot_arm(ad.models.two_link_planar(symbolic=True))
    with pytest.raises(TypeError, match="armdyn Robot"):
        plot_arm("puma560")
    with pytest.raises(ad.ModelError, match=r"the folder .*missing does not exist"):
        rr_run.animate(tmp_path / "missing" / "run.gif")
    with pytest.raises(ad.ModelError, match=r"an animation must end in \.gif or \.mp4"):
        rr_run.animate(tmp_path / "run.avi")
    for option, value in (("frames", 0), ("frames", 2.5), ("fps", -1.0), ("fps", 60), ("dpi", True)):
        with pytest.raises(ad.ModelError, match=option):
            rr_run.animate(tmp_path / "run.gif", **{option: value})
    assert not list(tmp_path.iterdir())


@pytest.mark.skipif(shutil.which("ffmpeg") is not None, reason="ffmpeg is installed")
def test_an_mp4_without_ffmpeg_is_a_clear_error(rr_run: object, tmp_path: Path) -> None:
    with pytest.raises(ad.ModelError, match=r"\.mp4 needs ffmpeg, which is not installed"):
        rr_run.animate(tmp_path / "run.mp4")


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed")
def test_an_mp4_with_ffmpeg(rr_run: object, tmp_path: Path) -> None:
    assert rr_run.animate(tmp_path / "run.mp4", frames=5).stat().st_size > 0
