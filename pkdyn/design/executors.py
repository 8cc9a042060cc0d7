"""Where designs are evaluated: the executors of :mod:`pkdyn.executors`, under their old name.

The executors (this process, local worker processes, a Dask cluster) serve design studies, the
Monte Carlo of :mod:`pkdyn.precision.monte_carlo` and the precision maps alike: they live in
:mod:`pkdyn.executors` (below the analyses, which use them); this module keeps the names the
design studies have always imported.
"""

from pkdyn.executors import (
    MAX_TIMEOUT,
    DaskExecutor,
    Executor,
    ProcessExecutor,
    SerialExecutor,
    check_timeout,
    make_executor,
)

__all__ = [
    "MAX_TIMEOUT",
    "DaskExecutor",
    "Executor",
    "ProcessExecutor",
    "SerialExecutor",
    "check_timeout",
    "make_executor",
]
