"""Every shipped scene (``scenes/*.toml``) runs from Python as from ``particles run``: built
in quick mode, its solver fields read at frame 0 (the elastic–plastic solver's initial
stress), run for a few frames (enough for a poured scene's first layer), its state finite."""

import numpy as np
import pytest

import partisim

from conftest import REPO

SCENES = sorted((REPO / "scenes").glob("*.toml"))


def test_the_shipped_scenes_are_found():
    assert len(SCENES) >= 20, SCENES


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    # One volume-map cache for the module: the thesis heaps share their maps.
    return tmp_path_factory.mktemp("volume-maps")


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_shipped_scene_runs(path, cache):
    sim = partisim.Simulation.from_scene(path, quick=True, volume_map_cache=cache)
    n0 = len(sim.positions)
    fields = sim.fields
    if "elastoplastic" in path.read_text() and n0 > 0:
        stress = fields["stress"]
        assert stress.shape == (n0, 6)
        # The geostatic start (if any) is there before the first frame: compressive or zero.
        assert np.all(stress[:, 1] <= 0.0)
    # A poured scene's (a `[pour]` table's) first layer is due after 0.167 s (frame 11) at
    # the quick spacing.
    frames = 12 if "[pour]" in path.read_text() else 2
    out = sim.run(frames, progress=False)
    assert out["ending"] == "completed", out
    n = len(sim.positions)
    assert n > 0
    assert np.all(np.isfinite(sim.positions)) and np.all(np.isfinite(sim.velocities))
    for name, values in sim.fields.items():
        assert len(values) == n, name
