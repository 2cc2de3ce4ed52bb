"""Health over a machine's life (pure Python, no rclpy): condition indicators, trend, early warning.

* :mod:`.indicators` — RMS, peak, crest factor, kurtosis, velocity RMS (10-1000 Hz), envelope RMS.
* :mod:`.iso20816` — ISO 20816-3 zones of velocity RMS by machine class.
* :mod:`.null_model`, :mod:`.null_table` — the trend statistics' null distribution and limits
  with a stated false-alarm rate per day.
* :mod:`.trend` — :class:`~.trend.HealthTrend`: baseline, HEALTHY / WARNING / ALARM, slope.
* :mod:`.monitor` — :class:`~.monitor.HealthMonitor`: one window or snapshot in, one
  :class:`~.monitor.HealthRecord` out (what the node publishes and ``bearing-trend`` prints).
* :mod:`.message` — a record into ``bearing_msgs/msg/HealthIndicators``.
* :mod:`.trend_cli`, :mod:`.trend_plot` — ``bearing-trend`` and its figure.
"""
