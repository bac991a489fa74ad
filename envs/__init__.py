"""Gymnasium handover environments, installed as :mod:`sandbox.envs`."""
