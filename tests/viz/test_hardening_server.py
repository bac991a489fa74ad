"""Which addresses the live viewer's server listens on (issue 13, finding 11 and item 8).

The listening sockets of the server process are read from ``/proc`` (the
kernel's own table), not from what the server prints.
"""

from __future__ import annotations

import os
import socket
from pathlib import Path

import pytest

from sandbox.viz.server import LiveServer, check_host
from tests.viz.test_server import _servers_watching, _wait_gone, no_server_left_behind  # noqa: F401

pytestmark = pytest.mark.skipif(not Path("/proc/self/net/tcp").is_file(),
                                reason="needs /proc/<pid>/net (Linux)")


def _address(hex_address: str) -> str:
    raw = bytes.fromhex(hex_address)
    if len(raw) == 4:
        return socket.inet_ntoa(raw[::-1])
    words = b"".join(raw[i:i + 4][::-1] for i in range(0, 16, 4))
    return socket.inet_ntop(socket.AF_INET6, words)


def listening(pid: int) -> list[tuple[str, int]]:
    """``(address, port)`` of every TCP socket process ``pid`` listens on."""
    fd_dir = Path(f"/proc/{pid}/fd")
    inodes = set()
    for fd in fd_dir.iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    found = []
    for table in ("tcp", "tcp6"):
        path = Path(f"/proc/{pid}/net/{table}")
        if not path.is_file():
            continue
        for line in path.read_text().splitlines()[1:]:
            fields = line.split()
            local, state, inode = fields[1], fields[3], fields[9]
            if state == "0A" and inode in inodes:  # 0A: LISTEN
                address, port = local.split(":")
                found.append((_address(address), int(port, 16)))
    return sorted(found)


def _web_port(server: LiveServer) -> int:
    return int(server.web_url.rsplit(":", 1)[1].split("/")[0])


def test_the_server_listens_on_127_0_0_1_only_by_default():
    """issue 13 finding 11: the live viewer and teleop server listened on 0.0.0.0 (every
    interface) while printing 127.0.0.1; both its sockets now listen on 127.0.0.1 only."""
    server = LiveServer()
    try:
        sockets = listening(server.pid)
        assert len(sockets) == 2, sockets  # the web page and the command socket
        assert {address for address, _ in sockets} == {"127.0.0.1"}
        assert ("127.0.0.1", _web_port(server)) in sockets
        assert server.web_url.startswith("http://127.0.0.1:")
    finally:
        server.close()
    assert _wait_gone(server.pid)


def test_a_wider_binding_is_an_explicit_choice(capsys):
    """issue 13 item 8: `host="0.0.0.0"` serves the page on every interface and says so;
    the command socket stays on 127.0.0.1."""
    from sandbox.viz import Viewer

    viewer = Viewer(live=True, host="0.0.0.0")
    try:
        server = viewer.server
        sockets = dict((port, address) for address, port in listening(server.pid))
        assert sockets.pop(_web_port(server)) == "0.0.0.0"
        assert set(sockets.values()) == {"127.0.0.1"}
        assert server.web_url.startswith("http://127.0.0.1:")  # what a local browser opens
        assert server.request(b"url").decode() == server.web_url
        assert "listening on 0.0.0.0" in capsys.readouterr().out
    finally:
        viewer.close()


@pytest.mark.parametrize("host", ["", "no-such-host.invalid", "203.0.113.7", 7, None])
def test_an_address_that_cannot_be_listened_on_is_refused_before_starting(host):
    """issue 13 item 8: a bad `host` is a ValueError and no server process is started."""
    with pytest.raises(ValueError, match="host"):
        LiveServer(host=host)
    assert _servers_watching(os.getpid()) == []


def test_play_host_is_checked_before_anything_starts(capsys):
    """issue 13 item 8: `play --host` names the option when the address is unusable."""
    from sandbox.cli import main

    assert main(["play", "--host", "no-such-host.invalid"]) == 2
    assert "--host: cannot listen on 'no-such-host.invalid'" in capsys.readouterr().err
    assert check_host("127.0.0.1") == "127.0.0.1"
