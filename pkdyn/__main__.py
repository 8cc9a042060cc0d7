"""``python -m pkdyn``: the ``pkdyn`` command line."""

from pkdyn.cli import run

run()
