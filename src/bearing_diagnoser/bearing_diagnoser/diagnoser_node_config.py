"""Parameters and /diagnostics contents of the ``diagnoser`` node (no rclpy)."""

from bearing_common.parameters import ParameterSpec, positive
from bearing_common.states import FaultState

PARAMETERS = (
    ParameterSpec("model_set", "", "decision defaults of this model set (window, band, thresholds); "
                  "empty = the model set named in the residual messages"),
    ParameterSpec("window", 0.0, "sliding window length (s); 0 = the model set's default",
                  lambda v: None if v >= 0 else "must be >= 0"),
    ParameterSpec("hop", 0.0, "window hop (s); 0 = the model set's default",
                  lambda v: None if v >= 0 else "must be >= 0"),
    ParameterSpec("false_alarm_probability", 0.0, "per-window false-alarm probability on noise that sets the "
                  "detection thresholds; 0 = the model set's default", lambda v: None if 0 <= v < 0.5 else "must be in [0, 0.5)"),
    ParameterSpec("stale_timeout", 1.0, "seconds without residuals before /diagnostics reports STALE", positive),
    ParameterSpec("diagnostics_period", 1.0, "seconds between /diagnostics messages", positive),
)

# diagnostic_msgs/DiagnosticStatus levels (OK=0, WARN=1, ERROR=2, STALE=3) per published state.
LEVEL_OK, LEVEL_WARN, LEVEL_ERROR, LEVEL_STALE = 0, 1, 2, 3
STATE_LEVEL = {FaultState.NORMAL: LEVEL_OK, FaultState.OUTER_RACE: LEVEL_ERROR,
               FaultState.INNER_RACE: LEVEL_ERROR, FaultState.BALL: LEVEL_ERROR,
               FaultState.UNKNOWN: LEVEL_WARN}


def health(state, silent: list, all_silent: bool) -> tuple:
    """(level, message) of the diagnoser's DiagnosticStatus.

    ``silent``: residual topics not heard from within the stale timeout;
    ``all_silent``: nothing heard at all within it (STALE).
    """
    if all_silent:
        return LEVEL_STALE, "no residuals: " + ", ".join(silent)
    level = STATE_LEVEL[FaultState(state)]
    message = FaultState(state).name
    if silent:
        level = max(level, LEVEL_WARN)
        message += " (waiting for " + ", ".join(silent) + ")"
    return level, message
