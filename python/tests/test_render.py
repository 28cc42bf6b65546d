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
    with pytest.raises(partisim.PartisimError, match="radius"):
        partisim.render(p, -1.0, width=32, height=32)
    with pytest.raises(ValueError, match=r"positions: expected shape \(N, 3\)"):
        partisim.render(p[:, :2], 0.0075, width=32, height=32)
    with pytest.raises(partisim.PartisimError):
        partisim.render(p, 0.0075, width=0, height=32)


def test_option_errors_speak_of_keywords_not_of_json():
    # These messages once quoted line and column of JSON text the caller never wrote.
    p = block()
    with pytest.raises(partisim.PartisimError) as e:
        partisim.render(p, 0.0075, width=32, height=32, background={"colour_of_sky": 1})
    msg = str(e.value)
    assert msg.startswith("render: background.colour_of_sky: unknown field `colour_of_sky`"), msg
    assert "line" not in msg and "column" not in msg and "\n" not in msg
    with pytest.raises(partisim.PartisimError) as e:
        partisim.render(p, 0.0075, camera={"eye": [1.0, 2.0]}, width=32, height=32)
    msg = str(e.value)
    assert msg.startswith("render: camera.eye: "), msg
    assert "line" not in msg and "column" not in msg


def test_a_nan_radius_is_reported_as_a_bad_radius():
    # It was reported as a JSON syntax error.
    with pytest.raises(partisim.PartisimError) as e:
        partisim.render(block(), float("nan"), width=32, height=32)
    assert str(e.value) == "render: radius: NaN: must be finite and > 0"


def test_a_bad_field_of_view_is_blamed_not_the_eye_derived_from_it():
    with pytest.raises(partisim.PartisimError) as e:
        partisim.render(block(), 0.0075, camera={"fov_deg": float("nan")}, width=32, height=32)
    assert str(e.value) == "render: camera.fov_deg: NaN: must be finite and > 0"


def test_huge_coordinates_blame_the_particle_not_a_camera():
    # The caller gave no camera; the message once blamed one.
    p = block()
    p[7, 0] = 1e30
    with pytest.raises(partisim.PartisimError) as e:
        partisim.render(p, 0.0075, width=32, height=32)
    msg = str(e.value)
    assert "particle 7" in msg and "coordinate x = 1e30" in msg and "camera" not in msg, msg


def test_array_likes_and_numpy_integers():
    p = block()
    img = partisim.render(p, 0.0075, width=48, height=32)
    assert np.array_equal(partisim.render(p.tolist(), 0.0075, width=48, height=32), img)
    assert np.array_equal(
        partisim.render(p, np.float32(0.0075), width=np.int64(48), height=np.uint16(32)), img
    )
    cam = {"eye": np.array([0.4, 0.5, 1.5]), "target": (0.37, 0.1, 0.37), "fov_deg": np.int32(30)}
    listed = {"eye": [0.4, 0.5, 1.5], "target": [0.37, 0.1, 0.37], "fov_deg": 30.0}
    assert np.array_equal(
        partisim.render(p, 0.0075, camera=cam, width=48, height=32),
        partisim.render(p, 0.0075, camera=listed, width=48, height=32),
    )
    # None takes the default.
    assert np.array_equal(partisim.render(p, 0.0075, width=48, height=32, camera=None,
                                          background=None), img)


def test_write_png_round_trips_and_is_atomic(tmp_path):
    img = partisim.render(block(), 0.0075, width=40, height=24)
    path = tmp_path / "frame.png"
    partisim.write_png(path, img)
    assert np.array_equal(partisim.read_png(path), img)
    # Integer arrays in 0..255 are accepted; the old file stays until the new is complete.
    ramp = (np.arange(24 * 40 * 3) % 256).reshape(24, 40, 3)
    partisim.write_png(str(path), ramp)
    assert np.array_equal(partisim.read_png(path), ramp.astype(np.uint8))
    with pytest.raises(ValueError):
        partisim.write_png(path, ramp + 1)  # 256 is out of range: nothing written
    assert np.array_equal(partisim.read_png(path), ramp.astype(np.uint8))
    assert sorted(q.name for q in tmp_path.iterdir()) == ["frame.png"]


def test_version_is_the_crates():
    import re
    from importlib.metadata import version

    assert re.fullmatch(r"\d+\.\d+\.\d+.*", partisim.__version__)
    assert partisim.__version__ == version("partisim")
