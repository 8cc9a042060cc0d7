import pytest

import pkdyn


@pytest.fixture(scope="session")
def delta() -> pkdyn.Robot:
    return pkdyn.load("delta")


@pytest.fixture(scope="session")
def gough_stewart() -> pkdyn.Robot:
    return pkdyn.load("gough_stewart")
