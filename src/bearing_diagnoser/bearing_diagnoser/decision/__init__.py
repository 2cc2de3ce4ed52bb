"""The decision core both front ends share: configuration, the front-end interface, window schedule,
per-stream blocks, the thesis' blocks, typed scores, sensor check, hysteresis and segments
(the package map: :mod:`bearing_diagnoser`)."""
