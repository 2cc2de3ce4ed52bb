"""The ``main()`` every node of the project shares: start, run, clean stop (rclpy imported lazily).

* SIGINT (Ctrl-C) or SIGTERM, once or repeated, ends the node with exit code 0 and
  no traceback. rclpy's own signal handlers are off: they shut the context down under
  the running code (KeyboardInterrupt, ExternalShutdownException or "context is not
  valid" errors, depending on timing). Here a signal only sets a flag
  (:class:`~bearing_common.stop_signals.StopSignals`) that the run loop polls.
* The run ends (stop requested, or the node's own end, e.g. the simulator's scenario);
  then the node's optional hook ``on_shutdown()`` is called while the context is still
  valid — the place for a last message (the diagnoser's /diagnostics "stopped"; call
  ``publisher.wait_for_all_acked(...)`` there if it must arrive) — and the node is
  destroyed and rclpy shut down.
* A signal while the process starts ends the start-up at once, with one line on stderr and
  exit code 0: from the console script's first line (:func:`run_executable`: the node
  module's imports of numpy, scipy, numba and rclpy take seconds under load) until its nodes
  are built (the JIT warm-ups: seconds of CPU, or a first numba compile after an install), and
  in any other section a node marks with ``stop.aborting()`` (the simulator's warm-up).
  The signal raises :class:`~bearing_common.stop_signals.StopRequested` in the main thread;
  where that thread is held in one C call (LLVM compiling a kernel), the signal watcher ends
  the process itself ``START_GRACE_S`` after the signal.
* Invalid parameters (ValueError while building the node) give one line on stderr
  and exit code 2.
* A stop still under way ``STOP_STALL_S`` after the signal prints the stack of every
  thread on stderr and ends the process with exit code 1 (``StopSignals(stall_s=...)``),
  so the log says where a clean-up or callback hung, before a supervisor escalates to
  SIGKILL at 5 s.
* rclpy's teardown (``destroy_node``, ``try_shutdown``) must end ``TEARDOWN_END_S`` after the
  stop signal (a run that ended by itself: after the teardown's start); past it, the process
  prints one line and ends with its exit code (0 after a stop) from a native timer thread
  (:mod:`.exit_timer`). ``destroy_node`` deletes the DDS endpoints (each announced on the
  rmw graph topic) and, with a process's last node, the DDS participant (joining Fast DDS's
  threads), all with the GIL held: 24-177 ms in 94 timed stops here, but rarely, under load,
  past the 4 s watchdog (issue 26; docs/graph.md: one caught waiting for another process's
  shared-memory port lock). The hook's last message is out by then; only the goodbyes to
  the others are cut short.
* Once rclpy is shut down (its log files closed), the process flushes its output and
  ends at once (``os._exit``): the interpreter's teardown is skipped. That teardown ran
  full garbage collections over the start-up heap (numba, llvmlite, scipy: about 160 000
  tracked objects, 0.15 s per collection), 0.8-1 s of CPU per node after the node had
  already stopped; four nodes stopping at once on two busy cores ran past the 4 s
  watchdog (``Timeout``, ``<no Python frame>``, exit 1). A stop is thus bounded by the
  node's own clean-up (the run loop's ``POLL_S``, ``on_shutdown()``) and ``TEARDOWN_END_S``,
  and then by the watchdog; the memory goes back to the system with the process.

A node with a run loop of its own passes ``run(node, stop)``, which must return soon
after ``stop`` becomes true (within ``POLL_S``, as the default spin does). Several nodes
in one process (:func:`run_nodes_main`: the fleet's multi-node processes) share one
single-threaded executor, and each node's hook is called.
"""

import contextlib
import ctypes
import importlib
import os
import signal
import sys
import time

from .exit_timer import exit_after
from .stop_signals import StopRequested, StopSignals

POLL_S = 0.1  #: s, longest a stop request waits for the default spin to notice it
STOP_STALL_S = 4.0  #: s, a stop taking longer prints every thread's stack and exits 1
TEARDOWN_END_S = 3.0  #: s after the stop signal (or the teardown's start) by which rclpy's teardown must end
MIN_TEARDOWN_S = 0.1  #: s the teardown gets when the run's own end already took the rest


def spin_until(nodes, stop) -> None:
    """The default run: execute the callbacks of ``nodes`` (a list, one executor) until ``stop`` is true."""
    executor = event_executor()
    for node in nodes:
        executor.add_node(node)
    try:
        while not stop:
            executor.spin_once(timeout_sec=POLL_S)
    finally:
        executor.shutdown()


def event_executor(context=None):
    """rclpy's EventsExecutor (``rclpy.experimental``: a C++ event queue), or the SingleThreadedExecutor
    where an rclpy lacks it.

    The nodes' CPU goes mostly into taking and publishing messages (100 chunks/s per motor);
    the Python executor rebuilds its wait set for every callback. With this one, 2 motors at
    48 kHz (benchmarks/fleet_benchmarks.py) took 0.23 instead of 0.32 cores in the observers'
    process, 0.21 instead of 0.34 in the diagnosers' and 0.07 instead of 0.11 in the fleet node."""
    try:
        from rclpy.experimental import EventsExecutor
    except ImportError:  # an older rclpy of a full ROS 2 install
        from rclpy.executors import SingleThreadedExecutor as EventsExecutor
    return EventsExecutor(context=context)


