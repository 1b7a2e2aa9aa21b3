"""Progress reaches a Python callback; a callback that raises stops the work with its
exception; the GIL is released while gcr works."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import gcr


class Stop(Exception):
    pass


def grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n × n points on the Cornell box's floor, facing up."""
    u = (np.arange(n) + 0.5) / n
    x, z = np.meshgrid(0.05 + 0.45 * u, 0.05 + 0.45 * u)
    points = np.stack([x.ravel(), np.zeros(n * n), z.ravel()], axis=1)
    return points, np.tile([0.0, 1.0, 0.0], (n * n, 1))


def test_the_callback_gets_the_gathers_progress(draft):
    events = []
    draft.radiosity(*grid(40), progress=events.append)
    assert events, "no progress reported"
    last = events[-1]
    assert last["stage"] == "gather" and last["points"] == 1600
    assert set(last) >= {"phase", "points", "error", "eta", "done", "elapsed", "target"}
    assert last["error"] is not None and last["error"] <= last["target"]
    assert 0.0 <= last["done"] <= 1.0


def test_the_callback_gets_the_training(tmp_path):
    events = []
    scene = gcr.Scene.load("cornell-box")
    gcr.solve(scene, gather="rays", cells=40, gather_rays=4, progress=events.append)
    stages = {e["phase"] for e in events if e["stage"] == "solve"}
    assert "final" in stages, events
    assert all(e["kernel_budget"] == 40 for e in events if e["stage"] == "solve")


def test_a_callback_that_raises_stops_the_work(draft):
    calls = []

    def stop(event):
        calls.append(event)
        raise Stop("enough")

    started = time.monotonic()
    with pytest.raises(Stop, match="enough"):
        draft.radiosity(*grid(150), progress=stop)
    assert len(calls) == 1
    # the whole gather takes several seconds; stopping takes at most a report period or so
    assert time.monotonic() - started < 5.0


def test_the_gil_is_released_during_a_gather(draft):
    ticks = 0
    running = threading.Event()

    def count():
        nonlocal ticks
        running.set()
        while running.is_set():
            ticks += 1
            time.sleep(0)

    thread = threading.Thread(target=count)
    thread.start()
    running.wait()
    before = ticks
    started = time.monotonic()
    draft.radiosity(*grid(60))
    took = time.monotonic() - started
    during = ticks - before
    running.clear()
    thread.join()
    assert took > 0.05, "the gather was too short to tell"
    # a thread blocked on the GIL would count at most a handful of switch intervals
    assert during > 1000, f"only {during} ticks in {took:.2f} s: the GIL was held"
