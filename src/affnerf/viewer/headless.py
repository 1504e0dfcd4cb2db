"""Screenshots of a local web page (the viewer) in headless Chromium, driven over the DevTools protocol.

``chromium --screenshot --virtual-time-budget=...`` hangs now and then on viser's page (its WebGL canvas redraws
without end), so Chromium is started with a DevTools port instead and asked for screenshots until one shows what
the caller waits for. Chromium renders WebGL with SwiftShader (on the CPU) here; no GPU is needed. Only pages on
this machine are loaded: every other host name fails to resolve and no proxy is used.
"""

from __future__ import annotations

import base64
import io
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.parse
import urllib.request
from collections.abc import Callable
from pathlib import Path

import numpy as np

#: Names the browser goes by, tried in this order.
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: Flags for a quiet, local-only headless browser with software WebGL.
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",  # CI runs as root
    "--disable-gpu",
    "--enable-unsafe-swiftshader",  # software WebGL (the silent fallback to it is deprecated)
    "--use-angle=swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--no-proxy-server",
    "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1, EXCLUDE localhost",
    "--remote-debugging-port=0",
)
LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")


def find_chromium() -> str | None:
    """The path of a Chromium (or Chrome) executable on PATH, or None."""
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return found
    return None


class DevTools:
    """A minimal DevTools-protocol client for one page: send a command, wait for its answer."""

    def __init__(self, ws_url: str, timeout: float) -> None:
        from websockets.sync.client import connect

        self._ws = connect(ws_url, max_size=None, open_timeout=timeout, proxy=None, compression=None)
        self._timeout = timeout
        self._next_id = 0

    def call(self, method: str, **params: object) -> dict:
        """Run ``method`` and return its result (events that arrive meanwhile are dropped)."""
        self._next_id += 1
        self._ws.send(json.dumps({"id": self._next_id, "method": method, "params": params}))
        while True:
            message = json.loads(self._ws.recv(timeout=self._timeout))
            if message.get("id") == self._next_id:
                if "error" in message:
                    raise RuntimeError(f"DevTools {method}: {message['error']}")
                return message.get("result", {})

    def close(self) -> None:
        self._ws.close()


def _devtools_port(user_data_dir: Path, proc: subprocess.Popen, deadline: float) -> int:
    """The DevTools port Chromium chose (it writes it to ``DevToolsActivePort`` in its profile folder)."""
    marker = user_data_dir / "DevToolsActivePort"
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"chromium exited with code {proc.returncode} before opening its DevTools port")
        lines = marker.read_text().splitlines() if marker.is_file() else []
        if len(lines) >= 2 and lines[0].strip().isdigit():
            return int(lines[0])
        time.sleep(0.1)
    raise TimeoutError("chromium did not open its DevTools port in time")


def _page_ws_url(port: int, timeout: float) -> str:
    """The DevTools websocket address of Chromium's first page."""
    opener = urllib.request.build_opener(urllib.request.ProxyHandler({}))
    with opener.open(f"http://127.0.0.1:{port}/json/list", timeout=timeout) as response:
        targets = json.load(response)
    return next(t["webSocketDebuggerUrl"] for t in targets if t.get("type") == "page")


def _decode_png(data: str) -> np.ndarray:
    from PIL import Image

    with Image.open(io.BytesIO(base64.b64decode(data))) as im:
        return np.asarray(im.convert("RGB"))


def _stop(proc: subprocess.Popen) -> None:
    """End Chromium and the helper processes it started (its own process group)."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
    try:
        os.killpg(proc.pid, signal.SIGKILL)  # leftovers of our own group only
    except (ProcessLookupError, PermissionError):
        pass
    proc.wait(timeout=10)


def screenshot(
    url: str,
    *,
    until: Callable[[np.ndarray], bool] | None = None,
    width: int = 1024,
    height: int = 768,
    timeout: float = 120.0,
    settle: float = 2.0,
    chromium: str | None = None,
) -> np.ndarray:
    """Load a local ``url`` in headless Chromium and screenshot it.

    Screenshots are taken every ``settle`` seconds after the page loads, until ``until(image)`` holds (without
    ``until``: the first one after ``settle`` seconds) or ``timeout`` passes; the last one is returned.

    Args:
        url: a page on this machine (127.0.0.1 or localhost).
        until: predicate on a (height, width, 3) uint8 screenshot.
        width: viewport width, pixels.
        height: viewport height, pixels.
        timeout: seconds for the whole run, Chromium's start included.
        settle: seconds between screenshots.
        chromium: the browser executable (default: :func:`find_chromium`).

    Returns:
        (height, width, 3) uint8 RGB.

    Raises:
        ValueError: for a URL on another machine.
        FileNotFoundError: when no Chromium is installed.
        TimeoutError, RuntimeError: when Chromium does not start or answer in time.
    """
    if urllib.parse.urlsplit(url).hostname not in LOCAL_HOSTS:
        raise ValueError(f"only local pages are loaded, not {url}")
    chromium = chromium or find_chromium()
    if chromium is None:
        raise FileNotFoundError(f"no Chromium found (looked for {', '.join(CHROMIUM_NAMES)})")
    deadline = time.monotonic() + timeout
    with tempfile.TemporaryDirectory(prefix="affnerf-chromium-") as profile:
        size = f"--window-size={width},{height}"
        args = [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", size, "about:blank"]
        proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            port = _devtools_port(Path(profile), proc, deadline)
            page = DevTools(_page_ws_url(port, 10.0), timeout=max(10.0, deadline - time.monotonic()))
            try:
                metrics = {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}
                page.call("Emulation.setDeviceMetricsOverride", **metrics)
                page.call("Page.navigate", url=url)
                while True:
                    time.sleep(settle)
                    image = _decode_png(page.call("Page.captureScreenshot", format="png")["data"])
                    if until is None or until(image) or time.monotonic() > deadline:
                        return image
            finally:
                page.close()
        finally:
            _stop(proc)
