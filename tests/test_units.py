import math

import numpy as np
import pytest

from pkdyn.units import quantity, value_range, vector


@pytest.mark.parametrize(
    ("value", "unit", "text"),
    [
        (5.328e-5, "m", "53.28 um"),
        (0.0005201, "m", "520.1 um"),
        (2.0e4, "N m/rad", "20 kN m/rad"),
        (0.0113, "m", "11.3 mm"),
        (1.0, "m", "1 m"),
        (0.0, "m", "0 m"),
        (-0.0, "m", "0 m"),
        (999.99999, "N", "1 kN"),
        (0.25, "s", "250 ms"),
        (12.5, "s", "12.5 s"),
        (3.14159, "rad", "3.142 rad"),
        (120.0, "Hz", "120 Hz"),
        (-4.2e-7, "m", "-420 nm"),
        (float("nan"), "m", "n/a"),
        (math.inf, "N/m", "inf N/m"),
        (-math.inf, "N/m", "-inf N/m"),
        (0.5, "", "0.5"),
        (0.2066773, "m^2", "0.2067 m^2"),
        (0.03784269, "m^3", "0.03784 m^3"),
        (0.01, "kg m^2", "10 g m^2"),
        (2.5e-6, "kg", "2.5 mg"),
        (2000.0, "kg", "2000 kg"),
        (-1.304e-10, "m", "-130.4 pm"),
        (1234.0, "rad", "1234 rad"),
        (123456.0, "rad", "123500 rad"),
    ],
)
def test_quantity(value, unit, text):
    assert quantity(value, unit) == text


def test_vector_has_no_negative_zero():
    assert vector([0.0, -0.0, 0.1], "rad") == "[0, 0, 0.1] rad"
    assert vector([1e-20, -2.5], "m", digits=3) == "[1e-20, -2.5] m"


def test_value_range_over_finite_values_any_shape():
    x = np.array([[2.0e-5, np.nan], [np.inf, 5.3e-5]])
    assert value_range("d", x, "m") == "d 20 um .. 53 um"
    assert value_range("LCI", [np.nan, np.nan]) == "LCI: none"
