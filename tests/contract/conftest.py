"""The contract harness's settings: hypothesis deterministic (derandomized, no example
database), a few examples per bad-input class, no deadline (each case has its own time limit)."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, Phase, settings

settings.register_profile(
    "contract",
    derandomize=True,
    database=None,
    deadline=None,
    max_examples=int(os.environ.get("PKDYN_CONTRACT_EXAMPLES", "3")),
    print_blob=False,
    suppress_health_check=list(HealthCheck),
    # PKDYN_CONTRACT_SHRINK=0: report the first failing example as found (faster while fixing)
    phases=[
        p
        for p in Phase
        if os.environ.get("PKDYN_CONTRACT_SHRINK", "1") != "0"
        or p not in (Phase.shrink, Phase.explain)
    ],
)
