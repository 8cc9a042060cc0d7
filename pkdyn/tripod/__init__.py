"""The walking tripod of Yang, Krut, Baradat and Pierrot (seed 003): modes, locks, walking.

- :mod:`pkdyn.tripod.locks`: lockable passive joints as rigid constraint models;
- :mod:`pkdyn.tripod.modes`: stances, modes PP and BE, the constraint set of each mode;
- :mod:`pkdyn.tripod.xfkmb`: the paper's ``B_iIKMX`` (locked values from the nacelle pose) and
  ``XFKMB_i`` (nacelle pose keeping the locked values, an optimisation).

The model itself is the library family :mod:`pkdyn.library.tripod`.
"""

from pkdyn.tripod.locks import LOCK_ARM, Lock, lock_constraint, lock_values
from pkdyn.tripod.modes import (
    BRANCHES,
    LOCKABLE,
    Mode,
    Stance,
    be_mode,
    foot_frame,
    foot_placement,
    locked_names,
    mode_robot,
    pp_mode,
    support_branches,
)

__all__ = [
    "BRANCHES",
    "LOCKABLE",
    "LOCK_ARM",
    "Lock",
    "Mode",
    "Stance",
    "be_mode",
    "foot_frame",
    "foot_placement",
    "lock_constraint",
    "lock_values",
    "locked_names",
    "mode_robot",
    "pp_mode",
    "support_branches",
]
