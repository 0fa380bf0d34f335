"""armdyn.viewer without a browser: the scenes of example-robot-data's URDFs and of the built-in arms, the overlays'
numbers against their closed forms, torque colours, the saved page (size, inline recording), the command line and
the error paths. Every viewer runs on 127.0.0.1 and is closed by its ``with`` block."""

from __future__ import annotations

import base64
import re
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn import viewer as view
from armdyn.control import ComputedTorque
from armdyn.errors import MissingDependencyError, ModelError
from armdyn.trajectories import Sinusoid
from tests.helpers import ROBOTS, URDFS, invoke

PANDA_Q = np.array([0.1, -0.5, 0.2, -2.0, 0.1, 1.6, 0.8, 0.02, 0.02])
FAST_URDFS = {URDFS["panda"], URDFS["ur5"]}


def _urdf_cases() -> list:
    cases = []
    for path in sorted(ROBOTS.rglob("*.urdf")):
        marks = () if path in FAST_URDFS else (pytest.mark.slow,)
        cases.append(pytest.param(path, id=str(path.relative_to(ROBOTS)), marks=marks))
    return cases


def _loaded(path: Path) -> ad.Robot:
    """The arm of a URDF as armdyn loads it (strict, else with strict=False), or a skip naming armdyn's refusal."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return ad.load_urdf(path)
        except ModelError:
            try:
                return ad.load_urdf(path, strict=False)
            except ModelError as error:
                pytest.skip(f"armdyn does not load it: {error}")


def _rotation(wxyz: np.ndarray) -> np.ndarray:
    w, x, y, z = wxyz
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


@pytest.mark.parametrize("path", _urdf_cases())
def test_every_example_robot_data_urdf_builds_a_scene_with_its_meshes(path: Path) -> None:
    arm = _loaded(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)  # a missing mesh warns: here it fails the test
        with view.Viewer(arm) as viewer:
            data = viewer.scene_data()
    assert data["warnings"] == []
    assert [link["name"] for link in data["links"]] == ["base", *arm.joint_names]
    for link in data["links"]:
        assert all(Path(file).is_file() for file in link["files"]), link
        assert (link["kind"] == "mesh") == bool(link["files"]), link
    text = path.read_text(encoding="utf-8", errors="replace")
    if "<mesh" in text and "<visual" in text:
        assert any(link["kind"] == "mesh" for link in data["links"])


@pytest.mark.parametrize("name", ad.models.names())
def test_each_built_in_arm_draws_as_capsules(name: str) -> None:
    arm = ad.models.load(name)
    with view.Viewer(arm) as viewer:
        assert re.fullmatch(r"http://127\.0\.0\.1:\d+", viewer.url)
        data = viewer.scene_data()
        assert data["warnings"] == []
        assert {link["kind"] for link in data["links"][1:]} == {"capsule"}
        assert data["link_color"] == view.LINK_COLOR
        # each link frame is drawn where the kinematics put it
        T = arm.link_transforms(viewer.q)
        for i in range(arm.n):
            node = viewer._nodes[i]
            np.testing.assert_allclose(node.position, T[i, :3, 3], atol=1e-12)
            np.testing.assert_allclose(_rotation(node.wxyz), T[i, :3, :3], atol=1e-9)


@pytest.fixture(scope="module")
def panda() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the mimic finger joint
        return ad.load_urdf(URDFS["panda"])


def test_the_ellipsoids_agree_with_lambda_manipulability_and_the_links_inertia(panda: ad.Robot) -> None:
    with view.Viewer(panda, q=PANDA_Q, overlays=view.OVERLAYS) as viewer:
        data = viewer.scene_data()
        drawn = {name: viewer._overlay[name][0] for name in ("lambda", "manipulability")}
        M, J = panda.inertia_matrix(PANDA_Q), panda.jacobian(PANDA_Q)[:3]
        tool = panda.tool_pose(PANDA_Q)[:3, 3]
        # Lambda = (J_v M^-1 J_v^T)^-1 (Section 3.5): axes its eigenvectors, radii LAMBDA_SCALE lambda_i / max
        oracles = {
            "lambda": (np.linalg.inv(J @ np.linalg.solve(M, J.T)), lambda e: view.LAMBDA_SCALE * e / e.max()),
            "manipulability": (J @ J.T, lambda e: view.MANIPULABILITY_SCALE * np.sqrt(e)),
        }
        for name, (matrix, radii_of) in oracles.items():
            ellipsoid, eigenvalues = data[name], np.linalg.eigvalsh(matrix)
            axes, radii = ellipsoid["axes"], ellipsoid["radii"]
            scale = np.abs(eigenvalues).max()
            np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
            assert np.linalg.det(axes) == pytest.approx(1.0)
            mine = np.diag(axes.T @ matrix @ axes)  # each axis's eigenvalue, in the axes' order
            np.testing.assert_allclose(matrix @ axes, axes * mine, atol=1e-9 * scale)  # eigenvectors
            np.testing.assert_allclose(np.sort(mine), eigenvalues, rtol=1e-9, atol=1e-12 * scale)
            np.testing.assert_allclose(radii, radii_of(mine), rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(ellipsoid["centre"], tool, atol=1e-12)
            # and the drawing is these numbers
            np.testing.assert_allclose(drawn[name].scale, np.maximum(radii, 1e-4), rtol=1e-9)
            np.testing.assert_allclose(_rotation(drawn[name].wxyz), axes, atol=1e-9)
            np.testing.assert_allclose(drawn[name].position, tool, atol=1e-12)
        assert data["lambda"]["radii"].max() == pytest.approx(view.LAMBDA_SCALE)
        # each link's ellipsoid: a uniform solid ellipsoid of semi-axes a has moments m (a_j^2 + a_k^2) / 5,
        # which must be the link's central inertia seen in the world
        T = panda.link_transforms(PANDA_Q)
        assert [e["link"] for e in data["inertia"]] == [link.name for link in panda.links if link.inertial.mass > 0]
        for ellipsoid in data["inertia"]:
            i = panda.joint_names.index(ellipsoid["link"])
            body, R = panda.links[i].inertial, T[i, :3, :3]
            a2 = ellipsoid["radii"] ** 2
            moments = body.mass / 5 * (a2.sum() - a2)
            solid = ellipsoid["axes"] @ np.diag(moments) @ ellipsoid["axes"].T
            world = R @ np.asarray(body.inertia, dtype=float) @ R.T
            np.testing.assert_allclose(solid, world, atol=1e-9 * np.abs(world).max())
            np.testing.assert_allclose(ellipsoid["centre"], T[i, :3, 3] + R @ body.com, atol=1e-12)


def test_centre_of_mass_and_gravity_overlays_agree_with_the_dynamics(panda: ad.Robot) -> None:
    data = view.scene_data(panda, PANDA_Q)
    mass = sum(link.inertial.mass for link in panda.links)
    # P(q) = -sum m_i g^T p_ci = -m g^T p_com (3.2.35)
    assert -mass * panda.gravity @ data["com"] == pytest.approx(panda.potential_energy(PANDA_Q), rel=1e-12)
    zero = np.zeros(panda.n)
    np.testing.assert_allclose(data["gravity"], panda.inverse_dynamics(PANDA_Q, zero, zero), atol=1e-10)
    with view.Viewer(panda, q=PANDA_Q, overlays=("com", "gravity")) as viewer:
        np.testing.assert_allclose(viewer._overlay["com"][0].position, data["com"], atol=1e-12)
        arrows = np.asarray(viewer._overlay["gravity"][0].points, dtype=float)  # viser holds float32
        lengths = np.linalg.norm(arrows[:, 1] - arrows[:, 0], axis=1)
        expected = view.GRAVITY_SCALE * np.abs(data["gravity"]) / np.abs(data["gravity"]).max()
        np.testing.assert_allclose(lengths, expected, atol=1e-6)


def test_a_singular_jacobian_hides_lambda() -> None:
    arm = ad.models.load("two_link_planar")  # planar: the tool cannot move along z, so J_v has rank 2
    q = np.array([0.3, 0.4])
    data = view.scene_data(arm, q)
    assert data["lambda"] is None
    assert np.sort(data["manipulability"]["radii"])[0] == pytest.approx(0.0, abs=1e-9)
    with view.Viewer(arm, q=q, overlays=("lambda",)) as viewer:
        assert viewer._overlay["lambda"][0].visible is False


@pytest.fixture(scope="module")
def panda_run(panda: ad.Robot) -> ad.simulation.Result:
    amplitude = np.r_[np.full(7, 0.4), 0.0, 0.0]
    return ad.simulate(
        panda, ComputedTorque(100, 20), Sinusoid(amplitude, 0.5, offset=PANDA_Q), t_final=2.0, q0=PANDA_Q
    )


def _recording(page: str) -> bytes:
    """The scene recording a saved page holds inline (viser's embed data), decompressed."""
    import zstandard

    found = re.search(r'window\.__VISER_EMBED_DATA__="([A-Za-z0-9+/=]+)"', page)
    assert found, "the recording is not inline"
    raw = base64.b64decode(found.group(1))
    size = int.from_bytes(raw[:8], "little")
    return zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=size)


