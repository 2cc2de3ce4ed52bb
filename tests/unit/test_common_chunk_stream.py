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


@pytest.mark.filterwarnings("ignore:overflow encountered in reduce:RuntimeWarning",
                            "ignore:invalid value encountered in reduce:RuntimeWarning")
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_finite_samples_whose_sum_overflows_are_accepted(dtype):
    """The finite check sums the samples first; a sum that overflows (NumPy warns) is checked sample by
    sample."""
    big = np.full(480, np.finfo(dtype).max / 2, dtype=dtype)
    stream = ChunkStream("vib", sample_rate=FS)
    assert stream.check(0.0, 0, FS, big).accepted
    t, i, fs, _ = chunk(1)
    v = stream.check(t, i, fs, np.where(np.arange(480) == 7, -np.inf, big).astype(dtype))
    assert not v.accepted and "non-finite samples: 1 NaN/inf of 480" in v.reason


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


# -- snapshot sensors: a short chunk now and then, each a snapshot of its own ------------------------

def snapshot(k, n=2560, interval=60.0, index="continued", fs=25600.0):
    """Snapshot ``k`` of a sensor sending ``n`` samples every ``interval`` s, its sample index
    numbered as some sensors do: on as if sampling never stopped, on without the pause, or from 0."""
    first = {"continued": int(round(k * interval * fs)), "packed": k * n, "zero": 0}[index]
    return k * interval, first, fs, np.ones(n)


@pytest.mark.parametrize("index", ["continued", "packed", "zero"])
def test_snapshot_mode_takes_every_paused_chunk_as_a_new_snapshot(index):
    stream = ChunkStream("vib", input_mode="snapshot")
    verdicts = [stream.check(*snapshot(k, index=index)) for k in range(5)]
    assert all(v.accepted and v.resync and v.snapshot and not v.restart for v in verdicts)
    assert [v.reason for v in verdicts[1:]] == [""] * 4  # nothing to log for a snapshot's pause
    assert stream.counts["snapshots"] == 5 and stream.counts["gaps"] == 0


@pytest.mark.parametrize("index", ["continued", "packed", "zero"])
def test_auto_mode_recognises_a_snapshot_sensor_at_its_second_snapshot(index):
    stream = ChunkStream("vib", input_mode="auto")
    verdicts = [stream.check(*snapshot(k, index=index)) for k in range(5)]
    assert all(v.accepted and v.resync and not v.restart for v in verdicts)
    assert [v.snapshot for v in verdicts] == [False, True, True, True, True]
    assert "snapshot sensor" in verdicts[1].reason and [v.reason for v in verdicts[2:]] == [""] * 3
    assert stream.counts["snapshots"] == 5 and stream.counts["gaps"] == 0  # the first chunk counted too


def test_auto_mode_keeps_a_stream_with_a_lost_chunk_a_stream():
    stream = ChunkStream("vib", input_mode="auto")
    verdicts = [stream.check(*chunk(i)) for i in (0, 1, 2, 4, 5, 6)]  # chunk 3 lost
    assert not any(v.snapshot for v in verdicts)
    assert "gap of 480 samples" in verdicts[3].reason and stream.counts["gaps"] == 1
    assert stream.counts["snapshots"] == 0


def test_auto_mode_returns_to_a_stream_when_chunks_continue_each_other():
    stream = ChunkStream("vib", input_mode="auto")
    verdicts = [stream.check(*chunk(i)) for i in (0, 2, 4, 5, 6)]  # one-chunk stretches, then a stream
    assert [v.snapshot for v in verdicts] == [False, True, True, False, False]
    assert "a stream again" in verdicts[3].reason and not verdicts[3].resync
    assert stream.counts["snapshots"] == 3 and stream.counts["gaps"] == 0


def test_snapshots_going_back_in_time_are_refused_and_a_replay_from_zero_is_a_restart():
    stream = ChunkStream("vib", input_mode="snapshot")
    for k in range(3):
        stream.check(*snapshot(k))
    t, i, fs, x = snapshot(1)
    assert "out-of-order" in stream.check(t, i, fs, x).reason
    v = stream.check(*snapshot(0))  # index 0 at the first snapshot's time: the replay began again
    assert v.accepted and v.restart and v.reason == "stream restarted"


def test_stream_mode_counts_a_snapshot_sensors_pauses_as_gaps():
    stream = ChunkStream("vib")
    verdicts = [stream.check(*snapshot(k)) for k in range(3)]
    assert not any(v.snapshot for v in verdicts) and stream.counts["gaps"] == 2


def test_an_unknown_input_mode_is_refused():
    with pytest.raises(ValueError, match="input_mode must be one of auto, stream, snapshot"):
        ChunkStream("vib", input_mode="burst")
