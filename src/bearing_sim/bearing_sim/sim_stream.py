"""The simulator node's signal as one endless stream of chunks (no rclpy).

Sample indices (and stamps = index / sample rate, s) continue across repeats of the
schedule and across live changes:

* ``noise_density`` changes from the next chunk on (:meth:`Simulator.set_noise_density`);
* ``rpm``: a live change restarts the simulation at the new constant speed from the
  static equilibrium at the next chunk, with the rest of the schedule, on the same time
  axis (replacing a speed profile). The signal therefore has one restart transient
  where the speed jumps. A planned speed change is a speed profile instead
  (``rpm_profile``, ``speed_wobble``): the shaft then turns continuously.

The shaft speed goes out as samples at ``speed_rate`` per second of signal time
(:meth:`SimulationStream.speed_samples`), the optional tachometer as the pulses of each
chunk (:meth:`SimulationStream.tacho_pulses`): the instants the simulated shaft passes
2π k / N, each moved by its own Gaussian timing error (seeded by the run's seed and the
pulse's number, so the same whatever the chunking).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from bearing_common.shaft_angle import pulse_times
from bearing_common.states import FaultState

from .sim_node_config import ENDLESS_SEGMENT_S, SimulationRun
from .simulator import SimChunk, Simulator

#: Tachometer timing errors are Gaussian truncated at this many standard deviations.
JITTER_TRUNCATION = 5.0


def remaining_schedule(schedule: list, elapsed: float, sample_rate: float) -> list:
    """The part of ``schedule`` [(state, s)] after ``elapsed`` s (remnants under half a sample dropped)."""
    out, start = [], 0.0
    for state, seconds in schedule:
        left = start + seconds - max(start, elapsed)
        if left > 0.5 / sample_rate:
            out.append((state, left))
        start += seconds
    return out


class SimulationStream:
    """Chunks of ``run`` (schedule None = normal operation without end), repeated if ``repeat``."""

    def __init__(self, run: SimulationRun, repeat: bool):
        self.schedule = run.schedule or [(FaultState.NORMAL, ENDLESS_SEGMENT_S)]
        self.repeat = repeat or run.schedule is None
        self.chunk_samples = run.chunk_samples
        self.config = run.config
        self.speed_rate = run.speed_rate
        self.tacho_per_rev, self.tacho_jitter = run.tacho_pulses, run.tacho_jitter
        self.sim = Simulator(self.config, self.schedule)
        self.index_offset = 0  # stream index of the current simulation's first sample
        self._restart_pending = False
        self._last_truth = None
        self._pulses_sent = 0  # tachometer pulses published so far
        self._pulse_base = 0  # pulse number of the current simulation's angle 0

    @property
    def sample_rate(self) -> float:
        """Hz."""
        return self.sim.sample_rate

    @property
    def rpm(self) -> float:
        """Shaft speed at the start of the current simulation (rev/min)."""
        return self.sim.config.initial_rpm

    def set_rpm(self, rpm: float) -> None:
        """Run at the constant ``rpm`` (rev/min) from the next chunk on."""
        self.config = dataclasses.replace(self.config, rpm=float(rpm), speed_profile=None)
        self._restart_pending = True

    def set_noise_density(self, noise_density: float) -> None:
        """Measurement noise density ((m/s^2)/sqrt(Hz)) from the next chunk on."""
        self.config = dataclasses.replace(self.config, noise_density=float(noise_density))
        self.sim.set_noise_density(self.config.noise_density)

    def next_chunk(self) -> SimChunk | None:
        """The next chunk, ``start_index`` and ``t0`` (s) on the stream's axis; None at the end."""
        if self._restart_pending:
            self._restart_pending = False
            rest = remaining_schedule(self.sim.schedule, self.sim.samples_done / self.sample_rate, self.sample_rate)
            if rest:
                self._restart(rest)
        if self.sim.finished:
            if not self.repeat:
                return None
            self._restart(self.schedule)
        chunk = self.sim.advance(self.chunk_samples)
        index = self.index_offset + chunk.start_index
        return SimChunk(index, index / self.sample_rate, chunk.accel, chunk.unbalance, chunk.truth,
                        chunk.shaft_speed)

    def _restart(self, schedule: list) -> None:
        self._pulse_base += self._pulse_count(self.sim.samples_done / self.sample_rate)
        self.index_offset += self.sim.samples_done
        self.sim = Simulator(self.config, schedule)

    def speed_samples(self, chunk: SimChunk) -> list:
        """[(stamp s, shaft speed rad/s)] at the multiples of 1/speed_rate s inside ``chunk``."""
        fs, rate = self.sample_rate, self.speed_rate
        first = math.ceil(chunk.start_index * rate / fs - 1e-9)
        end = math.ceil((chunk.start_index + len(chunk)) * rate / fs - 1e-9)
        stamps = np.arange(first, end) / rate
        omega = self.sim.shaft_speed(stamps - self.index_offset / fs)
        return list(zip(stamps.tolist(), np.atleast_1d(omega).tolist()))

    def tacho_pulses(self, chunk: SimChunk) -> tuple:
        """(pulse times s, number of the first) of the tachometer pulses inside ``chunk``:
        each the exact instant plus its own truncated-Gaussian error (module docstring)."""
        fs = self.sample_rate
        t0 = chunk.start_index / fs - self.index_offset / fs  # simulation time
        t1 = t0 + len(chunk) / fs
        margin = JITTER_TRUNCATION * self.tacho_jitter
        exact = pulse_times(self.sim.speed_profile, max(0.0, t0 - margin), t1 + margin, self.tacho_per_rev)
        numbers = self._pulse_base + self._pulse_count(exact, exact=True)
        errors = np.array([np.clip(np.random.default_rng((self.config.seed, 27, int(k))).standard_normal(),
                                   -JITTER_TRUNCATION, JITTER_TRUNCATION) for k in numbers])
        times = exact + self.tacho_jitter * errors.reshape(exact.shape)
        keep = (times >= t0) & (times < t1)
        first = self._pulses_sent
        self._pulses_sent += int(keep.sum())
        return np.sort(times[keep]) + self.index_offset / fs, first

    def _pulse_count(self, t, exact: bool = False):
        """Pulses of the current simulation up to time(s) t: its number of each exact pulse at t
        (``exact``), else how many passed before t."""
        step = 2.0 * math.pi / max(self.tacho_per_rev, 1)
        turns = np.asarray(self.sim.speed_profile.angle(t)) / step
        return np.rint(turns).astype(np.int64) if exact else int(math.ceil(float(turns) - 1e-9))

    def truth_changes(self, chunk: SimChunk) -> list:
        """[(state, onset s)] where the true state changes in ``chunk`` (or differs from the last chunk's)."""
        truth = chunk.truth
        changes = [0] if self._last_truth is None or truth[0] != self._last_truth else []
        changes += [int(i) + 1 for i in (truth[1:] != truth[:-1]).nonzero()[0]]
        self._last_truth = int(truth[-1])
        return [(FaultState(int(truth[i])), chunk.t0 + i / self.sample_rate) for i in changes]
