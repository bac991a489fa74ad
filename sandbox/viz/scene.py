"""The meshcat command stream: an in-process scene, its recording, its HTML replay.

meshcat's ``Visualizer`` talks to a "window" that receives commands
(``set_object``, ``set_transform``, ``set_property``, ``delete``). A
:class:`Scene` is such a window that needs no server: it keeps the scene tree
in this process (as meshcat's server does), forwards every command to a live
server if one is attached (:class:`~sandbox.viz.server.LiveServer`), and, while
recording, turns the stream into animation tracks keyed by time:

- ``set_transform`` -> position / quaternion / scale tracks of that node;
- ``set_property`` of ``visible``, ``scale``, ``position``... -> property tracks;
- ``set_object`` at time t > 0 -> the node is hidden before t and shown from t;
- ``delete`` at time t -> the node is hidden from t on (kept in the replay).

:meth:`Scene.static_html` writes the scene plus one meshcat animation into a
single self-contained HTML file (the viewer's JavaScript and every mesh
inlined, commands decoded synchronously in order): it opens from ``file://``
with no network.
"""

from __future__ import annotations

import base64
import os
from dataclasses import dataclass, field
from pathlib import Path

import meshcat
import numpy as np
import umsgpack

VIEWER_JS = Path(os.path.dirname(meshcat.__file__)) / "viewer" / "dist" / "main.min.js"
#: Animated properties and their three.js track types.
TRACK_TYPES = {"visible": "boolean", "scale": "vector3", "position": "vector3",
               "quaternion": "quaternion", "opacity": "number"}
#: three.js ``InterpolateDiscrete``: a key holds until the next one.
DISCRETE = 2300


@dataclass
class _Node:
    object: bytes | None = None
    transform: bytes | None = None
    properties: dict[str, bytes] = field(default_factory=dict)


class Timeline:
    """Animation tracks keyed by frame: ``{path: {property: {frame: value}}}``."""

    def __init__(self, fps: float) -> None:
        self.fps = float(fps)
        self.tracks: dict[str, dict[str, dict[int, object]]] = {}
        self.held: set[str] = set()

    def hold(self, path: str) -> None:
        """Make the tracks of ``path`` and its descendants step: each key holds until the next
        (three.js interpolates numbers and vectors between keys otherwise)."""
        self.held.add(path.rstrip("/"))

    def is_held(self, path: str) -> bool:
        """Whether ``path`` or one of its ancestors is held (kept when not recording)."""
        return any(path == p or path.startswith(p + "/") for p in self.held)

    def set(self, path: str, prop: str, frame: int, value) -> None:
        """Record ``value`` of ``prop`` at ``frame`` (a later call at the same frame wins)."""
        self.tracks.setdefault(path, {}).setdefault(prop, {})[int(frame)] = value

    def has(self, path: str, prop: str) -> bool:
        """Whether a track of ``prop`` was recorded for ``path``."""
        return prop in self.tracks.get(path, {})

    def drop_under(self, path: str) -> None:
        """Forget the tracks of ``path`` and its descendants (deleted when not recording)."""
        for key in [k for k in self.tracks if k == path or k.startswith(path + "/")]:
            del self.tracks[key]

    @property
    def n_frames(self) -> int:
        """Last frame with a key, plus one (0 when empty)."""
        frames = [f for props in self.tracks.values() for keys in props.values() for f in keys]
        return max(frames) + 1 if frames else 0

    def lower(self) -> list[dict]:
        """meshcat's ``set_animation`` payload: one clip per path, constant tracks dropped."""
        out = []
        for path, props in self.tracks.items():
            tracks = []
            for prop, keys in props.items():
                frames = sorted(keys)
                values = [keys[f] for f in frames]
                if len(frames) > 1 and all(_same(v, values[0]) for v in values[1:]):
                    if prop != "visible":
                        continue  # constant: the scene's final state already shows it
                track = {"name": "." + prop, "type": TRACK_TYPES[prop],
                         "keys": [{"time": f, "value": v} for f, v in zip(frames, values)]}
                if self.is_held(path):
                    track["interpolation"] = DISCRETE
                tracks.append(track)
            if tracks:
                out.append({"path": path, "clip": {"fps": self.fps, "name": "default",
                                                   "tracks": tracks}})
        return out


