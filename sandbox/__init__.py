"""Anticipatory human-robot handovers with Dynamic Interaction ProMPs.

The package is split so that heavy dependencies stay where they are used:

- :mod:`sandbox.core`: the method (numpy/scipy only).
- :mod:`sandbox.data`: demonstrations, recorded-data loading, synthetic handovers.
- :mod:`sandbox.robot`: the Baxter model (PyBullet, example-robot-data).
- :mod:`sandbox.envs`: Gymnasium environments.
- :mod:`sandbox.viz`: the meshcat viewer.
- :mod:`sandbox.episodes`: policies meet environments: the one rollout loop,
  scenarios and scenario files, recorded episodes, the keyboard teleop.
- :mod:`sandbox.eval`, :mod:`sandbox.bench`, :mod:`sandbox.commands`: evaluation,
  benchmarks and the command line on top.

Importing :mod:`sandbox` itself imports nothing heavy.
"""

__version__ = "0.1.0"
