"""The simulator node's signal as one endless stream of chunks (no rclpy).

Sample indices (and stamps = index / sample rate, s) continue across repeats of the
schedule and across live changes:

* ``noise_density`` changes from the next chunk on (:meth:`Simulator.set_noise_density`);
* ``rpm``: the 29-DOF model cannot change speed mid-run (the shaft, cage and defect
  angles are ω·t in the compiled model), so at the next chunk the simulation restarts
  at the new speed from the static equilibrium, with the rest of the schedule, on the
  same time axis. The signal therefore has one restart transient where the speed changes.
"""

from __future__ import annotations

import dataclasses

from bearing_common.states import FaultState

from .sim_node_config import SimulationRun
from .simulator import SimChunk, Simulator

ENDLESS_SEGMENT_S = 3600.0  #: s; normal operation without a schedule: hour-long segments, repeated


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
        self.sim = Simulator(self.config, self.schedule)
        self.index_offset = 0  # stream index of the current simulation's first sample
        self._restart_pending = False
        self._last_truth = None

    @property
    def sample_rate(self) -> float:
        """Hz."""
        return self.sim.sample_rate

    @property
    def rpm(self) -> float:
        """Shaft speed of the last chunk (rev/min)."""
        return self.sim.config.rpm

    def set_rpm(self, rpm: float) -> None:
        """Run at ``rpm`` (rev/min) from the next chunk on."""
        self.config = dataclasses.replace(self.config, rpm=float(rpm))
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
        return SimChunk(index, index / self.sample_rate, chunk.accel, chunk.unbalance, chunk.truth)

    def _restart(self, schedule: list) -> None:
        self.index_offset += self.sim.samples_done
        self.sim = Simulator(self.config, schedule)

    def truth_changes(self, chunk: SimChunk) -> list:
        """[(state, onset s)] where the true state changes in ``chunk`` (or differs from the last chunk's)."""
        truth = chunk.truth
        changes = [0] if self._last_truth is None or truth[0] != self._last_truth else []
        changes += [int(i) + 1 for i in (truth[1:] != truth[:-1]).nonzero()[0]]
        self._last_truth = int(truth[-1])
        return [(FaultState(int(truth[i])), chunk.t0 + i / self.sample_rate) for i in changes]
