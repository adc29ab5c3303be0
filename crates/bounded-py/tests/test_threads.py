"""The GIL is released while the library works: other Python threads run, two detect at once."""

import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import bounded
from conftest import open_box


@pytest.fixture
def no_forced_switches():
    """A switch interval so long that a thread holding the GIL keeps it until it lets go:
    another thread then runs only while the GIL is released."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(100.0)
    yield
    sys.setswitchinterval(before)


def counted_during(work):
    """How far a counting thread gets while `work()` runs on this thread.

    The counter yields the GIL after every step (time.sleep(0) releases it), so this thread
    can always take it back; whether the counter advances during `work` then depends only on
    whether `work` releases the GIL.
    """
    import time

    count = [0]
    stop = threading.Event()

    def counter():
        while not stop.is_set():
            count[0] += 1
            time.sleep(0)

    thread = threading.Thread(target=counter)
    thread.start()
    while count[0] < 10:  # the counter is running
        time.sleep(0.001)
    before = count[0]
    work()
    during = count[0] - before
    stop.set()
    thread.join()
    return during


def test_python_code_runs_during_a_detection(no_forced_switches):
    xyz = open_box(n=12_000)  # long enough to count through
    # The control: a C call that keeps the GIL (sorting ints runs no Python code) stops the
    # counter; this is what a detection that held the GIL would look like.
    held = counted_during(lambda: sorted(range(2_000_000), reverse=True))
    assert held <= 2, f"the counter advanced {held} times while the GIL was held"
    released = counted_during(lambda: bounded.detect(xyz))
    assert released >= 100, f"the counter advanced only {released} times during detect"
    released = counted_during(lambda: bounded.features(xyz))
    assert released >= 100, f"the counter advanced only {released} times during features"


def test_two_threads_detect_at_once():
    clouds = [open_box(), open_box(size=(3.0, 3.0, 1.5))]
    alone = [bounded.detect(xyz) for xyz in clouds]
    model = bounded.Model.embedded()  # one model shared by both threads
    start = threading.Barrier(2)

    def detect(xyz):
        start.wait()
        return bounded.detect(xyz, model=model)

    with ThreadPoolExecutor(max_workers=2) as pool:
        together = list(pool.map(detect, clouds))
    for a, b in zip(alone, together):
        np.testing.assert_array_equal(a.classes, b.classes)
        np.testing.assert_array_equal(a.probabilities, b.probabilities)
