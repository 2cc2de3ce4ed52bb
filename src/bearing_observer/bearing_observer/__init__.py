"""bearing_observer: Hammerstein-Wiener fault models and observers (pure-Python core).

Modules (no rclpy anywhere except ``node``):

- :mod:`.impulse_trains`   fault impulse trains in time units (thesis eqs. 2.55, 2.58)
- :mod:`.piecewise_linear` strictly monotone piecewise-linear blocks f, g (section 2.4)
- :mod:`.hw_model`         HW model dataclass, model files, model-set registry
- :mod:`.identification`   OE initialisation + HW simulation-error fit, preprocessing
- :mod:`.identify_cli`     the ``bearing-identify`` command
- :mod:`.observer`         the fault observer of Fig. 3.1 / eqs. 3.1-3.4
- :mod:`.obs_benchmarks`   ``make bench`` rows; :mod:`.obs_figures` the thesis figures
"""
