"""Parameters of the ``diagnoser`` node and the levels of its /diagnostics status (no rclpy)."""

from bearing_common.bearings import DEFAULT_BEARING
from bearing_common.chunk_stream import INPUT_MODE_HELP, INPUT_MODES
from bearing_common.parameters import ParameterSpec, bearing_check, non_negative, one_of, positive
from bearing_common.states import FaultState

from .health.health_session import DEFAULT_PERIOD, HealthSettings
from .health.iso20816 import DEFAULT_MACHINE_CLASS, ZONE_LIMITS_MM_S
from .health.trend import HealthState, parse_baseline


def _problem(parse):
    """A parameter check from a parser that raises ValueError."""
    def check(value):
        try:
            parse(value)
        except ValueError as exc:
            return str(exc)
        return None
    return check

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
    ParameterSpec("input_mode", "auto", INPUT_MODE_HELP, one_of(*INPUT_MODES)),
    ParameterSpec("health_period", DEFAULT_PERIOD, "seconds of a stream per health message (condition "
                  "indicators and trend); each snapshot of a snapshot sensor is one message", positive),
    ParameterSpec("machine_class", DEFAULT_MACHINE_CLASS, "ISO 20816-3 machine class of the velocity RMS zone: "
                  + ", ".join(ZONE_LIMITS_MM_S) + " (group 1: 300 kW-50 MW, group 2: 15-300 kW)",
                  one_of(*ZONE_LIMITS_MM_S), dynamic=True),
    ParameterSpec("baseline", "30", "the healthy baseline of the condition trend: the first N windows or "
                  "snapshots (a count, spanning at least baseline_min_duration), or a stated healthy period after "
                  "the first (a duration: 2h, 45min, 600s)", _problem(parse_baseline)),
    ParameterSpec("reference_file", "", "the machine's own healthy reference (JSON, bearing-diagnose "
                  "--save-baseline): loaded when the file exists; else learnt over the baseline period (at most 60 s "
                  "of signal from the start, deciding blind meanwhile) and saved there, so that a restart does not "
                  "learn again; empty = learnt and not saved"),
    ParameterSpec("baseline_min_duration", 600.0, "seconds the counted baseline spans at least (a stream's 1 s "
                  "windows then learn over 10 min, not 30 s); 0 = by count only", non_negative),
)


def health_settings(values: dict) -> HealthSettings:
    """The health's settings from the parameter values."""
    return HealthSettings(parse_baseline(values["baseline"], values["baseline_min_duration"]),
                          values["machine_class"], float(values["health_period"]))


#: Parameters whose change restarts the decision (new windows, thresholds or hypotheses).
RESTART_ON = ("bearing", "model_set", "rpm", "rpm_tolerance", "window", "false_alarm_rate",
              "false_alarm_probability", "sensor_bandwidth")

# diagnostic_msgs/DiagnosticStatus levels (OK=0, WARN=1, ERROR=2, STALE=3) per published state.
LEVEL_OK, LEVEL_WARN, LEVEL_ERROR, LEVEL_STALE = 0, 1, 2, 3
STATE_LEVEL = {FaultState.NORMAL: LEVEL_OK, FaultState.OUTER_RACE: LEVEL_ERROR,
               FaultState.INNER_RACE: LEVEL_ERROR, FaultState.BALL: LEVEL_ERROR,
               FaultState.UNKNOWN: LEVEL_WARN}

#: /diagnostics level of each condition trend state: an ALARM is as serious as a fault.
TREND_LEVEL = {HealthState.HEALTHY: LEVEL_OK, HealthState.WARNING: LEVEL_WARN, HealthState.ALARM: LEVEL_ERROR}
