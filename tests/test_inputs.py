"""pkdyn.inputs: number arrays refused with the input named, whatever shape the bad value has."""

from __future__ import annotations

import numpy as np
import pytest

from pkdyn.exceptions import InvalidInputError
from pkdyn.inputs import number_array, vector


@pytest.mark.parametrize("bad", ["1 2", b"1", {"a": 1}, 1j, [1.0, 2j], [[1.0], [2.0, 3.0]]])
def test_number_array_refuses_non_numbers(bad: object) -> None:
    with pytest.raises(InvalidInputError, match=r"^wrench: expected numbers \[N, N m\], got"):
        number_array("wrench", bad, "numbers [N, N m]")
    with pytest.raises(InvalidInputError, match="^x: expected numbers, got"):
        vector("x", bad)


def test_number_array_flattens_and_keeps_non_finite_values() -> None:
    out = number_array("x", [[1, 2], [np.inf, np.nan]])
    assert out.shape == (4,) and out.dtype == float
    assert out[0] == 1.0 and np.isinf(out[2]) and np.isnan(out[3])
