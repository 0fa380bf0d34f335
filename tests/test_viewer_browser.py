"""armdyn.viewer in a real browser (headless Chromium, software WebGL): the live viewer on 127.0.0.1 and the
saved page opened from disk with the network cut both draw the arm where its links project, and a saved Panda
run replays (the arm moves between two screenshots). Skipped, with the reason, without Chromium or viser.

The screenshots are kept in pytest's temporary folder (``--basetemp`` to choose it) for a human to look at."""

from __future__ import annotations

import http.server
import itertools
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn.control import ComputedTorque
from armdyn.trajectories import Sinusoid
from tests.browser import camera_query, hue_mask, project, require_chromium, screenshot, screenshots
from tests.helpers import URDFS

pytest.importorskip("viser", reason="the viewer's extra is not installed: pip install 'armdyn[view]'")
from armdyn import viewer as view

pytestmark = pytest.mark.slow

SIZE = (800, 600)
PANEL = 350
"""Width of viser's control panel at the right of the live page (px): the arm is looked for left of it."""
BAR = 40
"""Height of the saved page's playback bar at the bottom (px): its canvas is the window less the bar."""


@pytest.fixture(scope="module", autouse=True)
def chromium() -> str:
    return require_chromium()


def _link_points(arm: ad.Robot, q: np.ndarray) -> np.ndarray:
    """The base and every link frame's origin, (n + 1, 3): the capsules run between consecutive ones."""
    T = arm.link_transforms(q)
    return np.vstack([np.asarray(arm.base, dtype=float)[:3, 3], T[:, :3, 3]])


def _camera(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A camera that sees the whole arm: (eye, target)."""
    target = 0.5 * (points.min(axis=0) + points.max(axis=0))
    reach = max(float(np.ptp(points, axis=0).max()), 0.5)
    direction = np.array([1.0, -1.0, 0.6]) / np.linalg.norm([1.0, -1.0, 0.6])
    return target + 2.2 * reach * direction, target


def _drawn(image: np.ndarray) -> bool:
    """Whether the page has drawn an arm: a few thousand pixels of LINK_COLOR's hue."""
    return bool(hue_mask(image[: SIZE[1] - BAR, : SIZE[0] - PANEL], view.LINK_COLOR).sum() > 1000)


def _assert_arm_drawn(
    image: np.ndarray, points: np.ndarray, eye: np.ndarray, target: np.ndarray, canvas: tuple[int, int] = SIZE
) -> None:
    """The canvas (``canvas`` pixels at the image's top left) is not blank, and pixels of LINK_COLOR's hue lie
    on every link's projection and (nearly) nowhere else in the part of the image left of the live page's
    panel and above the saved page's playback bar."""
    assert image.std() > 10, "the screenshot is blank"
    mask = hue_mask(image, view.LINK_COLOR)
    mask[:, SIZE[0] - PANEL :] = False
    mask[SIZE[1] - BAR :, :] = False
    uv = project(points, eye, target, canvas)
    for k in range(len(points) - 1):
        if np.linalg.norm(points[k + 1] - points[k]) < 0.05:
            continue  # coincident frames (a spherical wrist): no capsule of their own
        u, v = np.round(0.5 * (uv[k] + uv[k + 1])).astype(int)
        window = mask[v - 6 : v + 7, u - 6 : u + 7]
        assert window.sum() >= 40, f"no link pixels around the projection of link {k + 1}'s capsule at ({u}, {v})"
    low, high = uv.min(axis=0) - 30, uv.max(axis=0) + 30
    rows, cols = np.nonzero(mask)
    inside = (cols >= low[0]) & (cols <= high[0]) & (rows >= low[1]) & (rows <= high[1])
    assert mask.sum() > 500
    assert inside.mean() > 0.95, f"{(~inside).sum()} link-coloured pixels away from the arm's projection"


@pytest.fixture(scope="module")
def puma(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[view.Viewer, np.ndarray, Path]]:
    arm = ad.models.load("puma560")
    folder = tmp_path_factory.mktemp("browser")
    with view.Viewer(arm) as viewer:
        yield viewer, _link_points(arm, viewer.q), folder


def test_the_live_viewer_draws_the_arm_where_it_projects(puma: tuple[view.Viewer, np.ndarray, Path]) -> None:
    viewer, points, folder = puma
    eye, target = _camera(points)
    url = f"{viewer.url}/?{camera_query(eye, target)}"
    image = screenshot(url, folder / "puma_live.png", SIZE, 1000, ready=_drawn)  # 1 s more: viser fades new shapes in
    _assert_arm_drawn(image, points, eye, target)


def test_the_saved_page_draws_the_arm_offline(puma: tuple[view.Viewer, np.ndarray, Path]) -> None:
    viewer, points, folder = puma
    page = viewer.save_html(folder / "puma.html")
    eye, target = _camera(points)
    url = f"{page.as_uri()}?{camera_query(eye, target)}"
    image = screenshot(url, folder / "puma_file.png", SIZE, 1000, offline=True, ready=_drawn)
    _assert_arm_drawn(image, points, eye, target, (SIZE[0], SIZE[1] - BAR))


class _Pixel(http.server.BaseHTTPRequestHandler):
    """Serves a 1x1 PNG at every path and counts the requests."""

    requests = 0
    PNG = bytes.fromhex(
        "89504e470d0a1a0a0000000d4948445200000001000000010802000000907753de0000000c4944415408d763f8cfc0000003"
        "010100c9fe92ef0000000049454e44ae426082"
    )

    def do_GET(self) -> None:
        type(self).requests += 1
        self.send_response(200)
        self.send_header("Content-Type", "image/png")
        self.send_header("Content-Length", str(len(self.PNG)))
        self.end_headers()
        self.wfile.write(self.PNG)

    def log_message(self, *args: object) -> None:
        pass


def test_the_cut_network_stops_a_file_page_loading_from_http(tmp_path: Path) -> None:
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Pixel)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        page = tmp_path / "fetch.html"
        page.write_text(
            "<html><body style='margin:0;height:100vh;background:#888'>"
            f"<img src='http://127.0.0.1:{server.server_port}/pixel.png' "
            "onload=\"document.body.style.background='#f00'\" onerror=\"document.body.style.background='#0f0'\">"
            "</body></html>"
        )
        online = screenshot(page.as_uri(), tmp_path / "online.png", (200, 150), 800)
        assert _Pixel.requests == 1
        np.testing.assert_array_equal(online[100, 100], [255, 0, 0])  # the image loaded
        offline = screenshot(page.as_uri(), tmp_path / "offline.png", (200, 150), 800, offline=True)
        assert _Pixel.requests == 1, "the page reached the server with the network cut"
        np.testing.assert_array_equal(offline[100, 100], [0, 255, 0])  # the image failed
        with pytest.raises(RuntimeError, match="ERR_PROXY_CONNECTION_FAILED"):  # and so does an http page
            screenshot(f"http://127.0.0.1:{server.server_port}/", tmp_path / "http.png", (200, 150), 100, offline=True)
        assert _Pixel.requests == 1
    finally:
        server.shutdown()
        server.server_close()


