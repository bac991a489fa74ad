"""The live meshcat server: started on demand, stopped by close(), at exit, and when its
parent is killed; a dead server turns the viewer offline instead of hanging it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sandbox.viz.server import LiveServer

pytestmark = pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")


def _alive(pid: int) -> bool:
    """Whether ``pid`` is a running process (a zombie waiting for its reaper counts as gone)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return False
    return state not in ("Z", "X")


def _wait_gone(pid: int, timeout: float = 15.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not _alive(pid):
            return True
        time.sleep(0.1)
    return not _alive(pid)


def _servers_watching(parent: int) -> list[int]:
    """Running viewer servers started for process ``parent``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            args = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"sandbox.viz.server" in args and str(parent).encode() in args:
            if _alive(int(entry.name)):
                found.append(int(entry.name))
    return found


@pytest.fixture(autouse=True)
def no_server_left_behind():
    yield
    leftovers = _servers_watching(os.getpid())
    for pid in leftovers:  # clean up our own children before failing
        os.kill(pid, signal.SIGKILL)
    assert leftovers == [], "a meshcat server outlived its test"


def test_start_answer_close():
    server = LiveServer()
    try:
        assert server.running() and _alive(server.pid)
        assert server.web_url.startswith("http://127.0.0.1:")
        assert server.request(b"url").decode() == server.web_url
    finally:
        server.close()
    assert _wait_gone(server.pid)
    assert not server.alive
    server.close()  # idempotent


def test_live_viewer_prints_its_url_and_feeds_the_server(capsys):
    from sandbox.viz import Viewer, objects

    with Viewer(live=True) as viewer:
        assert viewer.url in capsys.readouterr().out
        viewer.vis["probe"].set_object(objects.sphere(0.1, [1, 0, 0, 1]))
        scene = viewer.server.request(b"get_scene").decode()
        assert scene.count("fetch(") >= 4  # camera, grid, axes, probe...
        pid = viewer.server.pid
    assert _wait_gone(pid)


def test_offline_viewer_starts_no_server():
    from sandbox.viz import Viewer

    viewer = Viewer()
    assert viewer.server is None and viewer.url is None
    assert _servers_watching(os.getpid()) == []


_CHILD = """
import sys, time
from sandbox.viz import Viewer
viewer = Viewer(live=True)
print("SERVER", viewer.server.pid, flush=True)
if sys.argv[1] == "sleep":
    time.sleep(120)
"""


def _child(mode: str) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, mode], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    for line in proc.stdout:
        if line.startswith("SERVER"):
            return proc, int(line.split()[1])
    proc.kill()
    raise AssertionError("the child process did not start a server")


def test_server_stops_when_its_parent_exits_without_closing():
    proc, pid = _child("exit")
    proc.wait(timeout=60)
    assert _wait_gone(pid)


def test_server_stops_when_its_parent_is_killed():
    proc, pid = _child("sleep")
    try:
        assert _alive(pid)
        proc.send_signal(signal.SIGKILL)  # no atexit, no finalizer: only the watchdog is left
        proc.wait(timeout=10)
        assert _wait_gone(pid), "the server outlived its killed parent"
    finally:
        if _alive(pid):
            os.kill(pid, signal.SIGKILL)
        proc.kill()


def test_dead_server_turns_the_viewer_offline():
    import meshcat

    from sandbox.viz import objects
    from sandbox.viz.scene import Scene

    server = LiveServer(reply_timeout=0.5)
    scene = Scene(server)
    vis = meshcat.Visualizer(window=scene)
    os.kill(server.pid, signal.SIGKILL)
    assert _wait_gone(server.pid)
    with pytest.warns(RuntimeWarning, match="offline"):
        vis["a"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    vis["b"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))  # no wait, no warning now
    assert not server.alive
    assert "/meshcat/b" in scene.nodes  # the offline scene keeps everything
