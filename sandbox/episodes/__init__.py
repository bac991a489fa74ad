"""The episodes layer: where a policy meets an environment.

- :mod:`~sandbox.episodes.policy`: the :class:`~sandbox.episodes.policy.Policy`
  protocol (``reset()``, ``policy(obs) -> action``, read-only ``beliefs``) and
  :class:`~sandbox.episodes.policy.Beliefs`.
- :mod:`~sandbox.episodes.policies`: the Interaction ProMP controllers
  (:class:`~sandbox.episodes.policies.IProMPPolicy`, the static baseline, the
  recorded robot).
- :mod:`~sandbox.episodes.rollout`: the one episode loop,
  :func:`~sandbox.episodes.rollout.rollout`; every runner below is built on it.
- :mod:`~sandbox.episodes.scenarios`: seeded scenario runs (``episodes`` command).
- :mod:`~sandbox.episodes.scenario_files` (reading, validating) and
  :mod:`~sandbox.episodes.scenario_runner` (running): JSON/YAML scenario files
  (``play --scenario``; examples in ``scenario_examples/``).
- :mod:`~sandbox.episodes.recording`: an episode recorded (beliefs, outcome, replay).
- :mod:`~sandbox.episodes.keyboard`: the keyboard teleop runner (``play``);
  :mod:`~sandbox.episodes.demos_recording`: its episodes saved as demonstrations.
- :mod:`~sandbox.episodes.minari_export`: Minari datasets written (they name an env id).

It may import the core, data, robot, environments and viewer
(``tests/test_layering.py``). Importing it imports nothing heavy.
"""
