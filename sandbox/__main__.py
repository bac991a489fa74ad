"""``python -m sandbox``: the command-line entry point."""

from sandbox.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
