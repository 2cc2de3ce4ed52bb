"""Re-cutting a chunked stream (bearing-bag play --chunk-duration): indices, stamps, runs."""

import numpy as np
import pytest

from bearing_recordings.rechunk import NS_PER_S, Rechunker, SampleChunk

FS = 48000.0


def recorded(n_chunks, n, first=0, stamp0_ns=3 * NS_PER_S + 17, fs=FS, source="cwru", frame="drive_end"):
    """``n_chunks`` consecutive chunks of ``n`` samples, samples = their stream index."""
    return [SampleChunk(stamp0_ns + round(k * n * NS_PER_S / fs), first + k * n, fs, source, frame,
                        np.arange(first + k * n, first + (k + 1) * n, dtype=float)) for k in range(n_chunks)]


def recut(chunks, duration):
    r = Rechunker(duration)
    out = [c for chunk in chunks for c in r.push(chunk)]
    return out + r.flush()


@pytest.mark.parametrize("n_in, duration", [(480, 0.1), (480, 1.0), (4800, 0.01), (4800, 0.0123), (333, 0.1)])
def test_every_sample_keeps_its_index_and_every_stamp_is_its_first_samples_time(n_in, duration):
    chunks = recorded(25, n_in)
    out = recut(chunks, duration)
    n = int(round(duration * FS))
    assert [c.samples.size for c in out[:-1]] == [n] * (len(out) - 1) and 0 < out[-1].samples.size <= n
    joined = np.concatenate([c.samples for c in out])
    np.testing.assert_array_equal(joined, np.arange(25 * n_in))  # nothing lost, repeated or moved
    for c in out:
        assert c.samples[0] == c.first_index
        holder = max((r for r in chunks if r.first_index <= c.first_index), key=lambda r: r.first_index)
        assert c.stamp_ns == holder.stamp_ns + round((c.first_index - holder.first_index) * NS_PER_S / FS)
        assert (c.sample_rate, c.source, c.frame_id) == (FS, "cwru", "drive_end")


def test_a_cut_on_a_recorded_boundary_keeps_the_recorded_stamp_exactly():
    chunks = recorded(20, 480, stamp0_ns=1_700_000_000 * NS_PER_S + 123_456_789)
    out = recut(chunks, 0.1)  # 4800 samples = 10 recorded chunks
    assert [c.stamp_ns for c in out] == [chunks[0].stamp_ns, chunks[10].stamp_ns]


def test_a_chunk_is_complete_only_when_its_last_sample_has_arrived():
    r = Rechunker(0.1)
    chunks = recorded(20, 480)
    emitted = [len(r.push(c)) for c in chunks]
    assert emitted == [0] * 9 + [1] + [0] * 9 + [1]


def test_a_gap_a_restart_or_another_rate_ends_the_run_with_its_shorter_chunk():
    first = recorded(3, 480)  # indices 0..1439
    after_gap = recorded(3, 480, first=2400, stamp0_ns=first[0].stamp_ns + round(2400 * NS_PER_S / FS))
    restarted = recorded(2, 480, first=0, stamp0_ns=10 * NS_PER_S)
    other_rate = recorded(2, 120, first=960, fs=12000.0, stamp0_ns=20 * NS_PER_S)
    out = recut(first + after_gap + restarted + other_rate, 0.05)  # 2400 samples at 48 kHz
    assert [(c.first_index, c.samples.size) for c in out] == [(0, 1440), (2400, 1440), (0, 960), (960, 240)]
    assert out[1].stamp_ns == after_gap[0].stamp_ns and out[2].stamp_ns == 10 * NS_PER_S
    assert out[3].sample_rate == 12000.0
    # another source or frame ends a run too
    other_source = recorded(1, 480, first=1440, source="probe")
    assert [c.source for c in recut(first + other_source, 1.0)] == ["cwru", "probe"]


def test_empty_chunks_and_bad_durations():
    r = Rechunker(0.01)
    assert r.push(SampleChunk(0, 0, FS, "s", "f", np.empty(0))) == [] and r.flush() == []
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="chunk duration must be positive"):
            Rechunker(bad)
