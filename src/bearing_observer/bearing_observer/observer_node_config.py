"""Parameters and topics of the ``observer`` node (no rclpy)."""

from bearing_common.parameters import ParameterSpec, one_of, positive
from bearing_common.states import FaultState, parse_fault

FAULT_TYPES = ("outer_race", "inner_race")

PARAMETERS = (
    ParameterSpec("fault_type", "outer_race", "fault hypothesis of this observer: outer_race or inner_race",
                  one_of(*FAULT_TYPES)),
    ParameterSpec("model_set", "", "Hammerstein-Wiener model set, e.g. sim_48k or cwru_de_6205; empty = "
                  "chosen from the chunks' source and sample rate"),
    ParameterSpec("rpm", 1800.0, "shaft speed (rev/min) used until shaft_speed messages arrive", positive),
    ParameterSpec("speed_tolerance", 0.001, "relative shaft-speed change that re-tunes the impulse train",
                  positive),
)

def default_node_name(argv) -> str:
    """``or_observer`` / ``ir_observer`` from a ``fault_type:=...`` among the command-line arguments."""
    fault = "outer_race"
    for token in argv:
        if token.startswith("fault_type:="):
            fault = token.split(":=", 1)[1]
    try:
        state = parse_fault(fault)
    except ValueError:
        return "or_observer"  # the parameter check then reports the bad value
    return "ir_observer" if state == FaultState.INNER_RACE else "or_observer"
