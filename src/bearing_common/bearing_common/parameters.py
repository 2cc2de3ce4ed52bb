"""Declared ROS parameters: one table per node, declared with descriptions and checked.

The tables (``ParameterSpec`` lists) live in each node module's rclpy-free
companion so that tests and launch checks can read them without a ROS graph.
``declare`` and ``read`` are used by every node (rclpy imported lazily).
"""

from dataclasses import dataclass
from typing import Any, Callable, Optional


@dataclass(frozen=True)
class ParameterSpec:
    """One node parameter: name, default (its type is the parameter's type), description.

    ``check(value)`` returns an error text for an invalid value, or None.
    """

    name: str
    default: Any
    description: str
    check: Optional[Callable[[Any], Optional[str]]] = None

    def validate(self, value) -> Optional[str]:
        if self.check is None:
            return None
        return self.check(value)


def positive(value) -> Optional[str]:
    """Check for a strictly positive number."""
    return None if value > 0 else f"must be > 0, got {value}"


def one_of(*choices) -> Callable[[Any], Optional[str]]:
    """Check for membership in ``choices``."""
    def check(value):
        return None if value in choices else f"must be one of {', '.join(map(str, choices))}; got {value!r}"
    return check


def declare(node, specs) -> dict:
    """Declare ``specs`` on ``node`` with descriptions, validate the values given at start-up,
    and install a callback that rejects invalid later changes with a reason.

    Returns the current values by name. Raises ValueError on an invalid start-up value.
    """
    from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
    from rclpy.exceptions import InvalidParameterTypeException

    by_name = {s.name: s for s in specs}
    for spec in specs:
        try:
            node.declare_parameter(spec.name, spec.default, ParameterDescriptor(description=spec.description))
        except InvalidParameterTypeException as exc:
            raise ValueError(f"{spec.name}: wrong type, expected {type(spec.default).__name__} "
                             f"like {spec.default!r} ({exc})") from None
    values = {s.name: node.get_parameter(s.name).value for s in specs}
    errors = [f"{name}: {err}" for name, v in values.items() if (err := by_name[name].validate(v))]
    if errors:
        raise ValueError("invalid parameters: " + "; ".join(errors))

    def on_set(params):
        for param in params:
            spec = by_name.get(param.name)
            err = spec.validate(param.value) if spec is not None else None
            if err:
                return SetParametersResult(successful=False, reason=f"{param.name}: {err}")
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(on_set)
    return values
