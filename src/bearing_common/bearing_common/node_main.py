"""The ``main()`` every node of the project shares: init, run, clean exit (rclpy imported lazily).

A node stopped by Ctrl-C or SIGTERM exits 0 (rclpy raises ExternalShutdownException
out of spin on SIGTERM); invalid parameters (ValueError) give one line on stderr and
exit code 2 instead of a traceback.
"""

import sys


def run_node_main(program: str, make_node, run=None, args=None) -> int:
    """Initialise rclpy with ``args``, build ``make_node()``, ``run(node)`` (default: spin)."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    rclpy.init(args=args)
    node = None
    try:
        node = make_node()
        (run or rclpy.spin)(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as exc:
        print(f"{program}: {exc}", file=sys.stderr)
        return 2
    finally:
        if node is not None:
            node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
