"""Recordings in one home: vibration files in, rosbag2 in and out (pure Python; rclpy only in record/play).

* :mod:`.recording` — :class:`~.recording.Recording` (SI units) and the input checks.
* :mod:`.mat_files`, :mod:`.npz_files`, :mod:`.load` — MFPT / CWRU / one-signal .mat files
  (one channel rule), ``bearing-sim`` .npz, and the dispatch by kind.
* :mod:`.bag_types`, :mod:`.bag_read`, :mod:`.bag_write` — rosbag2 via ``rosbags``.
* :mod:`.bag_record`, :mod:`.bag_play`, :mod:`.bag_cli` — ``bearing-bag``, for machines
  without ``ros2 bag``.
"""
