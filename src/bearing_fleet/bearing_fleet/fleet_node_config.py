"""Parameters of the ``fleet`` node (no rclpy)."""

from bearing_common.parameters import ParameterSpec, positive

PARAMETERS = (
    ParameterSpec("period", 1.0, "seconds between fleet_state summaries (and one on every state change)", positive),
    ParameterSpec("stale_timeout", 5.0, "seconds without a decision before a motor is marked stale", positive,
                  dynamic=True),
    ParameterSpec("discovery_period", 1.0, "seconds between looks for new motors' fault_state topics", positive),
)
