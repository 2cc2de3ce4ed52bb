"""The monitoring graph's contract, shared by every package (pure Python, no numba, no matplotlib).

* :mod:`.states` — the fault-state integers (NORMAL, OUTER_RACE, INNER_RACE, BALL, UNKNOWN).
* :mod:`.topics` — every topic's name, message type and QoS (the one table).
* :mod:`.stamps` — header stamps to and from seconds.
* :mod:`.bearings` — bearing geometry, fault frequencies (thesis eqs. 2.51-2.54), the catalog.
* :mod:`.units` — unit constants (standard gravity, inch).
* :mod:`.parameters` — node parameter specs, declaration and live changes.
* :mod:`.node_main` — the ``main()`` every node shares (start, clean stop on signals, ``on_shutdown`` hook).
* :mod:`.stop_signals` — SIGINT / SIGTERM as a flag that loops poll (nodes, bearing-graph, bearing-bag).
* :mod:`.ros_env` — where the ROS 2 packages and executables are, sourced or not; the distribution.
"""
