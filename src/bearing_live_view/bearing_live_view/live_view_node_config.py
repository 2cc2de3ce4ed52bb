"""Parameters of the ``live_view`` node (no rclpy)."""

from bearing_common.parameters import ParameterSpec, positive

#: The port Foxglove's app connects to by default (``ws://localhost:8765``).
DEFAULT_PORT = 8765

#: This machine only: the server has no authentication, so serving a network is a deliberate choice.
DEFAULT_HOST = "127.0.0.1"


def port_check(value) -> str | None:
    """A TCP port: 1-65535, or 0 for any free one."""
    return None if 0 <= value <= 65535 else f"must be a TCP port 0-65535, got {value}"


PARAMETERS = (
    ParameterSpec("port", DEFAULT_PORT, "TCP port of the Foxglove WebSocket server (0: any free port, logged)",
                  port_check),
    ParameterSpec("host", DEFAULT_HOST, "address to listen on: 127.0.0.1 serves this machine only, 0.0.0.0 every "
                  "network interface (anyone who reaches it may watch: no authentication)"),
    ParameterSpec("discovery_period", 1.0, "seconds between looks for new topics to serve", positive),
    ParameterSpec("vibration_block", 0.01, "seconds of signal per min/max/RMS block of a served sample stream",
                  positive),
)