def _messages(page: str) -> dict:
    import msgspec

    inner = _recording(page)
    length = int.from_bytes(inner[:8], "little")
    return msgspec.msgpack.decode(inner[8 : 8 + length])


def test_a_two_second_panda_run_saves_as_one_offline_page_under_5_mb(
    panda: ad.Robot, panda_run: ad.simulation.Result, tmp_path: Path
) -> None:
    with panda_run.view(overlays=("lambda",)) as viewer:
        page = viewer.save_html(tmp_path / "panda.html")
        shapes = sum(len(drawing.shapes) for drawing in viewer._drawings.values())
    assert page.stat().st_size < 5e6
    text = page.read_text(encoding="utf-8")
    # nothing the page would fetch: no http(s) source, link, stylesheet or fetch (the favicon's xmlns is no fetch)
    assert not re.search(r"""(?:src|href)\s*=\s*["']?https?://|url\(\s*["']?https?://|fetch\(\s*["']https?://""", text)
    assert "playbackPath" not in text
    recording = _messages(text)
    assert recording["durationSeconds"] == pytest.approx(2.0, abs=2 / view.FRAME_RATE)
    kinds = [message["type"] for _, message in recording["messages"]]
    assert kinds.count("MeshMessage") == shapes  # each mesh sent once; frames move the link frames only
    times = sorted({time for time, message in recording["messages"]})
    assert len(times) == pytest.approx(2.0 * view.FRAME_RATE, abs=2)


