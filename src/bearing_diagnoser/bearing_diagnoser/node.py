"""The ``diagnoser`` node: fault states from the two observers' residuals.

Subscribes ``residual/outer_race``, ``residual/inner_race``, ``shaft_speed`` (stamped: a speed
that changes beyond 2 % is followed in the shaft-angle domain, :mod:`.spectral.angle_domain`) and
``shaft_pulses`` (tachometer pulses: when they come, the speed at each pulse, :mod:`.pulse_speed`,
replaces ``shaft_speed``); publishes
``fault_state`` (FaultState, reliable + transient local: a late subscriber sees the current
state) on every decision, and ``/diagnostics`` (status ``bearing_monitor/<motor>/drive_end``,
hardware id the motor: the ``motor`` parameter, the namespace or the host's name; OK NORMAL,
ERROR a fault, WARN UNKNOWN, a silent observer or an unusable sensor signal, STALE no input;
a last STALE "stopped" when the node ends; the condition trend and its indicators in the
key-values, a condition WARNING at least WARN, an ALARM ERROR), and ``health``
(HealthIndicators, reliable + transient local, keep last 60: condition indicators, ISO
20816-3 zone, trend state with since-time and slope, the fault-comb evidence per hypothesis;
one per ``health_period`` s of a stream, one per snapshot of a snapshot sensor), and
``envelope_spectrum`` (EnvelopeSpectrum, reliable + transient local, keep last 1: the spectrum the
spectral decision tested in its last window, max-held to at most 100 values, with each hypothesis'
line frequencies at the told and the measured speed; the fold front end of the simulator model
sets publishes none). Signal timing
comes from the residuals' stamps and sample indices only, so replays at any rate (with ``use_sim_time``) give the same
decisions. The logic lives in :class:`.diagnoser_session.DiagnoserSession`; this module only wires
ROS to it.
"""

import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node

from bearing_common import topics
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_seconds, to_stamp
from bearing_common.states import FaultState
from bearing_msgs.msg import EnvelopeSpectrum, FaultLines, HealthIndicators, Residual, ShaftSpeed, Tachometer
from bearing_msgs.msg import FaultState as FaultStateMsg

from .diagnoser_node_config import PARAMETERS
from .diagnoser_session import SENSOR_LOCATION, DiagnoserSession, Health, StateReport, motor_name, status_name
from .health.message import fill_health_message
from .spectrum_message import fill_spectrum_message


class DiagnoserNode(Node):
    """Thin adapter: Residual chunks -> DiagnoserSession -> FaultState, HealthIndicators and /diagnostics."""

    def __init__(self, name: str = "diagnoser", namespace: str | None = None):
        super().__init__(name, namespace=namespace)
        self.values = declare(self, PARAMETERS, on_change=lambda changed: self.session.configure(changed))
        self.session = DiagnoserSession(self.values, self._log)
        self.motor = motor_name(self.values["motor"], self.get_namespace())
        self.session.warm_up()  # before subscribing: being subscribed means being ready
        self.pub_state = self.create_publisher(FaultStateMsg, topics.FAULT_STATE.name, topics.qos(topics.FAULT_STATE))
        self.pub_diag = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS.name, topics.qos(topics.DIAGNOSTICS))
        self.pub_health = self.create_publisher(HealthIndicators, topics.HEALTH.name, topics.qos(topics.HEALTH))
        self.pub_spectrum = self.create_publisher(EnvelopeSpectrum, topics.ENVELOPE_SPECTRUM.name,
                                                  topics.qos(topics.ENVELOPE_SPECTRUM))
        self.residual_subscriptions = {
            h: self.create_subscription(Residual, topic.name, lambda msg, h=h: self.on_residual(h, msg),
                                        topics.qos(topic))
            for h, topic in topics.RESIDUALS.items()}
        self.create_subscription(ShaftSpeed, topics.SHAFT_SPEED.name, lambda msg: self.session.on_speed(
            msg.angular_velocity, to_seconds(msg.header.stamp) or None), topics.qos(topics.SHAFT_SPEED))
        self.create_subscription(Tachometer, topics.TACHOMETER.name, lambda msg: self.session.on_pulses(
            to_seconds(msg.header.stamp), msg.duration, msg.pulse_offsets, msg.first_pulse_index,
            msg.pulses_per_revolution), topics.qos(topics.TACHOMETER))
        self.create_timer(float(self.values["diagnostics_period"]), self.publish_diagnostics)

    def _log(self, level: str, text: str) -> None:
        logger = self.get_logger()
        if level == "warning":
            logger.warning(text)
        else:
            logger.info(text)

    def _now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def on_residual(self, hypothesis: FaultState, msg: Residual) -> None:
        if len(self.session.deployed) < len(self.residual_subscriptions):  # until every observer is known
            self.session.expect(h for h, sub in self.residual_subscriptions.items() if sub.get_publisher_count())
        reports = self.session.on_residual(hypothesis, to_seconds(msg.header.stamp), msg.first_sample_index,
                                           msg.sample_rate, msg.residual, msg.estimate or None,
                                           msg.impulse_train or None,
                                           msg.fault_frequency, msg.model_set, self._now())
        for report in reports:
            self.publish_state(report)
        for record in self.session.take_health():
            self.pub_health.publish(fill_health_message(HealthIndicators(), record, self.session.condition.monitor,
                                                        msg.header.frame_id or SENSOR_LOCATION))
        envelope = self.session.take_envelope()
        if envelope is not None:
            self.pub_spectrum.publish(fill_spectrum_message(EnvelopeSpectrum(), envelope[1], envelope[0],
                                                            msg.header.frame_id or SENSOR_LOCATION, FaultLines))

    def publish_state(self, report: StateReport) -> None:
        msg = FaultStateMsg(state=int(report.state), confidence=float(report.confidence),
                            model_set=report.model_set, detail=report.detail)
        msg.header.stamp = to_stamp(report.stamp)
        msg.onset = to_stamp(report.onset)
        scores = report.scores.as_dict()
        msg.hypotheses = list(scores)
        msg.scores = [float(v) for v in scores.values()]
        self.pub_state.publish(msg)
        if report.changed:
            self.get_logger().info(f"t={report.stamp:.3f} s  state {report.state.name} "
                                   f"(confidence {report.confidence:.2f}, onset {report.onset:.3f} s)")

    def _publish_health(self, health: Health) -> None:
        status = DiagnosticStatus(level=bytes([health.level]), name=status_name(self.motor), message=health.message,
                                  hardware_id=self.motor)
        status.values = [KeyValue(key=k, value=str(v)) for k, v in health.values.items()]
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self.pub_diag.publish(array)

    def publish_diagnostics(self) -> None:
        self._publish_health(self.session.health(self._now()))

    def on_shutdown(self) -> None:
        """Called by the node main while the context is still valid: a last status."""
        self._publish_health(self.session.final_health(self._now()))


def main(args=None) -> int:
    return run_node_main("diagnoser", DiagnoserNode, None, args)


if __name__ == "__main__":
    sys.exit(main())
