"""``python -m pkdyn.cli``."""

import sys

from pkdyn.cli import main

sys.exit(main())
