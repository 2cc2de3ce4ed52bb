"""One view of a fleet of monitored motors: the ``fleet`` node (``fleet_state``) and ``bearing-fleet``."""
