"""Declared ROS parameters: one table per node, checked at start-up and applied live when set.

The tables (``ParameterSpec`` lists) live in each node's rclpy-free companion module so
that tests and launch checks read them without a ROS graph. :func:`declare` is what every
node calls (rclpy imported lazily):

* every parameter is declared with its description; those that cannot change while the
  node runs (``dynamic=False``) are declared read-only, so ``ros2 param set`` is refused
  with rclpy's reason ("... is read-only");
* values given at start-up are validated (one ValueError naming each bad one);
* a later ``ros2 param set`` is validated first (refused with the reason) and, once
  accepted, applied: the returned ``values`` dict is updated and ``on_change({name:
  value})`` is called after the change is committed (a post-set callback).
"""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class ParameterSpec:
    """One node parameter: name, default (its type is the parameter's type), description.

    ``check(value)`` returns an error text for an invalid value, or None; it must accept
    every value the node can apply (a change is only committed after it passed).
    ``dynamic`` parameters may change while the node runs; the others are read-only.
    """

    name: str
    default: Any
    description: str
    check: Callable[[Any], str | None] | None = None
    dynamic: bool = False

    def validate(self, value) -> str | None:
        if self.check is None:
            return None
        return self.check(value)


def positive(value) -> str | None:
    """Check for a strictly positive number."""
    return None if value > 0 else f"must be > 0, got {value}"


def non_negative(value) -> str | None:
    """Check for a number >= 0."""
    return None if value >= 0 else f"must be >= 0, got {value}"


def one_of(*choices) -> Callable[[Any], str | None]:
    """Check for membership in ``choices``."""
    def check(value):
        return None if value in choices else f"must be one of {', '.join(map(str, choices))}; got {value!r}"
    return check


def bearing_check(value) -> str | None:
    """Check for a bearing :func:`bearing_common.bearings.load_bearing` resolves."""
    from .bearings import BearingError, load_bearing
    try:
        load_bearing(value)
    except BearingError as exc:
        return str(exc)
    return None


def declare(node, specs, on_change: Callable[[dict], None] | None = None) -> dict:
    """Declare ``specs`` on ``node``; return the current values by name (kept up to date).

    Raises ValueError on an invalid start-up value. ``on_change`` is called with the
    changed ``{name: value}`` after a successful ``set_parameters`` on dynamic parameters.
    """
    from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
    from rclpy.exceptions import InvalidParameterTypeException

    by_name = {s.name: s for s in specs}
    for spec in specs:
        descriptor = ParameterDescriptor(description=spec.description, read_only=not spec.dynamic)
        try:
            node.declare_parameter(spec.name, spec.default, descriptor)
        except InvalidParameterTypeException as exc:
            raise ValueError(f"{spec.name}: wrong type, expected {type(spec.default).__name__} "
                             f"like {spec.default!r} ({exc})") from None
    values = {s.name: node.get_parameter(s.name).value for s in specs}
    errors = [f"{name}: {err}" for name, v in values.items() if (err := by_name[name].validate(v))]
    if errors:
        raise ValueError("invalid parameters: " + "; ".join(errors))

    def before_set(params):
        for param in params:
            spec = by_name.get(param.name)
            if spec is None:
                continue  # rclpy itself refuses undeclared names, read-only ones and type changes
            err = spec.validate(param.value)
            if err:
                return SetParametersResult(successful=False, reason=f"{param.name}: {err}")
        return SetParametersResult(successful=True)

    def after_set(params):
        changed = {p.name: p.value for p in params if p.name in by_name}
        if not changed:
            return
        values.update(changed)
        if on_change is not None:
            try:
                on_change(changed)
            except Exception as exc:  # a post-set callback cannot refuse; report, keep running
                node.get_logger().error(f"applying {', '.join(changed)} failed: {exc}")

    node.add_on_set_parameters_callback(before_set)
    node.add_post_set_parameters_callback(after_set)
    return values
