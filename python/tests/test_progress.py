"""The progress callback is called; an exception raised in it, or Ctrl-C
(SIGINT → KeyboardInterrupt), stops the run and is re-raised."""

from __future__ import annotations

import os
import signal
import threading

import pytest

import railmbs
from conftest import SCENARIOS


def long_run() -> railmbs.Scenario:
    # 10⁴ s of the double pendulum: minutes of CPU, so that a run that is not
    # stopped would not end within the test.
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    sc.end_time = 1e4
    return sc


def test_progress_is_called_with_time_and_end_time():
    calls = []
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    sc.end_time = 0.5
    r = sc.run(progress=lambda t, t_end: calls.append((t, t_end)))
    assert calls, "progress was never called"
    assert calls[-1] == (r.summary["t_end"], 0.5)
    assert all(0.0 <= t <= t_end for t, t_end in calls)


class Stop(Exception):
    pass


def test_an_exception_in_the_callback_stops_the_run_and_is_reraised():
    calls = []

    def progress(t, t_end):
        calls.append(t)
        raise Stop(f"stopped at {t}")

    with pytest.raises(Stop):
        long_run().run(progress=progress)
    # Called once: the run stopped at its next output row.
    assert len(calls) == 1 and calls[0] < 1e4


def test_ctrl_c_stops_the_run_with_keyboard_interrupt(python_sigint_handler):
    """SIGINT while the run is in Rust (GIL released): the next progress
    tick runs Python's handler and the run stops with KeyboardInterrupt.
    The signal is sent from another thread once the run is under way (its
    first progress call), so it cannot hit the test before the run."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    timers, seen = [], []

    def progress(t, t_end):
        seen.append(t)
        if not timers:
            timers.append(threading.Timer(0.05, lambda: os.kill(os.getpid(), signal.SIGINT)))
            timers[0].start()

    try:
        with pytest.raises(KeyboardInterrupt):
            long_run().run(progress=progress)
    finally:
        for timer in timers:
            timer.cancel()
    assert timers, "the run never called progress"
    # Stopped early: a KeyboardInterrupt raised only after the run had
    # finished (its last progress call is at t_end) would not count.
    assert max(seen) < 1e4
