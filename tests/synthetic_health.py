"""Synthetic healthy machines for the trend's false-alarm checks (tests and ``make trend``)."""

import math

import numpy as np
from scipy.signal import lfilter

from bearing_diagnoser.health.trend import HealthState, HealthTrend, TrendConfig

DAY = 86400.0


def ar1(rng, shape, phi, burn=300):
    """Unit-variance stationary Gaussian AR(1) along the last axis."""
    e = rng.standard_normal(shape[:-1] + (shape[-1] + burn,)) * math.sqrt(1 - phi ** 2)
    return lfilter([1.0], [1.0, -phi], e, axis=-1)[..., burn:]


def false_onsets_per_day(phi, machines, steps, rate, seed):
    """Mean onsets per day of the warning level (no relevance band: the statistics alone) over
    ``machines`` simulated healthy machines, one snapshot a minute, one indicator; and its
    standard error."""
    config = TrendConfig(false_warnings_per_day=rate, false_alarms_per_day=rate, warning_change=1.0,
                         alarm_change=1.0, indicators=("x",))
    rng = np.random.default_rng(seed)
    y = 0.1 * ar1(rng, (machines, config.baseline_snapshots + steps), phi)
    per_day = []
    for life in y:
        trend = HealthTrend(config)
        onsets, was = 0, False
        for k, v in enumerate(np.exp(life)):
            trend.update(60.0 * k, {"x": v})
            now = trend.state != HealthState.HEALTHY
            onsets += now and not was
            was = now
        per_day.append(onsets / (steps * 60.0 / DAY))
    per_day = np.array(per_day)
    return per_day.mean(), per_day.std(ddof=1) / math.sqrt(machines)
