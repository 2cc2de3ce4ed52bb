"""bearing_observer: Hammerstein-Wiener fault models and observers (pure-Python core).

Modules (no rclpy anywhere except ``node``):

- :mod:`.impulse_trains`        fault impulse trains in time units (thesis eqs. 2.55, 2.58)
- :mod:`.piecewise_linear`      strictly monotone piecewise-linear blocks f, g, g^-1 (section 2.4)
- :mod:`.hw_model`              HW model dataclass and model files
- :mod:`.model_sets`            the model-set registry, the rule that picks a set, ``none``
- :mod:`.system_identification` output-error and HW fits, fit percent (general)
- :mod:`.fault_identification`  fault frequency, phase, periods, IR modulation; one fault model
- :mod:`.identify_cli`          the ``bearing-identify`` command
- :mod:`.realization`           state-space realizations, observer gains, modal filter
- :mod:`.observer`              the fault observer of Fig. 3.1 / eqs. 3.1-3.4 (its filter), warm-up
- :mod:`.phase_amplitude_estimator`  the observer's online train phase and gains, min_explained
- :mod:`.train_cache`           the observer's trains: cycle coordinates, rendered per update
- :mod:`.noise_gain`            white-noise gain of a residual filter (measured, H2)
- :mod:`.observer_session`      the observer node's logic per chunk and parameter (no rclpy)
- :mod:`.observer_node_config`  the node's parameters
- :mod:`.node`                  the ``observer`` node (rclpy)
- :mod:`.chunk_stream`          checks of a chunked signal stream

Compiled inner loops (numba, strict IEEE arithmetic: each docstring names the NumPy
formulation it reproduces bit for bit) sit next to the algorithm they serve;
:func:`.observer.warm_up` compiles them all.
"""
