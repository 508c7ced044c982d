"""``python -m snoworm``: the command-line interface (:mod:`snoworm.cli`)."""

from .cli import main

if __name__ == "__main__":  # pragma: no branch
    main(prog_name="snoworm")
