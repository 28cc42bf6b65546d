"""Ctrl-C (SIGINT, simulated with _thread.interrupt_main) stops a long call between frames
or windows with KeyboardInterrupt, keeping the work done."""

import _thread
import signal
import threading

import numpy as np
import pytest

import partisim
from conftest import REPO


@pytest.fixture(autouse=True)
def python_handles_sigint():
    """Python's own SIGINT handler for the test: a process started with SIGINT ignored (a
    background job of a non-interactive shell, as some CI runners start their jobs) has none,
    and `_thread.interrupt_main` then does nothing."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def interrupt_after(seconds: float) -> threading.Timer:
    t = threading.Timer(seconds, _thread.interrupt_main)
    t.start()
    return t


def test_a_scene_run_stops_between_frames():
    sim = partisim.Simulation.from_scene(REPO / "scenes" / "dam_break.toml", quick=True)
    timer = interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        sim.run(2000, progress=False)  # minutes if not interrupted
    timer.join()
    assert 0 < sim.frame < 2000
    assert np.isfinite(sim.positions).all()


def test_a_population_stops_between_windows():
    el = np.tile([60.0, 0.4, 10.0, 20.0, 30.0, 40.0], (2000, 1))
    el[:, 5] = np.linspace(0.0, 359.0, 2000)
    pop = partisim.Population(partisim.outer_solar_system(), el, window_steps=4)
    timer = interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        pop.advance(1e6)  # hours if not interrupted
    timer.join()
    assert 0 < pop.time_years < 1e6


def test_a_callback_stop_and_an_interrupt_both_leave_the_simulation_usable():
    sim = partisim.Simulation.from_scene(REPO / "scenes" / "dam_break.toml", quick=True)
    seen = []

    def until_frame_3(stats):
        seen.append(stats["frame"])
        return "frame 3 reached" if stats["frame"] == 3 else None

    outcome = sim.run(100, progress=False, callback=until_frame_3)
    assert outcome["ending"] == "stopped" and outcome["reason"] == "frame 3 reached"
    assert outcome["frame"] == 3 == sim.frame and seen == [1, 2, 3]
    assert sim.stats["frame"] == 3 and sim.stats["particles"] == len(sim.positions)

    timer = interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        sim.run(2000, progress=False)  # minutes if not interrupted
    timer.join()
    interrupted_at = sim.frame
    assert 3 < interrupted_at < 2003 and sim.stats["frame"] == interrupted_at

    # Both stops left a simulation that goes on frame by frame.
    assert sim.run(1, progress=False)["ending"] == "completed"
    assert sim.frame == interrupted_at + 1 and np.isfinite(sim.positions).all()
    assert sim.step()["frame"] == interrupted_at + 2
    # A false answer goes on (only a true one stops).
    assert sim.run(2, progress=False, callback=lambda s: False)["frame"] == interrupted_at + 4
