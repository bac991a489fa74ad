"""A meshcat server owned by this process: started on demand, never left behind.

meshcat's own ``Visualizer()`` starts ``meshcat.servers.zmqserver`` in a new
session and kills it only at interpreter exit (and its ``close()`` fails in
meshcat 0.3.2), so a crashed or killed Python leaves the server running. Here
the server is this module run as a child process (``python -m
sandbox.viz.server --parent PID``) that

- is stopped by :meth:`LiveServer.close` (terminate, then kill after a grace
  period), by an ``atexit`` hook, and on garbage collection;
- watches its parent twice a second and exits when the parent is gone, so
  even a ``kill -9`` of the parent leaves no orphan;
- stays in the parent's session, so Ctrl-C in a terminal stops both.

Commands go over meshcat's ZeroMQ request/reply socket with a timeout: a dead
server turns the viewer offline (a warning) instead of hanging the simulation.

Addresses: the web server (what a browser opens) listens on ``host``, by
default :data:`DEFAULT_HOST` (127.0.0.1, this machine only; meshcat itself
listens on every interface); another address, e.g. ``"0.0.0.0"`` for every
interface, is an explicit choice (``play --host``). The command socket always
listens on 127.0.0.1: only this process talks to it.
"""

from __future__ import annotations

import argparse
import atexit
import os
import selectors
import socket
import subprocess
import sys
import time
import warnings
import weakref

START_TIMEOUT = 30.0
#: Seconds the server waits for a command's reply before the viewer goes offline.
REPLY_TIMEOUT = 10.0
#: Address the web server listens on unless told otherwise: this machine only.
DEFAULT_HOST = "127.0.0.1"
#: Addresses meaning "every interface".
WILDCARD_HOSTS = ("0.0.0.0", "::", "")


def check_host(host: str) -> str:
    """Return ``host`` after checking this machine can listen on it.

    Raises
    ------
    ValueError
        If ``host`` is not a non-empty string, or no socket can be bound to it
        (an unknown name, an address of another machine).
    """
    if not isinstance(host, str) or not host.strip():
        raise ValueError(f"host: expected an address to listen on such as {DEFAULT_HOST!r} or "
                         f"'0.0.0.0' (every interface), got {host!r}")
    try:
        with socket.create_server((host, 0), family=_family(host)):
            pass
    except (OSError, OverflowError) as error:
        raise ValueError(f"host: cannot listen on {host!r} ({error})") from None
    return host


def _family(host: str) -> socket.AddressFamily:
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def web_url(host: str, port: int) -> str:
    """The URL a browser on this machine opens (127.0.0.1 for a wildcard address)."""
    shown = DEFAULT_HOST if host in WILDCARD_HOSTS else host
    return f"http://{f'[{shown}]' if ':' in shown else shown}:{port}/static/"


def _stop_process(proc: subprocess.Popen, grace: float = 3.0) -> None:
    """Terminate ``proc`` (our own child), kill it if it does not exit within ``grace`` s."""
    if proc.poll() is not None:
        return
    proc.terminate()
    try:
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=grace)


def _read_urls(proc: subprocess.Popen, timeout: float) -> tuple[str, str]:
    """Read ``zmq_url=...`` and ``web_url=...`` from the server's stdout, with a deadline."""
    urls: dict[str, str] = {}
    deadline = time.monotonic() + timeout
    buffer = b""
    with selectors.DefaultSelector() as selector:
        selector.register(proc.stdout, selectors.EVENT_READ)
        while len(urls) < 2:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or proc.poll() is not None:
                raise RuntimeError(
                    f"the meshcat server did not start (exit code {proc.poll()}, "
                    f"output so far {buffer!r})"
                )
            if not selector.select(timeout=min(remaining, 0.5)):
                continue
            chunk = os.read(proc.stdout.fileno(), 4096)
            buffer += chunk
            *lines, rest = buffer.split(b"\n")
            for line in lines:
                key, _, value = line.decode("utf-8", "replace").strip().partition("=")
                if key in ("zmq_url", "web_url"):
                    urls[key] = value
            buffer = rest
            if not chunk and proc.poll() is not None:
                continue
    return urls["zmq_url"], urls["web_url"]


