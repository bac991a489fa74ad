"""meshcat viewer: PyBullet bodies, prediction overlays, live in a browser or as an HTML replay.

The only package of the project that imports meshcat. Main entry points:

- :class:`Viewer`: mirror PyBullet bodies (:meth:`Viewer.add_body`,
  :meth:`Viewer.add_baxter`), update them each frame (:meth:`Viewer.update`),
  draw a predictor's state (:meth:`Viewer.add_overlay` ->
  :class:`PredictionOverlay`), view live (``live=True`` starts a meshcat
  server, stopped by :meth:`Viewer.close` or at exit) and save one
  self-contained HTML replay (:meth:`Viewer.save_html`);
- :func:`load_mesh`: DAE/OBJ/STL files as compact, simplified, cached triangles.

Modules: :mod:`~sandbox.viz.collada`, :mod:`~sandbox.viz.meshes` and
:mod:`~sandbox.viz.geometry` are numpy only; :mod:`~sandbox.viz.bodies` reads
PyBullet; :mod:`~sandbox.viz.objects`, :mod:`~sandbox.viz.scene`,
:mod:`~sandbox.viz.mirror`, :mod:`~sandbox.viz.overlays`, :mod:`~sandbox.viz.skeleton` and
:mod:`~sandbox.viz.viewer` build meshcat commands; :mod:`~sandbox.viz.server`
owns the live server process. Names below are imported lazily, so importing
a numpy-only module does not load meshcat.

Units: metres, radians, seconds; poses are 4x4 homogeneous matrices in the
PyBullet world (Baxter's ``base`` frame when loaded by
:func:`sandbox.robot.bullet.load_baxter`).
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "Viewer": "sandbox.viz.viewer",
    "PredictionOverlay": "sandbox.viz.overlays",
    "OverlayStyle": "sandbox.viz.overlays",
    "BodyMirror": "sandbox.viz.mirror",
    "Scene": "sandbox.viz.scene",
    "TrackedArm": "sandbox.viz.skeleton",
    "LiveServer": "sandbox.viz.server",
    "load_mesh": "sandbox.viz.meshes",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'sandbox.viz' has no attribute {name!r}")
