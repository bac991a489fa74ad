"""The viewer: a meshcat scene of a PyBullet simulation, live in the browser and/or recorded.

Typical use (an environment's ``render_mode="human"``, the ``play`` command)::

    viewer = Viewer(live=True)                 # starts a server, prints its URL
    viewer.add_baxter(baxter)                  # or add_body(client, body_id, "box")
    for step in episode:
        ...simulate...
        viewer.update(t)                       # moved links only; recorded at time t
        overlay.show(predictor, t)             # overlay = viewer.add_overlay(model.tasks, rng=rng)
    viewer.save_html("replay.html")            # one self-contained file
    viewer.close()                             # stops the server

With ``live=False`` (the default) no server is started at all: the scene is
kept in this process and :meth:`Viewer.save_html` still writes the replay.
"""

from __future__ import annotations

import time
from pathlib import Path

import meshcat
import numpy as np
from numpy.typing import ArrayLike

from sandbox.robot import FLOOR_Z
from sandbox.validation import check_array, check_positive
from sandbox.viz.meshes import DEFAULT_RESOLUTION
from sandbox.viz.mirror import BodyMirror
from sandbox.viz.scene import Scene
from sandbox.viz.server import DEFAULT_HOST, LiveServer
from sandbox.viz.skeleton import TrackedArm

#: Default camera position and the point it looks at, in the world (m).
DEFAULT_CAMERA = (2.3, 1.1, 1.25)
DEFAULT_TARGET = (0.55, 0.05, 0.1)
#: A link name that identifies a Baxter among simulated bodies.
BAXTER_LINK = "left_upper_shoulder"
#: Pose (with scale) of the overlays' bar panel in the camera frame (x right, y up, looking
#: along -z): 1.5 m ahead, upper left, facing the camera, so it stays in view as the view turns.
HUD_POSE = np.array([[0.0, 0.45, 0, -0.55], [0, 0, 0.45, 0.31], [0.45, 0, 0, -1.5], [0, 0, 0, 1]])
#: Height of the floor grid (m) in Baxter's base frame: 4 mm under the floor's top
#: (:data:`sandbox.robot.FLOOR_Z`), so that the simulated floor slab, when drawn, hides it
#: instead of flickering through it (-0.93 m, where the grid has always been).
GRID_Z = round(FLOOR_Z - 0.004, 3)


