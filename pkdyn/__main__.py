"""``python -m pkdyn``: the ``pkdyn`` command line."""

import sys

from pkdyn.cli import main

sys.exit(main())
