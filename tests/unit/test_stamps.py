"""Header stamps to and from seconds, including the nanosecond carry."""

import pytest

from bearing_common.stamps import to_seconds, to_stamp


@pytest.mark.parametrize("t, sec, nanosec", [(0.0, 0, 0), (0.01, 0, 10_000_000), (12.345, 12, 345_000_000),
                                             (0.9999999999, 1, 0), (1.9999999996, 2, 0)])
def test_to_stamp_rounds_and_carries(t, sec, nanosec):
    stamp = to_stamp(t)
    assert (stamp.sec, stamp.nanosec) == (sec, nanosec)


def test_round_trip_is_exact_to_a_nanosecond():
    for i in range(0, 48000 * 3, 480):
        t = i / 48000.0
        assert to_seconds(to_stamp(t)) == pytest.approx(t, abs=1e-9)