def test_a_saved_two_second_panda_run_replays_offline(tmp_path: Path) -> None:
    with pytest.warns(UserWarning, match="mimic"):
        panda = ad.load_urdf(URDFS["panda"])
    q0 = np.array([0.1, -0.5, 0.2, -2.0, 0.1, 1.6, 0.8, 0.02, 0.02])
    amplitude = np.r_[np.full(7, 0.4), 0.0, 0.0]
    run = ad.simulate(panda, ComputedTorque(100, 20), Sinusoid(amplitude, 0.5, offset=q0), t_final=2.0, q0=q0)
    with run.view() as viewer:
        page = viewer.save_html(tmp_path / "panda.html")
    assert page.stat().st_size <= 5_000_000
    # the page plays the run from its start once loaded (in a loop): shots 0.6 s apart show several times of it
    times = (0, 600, 1200, 1800)
    shots = [(t, tmp_path / f"panda_{t}.png") for t in times]
    images = screenshots(page.as_uri(), shots, SIZE, offline=True, ready=_drawn)
    for image in images:
        assert hue_mask(image[: SIZE[1] - BAR], view.LINK_COLOR).sum() > 2000, "the Panda is not drawn"
    moved = []
    for first, second in itertools.pairwise(images):
        differ = np.abs(first.astype(np.int16) - second).max(axis=-1) > 30
        differ[SIZE[1] - BAR :] = False  # the playback bar's time and progress
        coloured = hue_mask(first, view.LINK_COLOR, 0.5) | hue_mask(second, view.LINK_COLOR, 0.5)
        moved.append((int(differ.sum()), float(coloured[differ].mean()) if differ.any() else 0.0))
    # the arm moved between some two shots, and what changed is the arm (coloured), not the grid or the page
    assert max(count for count, _ in moved) > 2000, moved
    assert all(share > 0.8 for count, share in moved if count > 2000), moved
