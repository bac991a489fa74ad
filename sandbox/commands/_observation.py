"""The observation options every data-reading command shares: ``--spec`` and ``--observe``.

``--spec FILE`` describes a recorded set's columns (YAML or JSON, see
:mod:`sandbox.data.spec`); ``--observe hand,arm,emg`` chooses the modalities
(names from the built-ins or the spec; default the spec's, ``hand``);
``--human-columns`` and ``--robot-columns`` are shorthands that rename the
hand's and the robot's columns of that spec (a joint-space robot part must be
Baxter's 7 arm joints: :func:`check_robot`); ``--session S`` draws a synthetic
set's recording session (:mod:`sandbox.data.synthetic.session`).
"""

from __future__ import annotations

import argparse

from sandbox.commands import _types

#: ``--time-unit`` choices (the spec's TIME_UNITS; not imported: --help stays light).
TIME_UNITS = ("s", "ms", "us", "ns")


def add_arguments(parser: argparse.ArgumentParser, *, columns: bool = True) -> None:
    """Add ``--spec``, ``--observe`` (and ``--human-columns``, ``--robot-columns``)."""
    parser.add_argument("--spec", default=None, metavar="FILE",
                        help="YAML/JSON file naming the time, robot and modality columns of a "
                             "recorded set (default: the Baxter recordings' layout)")
    parser.add_argument("--time-unit", default=None, choices=TIME_UNITS,
                        metavar="UNIT",
                        help="unit of the time column: s, ms, us or ns (default: the spec's "
                             "time_unit, else s); converted to seconds as the files are read")
    parser.add_argument("--observe", default=None, metavar="NAMES",
                        help="comma-separated modalities to observe: hand, arm (elbow + "
                             "shoulder), emg, or the spec's own (default: hand)")
    if columns:
        parser.add_argument("--human-columns", default=None, metavar="A,B,C",
                            help="columns of the hand (default human_left_hand_x,y,z)")
        parser.add_argument("--robot-columns", default=None, metavar="A,B,...",
                            help="robot columns (default left_s0 ... left_w2)")


def add_cache_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--no-cache`` (read with :func:`cache`)."""
    parser.add_argument("--no-cache", action="store_true",
                        help="load and preprocess every trial file afresh, without the on-disk "
                             "cache of loaded trials (python -m sandbox data cache)")


def add_session_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--session S`` (synthetic sets only; read as ``args.session``, None if not given)."""
    parser.add_argument("--session", type=_types.SEED, default=None, metavar="S",
                        help="recording session of a synthetic set, an integer >= 0: its seed "
                             "draws the tracker's calibration, where the fingertip meets the "
                             "hand, the tempo and the motion's tail (default: none, today's "
                             "data); refused for a folder or minari:ID")


def cache(args: argparse.Namespace):
    """The on-disk cache of loaded trials (:mod:`sandbox.data.cache`): False with
    ``--no-cache``; with ``--verbose``, one that names every entry it does not use."""
    if getattr(args, "no_cache", False):
        return False
    if getattr(args, "verbose", False):
        from sandbox.data.cache import TrialCache

        return TrialCache(verbose=True)
    return True


def split(text: str | None) -> list[str] | None:
    """``"a, b"`` -> ``["a", "b"]`` (None stays None)."""
    return None if text is None else [s.strip() for s in text.split(",") if s.strip()]


def data_spec(args: argparse.Namespace):
    """The :class:`~sandbox.data.spec.DataSpec` the options describe."""
    from sandbox.data.spec import resolve

    _columns_need_a_folder(args)
    spec = resolve(args.spec, human_columns=split(getattr(args, "human_columns", None)),
                   robot_columns=split(getattr(args, "robot_columns", None)),
                   time_unit=getattr(args, "time_unit", None))
    check_robot(spec)
    return spec


#: Joints of the arm the commands evaluate and drive (Baxter's left arm).
ARM_JOINTS = 7


def check_robot(spec) -> None:
    """Refuse a joint-space robot part that is not Baxter's 7-joint arm (``ValueError``):
    its forward kinematics (e_p) and the environments need exactly those joints."""
    if spec.robot_space == "joint" and len(spec.robot) != ARM_JOINTS:
        raise ValueError(f"robot: expected the {ARM_JOINTS} joint angles (rad) of Baxter's arm "
                         f"for a joint-space robot part, got {len(spec.robot)} columns "
                         f"{list(spec.robot)}; a position (m) is 'robot: {{columns: [...], "
                         f"space: task}}' in a spec file")


def _columns_need_a_folder(args: argparse.Namespace) -> None:
    """``--human-columns``/``--robot-columns`` rename a folder's columns: refused when every
    data source of the command is a ``synthetic:NAME`` set (its columns are its own)."""
    sources = [s for s in (getattr(args, "data", None), getattr(args, "test", None)) if s]
    if not sources or not all(str(s).startswith("synthetic:") for s in sources):
        return
    for option in ("human_columns", "robot_columns"):
        if getattr(args, option, None) is not None:
            raise ValueError(f"--{option.replace('_', '-')}: expected a recorded folder as "
                             f"--data (a synthetic set has its own columns), got "
                             f"--data {sources[0]}")


def observe(args: argparse.Namespace, spec=None) -> tuple[str, ...]:
    """The modalities chosen (checked against the spec; the spec's default if not given)."""
    spec = data_spec(args) if spec is None else spec
    return tuple(m.name for m in spec.observed(split(args.observe)))
