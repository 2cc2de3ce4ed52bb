"""Recordings in one home: vibration files in, rosbag2 in and out (pure Python; rclpy only in record/play).

* :mod:`.recording` — :class:`~.recording.Recording` (SI units) and the input checks.
* :mod:`.mat_files`, :mod:`.npz_files`, :mod:`.load` — MFPT / CWRU / one-signal .mat files
  (one channel rule), ``bearing-sim`` .npz, and the dispatch by kind.
* :mod:`.table_files`, :mod:`.wav_files`, :mod:`.measurement_units` — CSV/TSV tables, WAV files,
  and what a file's numbers measure (``--units``, ``--sensitivity``).
* :mod:`.femto_files`, :mod:`.snapshots`, :mod:`.recording_files` — FEMTO snapshots, a life as
  snapshots, which paths are recordings.
* :mod:`.bag_types`, :mod:`.bag_read`, :mod:`.bag_write` — rosbag2 via ``rosbags``.
* :mod:`.bag_record`, :mod:`.bag_play`, :mod:`.bag_cli` — ``bearing-bag``, for machines
  without ``ros2 bag``.
"""
