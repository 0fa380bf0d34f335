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

import os
import shutil
import signal
import subprocess
import tempfile
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
    wait_ms: int = 4000,
    *,
    offline: bool = False,
    timeout: float = 60.0,
) -> np.ndarray:
    """Open ``url`` in headless Chromium, wait, save a PNG screenshot at ``path`` and return its pixels.

    Parameters
    ----------
    url : str
        The page (``http://127.0.0.1:PORT/...`` or ``file:///...``).
    path : str or Path
        Where the PNG goes (kept for a human to look at).
    size : tuple of int
        The window's (width, height) in pixels.
    wait_ms : int
        Chromium's virtual-time budget: how long the page runs (timers, animation frames) before the shot.
    offline : bool
        Cut the network (`OFFLINE_FLAGS`): every http(s)/WebSocket request of the page fails.
    timeout : float
        Seconds of real time before the browser is killed.

    Returns
    -------
    numpy.ndarray
        The image, (height, width, 3) uint8 RGB.

    Raises
    ------
    RuntimeError
        When the browser ends without writing the screenshot or overruns ``timeout``.
    """
    from PIL import Image

    browser = require_chromium()
    path = Path(path)
    path.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="armdyn-chromium-") as profile:
        command = [
            browser,
            *FLAGS,
            *(OFFLINE_FLAGS if offline else ()),
            f"--user-data-dir={profile}",
            f"--window-size={size[0]},{size[1]}",
            f"--virtual-time-budget={int(wait_ms)}",
            f"--screenshot={path}",
            url,
        ]
        process = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True
        )
        try:
            log, _ = process.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
            raise RuntimeError(f"{browser} did not finish {url} within {timeout} s") from None
    if not path.is_file():
        tail = "\n".join(line for line in log.splitlines() if "GL Driver" not in line)[-2000:]
        raise RuntimeError(f"{browser} wrote no screenshot of {url} (exit {process.returncode}):\n{tail}")
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


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
