"""The live view: the running graph served to Foxglove over its WebSocket protocol (the ``live_view`` node)."""
