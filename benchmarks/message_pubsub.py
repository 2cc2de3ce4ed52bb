"""One side of a DDS stream for message_benchmarks.py: ``pub|sub N HZ SECONDS``.

VibrationChunks of N float64 samples at HZ for SECONDS (reliable, keep last 50, the
EventsExecutor, as the graph's nodes); prints the process's CPU per message in µs last.
"""

import array
import sys
import time

import numpy as np


def main() -> int:
    import rclpy
    from rclpy.experimental import EventsExecutor

    from bearing_common import topics
    from bearing_msgs.msg import VibrationChunk

    role, n, hz, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    rclpy.init()
    node = rclpy.create_node(f"message_bench_{role}")
    executor = EventsExecutor()
    executor.add_node(node)
    qos = topics.qos(topics.VIBRATION)
    if role == "pub":
        pub = node.create_publisher(VibrationChunk, "bench_chunks", qos)
        while pub.get_subscription_count() < 1:
            executor.spin_once(timeout_sec=0.05)
        time.sleep(1.0)
        data = np.random.default_rng(0).normal(size=n).tobytes()
        t0, c0, k = time.monotonic(), time.process_time(), 0
        while time.monotonic() - t0 < seconds:
            msg = VibrationChunk(sample_rate=48000.0, first_sample_index=k * n, source="bench")
            msg.samples = array.array("d", data)
            pub.publish(msg)
            k += 1
            while time.monotonic() < t0 + k / hz:
                executor.spin_once(timeout_sec=max(0.0, t0 + k / hz - time.monotonic()))
        print(f"published {k} {(time.process_time() - c0) / k * 1e6:.1f}", flush=True)
        time.sleep(1.0)
    else:
        got = {"n": 0, "c0": None}

        def on_chunk(msg):
            if got["c0"] is None:
                got["c0"] = time.process_time()
            got["n"] += 1

        node.create_subscription(VibrationChunk, "bench_chunks", on_chunk, qos)
        deadline = time.monotonic() + seconds + 30.0
        while time.monotonic() < deadline and got["n"] < seconds * hz - 1:
            executor.spin_once(timeout_sec=0.1)
        print(f"received {got['n']} {(time.process_time() - got['c0']) / max(1, got['n'] - 1) * 1e6:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