class Viewer:
    """A meshcat scene of PyBullet bodies and prediction overlays.

    Parameters
    ----------
    live : bool
        Start a meshcat server (a child process, stopped by :meth:`close` or
        when this process ends) and print its URL.
    fps : float
        Frame rate of the recording; :meth:`update` sends at most one frame per
        ``1 / fps`` of simulated time.
    record : bool
        Keep the frames for :meth:`save_html`.
    resolution : float or None
        Mesh simplification grid (m); ``None`` sends full meshes.
    camera : array_like, shape (3,)
        Initial camera position (m).
    target : array_like, shape (3,)
        Point the camera looks at and orbits (m).
    fov : float
        Vertical field of view of the camera (degrees).
    floor_z : float or None
        Height of the floor grid (m), default :data:`GRID_Z`; ``None`` hides the grid.
    realtime : bool
        Make :meth:`update` wait so that time ``t`` is shown ``t`` seconds
        after the first update (for live viewing of a fast simulation; slower
        or faster with :meth:`set_rate`).
    open_browser : bool
        Open the URL in the default browser (live only).
    host : str
        Address the live server's web page is served on (live only): default
        127.0.0.1, this machine only; ``"0.0.0.0"`` lets other machines watch.

    Attributes
    ----------
    vis : meshcat.Visualizer
        Root node (``/meshcat``), in the simulation's world frame; draw anything
        else under it. (It is shifted by ``-target`` in the browser's world,
        around whose origin meshcat's camera orbits.)
    scene : Scene
        The in-process scene and its recording.
    server : LiveServer or None
    bodies : dict of str to BodyMirror or TrackedArm
        What :meth:`update` redraws each frame.
    overlay : PredictionOverlay or None
        Set by :meth:`add_overlay`.
    rate : float
        Simulated seconds shown per second of wall-clock time with ``realtime``
        (:meth:`set_rate`; default 1).
    """

    def __init__(self, *, live: bool = False, fps: float = 30.0, record: bool = True,
                 resolution: float | None = DEFAULT_RESOLUTION,
                 camera: ArrayLike = DEFAULT_CAMERA, target: ArrayLike = DEFAULT_TARGET,
                 fov: float = 45.0, floor_z: float | None = GRID_Z,
                 realtime: bool = False, open_browser: bool = False,
                 host: str = DEFAULT_HOST) -> None:
        camera = check_array(camera, "camera", 1, shape=(3,))
        target = check_array(target, "target", 1, shape=(3,))
        fov, fps = check_positive(fov, "fov"), check_positive(fps, "fps")
        self.server = LiveServer(host=host) if live else None  # after every check: no leak
        self.scene = Scene(self.server, fps)
        self.vis = meshcat.Visualizer(window=self.scene)
        self.record = bool(record)
        self.realtime = bool(realtime)
        self.resolution = resolution
        self.bodies: dict[str, BodyMirror | TrackedArm] = {}
        self.overlay = None
        self.camera = camera
        self.fov = fov
        self.target = target
        self._frame: int | None = None
        self._wall_start: float | None = None
        self.rate = 1.0
        self._setup(floor_z)
        if self.server is not None:
            where = ("" if self.server.host == DEFAULT_HOST else
                     f" (listening on {self.server.host}: other machines can watch)")
            print(f"meshcat viewer: {self.server.web_url}{where}", flush=True)
            if open_browser:
                import webbrowser

                webbrowser.open(self.server.web_url, new=2)

    def _setup(self, floor_z: float | None) -> None:
        # meshcat's camera orbits the origin of the browser's world: shift our world so
        # that `target` sits there (everything drawn lives under /meshcat)
        shift = np.eye(4)
        shift[:3, 3] = -self.target
        self.vis.set_transform(shift)
        root = self.vis["/"]
        x, y, z = self.camera - self.target  # the camera's parent frame is y-up (+90 deg about x)
        camera = root["Cameras/default/rotated/<object>"]
        camera.set_property("position", [x, z, -y])
        camera.set_property("fov", float(self.fov))
        if floor_z is None:
            root["Grid"].set_property("visible", False)
        else:
            grid = np.eye(4)
            grid[2, 3] = float(floor_z) - self.target[2]
            root["Grid"].set_transform(grid)
        root["Axes"].set_property("visible", False)

    # -- content -------------------------------------------------------------------------

    @property
    def url(self) -> str | None:
        """Address of the live viewer (``None`` when offline)."""
        return self.server.web_url if self.server is not None else None

    def add_body(self, client, body: int, name: str, **options) -> BodyMirror:
        """Mirror a PyBullet body under ``/meshcat/bodies/<name>``.

        ``options`` go to :class:`~sandbox.viz.mirror.BodyMirror` (``links``,
        ``colors``, ``resolution``; default resolution: the viewer's).
        """
        if name in self.bodies:
            raise ValueError(f"name: a body named {name!r} is already mirrored")
        options.setdefault("resolution", self.resolution)
        mirror = BodyMirror(self.vis["bodies"], client, body, name, **options)
        self.bodies[name] = mirror
        return mirror

    def add_baxter(self, baxter, name: str = "baxter", **options) -> BodyMirror:
        """Mirror a :class:`~sandbox.robot.bullet.BulletBaxter`, only the links the URDF draws.

        (PyBullet would otherwise show the collision cylinders of links that
        have no visual, e.g. ``left_hand_link``.)
        """
        from sandbox.robot import visuals

        drawn = {v.link for v in visuals()}
        options.setdefault("links", [n for n in baxter.links if n in drawn])
        return self.add_body(baxter.client, baxter.body, name, **options)

    def add_simulation(self, sim) -> list[BodyMirror]:
        """Mirror every named body of a simulation (``sim.client``, ``sim.bodies``).

        Bodies already mirrored are skipped; a Baxter (recognised by its link
        names) is drawn as in :meth:`add_baxter`.
        """
        from sandbox.robot import visuals
        from sandbox.viz.bodies import link_names

        drawn = {v.link for v in visuals()}
        added = []
        for name, body in sim.bodies.items():
            if name in self.bodies:
                continue
            links = set(link_names(sim.client, body).values())
            options = {"links": sorted(links & drawn)} if BAXTER_LINK in links else {}
            added.append(self.add_body(sim.client, body, name, **options))
        return added

    def add_tracked_arm(self, source, name: str = "tracked_arm", **options):
        """Draw the tracked human arm under ``/meshcat/bodies/<name>``, redrawn by :meth:`update`.

        Parameters
        ----------
        source : callable
            Returns ``(hand, arm)`` now: tracked hand (3,) and arm (6,: elbow then
            shoulder) m, NaN where not measured (hidden then), e.g.
            ``env.unwrapped.tracked_arm``.
        name : str
        **options
            Passed to :class:`~sandbox.viz.skeleton.TrackedArm` (``style``).

        Returns
        -------
        TrackedArm
            Also kept in :attr:`bodies` (removed by :meth:`remove_body`).
        """
        if name in self.bodies:
            raise ValueError(f"name: a body named {name!r} is already mirrored")
        self.bodies[name] = TrackedArm(self.vis["bodies"][name], source, **options)
        return self.bodies[name]

    def remove_body(self, name: str) -> None:
        """Stop mirroring a body and remove it (hidden from then on in a recording)."""
        if name not in self.bodies:
            raise ValueError(f"name: expected one of {sorted(self.bodies)}, got {name!r}")
        self.bodies.pop(name).node.delete()

    def add_overlay(self, tasks, *, rng: np.random.Generator, **options):
        """Create the prediction overlays under ``/meshcat/overlays``.

        Parameters
        ----------
        tasks : sequence of str
            Task names (bar order and colours), e.g. ``model.tasks``.
        rng : numpy.random.Generator
            Draws the samples of the uncertainty tube.
        **options
            Passed to :class:`~sandbox.viz.overlays.PredictionOverlay`; by
            default the bar panel hangs on the camera (upper left of the view).

        Returns
        -------
        PredictionOverlay
            Also kept as :attr:`overlay`.
        """
        from sandbox.viz.overlays import PredictionOverlay

        if self.overlay is not None:
            self.overlay.vis.delete()
            self.overlay.panel.delete()
        if "panel" not in options and "panel_pose" not in options:
            options["panel"] = self.vis["/Cameras/default/rotated/<object>/overlay_panel"]
            options["panel_pose"] = HUD_POSE
        self.overlay = PredictionOverlay(self.vis["overlays"], tasks=tasks, rng=rng, **options)
        return self.overlay

    # -- time ----------------------------------------------------------------------------

    def begin(self, t: float) -> bool:
        """Start frame ``t`` (s); ``False`` if it falls in the frame already sent (skip it)."""
        if not np.isfinite(t) or t < 0:
            raise ValueError(f"t: expected a finite time >= 0 (s), got {t!r}")
        frame = int(round(float(t) * self.scene.timeline.fps))
        if frame == self._frame:
            return False
        if self._frame is not None and frame < self._frame:
            self._wall_start = None  # time went back (a new episode): pace from here
        self._frame = frame
        if self.record:
            self.scene.set_time(t)
        if self.realtime:
            self._pace(float(t))
        return True

    def update(self, t: float, *, force: bool = False) -> int:
        """Show the bodies at simulated time ``t`` (s); return the number of transforms sent.

        Calls within the frame already shown (``1 / fps``) do nothing unless ``force``.
        """
        if not self.begin(t) and not force:
            return 0
        return sum(mirror.update() for mirror in self.bodies.values())

    def _pace(self, t: float) -> None:
        now = time.monotonic()
        if self._wall_start is None:
            self._wall_start = now - t / self.rate
        delay = self._wall_start + t / self.rate - now
        if delay > 0:
            time.sleep(delay)

    def set_rate(self, rate: float) -> None:
        """With ``realtime``: show ``rate`` s of simulated time per second (1: real time,
        0.25: slow motion), from the next frame on."""
        self.rate = check_positive(rate, "rate")
        self._wall_start = None

    def restart_pacing(self) -> None:
        """With ``realtime``: show the next frame now and pace from it (e.g. after a pause)."""
        self._wall_start = None

    def restart_recording(self) -> None:
        """Start a new recording (e.g. at ``env.reset``): the next replay begins at the next
        :meth:`update`; objects that ended hidden are dropped from it."""
        self.scene.restart()
        self._frame = None
        self._wall_start = None

    # -- output --------------------------------------------------------------------------

    def static_html(self) -> str:
        """The self-contained HTML replay as a string."""
        return self.scene.static_html()

    def save_html(self, path: str | Path) -> Path:
        """Write the replay (scene + recorded animation) to ``path``; return it."""
        path = Path(path)
        if path.suffix.lower() not in (".html", ".htm"):
            raise ValueError(f"path: expected a file name ending in .html, got {str(path)!r}")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.static_html(), encoding="utf-8")
        return path

    def close(self) -> None:
        """Stop the live server, if any (idempotent); the scene stays available offline."""
        if self.server is not None:
            self.server.close()
        self.scene.live = None

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
