"""Parameters of the ``observer`` node (no rclpy): name, default, description, check, live or read-only."""

from bearing_common.bearings import DEFAULT_BEARING
from bearing_common.chunk_stream import INPUT_MODE_HELP, INPUT_MODES
from bearing_common.model_set_info import FAULT_TYPES
from bearing_common.parameters import ParameterSpec, bearing_check, one_of, positive
from bearing_common.states import FaultState, parse_fault

from .hw_model import ModelFileError
from .model_sets import model_set


def model_set_check(value: str) -> str | None:
    """Check for ``""`` (automatic) or a model set :func:`.model_sets.model_set` resolves."""
    if value == "":
        return None
    try:
        model_set(value)
    except ModelFileError as exc:
        return str(exc)
    return None


PARAMETERS = (
    ParameterSpec("fault_type", "outer_race", "fault hypothesis of this observer: outer_race or inner_race",
                  one_of(*FAULT_TYPES)),
    ParameterSpec("bearing", DEFAULT_BEARING, "the watched bearing: catalog name (6205, 6203, mfpt, za2115), "
                  "YAML file or 'N,d,D,angle'; gives the fault frequency", bearing_check, dynamic=True),
    ParameterSpec("model_set", "", "model set name or directory, e.g. sim_48k, cwru_de_6205 or none (no model: "
                  "residual = measurement); empty = chosen from the chunks' source and sample rate and the bearing",
                  model_set_check, dynamic=True),
    ParameterSpec("rpm", 1800.0, "shaft speed (rev/min) used until shaft_speed messages arrive", positive,
                  dynamic=True),
    ParameterSpec("speed_tolerance", 0.001, "relative shaft-speed change that re-tunes the impulse train",
                  positive, dynamic=True),
    ParameterSpec("input_mode", "auto", INPUT_MODE_HELP + "; a snapshot restarts the observer's state, quietly",
                  one_of(*INPUT_MODES)),
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
