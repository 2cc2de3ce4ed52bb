"""bearing_diagnoser: fault states from the observers' residuals (thesis section 3.2, taken further).

The decision, by where to look (no rclpy anywhere except ``node``):

- :mod:`.diagnoser`            the incremental decision: observer chunks in, decisions out
- :mod:`.front_ends`           which front end decides a model set's streams; defaults; the textbook baseline
- :mod:`.decision`             the core both front ends share:
  :mod:`~.decision.config` (what the decision is configured with),
  :mod:`~.decision.front_end` (the one interface a front end implements),
  :mod:`~.decision.schedule` (when windows are due, by stream index),
  :mod:`~.decision.stream_blocks` (each observer stream's blocks and energy envelope),
  :mod:`~.decision.thesis_blocks` (the thesis' own blocks: model explains, cross-correlation),
  :mod:`~.decision.scores` (what a window shows, typed),
  :mod:`~.decision.sensor_health` (is the signal fit to diagnose),
  :mod:`~.decision.not_diagnosed` (why a window was not diagnosed: one kind, one reason),
  :mod:`~.decision.state_tracker` (hysteresis, onsets, confidence),
  :mod:`~.decision.segments` (runs of one state, what ``bearing-diagnose`` prints),
  :mod:`~.decision.pairwise_sum` (NumPy's summation in compiled loops)
- :mod:`.spectral`             the envelope-spectrum front end (real machines):
  :mod:`~.spectral.settings`, :mod:`~.spectral.front_end`,
  :mod:`~.spectral.evidence_stream` (window schedule, speed and band re-estimation),
  :mod:`~.spectral.band_choice` (how the demodulation band is picked),
  :mod:`~.spectral.envelope_spectrum` (prewhitening, squared envelope spectrum),
  :mod:`~.spectral.fault_combs` (OR, IR, BALL combs over slip),
  :mod:`~.spectral.significance` (p-values), :mod:`~.spectral.gamma_tail` (the far tail, compiled),
  :mod:`~.spectral.window_label` (label, posterior),
  :mod:`~.spectral.shaft_speed` (the speed from the 1x line)
- :mod:`.fold`                 the folding front end (simulator model sets):
  :mod:`~.fold.settings`, :mod:`~.fold.front_end`, :mod:`~.fold.scoring` (window statistics, label),
  :mod:`~.fold.folding` (folded periodicity, explain-away), :mod:`~.fold.decoys` (CFAR decoy lines),
  :mod:`~.fold.envelope_reference` (its textbook statistic), :mod:`~.fold.calibration` (thresholds)
- :mod:`.warm_up`              compiled kernels and tables, before the first window

Around the decision:

- :mod:`.diagnoser_session`    the diagnoser node's logic per chunk, parameter and health (no rclpy)
- :mod:`.diagnoser_node_config` the node's parameters and /diagnostics levels
- :mod:`.node`                 the ``diagnoser`` node (rclpy)
- :mod:`.pipeline`             the graph's sessions in one process, fed with recorded chunks (offline = live)
- :mod:`.recording_diagnosis`  a whole recording through the pipeline: ``bearing-diagnose``'s run
- :mod:`.diagnose_cli`         the ``bearing-diagnose`` command
- :mod:`.accuracy`, :mod:`.accuracy_cli`  accuracy on labelled recordings (``bearing-accuracy``)
- :mod:`.plots`                the figures of ``bearing-diagnose --plot``
- :mod:`.reports`              what a person reads: the evidence in physical terms
  (:mod:`~.reports.diagnosis_summary`), the terminal text (:mod:`~.reports.terminal_text`), the
  HTML pages of ``--report`` (:mod:`~.reports.diagnosis_page`, :mod:`~.reports.trend_page`,
  :mod:`~.reports.envelope_view`, :mod:`~.reports.html_page`)
- :mod:`.health`               condition indicators, trend and early warning, ``bearing-trend``
- :mod:`.synthetic`            test signals with known answers
"""
