"""The free render function: options, shapes and bad input (its pixels are compared with
the Rust run's image in test_sim.py)."""

import numpy as np
import pytest

import partisim


def block(dtype=np.float64):
    g = np.stack(np.meshgrid(*[np.arange(8) * 0.02] * 3, indexing="ij"), -1).reshape(-1, 3)
    return (g + [0.3, 0.05, 0.3]).astype(dtype)


def test_image_shape_and_options():
    p = block()
    img = partisim.render(p, 0.0075, width=64, height=48)
    assert img.shape == (48, 64, 3) and img.dtype == np.uint8
    img32 = partisim.render(block(np.float32), 0.0075, width=64, height=48)
    assert np.array_equal(img, img32)  # the renderer works in float32 either way
    cam = {"eye": [0.4, 0.5, 1.5], "target": [0.37, 0.1, 0.37], "fov_deg": 30.0}
    other = partisim.render(p, 0.0075, camera=cam, width=64, height=48,
                            background={"ground": False})
    assert other.shape == (48, 64, 3) and not np.array_equal(other, img)


def test_bad_input_raises_clear_errors():
    p = block()
    with pytest.raises(partisim.PartisimError, match="unknown field `colour_of_sky`"):
        partisim.render(p, 0.0075, width=32, height=32, background={"colour_of_sky": 1})
    with pytest.raises(partisim.PartisimError, match="particle_radius"):
        partisim.render(p, -1.0, width=32, height=32)
    with pytest.raises(ValueError, match=r"positions: expected shape \(N, 3\)"):
        partisim.render(p[:, :2], 0.0075, width=32, height=32)
    with pytest.raises(partisim.PartisimError):
        partisim.render(p, 0.0075, width=0, height=32)
