"""Parameters of the ``diagnoser`` node and the levels of its /diagnostics status (no rclpy)."""

from bearing_common.bearings import DEFAULT_BEARING
from bearing_common.parameters import ParameterSpec, bearing_check, non_negative, positive
from bearing_common.states import FaultState

PARAMETERS = (
    ParameterSpec("bearing", DEFAULT_BEARING, "monitored bearing: catalog name (6205, 6203, mfpt, za2115), "
                  "a YAML file, or 'N,d,D,angle' with units", bearing_check, dynamic=True),
    ParameterSpec("model_set", "", "decision defaults of this model set; empty = the model set named in the "
                  "residual messages", dynamic=True),
    ParameterSpec("rpm", 0.0, "nominal shaft speed (rev/min) used while no shaft_speed arrives, refined from the "
                  "vibration within rpm_tolerance; 0 = unknown: estimated from the vibration (unreliable)",
                  non_negative, dynamic=True),
    ParameterSpec("rpm_tolerance", 0.10, "relative tolerance of the rpm parameter (the nameplate speed of a "
                  "drive-fed motor can be 10 % off the shaft's; measured speeds beyond it are reported)",
                  lambda v: None if 0.0 < v < 0.5 else "must be in (0, 0.5)", dynamic=True),
    ParameterSpec("window", 0.0, "analysis window (s); 0 = derived: 4 cage periods of the bearing (real "
                  "machines), the model set's default (simulator)", non_negative, dynamic=True),
    ParameterSpec("false_alarm_rate", 0.0, "false alarms per hour of healthy operation (Gaussian noise) that "
                  "the spectral decision (real machines) may give; 0 = its default (1e-3)",
                  lambda v: None if 0 <= v < 3600 else "must be in [0, 3600)", dynamic=True),
    ParameterSpec("false_alarm_probability", 0.0, "false-alarm probability per window and hypothesis of the "
                  "fold decision (the simulator's model sets); 0 = its default (1e-4)",
                  lambda v: None if 0 <= v < 0.5 else "must be in [0, 0.5)", dynamic=True),
    ParameterSpec("sensor_bandwidth", 0.0, "usable bandwidth of the sensor chain (Hz); 0 = up to 0.45 x the "
                  "sample rate", non_negative, dynamic=True),
    ParameterSpec("stale_timeout", 1.0, "seconds without residuals before /diagnostics reports STALE", positive,
                  dynamic=True),
    ParameterSpec("diagnostics_period", 1.0, "seconds between /diagnostics messages", positive),
    ParameterSpec("motor", "", "the motor in /diagnostics (status bearing_monitor/<motor>/drive_end, hardware_id "
                  "<motor>); empty = the node's namespace without the leading slash, or the host's name in the "
                  "root namespace"),
)

#: Parameters whose change restarts the decision (new windows, thresholds or hypotheses).
RESTART_ON = ("bearing", "model_set", "rpm", "rpm_tolerance", "window", "false_alarm_rate",
              "false_alarm_probability", "sensor_bandwidth")

# diagnostic_msgs/DiagnosticStatus levels (OK=0, WARN=1, ERROR=2, STALE=3) per published state.
LEVEL_OK, LEVEL_WARN, LEVEL_ERROR, LEVEL_STALE = 0, 1, 2, 3
STATE_LEVEL = {FaultState.NORMAL: LEVEL_OK, FaultState.OUTER_RACE: LEVEL_ERROR,
               FaultState.INNER_RACE: LEVEL_ERROR, FaultState.BALL: LEVEL_ERROR,
               FaultState.UNKNOWN: LEVEL_WARN}
