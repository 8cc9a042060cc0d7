"""``python -m pkdyn``: the ``pkdyn`` command line."""

from pkdyn.cli import run

if __name__ == "__main__":  # importing the module (e.g. the docs build) runs nothing
    run()
