"""ChunkStream: bad chunks are rejected with reasons and counted; gaps force a resync."""

import numpy as np
import pytest

from bearing_common.chunk_stream import ChunkStream

FS = 48000.0


def chunk(i, n=480):
    return i * n / FS, i * n, FS, np.ones(n)


def test_contiguous_stream_resyncs_only_at_start():
    stream = ChunkStream("vib")
    verdicts = [stream.check(*chunk(i)) for i in range(5)]
    assert all(v.accepted for v in verdicts)
    assert [v.resync for v in verdicts] == [True, False, False, False, False]
    assert stream.counts["accepted"] == 5 and stream.counts["rejected"] == 0


def test_gap_is_accepted_with_resync_and_counted():
    stream = ChunkStream("vib")
    stream.check(*chunk(0))
    v = stream.check(*chunk(2))  # chunk 1 lost
    assert v.accepted and v.resync and "gap of 480 samples" in v.reason
    assert stream.counts["gaps"] == 1


@pytest.mark.parametrize("mutate, reason", [
    (lambda t, i, fs, x: (t, i, 0.0, x), "not plausible"),
    (lambda t, i, fs, x: (t, i, 1.2e-7, x), "not plausible"),
    (lambda t, i, fs, x: (t, i, float("nan"), x), "not plausible"),
    (lambda t, i, fs, x: (t, i, 12000.0, x), "wrong sample rate"),
    (lambda t, i, fs, x: (t, i, fs, x[:0]), "empty chunk"),
    (lambda t, i, fs, x: (t, i, fs, np.where(np.arange(len(x)) == 3, np.inf, x)), "non-finite samples"),
    (lambda t, i, fs, x: (t, i, fs, np.ones(3_000_000)), "huge chunk"),
])
def test_bad_chunks_are_rejected_with_reason(mutate, reason):
    stream = ChunkStream("vib", sample_rate=FS)
    stream.check(*chunk(0))
    v = stream.check(*mutate(*chunk(1)))
    assert not v.accepted and reason in v.reason
    assert stream.counts["rejected"] == 1


def test_out_of_order_and_duplicate_stamps_are_rejected():
    stream = ChunkStream("vib")
    stream.check(*chunk(0))
    stream.check(*chunk(1))
    assert "out-of-order" in stream.check(*chunk(1)).reason
    t, i, fs, x = chunk(3)
    assert "out-of-order" in stream.check(0.001, i, fs, x).reason


def test_nan_chunk_forces_resync_on_next_chunk():
    stream = ChunkStream("vib")
    stream.check(*chunk(0))
    t, i, fs, x = chunk(1)
    assert not stream.check(t, i, fs, x * np.nan).accepted
    v = stream.check(*chunk(2))
    assert v.accepted and v.resync


def test_restarted_producer_is_followed():
    stream = ChunkStream("vib")
    for i in range(3):
        stream.check(*chunk(i))
    v = stream.check(*chunk(0))
    assert v.accepted and v.resync and v.reason == "stream restarted"


def test_restarted_producer_is_followed_when_its_first_chunks_were_missed():
    stream = ChunkStream("vib")
    for i in range(100, 103):
        stream.check(*chunk(i))
    v = stream.check(*chunk(2))  # chunks 0 and 1 of the new run never arrived
    assert v.accepted and v.resync and v.restart and v.reason == "stream restarted"
    assert stream.check(*chunk(3)).accepted


def test_restarted_sensor_with_a_running_clock_is_followed():
    stream = ChunkStream("vib")
    for i in range(100, 103):
        stream.check(*chunk(i))
    t, i, fs, x = chunk(2)
    v = stream.check(t + 10.0, i, fs, x)  # a driver restarted 10 s later; its first two chunks lost
    assert v.accepted and v.restart and v.reason == "stream restarted"


def test_a_refused_chunk_claiming_a_restart_changes_nothing():
    stream = ChunkStream("vib")
    for i in range(3):
        stream.check(*chunk(i))
    t, i, fs, x = chunk(0)
    assert not stream.check(t + 5.0, i, 0.0, x).accepted  # index 0, but a malformed rate
    v = stream.check(*chunk(3))
    assert v.accepted and not v.resync and not v.restart
