"""The end of a stream waits for the subscribers' acknowledgements (bearing_common.delivery)."""

import pytest

from bearing_common import delivery, topics


class FakePublisher:
    """Acknowledged after ``polls`` calls of ``wait_for_all_acked`` (never for None)."""

    def __init__(self, topic_name: str, polls: int | None):
        self.topic_name, self.polls, self.calls = topic_name, polls, 0

    def wait_for_all_acked(self, timeout) -> bool:
        assert timeout.nanoseconds == int(delivery.ACK_POLL_S * 1e9)
        self.calls += 1
        return self.polls is not None and self.calls >= self.polls


@pytest.fixture
def fast(monkeypatch):
    monkeypatch.setattr(delivery.time, "monotonic", iter(range(0, 10_000)).__next__)  # 1 s per look at the clock


def test_waits_for_every_publisher_until_acknowledged(fast):
    pubs = [FakePublisher(topics.VIBRATION.name, 3), FakePublisher(topics.SHAFT_SPEED.name, 1)]
    assert delivery.wait_acknowledged(pubs, timeout=100.0) == []
    assert [p.calls for p in pubs] == [3, 1]  # an acknowledged publisher is not asked again


def test_names_what_is_not_acknowledged_at_the_timeout(fast):
    pubs = [FakePublisher(topics.VIBRATION.name, None), FakePublisher(topics.TRUTH.name, 2)]
    assert delivery.wait_acknowledged(pubs, timeout=4.0) == [topics.VIBRATION.name]
    assert pubs[0].calls == 4  # one poll per second of the fake clock until the deadline


def test_a_stop_request_ends_the_wait():
    class Stop:
        def __init__(self):
            self.looks = 0

        def __bool__(self):
            self.looks += 1
            return self.looks > 2

    pub = FakePublisher(topics.UNBALANCE.name, None)
    assert delivery.wait_acknowledged([pub], timeout=3600.0, stop=Stop()) == [topics.UNBALANCE.name]
    assert pub.calls == 2
