"""Screenshots of a live meshcat page in headless Chromium, through the DevTools protocol.

``chromium --screenshot`` shoots at the page's load event, before the live
page's WebSocket has delivered the scene (and ``--virtual-time-budget`` never
ends while the socket is open). Here Chromium runs with a DevTools port; the
page is opened, the scene is awaited (its mesh count stops changing) and
``Page.captureScreenshot`` takes pictures until two in a row are the same (on
a busy machine the meshes are drawn some time after they arrive). Only tornado (meshcat's own
dependency) is needed.
"""

from __future__ import annotations

import asyncio
import base64
import io
import json
import re
import subprocess
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np

MESHES = "(() => { let n = 0; viewer.scene.traverse(o => { if (o.isMesh) n++; }); return n; })()"


def _devtools_port(proc: subprocess.Popen, timeout: float) -> int:
    deadline, text = time.monotonic() + timeout, ""
    while time.monotonic() < deadline:
        line = proc.stderr.readline().decode("utf-8", "replace")
        text += line
        found = re.search(r"DevTools listening on ws://[^:]+:(\d+)/", line)
        if found:
            return int(found.group(1))
        if not line and proc.poll() is not None:
            break
    raise AssertionError(f"Chromium did not open its DevTools port: {text[-2000:]}")


class _Session:
    def __init__(self, socket) -> None:
        self.socket, self.next_id = socket, 0

    async def call(self, method: str, **params):
        self.next_id += 1
        await self.socket.write_message(json.dumps({"id": self.next_id, "method": method,
                                                    "params": params}))
        while True:
            reply = json.loads(await self.socket.read_message())
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise AssertionError(f"{method}: {reply['error']}")
                return reply["result"]


async def _shoot(port: int, url: str, size: tuple[int, int], settle: float,
                 timeout: float) -> bytes:
    from tornado.websocket import websocket_connect

    with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as reply:
        pages = [t for t in json.load(reply) if t["type"] == "page"]
    socket = await websocket_connect(pages[0]["webSocketDebuggerUrl"], max_message_size=1 << 28)
    session = _Session(socket)
    await session.call("Emulation.setDeviceMetricsOverride", width=size[0], height=size[1],
                       deviceScaleFactor=1, mobile=False)
    await session.call("Page.navigate", url=url)
    deadline, last, stable_since = time.monotonic() + timeout, None, time.monotonic()
    while time.monotonic() < deadline:  # wait until the scene has come and stopped growing
        await asyncio.sleep(0.25)
        result = await session.call("Runtime.evaluate", expression=MESHES, returnByValue=True)
        count = result["result"].get("value")
        if count != last:
            last, stable_since = count, time.monotonic()
        elif count and time.monotonic() - stable_since >= settle:
            break
    shot = None
    while time.monotonic() < deadline:  # then until two shots agree (meshes drawn, not queued)
        again = (await session.call("Page.captureScreenshot", format="png"))["data"]
        if again == shot:
            break
        shot = again
        await asyncio.sleep(0.5)
    socket.close()
    return base64.b64decode(shot)


async def _probe(port: int, url: str, hook: str, expression: str, settle: float,
                 timeout: float, reloads: int):
    """Open ``url`` (then reload it ``reloads`` times) with ``hook`` run before the page's
    own scripts; each time the scene has come and stopped growing, the value of
    ``expression``."""
    from tornado.websocket import websocket_connect

    with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as reply:
        pages = [t for t in json.load(reply) if t["type"] == "page"]
    socket = await websocket_connect(pages[0]["webSocketDebuggerUrl"], max_message_size=1 << 28)
    session = _Session(socket)
    await session.call("Page.enable")
    await session.call("Page.addScriptToEvaluateOnNewDocument", source=hook)
    values = []
    for load in range(1 + reloads):
        if load == 0:
            await session.call("Page.navigate", url=url)
        else:
            await session.call("Page.reload", ignoreCache=True)
        await asyncio.sleep(0.5)
        deadline, last, stable_since = time.monotonic() + timeout, None, time.monotonic()
        while time.monotonic() < deadline:
            await asyncio.sleep(0.25)
            result = await session.call("Runtime.evaluate", expression=MESHES,
                                        returnByValue=True)
            count = result["result"].get("value")
            if count != last:
                last, stable_since = count, time.monotonic()
            elif count and time.monotonic() - stable_since >= settle:
                break
        result = await session.call("Runtime.evaluate", expression=expression,
                                    returnByValue=True)
        values.append(result["result"].get("value"))
    socket.close()
    return values


def _chromium(chromium: str, profile: Path, size: tuple[int, int], run):
    """Start headless Chromium with a DevTools port; ``run(port)`` (a coroutine); stop it."""
    command = [chromium, "--headless", "--no-sandbox", "--disable-gpu",
               "--enable-unsafe-swiftshader", "--disable-background-networking",
               "--disable-component-update", "--disable-sync", "--no-first-run",
               "--hide-scrollbars", "--remote-debugging-port=0", f"--user-data-dir={profile}",
               f"--window-size={size[0]},{size[1]}", "about:blank"]
    proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    try:
        port = _devtools_port(proc, 60.0)
        threading.Thread(target=proc.stderr.read, daemon=True).start()  # never a full pipe
        return asyncio.run(run(port))
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def live_probe(chromium: str, url: str, profile: Path, *, hook: str, expression: str,
               reloads: int = 0, size: tuple[int, int] = (640, 480), settle: float = 1.5,
               timeout: float = 120.0) -> list:
    """The values (JSON) of the JavaScript ``expression`` on the live page ``url`` once its
    scene has arrived, after opening it and after each of ``reloads`` reloads; ``hook``
    runs in the page before its own scripts (e.g. to log what the WebSocket delivers).
    Other arguments as :func:`live_screenshot`'s."""
    return _chromium(chromium, profile, size,
                     lambda port: _probe(port, url, hook, expression, settle, timeout,
                                         reloads))


def live_screenshot(chromium: str, url: str, profile: Path, size: tuple[int, int] = (640, 480),
                    settle: float = 1.5, timeout: float = 120.0) -> np.ndarray:
    """RGB pixels (h, w, 3) of the live page ``url`` once its scene has arrived.

    Parameters
    ----------
    chromium : str
        The browser executable.
    url : str
        A live meshcat page (``viewer.url``).
    profile : Path
        A fresh folder for the browser's profile.
    size : tuple of int
        Viewport (width, height) in pixels.
    settle : float
        Seconds the number of meshes must stay the same before the shot.
    timeout : float
        Seconds to wait for the scene at most.
    """
    from PIL import Image

    png = _chromium(chromium, profile, size,
                    lambda port: _shoot(port, url, size, settle, timeout))
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)
