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


# A sphere of 0.3 m as a volume-map solid at a 4 mm spacing: a map of millions of nodes,
# hundreds of thousands of them in the sphere's band, each a quadrature of 16 x 32 rays.
SPHERE_SCENE = """
name = "sphere_map"
[simulation]
precision = "f32"
particle_spacing = 0.006
duration = 0.02
frame_dt = 0.02
[solver]
kind = "pbf"
substeps = 1
solver_iterations = 1
[boundary]
model = "volume-map"
[tank]
min = [0.0, 0.0, 0.0]
max = [0.8, 0.8, 0.8]
[[solid]]
kind = "sphere"
center = [0.4, 0.4, 0.4]
radius = 0.3
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.02, 0.02, 0.02]
"""


def test_a_volume_map_build_stops_on_ctrl_c(tmp_path):
    """from_scene was deaf to Ctrl-C while it built volume maps; the build now checks a
    cancellation flag per row of nodes."""
    import time

    path = tmp_path / "sphere.toml"
    path.write_text(SPHERE_SCENE)
    cache = tmp_path / "cache"
    timer = interrupt_after(0.5)
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        partisim.Simulation.from_scene(path, volume_map_cache=cache)
    stopped_after = time.monotonic() - start
    timer.join()
    # The bound of the bad-input suite's Ctrl-C cases (the build runs far longer whole).
    assert stopped_after < 10.0
