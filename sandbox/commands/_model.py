"""``--model FILE``: a model saved by ``fit`` instead of one fitted by the command.

``evaluate`` predicts every trial with it (test-only: no refit, no
leave-one-out); ``play`` and ``demo`` drive the robot with it. The file is
read with the core's loader (:meth:`sandbox.core.IProMP.load`: no pickle,
every member checked) and checked against what the command will feed it
before any work: a mismatch is one ``ValueError`` line.
"""

from __future__ import annotations

import argparse
import sys


def add_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """Add ``--model FILE`` (``what``: what the command does with it)."""
    parser.add_argument("--model", default=None, metavar="FILE",
                        help=f"a model saved by 'python -m sandbox fit' (.npz): {what}")


def load(path: str):
    """The fitted :class:`~sandbox.core.IProMP` in ``path``; errors name ``--model``."""
    from sandbox.core import IProMP

    try:
        model = IProMP.load(path)
    except ValueError as error:
        raise ValueError(f"--model: {error}") from None
    if getattr(model, "span_note", None):       # a file written before span_reg
        print(f"--model {path}: {model.span_note}", file=sys.stderr)
    return model


def observe(model, explicit, option: str = "--observe") -> tuple[str, ...]:
    """The modalities to feed ``model``: its own, or ``explicit`` (names or ``"a,b"``) if
    those are the same set; anything else is a ``ValueError``."""
    names = tuple(model.modality_names)
    if explicit is None:
        return names
    asked = tuple(n.strip() for n in explicit.split(",")) if isinstance(explicit, str) \
        else tuple(explicit)
    if set(asked) != set(names):
        raise ValueError(f"{option}: the model given by --model observes {','.join(names)}, "
                         f"got {','.join(asked)} (fit another model to observe those)")
    return names


def within(model, available, source: str) -> tuple[str, ...]:
    """The model's modalities, if ``source`` carries all of them (``available``)."""
    names = tuple(model.modality_names)
    missing = [n for n in names if n not in available]
    if missing:
        raise ValueError(f"--model: the model observes {','.join(names)}, but {source} "
                         f"carries only {','.join(available)} (missing {','.join(missing)})")
    return names


def tasks(model, wanted, source: str) -> None:
    """``ValueError`` unless every task in ``wanted`` is one of the model's."""
    unknown = [t for t in wanted if t not in model.tasks]
    if unknown:
        raise ValueError(f"--model: {source} has tasks {unknown} the model does not know "
                         f"(it knows {list(model.tasks)})")


#: Joints of the robot arm the environments drive (Baxter's left arm).
BAXTER_JOINTS = 7


def baxter(model) -> None:
    """``ValueError`` unless an arm can follow the model: Baxter's seven left-arm joints
    (retargeted to another arm) or a task-space position (3 dims, m; through the arm's
    inverse kinematics, :mod:`sandbox.episodes.steering`)."""
    if getattr(model, "robot_space", "joint") == "task":
        if model.n_robot != 3:
            raise ValueError(f"--model: its robot part is in task space with {model.n_robot} "
                             f"dims; an arm follows a position x, y, z (3 dims, m)")
        return
    if model.n_robot != BAXTER_JOINTS:
        raise ValueError(f"--model: the model drives {model.n_robot} robot dims, the "
                         f"environments' Baxter arm has {BAXTER_JOINTS} joints")
