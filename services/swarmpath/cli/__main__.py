"""``python -m swarmpath.cli ...``: the same as the ``swarmpath`` console script."""

from swarmpath.cli import main

if __name__ == "__main__":
    main()
