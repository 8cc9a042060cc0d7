"""The walking tripod of Yang, Krut, Baradat and Pierrot (seed 003): modes, locks, walking.

- :mod:`pkdyn.tripod.locks`: lockable passive joints as rigid constraint models;
- :mod:`pkdyn.tripod.modes`: stances, modes PP and BE, the constraint set of each mode;
- :mod:`pkdyn.tripod.xfkmb`: the paper's ``B_iIKMX`` (locked values from the nacelle pose) and
  ``XFKMB_i`` (nacelle pose keeping the locked values, an optimisation);
- :mod:`pkdyn.tripod.machining`, :mod:`pkdyn.tripod.scenario`, :mod:`pkdyn.tripod.analysis`: the
  machining-and-walking scenario and its checks;
- the four-branch walker the paper proposes (``pkdyn.load("tripod", branches=4)``):
  :mod:`pkdyn.tripod.clearance` (closed-form clearances), :mod:`pkdyn.tripod.redundancy` (the
  nacelle path chosen while a foot swings), :mod:`pkdyn.tripod.compare` (tripod against walker).

The model itself is the library family :mod:`pkdyn.library.tripod`.
"""

from pkdyn.tripod.locks import LOCK_ARM, Lock, lock_constraint, lock_values
from pkdyn.tripod.modes import (
    BRANCHES,
    LOCKABLE,
    Mode,
    Stance,
    be_mode,
    branch_numbers,
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
    "branch_numbers",
    "foot_frame",
    "foot_placement",
    "lock_constraint",
    "lock_values",
    "locked_names",
    "mode_robot",
    "pp_mode",
    "support_branches",
]
