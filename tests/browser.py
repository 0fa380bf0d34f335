"""Headless Chromium for the viewer's tests: find the browser, take a screenshot of a page, read its pixels.

WebGL has to work without a GPU: Chromium renders it in software through SwiftShader behind ANGLE
(``--use-angle=swiftshader --enable-unsafe-swiftshader``; with ``--disable-gpu`` alone the page's WebGL
context is never made and Chromium can wait for ever, hence the hard timeout of :func:`screenshot`).

With ``offline=True`` every http(s) and WebSocket request goes to a proxy on 127.0.0.1:9 (the discard port,
where nothing listens) and ``<-loopback>`` takes away the implicit bypass of localhost, so no request of the
page reaches any server, not even one on this machine; ``file://`` pages still load.

When no Chromium is installed, :func:`require_chromium` skips the test with the reason.
"""

from __future__ import annotations

import base64
import contextlib
import json
import os
import select
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
"""The executables looked for on PATH, in order (``ARMDYN_CHROMIUM`` names another)."""

FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--hide-scrollbars",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-extensions",
    "--disable-dev-shm-usage",
)
"""Chromium's flags for software WebGL in a headless browser (checked with Chromium 156 on Debian 12)."""

OFFLINE_FLAGS = ("--proxy-server=127.0.0.1:9", "--proxy-bypass-list=<-loopback>")
"""Flags that cut the network: every request goes to a proxy that does not exist, localhost included."""


def find_chromium() -> str | None:
    """The path of a Chromium-like browser: ``$ARMDYN_CHROMIUM`` if set, else the first of `CANDIDATES` on
    PATH; None when there is none."""
    named = os.environ.get("ARMDYN_CHROMIUM")
    if named:
        return shutil.which(named)
    for name in CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    return None


def _binary(path: str) -> str:
    """The browser itself behind a launcher script: Debian's /usr/bin/chromium is a shell script that execs
    /usr/lib/chromium/chromium and does not pass on the file descriptors 3 and 4 of ``--remote-debugging-pipe``."""
    with open(path, "rb") as file:
        script = file.read(2) == b"#!"
    if script:
        for candidate in ("/usr/lib/chromium/chromium", "/usr/lib/chromium-browser/chromium-browser"):
            if os.access(candidate, os.X_OK):
                return candidate
    return path


def require_chromium() -> str:
    """The browser's path, or skip the calling test naming what is missing and how to install it."""
    path = find_chromium()
    if path is None:
        pytest.skip(
            "no headless Chromium found (looked for " + ", ".join(CANDIDATES) + " on PATH and $ARMDYN_CHROMIUM); "
            "install Debian's package: apt-get install chromium"
        )
    return path


def screenshot(
    url: str,
    path: str | Path,
    size: tuple[int, int] = (800, 600),
    wait_ms: int = 5000,
    *,
    offline: bool = False,
    timeout: float = 60.0,
    ready: Callable[[np.ndarray], bool] | None = None,
) -> np.ndarray:
    """Open ``url`` in headless Chromium, wait ``wait_ms``, save a PNG screenshot at ``path`` and return its pixels.

    Parameters
    ----------
    url : str
        The page (``http://127.0.0.1:PORT/...`` or ``file:///...``).
    path : str or Path
        Where the PNG goes (kept for a human to look at).
    size : tuple of int
        The window's (width, height) in pixels.
    wait_ms : int
        Real time from the start of the page's navigation (or from ``ready``) to the shot, ms.
    offline : bool
        Cut the network (`OFFLINE_FLAGS`): every http(s)/WebSocket request of the page fails.
    timeout : float
        Seconds of real time for the whole run before the browser is killed.
    ready : callable, optional
        A test of a screenshot (pixels in, bool out): the page is shot every half second until it passes, and
        ``wait_ms`` counts from then (a page that loads slowly on a busy machine is waited for).

    Returns
    -------
    numpy.ndarray
        The image, (height, width, 3) uint8 RGB.

    Raises
    ------
    RuntimeError
        When the browser fails, says the page could not be loaded, or overruns ``timeout``.
    """
    return screenshots(url, [(wait_ms, path)], size, offline=offline, timeout=timeout, ready=ready)[0]


