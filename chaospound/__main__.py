"""``python -m chaospound``: the command line (see :mod:`chaospound.cli`)."""

from chaospound.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
