"""Simulation against `cargo xtask run`'s frames (VTK) and images (PNG), bit for bit."""

from pathlib import Path

import numpy as np
import pytest

import partisim
from conftest import REPO, read_vtk_frame, xtask_run

SCENE = REPO / "scenes" / "dam_break.toml"
FRAMES = 2


@pytest.fixture(scope="module")
def rust_run(tmp_path_factory):
    return xtask_run(SCENE, tmp_path_factory.mktemp("xtask") / "run", FRAMES, render=True)


def check_frame(sim, frame: dict):
    ids = frame["ids"]
    # The scene is float32, as the VTK frames are.
    for name in ("positions", "velocities", "densities"):
        ours = getattr(sim, name)
        assert ours.dtype == np.float32
        assert np.array_equal(ours[ids], frame[name]), name


def test_frames_equal_xtask_run(rust_run):
    sim = partisim.Simulation.from_scene(SCENE, quick=True)
    assert sim.precision == "f32" and sim.frame == 0 and sim.stats is None
    check_frame(sim, read_vtk_frame(rust_run / "frame_00000.vtk"))
    stats = sim.step()
    assert stats["substeps"] == 4 and stats["neighbour_pairs"] > 0
    # The dict and stats.csv are the same frame record: the counts agree exactly.
    header, row = (rust_run / "stats.csv").read_text().splitlines()[:2]
    csv = dict(zip(header.split(","), row.split(",")))
    for key in ("frame", "particles", "iterations", "neighbour_pairs", "substeps"):
        assert int(csv[key]) == stats[key], key
    assert set(stats["phases_s"]) | {"total"} == {k[:-2] for k in csv if k.endswith("_s")} - {
        "time", "max_speed_m"}
    check_frame(sim, read_vtk_frame(rust_run / "frame_00001.vtk"))
    outcome = sim.run(FRAMES - 1, progress=False)
    assert outcome["ending"] == "completed" and outcome["frame"] == FRAMES
    assert sim.frame == FRAMES and sim.time == pytest.approx(FRAMES * 0.016, rel=1e-12)
    assert sim.stats["reordered"] in (True, False)
    check_frame(sim, read_vtk_frame(rust_run / f"frame_{FRAMES:05}.vtk"))


def test_write_vtk_is_the_runs_format(rust_run, tmp_path):
    sim = partisim.Simulation.from_scene(SCENE, quick=True)
    sim.step()
    sim.write_vtk(tmp_path / "f.vtk")
    assert (tmp_path / "f.vtk").read_bytes() == (rust_run / "frame_00001.vtk").read_bytes()


def test_the_scene_image_equals_xtask_run_render(rust_run):
    sim = partisim.Simulation.from_scene(SCENE, quick=True)
    png = partisim.read_png(rust_run / "render" / "frame_00000.png")
    image = sim.render()
    assert image.shape == (450, 800, 3) and image.dtype == np.uint8
    assert np.array_equal(image, png)
    # The free function with the scene's settings (tank, default camera, particle radius
    # 0.75 x the quick spacing 0.025 m) gives the same image.
    free = partisim.render(sim.positions, 0.75 * 0.025, width=800, height=450,
                           tank=((0.0, 0.0, 0.0), (1.6, 1.0, 0.6)))
    assert np.array_equal(free, png)


def test_bad_scenes_raise_clear_errors(tmp_path):
    with pytest.raises(partisim.PartisimError, match="no_such_scene.toml"):
        partisim.Simulation.from_scene(tmp_path / "no_such_scene.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.read_text().replace("substeps = 4", "substeps = -4"))
    with pytest.raises(partisim.PartisimError, match="substeps"):
        partisim.Simulation.from_scene(bad, quick=True)
