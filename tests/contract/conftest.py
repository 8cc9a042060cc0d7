"""The contract harness's settings: hypothesis deterministic (derandomized, no example
database), a few examples per bad-input class, no deadline (each case has its own time limit)."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, Phase, settings

SHRINK = os.environ.get("PKDYN_CONTRACT_SHRINK", "1") != "0"
"""``PKDYN_CONTRACT_SHRINK=0``: report the first failing example as found (faster while
fixing)."""

settings.register_profile(
    "contract",
    derandomize=True,
    database=None,
    deadline=None,
    max_examples=int(os.environ.get("PKDYN_CONTRACT_EXAMPLES", "3")),
    print_blob=False,
    suppress_health_check=list(HealthCheck),
    phases=[p for p in Phase if SHRINK or p not in (Phase.shrink, Phase.explain)],
)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: a contract case run in real processes (seconds)")
