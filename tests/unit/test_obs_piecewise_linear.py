"""Monotone piecewise-linear blocks f, g (thesis section 2.4, appendix E)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_observer.piecewise_linear import MonotonePiecewiseLinear


def test_eval_inverse_roundtrip_including_extrapolation():
    g = MonotonePiecewiseLinear([-2.0, 0.0, 1.0, 3.0], [-10.0, 0.0, 1.0, 7.0])
    v = np.linspace(-5, 6, 1001)
    assert_allclose(g.inverse(g(v)), v, atol=1e-12)
    assert_allclose(g([-3.0, 0.5, 4.0]), [-15.0, 0.5, 10.0])  # end slopes 5 and 3
    assert g.slope_at(2.0) == pytest.approx(3.0)


def test_dict_roundtrip_and_identity():
    g = MonotonePiecewiseLinear.gain(2.5)
    h = MonotonePiecewiseLinear.from_dict(g.to_dict())
    assert_allclose(h(np.array([-4.0, 1.0])), [-10.0, 2.5])
    assert MonotonePiecewiseLinear.identity().is_identity()


@pytest.mark.parametrize("x,y,msg", [
    ([0, 1], [1, 1], "strictly increasing"),
    ([0, 0], [0, 1], "strictly increasing"),
    ([0], [0], "length"),
    ([0, np.nan], [0, 1], "finite"),
])
def test_rejects_non_monotone_or_bad(x, y, msg):
    with pytest.raises(ValueError, match=msg):
        MonotonePiecewiseLinear(x, y)