def test_torques_colour_the_links_relative_to_the_limits(panda_run: ad.simulation.Result) -> None:
    tau = np.abs(panda_run.tau)
    with panda_run.view() as viewer:
        for joint in (0, 3):
            row = int(np.argmax(tau[:, joint]))
            viewer.show_time(float(panda_run.t[row]))
            np.testing.assert_allclose(viewer.q, panda_run.q[row])
            assert tuple(viewer._meshes[joint][0].color) == view.TORQUE_COLOR  # its largest |tau|: the limit
    limits = 2 * tau.max(axis=0)
    with panda_run.view(torque_limits=limits) as viewer:
        row = int(np.argmax(tau[:, 3]))
        viewer.show_time(float(panda_run.t[row]))
        expected = np.rint(np.add(view.LINK_COLOR, 0.5 * np.subtract(view.TORQUE_COLOR, view.LINK_COLOR)))
        np.testing.assert_allclose(viewer._meshes[3][0].color, expected, atol=1)


def test_play_advances_the_time_slider_and_pause_holds_it() -> None:
    arm = ad.models.load("puma560")
    run = ad.simulate(arm, ComputedTorque(100, 20), Sinusoid(0.5, 0.5, offset=arm.qn), t_final=1.0, q0=arm.qn)
    with run.view() as viewer:
        start = viewer.q
        viewer._playing.value = True  # as the page's checkbox
        time.sleep(0.4)
        viewer._playing.value = False
        time.sleep(0.1)
        held = viewer._time.value
        assert held > 0.1
        row = int(np.searchsorted(run.t, held))
        np.testing.assert_allclose(viewer.q, run.q[row])
        assert np.abs(viewer.q - start).max() > 0.01
        time.sleep(0.2)
        assert viewer._time.value == held


@pytest.mark.slow
def test_a_run_with_drives_shows_their_inputs() -> None:
    from armdyn import actuators as act
    from armdyn.control import DrivePID

    arm = act.puma560_with_drives()
    q0 = ad.models.puma560().configuration("qn")
    run = ad.simulate(arm, DrivePID(20.0, 0.5), Sinusoid(0.1, 0.5, 0.0, q0), t_final=0.3, q0=q0)
    with run.view() as viewer:
        viewer.show_time(0.2)
        row = int(np.searchsorted(run.t, 0.2))
        shown = [float(x) for x in re.findall(r"q\d: (-?[\d.e+-]+)", viewer._inputs.content)]
        np.testing.assert_allclose(shown, run.drives.v[row], rtol=5e-3)


def test_a_dh_arm_saves_a_page_and_set_configuration_moves_it(tmp_path: Path) -> None:
    arm = ad.models.load("puma560")
    with arm.view(overlays=("inertia", "com")) as viewer:
        q = np.array([0.3, -0.4, 0.5, 0.1, 0.2, 0.3])
        viewer.set_configuration(q)
        np.testing.assert_allclose(viewer.scene_data()["q"], q)
        np.testing.assert_allclose(viewer._nodes[2].position, arm.link_transforms(q)[2, :3, 3], atol=1e-12)
        page = viewer.save_html(tmp_path / "puma.html")
    assert page.stat().st_size < 2e6
    assert _messages(page.read_text(encoding="utf-8"))["messages"]


