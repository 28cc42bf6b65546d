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
