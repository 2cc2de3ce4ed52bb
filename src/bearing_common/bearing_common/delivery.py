"""The end of a stream: wait until every reliable subscriber has acknowledged what was published.

A process that exits right after its last message can take with it messages a remote reader
has not received yet: a datagram lost on the network is repaired only by its writer, and a
reader notices a lost *last* message only at the writer's next heartbeat (Fast DDS's default
period: 3 s). A fixed linger guesses; this waits for the acknowledgements themselves, in short
steps, so that a stop request ends the wait at once.
"""

from __future__ import annotations

import time

#: Longest wait (s) at a stream's end for reliable subscribers to acknowledge every message:
#: past one Fast DDS heartbeat period (3 s) and its repair.
ACK_TIMEOUT_S = 5.0

#: Step (s) of the wait: a stop request is seen within it.
ACK_POLL_S = 0.1


def wait_acknowledged(publishers, timeout: float = ACK_TIMEOUT_S, stop=()) -> list[str]:
    """Wait, at most ``timeout`` s or until ``stop`` is true, until every one of ``publishers``
    (rclpy publishers) has every message acknowledged by its reliable subscribers; return the
    topic names still waiting (empty when all were acknowledged)."""
    from rclpy.duration import Duration

    step = Duration(seconds=ACK_POLL_S)
    deadline = time.monotonic() + timeout
    pending = list(publishers)
    while pending and not stop:
        pending = [p for p in pending if not p.wait_for_all_acked(step)]
        if time.monotonic() >= deadline:
            break
    return [p.topic_name for p in pending]