def test_missing_meshes_are_drawn_as_capsules_with_a_warning_naming_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS.parent.parent))  # package://example-robot-data from tmp_path
    (tmp_path / "broken.stl").write_text("not a mesh")
    text = URDFS["ur5"].read_text(encoding="utf-8")
    meshes = [name for name in re.findall(r'filename="([^"]+)"', text) if "/visual/" in name]
    text = text.replace(meshes[1], "package://nowhere/missing.stl").replace(meshes[3], "broken.stl")
    urdf = tmp_path / "ur5_broken.urdf"
    urdf.write_text(text, encoding="utf-8")
    arm = ad.load_urdf(urdf)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with view.Viewer(arm) as viewer:
            data = viewer.scene_data()
    assert [str(warning.message) for warning in caught if warning.category is UserWarning] == data["warnings"]
    assert any("package://nowhere/missing.stl" in note and "not found" in note for note in data["warnings"])
    assert any("broken.stl" in note and "cannot be loaded" in note for note in data["warnings"])
    assert any(link["kind"] == "capsule" for link in data["links"])


def test_mesh_paths_resolve_from_package_file_and_relative_names(tmp_path: Path) -> None:
    mesh = tmp_path / "ws" / "src" / "mypkg" / "meshes" / "a.stl"
    mesh.parent.mkdir(parents=True)
    mesh.write_text("solid a\nendsolid a\n")
    urdf = tmp_path / "ws" / "src" / "mypkg" / "urdf" / "r.urdf"
    urdf.parent.mkdir()
    urdf.write_text("<robot name='r'/>")
    assert view.resolve_mesh("package://mypkg/meshes/a.stl", urdf) == mesh.resolve()
    assert view.resolve_mesh("../meshes/a.stl", urdf) == (urdf.parent / "../meshes/a.stl")
    assert view.resolve_mesh(f"file://{mesh}", urdf) == mesh
    assert view.resolve_mesh("package://otherpkg/meshes/a.stl", urdf) is None
    assert view.resolve_mesh("package://example-robot-data/robots/ur_description/meshes/ur5/visual/base.dae",
                             URDFS["ur5"]) is not None  # fmt: skip


def test_a_missing_extra_names_it(monkeypatch: pytest.MonkeyPatch) -> None:
    arm = ad.models.load("two_link_planar")
    for module in ("viser", "trimesh"):
        with monkeypatch.context() as patch:
            patch.setitem(sys.modules, module, None)  # import fails as if not installed
            with pytest.raises(MissingDependencyError, match=r"pip install 'armdyn\[view\]'") as caught:
                arm.view()
            assert caught.value.module == module and caught.value.extra == "view"


def test_bad_input_is_refused(tmp_path: Path) -> None:
    arm = ad.models.load("two_link_planar")
    with pytest.raises(ModelError, match="overlay 'mass'"):
        view.Viewer(arm, overlays=("mass",))
    with arm.view() as viewer:
        with pytest.raises(ModelError, match="q must be finite"):
            viewer.set_configuration([0.0, np.nan])
        with pytest.raises(ModelError, match=r"q must have shape \(2,\)"):
            viewer.set_configuration([0.0, 1.0, 2.0])
        with pytest.raises(ModelError, match="one state of 2 values"):
            viewer.set_configuration([[0.0, 1.0]])
        with pytest.raises(ModelError, match="q must be real"):
            viewer.set_configuration([0.0, 1j])
        with pytest.raises(ModelError, match="does not exist"):
            viewer.save_html(tmp_path / "nowhere" / "page.html")
        with pytest.raises(ModelError, match="needs a run"):
            viewer.show_time(0.5)
    with pytest.raises(ModelError, match="positive mass"):
        view.equivalent_ellipsoid(0.0, np.eye(3))


def test_the_command_line_writes_pages_and_exits(tmp_path: Path) -> None:
    page = tmp_path / "arm.html"
    result = invoke("view", "puma560", "--html", str(page), "--overlays", "com,lambda")
    assert result.exit_code == 0, result.output
    assert page.is_file() and _messages(page.read_text(encoding="utf-8"))["messages"]
    run = tmp_path / "run.html"
    result = invoke("simulate", "two_link_planar", "--t-final", "0.5", "--html", str(run))
    assert result.exit_code == 0, result.output
    recording = _messages(run.read_text(encoding="utf-8"))
    assert recording["durationSeconds"] == pytest.approx(0.5, abs=2 / view.FRAME_RATE)
    result = invoke("view", "puma560", "--html", str(tmp_path / "arm.txt"))
    assert result.exit_code != 0 and ".html" in result.output
