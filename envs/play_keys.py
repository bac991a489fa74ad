"""Keys for Gymnasium's ``play``: the keyboard plays the robot, choosing where to meet the hand.

:func:`gymnasium.utils.play.play` maps pressed keys to a fixed *action*. Here
the action is the robot's (seven joint targets and a gripper command), so the
keyboard plays Baxter while the human hand follows the environment's own
motion (synthetic, recorded or scripted)::

    import gymnasium as gym
    from gymnasium.utils.play import play   # needs pygame and a display

    import sandbox.envs
    from sandbox.envs.play_keys import keys_to_action

    mapping, noop = keys_to_action("diverging")
    env = gym.make("sandbox/BaxterHandoverDiverging-v1", render_mode="rgb_array")
    play(env, keys_to_action=mapping, noop=noop, seed=0)

Key ``1`` .. ``K`` moves the arm to the handover pose of the family's k-th
task (:func:`sandbox.envs.sources.family_tasks` order), gripper open; the same key
with space closes the gripper there; no key: the home pose, gripper open.
Driving the *human* hand is not an action, so ``play`` cannot do it: that is
what ``python -m sandbox play`` (:mod:`sandbox.episodes.keyboard`) is for.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sandbox.robot import Q_HOME

#: Gripper commands of the mapping.
OPEN, CLOSE = -1.0, 1.0


def handover_poses(family: str, *, n_per_task: int = 3, seed: int = 0
                   ) -> dict[str, NDArray[np.float64]]:
    """Task -> the robot's mean final joints (7,) rad over ``n_per_task`` synthetic demos.

    The synthetic robot ends each demo at the handover (IK to the meeting
    point), so this is where the arm takes the object for that task.
    """
    from sandbox.data.synthetic import make_dataset
    from sandbox.envs.sources import FAMILIES, family_tasks

    if family not in FAMILIES:
        raise ValueError(f"family: expected one of {list(FAMILIES)}, got {family!r}")
    demos = make_dataset(family, n_per_task, np.random.default_rng(seed))
    return {t: np.mean([d.robot[-1] for d in demos if d.task == t], axis=0)
            for t in family_tasks(family)}


def keys_to_action(family: str = "diverging", *, n_per_task: int = 3, seed: int = 0
                   ) -> tuple[dict, NDArray[np.float64]]:
    """``(keys_to_action, noop)`` for :func:`gymnasium.utils.play.play` (module docstring).

    Returns
    -------
    keys_to_action : dict
        ``"k"`` -> task k's handover pose with the gripper open, ``("k", " ")``
        -> the same pose with it closed; actions of shape (8,).
    noop : ndarray, shape (8,)
        The home pose, gripper open.
    """
    poses = handover_poses(family, n_per_task=n_per_task, seed=seed)
    if len(poses) > 9:
        raise ValueError(f"family: expected at most 9 tasks for keys 1-9, got {len(poses)}")
    mapping: dict = {}
    for k, q in enumerate(poses.values(), start=1):
        mapping[str(k)] = np.append(q, OPEN)
        mapping[(str(k), " ")] = np.append(q, CLOSE)
    return mapping, np.append(Q_HOME, OPEN)
