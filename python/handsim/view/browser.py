"""Headless Chromium driven over the DevTools protocol: opens the viewer's page, waits, takes screenshots and
evaluates JavaScript. What the browser test, the frame-rate bench and ``--screenshot`` use; it needs only the
Debian ``chromium`` package and ``websockets`` (a viser dependency), no browser download.

WebGL in a headless browser without a GPU runs on SwiftShader (Chromium's CPU renderer): ``--use-angle=
swiftshader`` with ``--enable-unsafe-swiftshader`` (newer Chromium refuses it for WebGL otherwise). Every wait is
bounded; nothing leaves the loopback interface.
"""
from __future__ import annotations

import base64
import io
import itertools
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from typing import Optional

import numpy as np

CANDIDATES = ("chromium", "chromium-browser", "chromium-headless-shell", "google-chrome")


def find_chromium() -> Optional[str]:
    """The Chromium binary: $HANDSIM_CHROMIUM, else the first of CANDIDATES on PATH (None: none)."""
    exe = os.environ.get("HANDSIM_CHROMIUM")
    if exe:
        return exe if shutil.which(exe) else None
    for name in CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    return None


class BrowserError(RuntimeError):
    pass


class Browser:
    """One headless Chromium with one page of `width` x `height` CSS pixels. Use as a context manager."""

    def __init__(self, width: int = 1280, height: int = 800, timeout: float = 30.0, executable: str = None):
        from websockets.sync.client import connect

        exe = executable or find_chromium()
        if exe is None:
            raise BrowserError("no Chromium found (apt install chromium, or set HANDSIM_CHROMIUM)")
        self.width, self.height, self.timeout = int(width), int(height), float(timeout)
        self._dir = tempfile.mkdtemp(prefix="handsim-chromium-")
        self._log = open(os.path.join(self._dir, "chromium.log"), "wb")
        args = [exe, "--headless=new", f"--user-data-dir={self._dir}/profile", "--remote-debugging-port=0",
                "--remote-debugging-address=127.0.0.1", "--no-first-run", "--no-default-browser-check",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                "--disable-dev-shm-usage", "--disable-background-networking", "--disable-extensions",
                "--disable-sync", "--hide-scrollbars", "--mute-audio", "--disable-background-timer-throttling",
                "--disable-renderer-backgrounding", "--disable-backgrounding-occluded-windows",
                f"--window-size={self.width},{self.height}", "about:blank"]
        if hasattr(os, "geteuid") and os.geteuid() == 0:
            args.insert(1, "--no-sandbox")  # Chromium refuses to run its sandbox as root (CI runs as root)
        self._proc = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self._ids = itertools.count(1)
        self._ws = None
        try:
            port = self._devtools_port()
            page = self._page_socket(port)
            self._ws = connect(page, max_size=None, open_timeout=self.timeout, close_timeout=2)
            self.call("Page.enable")
            self.call("Runtime.enable")
            self.call("Emulation.setDeviceMetricsOverride",
                      {"width": self.width, "height": self.height, "deviceScaleFactor": 1, "mobile": False})
        except BaseException:
            self.close()
            raise

    def _devtools_port(self) -> int:
        path = os.path.join(self._dir, "profile", "DevToolsActivePort")
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                raise BrowserError(f"chromium exited with {self._proc.returncode}: {self.log()[-2000:]}")
            try:
                with open(path) as f:
                    first = f.readline().strip()
                if first:
                    return int(first)
            except (OSError, ValueError):
                pass
            time.sleep(0.05)
        raise BrowserError(f"chromium did not open its DevTools port within {self.timeout:.0f} s")

    def _page_socket(self, port: int) -> str:
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as r:
                    targets = json.load(r)
                pages = [t for t in targets if t.get("type") == "page" and t.get("webSocketDebuggerUrl")]
                if pages:
                    return pages[0]["webSocketDebuggerUrl"]
            except OSError:
                pass
            time.sleep(0.1)
        raise BrowserError("chromium has no page to drive")

    def log(self) -> str:
        try:
            with open(os.path.join(self._dir, "chromium.log"), "rb") as f:
                return f.read().decode("utf-8", "replace")
        except OSError:
            return ""

    def call(self, method: str, params: dict = None, timeout: float = None) -> dict:
        """One DevTools command; its result (events in between are dropped)."""
        if self._ws is None:
            raise BrowserError("browser is closed")
        ident = next(self._ids)
        self._ws.send(json.dumps({"id": ident, "method": method, "params": params or {}}))
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise BrowserError(f"{method}: no answer within {self.timeout:.0f} s")
            try:
                msg = json.loads(self._ws.recv(timeout=left))
            except TimeoutError:
                continue
            if msg.get("id") == ident:
                if "error" in msg:
                    raise BrowserError(f"{method}: {msg['error']}")
                return msg.get("result", {})

    def goto(self, url: str):
        self.call("Page.navigate", {"url": url})

    def evaluate(self, expression: str, timeout: float = None):
        r = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True, "awaitPromise": True},
                      timeout)
        if "exceptionDetails" in r:
            raise BrowserError(f"evaluate: {r['exceptionDetails'].get('text')}: {expression[:80]}")
        return r.get("result", {}).get("value")

    def wait_for(self, expression: str, timeout: float = None) -> bool:
        """Polls a JavaScript expression until it is truthy (False when `timeout` runs out)."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while time.monotonic() < deadline:
            try:
                if self.evaluate(expression, timeout=max(1.0, deadline - time.monotonic())):
                    return True
            except BrowserError:
                pass
            time.sleep(0.1)
        return False

    def screenshot(self) -> np.ndarray:
        """(H, W, 3) uint8 of the page as drawn now."""
        from PIL import Image
        data = self.call("Page.captureScreenshot", {"format": "png"})["data"]
        return np.asarray(Image.open(io.BytesIO(base64.b64decode(data))).convert("RGB"))

    def close(self):
        if self._ws is not None:
            try:
                self._ws.close()
            except Exception:
                pass
            self._ws = None
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait(5)
        self._log.close()
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
