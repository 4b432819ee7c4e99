"""``python -m chaospound.cli``: the command line (as ``python -m chaospound``)."""

from chaospound.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
