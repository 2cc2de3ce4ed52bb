"""Fixtures for tests that run real nodes over DDS."""

import pytest
from ros_harness import RosGraph, session_domain_id


@pytest.fixture
def ros_graph():
    """An isolated graph; every process it started is stopped after the test, pass or fail."""
    graph = RosGraph(session_domain_id())
    try:
        yield graph
    finally:
        graph.close()
