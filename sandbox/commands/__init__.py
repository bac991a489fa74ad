"""Subcommands of ``python -m sandbox``; one module per command (see :mod:`sandbox.cli`)."""
