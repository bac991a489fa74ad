"""``python -m sandbox``: the command-line entry point (:func:`sandbox.cli.run`)."""

if __name__ == "__main__":
    try:
        from sandbox.cli import run
    except KeyboardInterrupt:      # Ctrl-C while Python imports the package: quietly, 130
        raise SystemExit(130) from None
    run()
