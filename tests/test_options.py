"""Scalar option validation (geotex.options): one behaviour everywhere."""

import math

import numpy as np
import pytest

from geotex.errors import InputError
from geotex.options import count, finite_number, positive_number


@pytest.mark.parametrize("value", [1, 2.5, np.float32(0.5), np.int64(3)])
def test_numbers_are_accepted_as_plain_floats(value):
    out = positive_number(value, name="size")
    assert type(out) is float and out == float(value)
    assert type(finite_number(-value, name="x")) is float


@pytest.mark.parametrize("value", [0, -1.0, math.nan, math.inf, True, "2", None, [1.0]])
def test_positive_number_refuses_with_the_name(value):
    with pytest.raises(InputError, match=r"^size must be a positive number, got "):
        positive_number(value, name="size")


@pytest.mark.parametrize("value", [math.nan, -math.inf, False, "1", None])
def test_finite_number_refuses(value):
    with pytest.raises(InputError, match="^angle must be a finite number"):
        finite_number(value, name="angle")


def test_count():
    assert count(np.int32(4), name="n") == 4 and type(count(4, name="n")) is int
    assert count(0, name="n", minimum=0) == 0
    for bad in (0, 2.0, True, "3", -5):
        with pytest.raises(InputError, match=r"^n must be an integer >= 1, got "):
            count(bad, name="n")
