"""Demonstrations: the container, recorded-data loading and synthetic handovers."""

from sandbox.data.demonstration import Demonstration, stack_tasks

__all__ = ["Demonstration", "stack_tasks"]
