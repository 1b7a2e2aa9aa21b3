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
    """Another Python thread keeps running while gcr gathers: it ticks in most 20 ms windows of
    the call (a held GIL would leave the whole call without a tick)."""
    ticks: list[float] = []
    running = threading.Event()

    def count():
        running.set()
        while running.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    thread = threading.Thread(target=count)
    thread.start()
    running.wait()
    started = time.monotonic()
    draft.radiosity(*grid(120))
    ended = time.monotonic()
    running.clear()
    thread.join()
    windows = int((ended - started) / 0.02)
    assert windows >= 5, f"the gather took {ended - started:.3f} s: too short to tell"
    ticked = {int((t - started) / 0.02) for t in ticks if started <= t < started + 0.02 * windows}
    assert len(ticked) >= windows // 2, f"ticks in {len(ticked)} of {windows} windows: the GIL was held"
