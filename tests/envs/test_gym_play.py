"""Gymnasium's ``play`` drives the robot with :mod:`sandbox.envs.play_keys`, headless.

``gymnasium.utils.play`` needs pygame and switches matplotlib to TkAgg when
imported, so it runs in a subprocess with SDL's dummy video driver; the
callback ``play`` calls after every step posts the key events (a scripted
keyboard).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from sandbox.envs.play_keys import CLOSE, OPEN, handover_poses, keys_to_action
from sandbox.robot import Q_HOME

#: Step after which "2" is pressed, then space with it, then the window is closed.
PRESS_2, PRESS_SPACE, QUIT = 3, 120, 160

SCRIPT = f"""
import json, os
os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"
import gymnasium as gym
import pygame
from gymnasium.utils.play import play

import sandbox.envs
from sandbox.envs.play_keys import keys_to_action

mapping, noop = keys_to_action("diverging")
env = gym.make("sandbox/BaxterHandoverDiverging-v1", render_mode="rgb_array",
               max_episode_steps=1000)
log = []

def keyboard(obs_t, obs_tp1, action, reward, terminated, truncated, info):
    log.append({{"action": action.tolist(), "q": obs_tp1["q"].tolist(),
                "gripper": float(obs_tp1["gripper"][0]), "done": terminated or truncated}})
    events = {{{PRESS_2}: (pygame.KEYDOWN, ord("2")), {PRESS_SPACE}: (pygame.KEYDOWN, ord(" ")),
              {QUIT}: (pygame.QUIT, None)}}
    if len(log) in events:
        kind, key = events[len(log)]
        pygame.event.post(pygame.event.Event(kind, key=key) if key else pygame.event.Event(kind))

play(env, keys_to_action=mapping, noop=noop, seed=0, fps=1000, callback=keyboard)
env.close()
print("LOG " + json.dumps(log))
"""


@pytest.fixture(scope="module")
def played():
    pytest.importorskip("pygame")
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         timeout=600, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert out.returncode == 0, out.stderr[-3000:]
    line = next(s for s in out.stdout.splitlines() if s.startswith("LOG "))
    return json.loads(line[4:])


def test_keys_map_to_handover_poses_within_the_action_space(diverging_env):
    mapping, noop = keys_to_action("diverging")
    poses = list(handover_poses("diverging").values())
    assert len(mapping) == 2 * len(poses) == 10
    np.testing.assert_array_equal(noop, np.append(Q_HOME, OPEN))
    np.testing.assert_array_equal(mapping["2"], np.append(poses[1], OPEN))
    np.testing.assert_array_equal(mapping[("2", " ")], np.append(poses[1], CLOSE))
    assert all(diverging_env.action_space.contains(a) for a in [noop, *mapping.values()])
    assert min(np.linalg.norm(p - Q_HOME) for p in poses) > 0.1  # the keys do move the arm


@pytest.mark.slow
def test_play_steps_the_key_actions_and_the_arm_follows(played):
    mapping, noop = keys_to_action("diverging")
    actions = np.array([step["action"] for step in played])
    assert len(played) == QUIT and not any(step["done"] for step in played)
    assert (actions[:PRESS_2] == noop).all()                         # no key yet
    assert (actions[PRESS_2:PRESS_SPACE] == mapping["2"]).all()
    assert (actions[PRESS_SPACE:] == mapping[("2", " ")]).all()
    target = mapping["2"][:7]
    q = np.array([step["q"] for step in played])
    start, reached = np.linalg.norm(q[PRESS_2] - target), np.linalg.norm(q[PRESS_SPACE] - target)
    assert reached < start / 4, (start, reached)
    gripper = np.array([step["gripper"] for step in played])
    assert (gripper[:PRESS_SPACE] > 0.99).all() and gripper[-1] < 0.05   # open, then closed


def test_an_unknown_family_is_refused():
    with pytest.raises(ValueError, match="family"):
        keys_to_action("cups")