class LiveServer:
    """A running meshcat server (child process) and a request socket to it.

    Parameters
    ----------
    host : str
        Address the web server listens on (default 127.0.0.1, this machine
        only; ``"0.0.0.0"``: every interface, reachable from the network).
    start_timeout : float
        Seconds to wait for the server to report its URLs.
    reply_timeout : float
        Seconds to wait for each command's reply before going offline.

    Attributes
    ----------
    web_url : str
        Address to open in a browser (``http://127.0.0.1:<port>/static/``).
    host : str
        Address the web server listens on.
    zmq_url : str
        The server's command socket.
    pid : int
        Process id of the server.
    alive : bool
        False once closed or after the server stopped answering.
    """

    def __init__(self, *, host: str = DEFAULT_HOST, start_timeout: float = START_TIMEOUT,
                 reply_timeout: float = REPLY_TIMEOUT) -> None:
        import zmq

        self.host = check_host(host)
        self._proc = subprocess.Popen(
            [sys.executable, "-u", "-m", "sandbox.viz.server", "--parent", str(os.getpid()),
             "--host", self.host],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
        )
        self._finalizer = weakref.finalize(self, _stop_process, self._proc)
        atexit.register(self._finalizer)
        try:
            self.zmq_url, self.web_url = _read_urls(self._proc, start_timeout)
        except BaseException:
            self._finalizer()
            raise
        self._proc.stdout.close()
        self.pid = self._proc.pid
        self._context = zmq.Context.instance()
        self._socket = self._context.socket(zmq.REQ)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.setsockopt(zmq.RCVTIMEO, int(reply_timeout * 1000))
        self._socket.setsockopt(zmq.SNDTIMEO, int(reply_timeout * 1000))
        self._socket.connect(self.zmq_url)
        self.alive = True

    def send(self, kind: str, path: str, packed: bytes) -> bool:
        """Forward one packed meshcat command; return whether the server acknowledged it."""
        if not self.alive:
            return False
        import zmq

        try:
            self._socket.send_multipart([kind.encode("utf-8"), path.encode("utf-8"), packed])
            self._socket.recv()
            return True
        except zmq.ZMQError as error:
            warnings.warn(
                f"the meshcat server stopped answering ({error}); the viewer continues offline",
                RuntimeWarning,
                stacklevel=3,
            )
            self.close()
            return False

    def request(self, message: bytes) -> bytes:
        """Send a raw request (``b"url"``, ``b"wait"``, ``b"get_scene"``) and return the reply."""
        if not self.alive:
            raise RuntimeError("the meshcat server is closed")
        self._socket.send(message)
        return self._socket.recv()

    def running(self) -> bool:
        """Whether the server process is still running."""
        return self._proc.poll() is None

    def close(self) -> None:
        """Stop the server and close the socket (idempotent)."""
        if getattr(self, "_socket", None) is not None:
            self._socket.close(linger=0)
            self._socket = None
        self.alive = False
        self._finalizer()
        atexit.unregister(self._finalizer)

    def __enter__(self) -> LiveServer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# -- the server process ----------------------------------------------------------------------


def _parent_gone(parent: int) -> bool:
    if os.getppid() != parent:
        return True
    try:
        os.kill(parent, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    return False


def _bridge(host: str, zmq_url: str | None):
    """meshcat's ZeroMQ/WebSocket bridge, its web server listening on ``host`` only.

    meshcat binds the command socket to its ``host`` argument but starts the
    web server with tornado's default address, every interface. Here the
    bridge gets 127.0.0.1 (the command socket) and its web server ``host``.
    """
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class Bridge(ZMQWebSocketBridge):
        def make_app(self):
            app = super().make_app()
            listen = app.listen
            app.listen = lambda port, **kw: listen(port, address=host, **kw)
            return app

        def send_scene(self, websocket):
            for message in scene_messages(self.tree):
                websocket.write_message(message, binary=True)

    bridge = Bridge(zmq_url=zmq_url, host=DEFAULT_HOST)
    bridge.web_url = web_url(host, bridge.fileserver_port)
    return bridge


#: Scene nodes a browser tab gets first: the camera (and the panel hung on it).
FIRST = ("Cameras",)


def scene_messages(tree) -> list[bytes]:
    """What a newly opened (or reloaded) tab is sent: the scene as it is now.

    meshcat sends its tree in the order the nodes were made: the robot's meshes
    (megabytes) before the camera, so a tab showed meshcat's default far camera,
    and no panel, for seconds. Here the nodes of :data:`FIRST` come first, then
    the rest; and of the values a property was set to, only the last is sent (a
    bar's height is set at every belief update).
    """
    from meshcat.servers.tree import walk

    first = [tree[name] for name in FIRST if name in tree]
    rest = [node for name, node in tree.items() if name not in FIRST]
    out = _node_messages(tree)
    for top in [*first, *rest]:
        for node in walk(top):
            out.extend(_node_messages(node))
    return out


def _node_messages(node) -> list[bytes]:
    """One node's own messages, as meshcat sends them: object, properties, transform,
    animation."""
    out = [] if node.object is None else [node.object]
    out.extend(_last_values(node.properties))
    out.extend(m for m in (node.transform, node.animation) if m is not None)
    return out


def _last_values(properties: list[bytes]) -> list[bytes]:
    """The last ``set_property`` message of each property, in the order they were last set."""
    import umsgpack

    last: dict = {}
    for packed in properties:
        try:
            name = umsgpack.unpackb(packed).get("property")
        except Exception:  # noqa: BLE001 - not ours to judge: send it as it came
            name = object()
        last.pop(name, None)
        last[name] = packed
    return list(last.values())


def main(argv: list[str] | None = None) -> int:
    """Run meshcat's ZeroMQ/WebSocket bridge until the parent process goes away."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parent", type=int, required=True, help="pid to watch")
    parser.add_argument("--zmq-url", default=None)
    parser.add_argument("--host", default=DEFAULT_HOST,
                        help="address the web server listens on (default 127.0.0.1)")
    args = parser.parse_args(argv)

    import tornado.ioloop

    bridge = _bridge(args.host, args.zmq_url)
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}", flush=True)
    sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - the parent closed its end of the pipe
    loop = tornado.ioloop.IOLoop.current()

    def watch() -> None:
        if _parent_gone(args.parent):
            loop.stop()

    tornado.ioloop.PeriodicCallback(watch, 500).start()
    try:
        loop.start()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
