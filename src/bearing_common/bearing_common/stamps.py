"""Header stamps (builtin_interfaces/Time) to and from float seconds.

Works on rclpy messages and on rosbags' decoded messages alike (both have
``sec`` and ``nanosec``). ``to_stamp`` rounds to the nearest nanosecond and
carries into ``sec``, so 0.9999999999 s becomes 1 s 0 ns, never 0 s 0 ns.
"""


def to_seconds(stamp) -> float:
    """``stamp.sec + stamp.nanosec`` in seconds."""
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def to_stamp(seconds: float):
    """builtin_interfaces/Time for ``seconds`` (>= 0)."""
    from builtin_interfaces.msg import Time

    sec, nanosec = divmod(int(round(seconds * 1e9)), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)