def screenshots(
    url: str,
    shots: list[tuple[int, str | Path]],
    size: tuple[int, int] = (800, 600),
    *,
    offline: bool = False,
    timeout: float = 60.0,
    ready: Callable[[np.ndarray], bool] | None = None,
) -> list[np.ndarray]:
    """Screenshots of one page at several times after its navigation, in one browser.

    Chromium is driven through the DevTools protocol on a pipe (``--remote-debugging-pipe``): navigate, sleep,
    ``Page.captureScreenshot``. Real time, not Chromium's virtual time: ``--virtual-time-budget`` waits for
    the network to fall idle, which a page holding a WebSocket open never does, and then hangs.

    Parameters
    ----------
    url : str
        The page.
    shots : list of (int, str or Path)
        (time after the navigation began, or after ``ready``, in ms; where the PNG goes), in increasing time.
    size : tuple of int
        The window's (width, height) in pixels.
    offline : bool
        Cut the network (`OFFLINE_FLAGS`).
    timeout : float
        Seconds of real time for the whole run before the browser is killed.
    ready : callable, optional
        A test of a screenshot: the page is shot every half second until it passes; the times count from then.

    Returns
    -------
    list of numpy.ndarray
        The images, each (height, width, 3) uint8 RGB.

    Raises
    ------
    RuntimeError
        When the browser fails, says the page could not be loaded, or overruns ``timeout`` (or ``ready`` never
        passes within it).
    """
    from PIL import Image

    def shoot(path: str | Path) -> np.ndarray:
        data = tools.call("Page.captureScreenshot", {"format": "png"}, session)["data"]
        Path(path).write_bytes(base64.b64decode(data))
        with Image.open(path) as image:
            return np.asarray(image.convert("RGB"))

    browser = _binary(require_chromium())
    deadline = time.monotonic() + timeout
    images = []
    with (
        tempfile.TemporaryDirectory(prefix="armdyn-chromium-") as profile,
        _DevTools(
            [
                browser,
                *FLAGS,
                *(OFFLINE_FLAGS if offline else ()),
                f"--user-data-dir={profile}",
                f"--window-size={size[0]},{size[1]}",
                "about:blank",
            ],
            deadline,
        ) as tools,
    ):
        target = tools.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = tools.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        tools.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": size[0], "height": size[1], "deviceScaleFactor": 1, "mobile": False},
            session,
        )
        start = time.monotonic()
        answer = tools.call("Page.navigate", {"url": url}, session)
        if answer.get("errorText"):
            raise RuntimeError(f"{browser} could not load {url}: {answer['errorText']}")
        if ready is not None:
            while True:
                time.sleep(0.5)
                try:
                    if ready(shoot(shots[0][1])):
                        break
                except RuntimeError as error:  # the page is not yet there to be shot
                    if "Not attached" not in str(error):
                        raise
                if time.monotonic() > deadline - 1.0:
                    raise RuntimeError(f"{url} was never ready within {timeout} s (last shot: {shots[0][1]})")
            start = time.monotonic()
        for wait_ms, path in shots:
            time.sleep(max(0.0, start + wait_ms / 1000.0 - time.monotonic()))
            images.append(shoot(path))
    return images