def run_node_main(program: str, make_node, run=None, args=None):
    """Initialise rclpy with ``args``, build ``make_node()``, ``run(node, stop)`` (default:
    :func:`spin_until`), call ``node.on_shutdown()`` if it exists; end the process with the
    exit code (a process's main: it does not return)."""
    run_nodes = None if run is None else (lambda nodes, stop: run(nodes[0], stop))
    run_nodes_main(program, lambda: [make_node()], run_nodes, args)


def run_nodes_main(program: str, make_nodes, run=None, args=None):
    """:func:`run_node_main` for several nodes in one process: ``make_nodes()`` returns a list,
    ``run(nodes, stop)`` (default: :func:`spin_until`, one executor for all), then each node's
    ``on_shutdown()``; end the process with the exit code."""
    end_process(run_nodes(program, make_nodes, run, args))


def end_process(code: int):
    """Flush Python's and C's buffered output, then exit with ``code`` without the interpreter's teardown."""
    flush_output()
    os._exit(code)


def flush_output() -> None:
    """Python's and C's buffered output out to the file descriptors."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    ctypes.CDLL(None).fflush(None)


def run_executable(program: str, main: str, args=None):
    """The console script of a node executable: ``main`` ("module:function", the node's
    ``main(args)``, which calls :func:`run_node_main`) imported and run with the process's stop
    signals handled from the start, so that a stop during the module's imports ends the start-up
    (one line, exit 0) as one during the nodes' construction does. Light: import nothing heavy
    before calling it."""
    with process_stop_signals(program):
        module, _, function = main.partition(":")
        return getattr(importlib.import_module(module), function)(args)


_process_stop: StopSignals | None = None  #: the process's, once a start entered it (a process has one)


@contextlib.contextmanager
def process_stop_signals(program: str):
    """The process's :class:`StopSignals` (with the stall watchdog), entered on first use with the
    start-up abortable; a stop while starting (StopRequested, or any error the interrupted start-up
    raises after it) ends the process with one line and exit code 0."""
    global _process_stop
    if _process_stop is not None:
        yield _process_stop
        return
    stop = StopSignals(stall_s=STOP_STALL_S, stuck_start=lambda signum: stopped_while_starting(program, signum))
    stop.abort = True  # starting, until the nodes are built (set before the handlers are)
    try:
        with stop:  # a signal may raise StopRequested as soon as its handler is in place
            _process_stop = stop
            yield stop
    except StopRequested:
        stopped_while_starting(program, stop.signal)
    except Exception:
        if stop.aborted:  # the interrupted start-up's own failure (a StopRequested swallowed in a finalizer
            stopped_while_starting(program, stop.signal)  # left numba's compile half done): still a stop
        raise
    finally:
        _process_stop = None


def stopped_while_starting(program: str, signum: int):
    """End the process as a stop during its start-up: one line on stderr, exit code 0."""
    print(f"{program}: {signal.Signals(signum).name} while starting: stopped", file=sys.stderr)  # noqa: T201
    end_process(0)


def run_nodes(program: str, make_nodes, run=None, args=None) -> int:
    """The run of :func:`run_nodes_main` up to rclpy's shutdown; return the exit code."""
    with process_stop_signals(program) as stop:
        nodes, rclpy, code = [], None, 1  # rclpy is bound once its import completed; 1 until the run ended well
        try:
            try:
                with stop.aborting():
                    import rclpy
                    from rclpy.signals import SignalHandlerOptions

                    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
                    try:
                        nodes = make_nodes()
                    except ValueError as exc:
                        print(f"{program}: {exc}", file=sys.stderr)  # noqa: T201 (the one-line error is the interface)
                        code = 2
                        return code
            except StopRequested:
                code = 0  # a stop while starting: process_stop_signals ends it as one
                raise
            (run or spin_until)(nodes, stop)
            if stop:
                nodes[0].get_logger().info(f"{signal.Signals(stop.signal).name} received: stopping")
            for node in nodes:
                hook = getattr(node, "on_shutdown", None)
                if hook is not None:
                    hook()
            code = 0
        finally:
            tear_down(program, nodes, rclpy, code, stop.arrived)
    return code


def tear_down(program: str, nodes: list, rclpy, code: int, since: float | None) -> None:
    """Destroy ``nodes`` and shut rclpy down, ending by :data:`TEARDOWN_END_S` after ``since`` (the stop
    signal's time.monotonic(); None: now): past it the process ends with ``code`` and one line (see
    the module's docstring)."""
    flush_output()
    now = time.monotonic()
    left = max(TEARDOWN_END_S - (now - (now if since is None else since)), MIN_TEARDOWN_S)
    with exit_after(left, code, f"{program}: rclpy's teardown (the node's and DDS participant's deletion) "
                                f"still ran {TEARDOWN_END_S:g} s after the stop: ended without it"):
        for node in nodes:
            node.destroy_node()
        if rclpy is not None:
            rclpy.try_shutdown()