def _same(a, b) -> bool:
    return a == b if isinstance(a, bool | str) else bool(np.allclose(a, b, atol=1e-9))


def decompose(matrix: np.ndarray) -> tuple[list[float], list[float], list[float]]:
    """Position, quaternion (x, y, z, w) and scale of a 4x4 transform (three.js convention).

    The scale is the column norms of the linear part (negative determinant
    flips the x scale), as ``THREE.Matrix4.decompose`` does.
    """
    linear = np.asarray(matrix, dtype=np.float64)[:3, :3]
    scale = np.linalg.norm(linear, axis=0)
    if np.linalg.det(linear) < 0:
        scale[0] = -scale[0]
    rot = linear / np.where(scale == 0, 1.0, scale)
    return (
        [float(v) for v in np.asarray(matrix)[:3, 3]],
        [float(v) for v in quaternion_xyzw(rot)],
        [float(v) for v in scale],
    )


def quaternion_xyzw(rot: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w) of a rotation matrix (3, 3), w >= 0."""
    m = rot
    w = np.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = np.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2
    y = np.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2
    z = np.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2
    x = np.copysign(x, m[2, 1] - m[1, 2])
    y = np.copysign(y, m[0, 2] - m[2, 0])
    z = np.copysign(z, m[1, 0] - m[0, 1])
    q = np.array([x, y, z, w])
    return q / np.linalg.norm(q)


class Scene:
    """A meshcat window kept in this process; optionally mirrored live and recorded.

    Parameters
    ----------
    live : LiveServer or None
        A running server to forward every command to (``None``: offline).
    fps : float
        Frame rate of the recording (frames per second of replay time).

    Notes
    -----
    Use it through a ``meshcat.Visualizer``: ``meshcat.Visualizer(window=scene)``.
    """

    def __init__(self, live=None, fps: float = 30.0) -> None:
        if not np.isfinite(fps) or fps <= 0:
            raise ValueError(f"fps: expected a finite number > 0, got {fps!r}")
        self.live = live
        self.nodes: dict[str, _Node] = {}
        self.timeline = Timeline(fps)
        self.recording = False
        self.frame = 0

    # -- recording clock ---------------------------------------------------------------------

    def set_time(self, t: float) -> None:
        """Start (or continue) recording at replay time ``t`` (s, >= 0); commands now land at it."""
        if not np.isfinite(t) or t < 0:
            raise ValueError(f"t: expected a finite time >= 0 (s), got {t!r}")
        self.recording = True
        self.frame = int(round(float(t) * self.timeline.fps))

    def restart(self) -> None:
        """Forget the recording (e.g. at a new episode); objects hidden at its end are dropped."""
        for path, props in list(self.timeline.tracks.items()):
            keys = props.get("visible")
            if keys and not keys[max(keys)] and path in self.nodes:
                del self.nodes[path]
        held = self.timeline.held
        self.timeline = Timeline(self.timeline.fps)
        self.timeline.held = held
        self.recording = False
        self.frame = 0

    def hold(self, path: str) -> None:
        """Replay the properties under ``path`` as steps, not interpolated (see
        :meth:`Timeline.hold`): e.g. a bar whose value label changes at the same frame."""
        self.timeline.hold(path)

    # -- the meshcat window interface --------------------------------------------------------

    def send(self, command) -> None:
        """Apply one meshcat command (``SetObject``, ``SetTransform``, ``SetProperty``...)."""
        data = command.lower()
        kind, path = data["type"], data["path"]
        packed = umsgpack.packb(data)
        if self.live is not None:
            self.live.send(kind, path, packed)
        if kind == "set_animation":
            return
        if kind == "delete":
            self._delete(path)
            return
        node = self.nodes.setdefault(path, _Node())
        if kind == "set_object":
            self._appear(path, node)
            node.object, node.properties = packed, {}
        elif kind == "set_transform":
            node.transform = packed
            if self.recording:
                self._record_transform(path, np.reshape(data["matrix"], (4, 4)).T)
        elif kind == "set_property":
            node.properties[data["property"]] = packed
            if self.recording and data["property"] in TRACK_TYPES:
                self.timeline.set(path, data["property"], self.frame, data["value"])

    def get_scene(self) -> str:
        """The self-contained HTML replay (what ``Visualizer.static_html()`` returns)."""
        return self.static_html()

    # -- output ------------------------------------------------------------------------------

    def commands(self) -> list[bytes]:
        """Packed commands that rebuild the current scene, then its animation if recorded."""
        out = []
        for node in self.nodes.values():
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties.values())
            if node.transform is not None:
                out.append(node.transform)
        animation = self.timeline.lower()
        if animation:
            out.append(umsgpack.packb(_animation_command(animation)))
        return out

    def static_html(self, title: str = "handover-sandbox replay") -> str:
        """One HTML page holding the viewer, the scene and its animation (no external file)."""
        blobs = ",\n".join(f'"{base64.b64encode(c).decode("ascii")}"' for c in self.commands())
        frames = self.timeline.n_frames
        duration = (frames - 1) / self.timeline.fps if frames > 1 else 0.0
        return _HTML.format(title=title, viewer=VIEWER_JS.read_text(encoding="utf-8"), blobs=blobs,
                            duration=f"{duration:.6f}")

    # -- internals ---------------------------------------------------------------------------

    def _record_transform(self, path: str, matrix: np.ndarray) -> None:
        position, quaternion, scale = decompose(matrix)
        self.timeline.set(path, "position", self.frame, position)
        self.timeline.set(path, "quaternion", self.frame, quaternion)
        if self.timeline.has(path, "scale") or not np.allclose(scale, 1.0):
            self.timeline.set(path, "scale", self.frame, scale)

    def _appear(self, path: str, node: _Node) -> None:
        if not self.recording:
            return
        if not self.timeline.has(path, "visible") and self.frame > 0 and node.object is None:
            self.timeline.set(path, "visible", 0, False)
        if self.timeline.has(path, "visible") or self.frame > 0:
            self.timeline.set(path, "visible", self.frame, True)
            node.properties.pop("visible", None)

    def _delete(self, path: str) -> None:
        under = [k for k in self.nodes if k == path or k.startswith(path.rstrip("/") + "/")]
        if not self.recording:
            for key in under:
                del self.nodes[key]
            self.timeline.drop_under(path)
            return
        # recording: hide each drawn object under the path (not the group, so that a
        # descendant drawn again later shows without its deleted siblings)
        for key in under:
            if self.nodes[key].object is None:
                continue
            if not self.timeline.has(key, "visible"):
                self.timeline.set(key, "visible", 0, True)
            self.timeline.set(key, "visible", self.frame, False)


def _animation_command(animation: list[dict]) -> dict:
    return {"type": "set_animation", "animations": animation,
            "options": {"play": True, "repetitions": 1}, "path": ""}


_HTML = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>body {{margin: 0;}} #meshcat-pane {{width: 100vw; height: 100vh; overflow: hidden;}}</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
{viewer}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var commands = [
{blobs}
];
for (var i = 0; i < commands.length; i++) {{
    var text = atob(commands[i]);
    var bytes = new Uint8Array(text.length);
    for (var j = 0; j < text.length; j++) {{ bytes[j] = text.charCodeAt(j); }}
    viewer.handle_command_bytearray(bytes);
}}
// replay.html#t=1.5 shows the frame at 1.5 s, paused. A #t= that is not a time within the
// recording shows its first frame and says so in a banner (never the last frame silently).
var duration = {duration};
var asked = /[#&]t=([^&]*)/.exec(location.hash);
if (asked && viewer.animator.actions.length) {{
    var t = /^[0-9]+([.][0-9]*)?$/.test(asked[1]) ? parseFloat(asked[1]) : NaN;
    viewer.animator.pause();
    if (isFinite(t) && t <= duration + 1e-9) {{
        viewer.animator.seek(t);
    }} else {{
        viewer.animator.seek(0);
        var banner = document.createElement("div");
        banner.id = "bad-time";
        banner.textContent = "#t=" + decodeURIComponent(asked[1]) + " is not a time in [0, " +
            duration.toFixed(2) + "] s: showing t = 0";
        banner.style.cssText = "position:fixed;top:0;left:0;right:0;padding:6px 10px;" +
            "background:#c0392b;color:#fff;font:14px sans-serif;z-index:10";
        document.body.appendChild(banner);
        document.title = document.title + " (bad #t)";
    }}
}}
document.title = document.title + " (loaded)";
</script>
</body>
</html>
"""
