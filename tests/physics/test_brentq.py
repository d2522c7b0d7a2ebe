"""atlas's Brent's method (atlas.physics.running._brentq) against scipy's brentq, the code it
transcribes: the same roots, bit for bit, on smooth, flat and steep functions; and the
tolerance honoured against the exact roots."""

import math

import pytest
from scipy.optimize import brentq

from atlas.physics.running import _brentq

CASES = [
    (lambda x: x**3 - 2.0 * x - 5.0, 2.0, 3.0),                # Wallis's cubic
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: math.exp(x) - 1e6, 0.0, 20.0),                  # steep
    (lambda x: (x - 0.3) ** 3, 0.0, 1.0),                      # flat at the root
    (lambda x: math.tanh(50.0 * (x - 0.123456789)), -1.0, 1.0),  # a step
]


@pytest.mark.parametrize("f, a, b", CASES)
@pytest.mark.parametrize("xtol, rtol", [(2e-12, 8.881784197001252e-16), (1e-15, 1e-13),
                                        (2e-12, 1e-3)])
def test_same_root_as_scipy(f, a, b, xtol, rtol):
    """The same root; or, where scipy's gives up after 100 iterations (a root too flat for
    the tolerance), atlas's too."""
    try:
        expected = brentq(f, a, b, xtol=xtol, rtol=rtol)
    except RuntimeError:
        with pytest.raises(RuntimeError):
            _brentq(f, a, b, xtol=xtol, rtol=rtol)
        return
    assert _brentq(f, a, b, xtol=xtol, rtol=rtol) == expected


def test_tolerance_against_exact_roots():
    assert _brentq(lambda x: x * x - 2.0, 0.0, 2.0, xtol=1e-15) == pytest.approx(
        math.sqrt(2.0), abs=2e-15)
    assert _brentq(lambda x: math.sin(x), 3.0, 4.0, xtol=1e-15) == pytest.approx(math.pi,
                                                                               abs=2e-15)
    with pytest.raises(ValueError):
        _brentq(lambda x: x * x + 1.0, -1.0, 1.0)