class _DevTools:
    """Chromium with the DevTools protocol on a pipe: JSON messages ending in NUL, commands in on the
    child's fd 3, answers and events out on its fd 4."""

    def __init__(self, command: list[str], deadline: float) -> None:
        self.deadline = deadline
        to_child, self._write = os.pipe()
        self._read, from_child = os.pipe()

        def wire() -> None:  # in the child: the pipes' ends on fds 3 and 4, open across exec
            ends = os.dup(to_child), os.dup(from_child)
            os.dup2(ends[0], 3)
            os.dup2(ends[1], 4)

        self.process = subprocess.Popen(
            [*command[:1], "--remote-debugging-pipe", *command[1:]],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=wire,
            close_fds=False,
            start_new_session=True,
        )
        os.close(to_child)
        os.close(from_child)
        self._buffer = b""
        self._id = 0

    def call(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        """Send one command and return its result (events in between are dropped)."""
        self._id += 1
        message: dict = {"id": self._id, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        os.write(self._write, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self._buffer:
                left = self.deadline - time.monotonic()
                ready, _, _ = select.select([self._read], [], [], max(left, 0.0))
                if not ready:
                    raise RuntimeError(f"Chromium did not answer {method} in time")
                chunk = os.read(self._read, 1 << 20)
                if not chunk:
                    raise RuntimeError(f"Chromium ended before answering {method} (exit {self.process.poll()})")
                self._buffer += chunk
            raw, self._buffer = self._buffer.split(b"\0", 1)
            answer = json.loads(raw)
            if answer.get("id") == self._id:
                if "error" in answer:
                    raise RuntimeError(f"Chromium refused {method}: {answer['error']}")
                return answer.get("result", {})

    def __enter__(self) -> _DevTools:
        return self

    def __exit__(self, *exc: object) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.process.pid, signal.SIGKILL)
        self.process.wait()
        os.close(self._write)
        os.close(self._read)


def colour_mask(image: np.ndarray, rgb: tuple[int, int, int], tolerance: int = 40) -> np.ndarray:
    """Pixels within ``tolerance`` (per channel) of the colour ``rgb``: a (height, width) boolean mask."""
    difference = np.abs(image.astype(np.int16) - np.asarray(rgb, dtype=np.int16))
    return np.asarray(difference.max(axis=-1) <= tolerance)


def hue_mask(image: np.ndarray, rgb: tuple[int, int, int], tolerance: float = 0.06, min_saturation: float = 0.25):
    """Pixels of the same hue as ``rgb`` (within ``tolerance`` of a turn) and saturated: a boolean mask.

    Lit and shaded faces of one material keep their hue while their brightness changes, so this finds a
    coloured object's pixels where `colour_mask` finds only its faces lit like the reference colour.
    """
    hue, saturation = _hue_saturation(image.astype(np.float64) / 255.0)
    ref_hue, _ = _hue_saturation(np.asarray(rgb, dtype=np.float64)[None, None, :] / 255.0)
    distance = np.abs(hue - ref_hue[0, 0])
    distance = np.minimum(distance, 1.0 - distance)
    return np.asarray((distance <= tolerance) & (saturation >= min_saturation))


def _hue_saturation(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """HSV hue (turns, in [0, 1)) and saturation of an (..., 3) RGB array in [0, 1]."""
    high = rgb.max(axis=-1)
    low = rgb.min(axis=-1)
    chroma = high - low
    safe = np.where(chroma > 0, chroma, 1.0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    hue = np.where(high == r, ((g - b) / safe) % 6.0, np.where(high == g, (b - r) / safe + 2.0, (r - g) / safe + 4.0))
    hue = np.where(chroma > 0, hue / 6.0, 0.0)
    saturation = np.where(high > 0, chroma / np.where(high > 0, high, 1.0), 0.0)
    return hue, saturation


def project(points: np.ndarray, eye, target, size: tuple[int, int], fov_deg: float = 75.0, up=(0.0, 0.0, 1.0)):
    """Pixel coordinates (u right, v down) of world points seen by a pinhole camera at ``eye`` looking at
    ``target`` with vertical field of view ``fov_deg`` (viser's client: 75 degrees, z up).

    Parameters
    ----------
    points : numpy.ndarray
        (..., 3) world points.
    eye, target, up : array_like
        The camera's position, the point it looks at and the world's up direction.
    size : tuple of int
        The image's (width, height).
    fov_deg : float
        Vertical field of view in degrees.

    Returns
    -------
    numpy.ndarray
        (..., 2) pixel coordinates (u, v); v grows downwards as in an image array's row index.
    """
    eye = np.asarray(eye, dtype=float)
    forward = np.asarray(target, dtype=float) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(up, dtype=float))
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    relative = np.asarray(points, dtype=float) - eye
    depth = relative @ forward
    focal = 0.5 * size[1] / np.tan(np.radians(fov_deg) / 2.0)
    u = 0.5 * size[0] + focal * (relative @ right) / depth
    v = 0.5 * size[1] - focal * (relative @ true_up) / depth
    return np.stack([u, v], axis=-1)


def camera_query(eye, target, up=(0.0, 0.0, 1.0)) -> str:
    """The URL query that opens viser's client with the camera at ``eye`` looking at ``target``."""

    def fmt(vector) -> str:
        return ",".join(f"{float(x):.6g}" for x in vector)

    return f"initialCameraPosition={fmt(eye)}&initialCameraLookAt={fmt(target)}&initialCameraUp={fmt(up)}"
