"""neighbour_lists against a brute force written here in numpy."""

import numpy as np
import pytest

import partisim
from partisim.neighbours import METHODS


def brute_force(p: np.ndarray, radius: float):
    d2 = ((p[:, None, :] - p[None, :, :]) ** 2).sum(-1)
    inside = d2 < radius * radius
    np.fill_diagonal(inside, False)
    return [set(np.nonzero(row)[0]) for row in inside], d2


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_lists_equal_brute_force(method, dtype):
    rng = np.random.default_rng(7)
    p = (rng.random((600, 3)) * [1.0, 0.5, 0.8]).astype(dtype)
    radius = 0.09
    offsets, indices = partisim.neighbour_lists(p, radius, method=method)
    assert offsets.dtype == np.int64 and indices.dtype == np.uint32
    assert offsets.shape == (601,) and offsets[0] == 0 and offsets[-1] == len(indices)
    expected, d2 = brute_force(p.astype(np.float64), radius)
    # Pairs within a relative 1e-5 of the radius may go either way (the crate's round-off
    # margin, neighbour_search::CELL_MARGIN, and float32 distances): compared outside it.
    r2 = radius * radius
    ambiguous = np.abs(d2 - r2) < 1e-5 * r2
    for i in range(len(p)):
        got = set(indices[offsets[i] : offsets[i + 1]].tolist())
        assert len(got) == offsets[i + 1] - offsets[i], f"particle {i}: a neighbour twice"
        amb = set(np.nonzero(ambiguous[i])[0])
        assert got - amb == expected[i] - amb, f"particle {i}"


def test_non_contiguous_input_is_accepted():
    p = np.random.default_rng(1).random((200, 6))[:, ::2]
    o1, i1 = partisim.neighbour_lists(p, 0.2)
    o2, i2 = partisim.neighbour_lists(np.ascontiguousarray(p), 0.2)
    assert np.array_equal(o1, o2) and np.array_equal(i1, i2)


def test_array_likes_are_converted_as_numpy_converts_them():
    rng = np.random.default_rng(3)
    p = rng.random((300, 3))
    expected = partisim.neighbour_lists(p, 0.15)
    grid = (rng.integers(0, 6, (300, 3))).astype(np.int64)
    as_float = partisim.neighbour_lists(grid.astype(np.float64), 1.5)
    for like in (
        p.tolist(),  # a list of lists
        tuple(map(tuple, p.tolist())),  # tuples
        p.astype(">f8"),  # big-endian float64
        np.asfortranarray(p),  # column major
        np.repeat(p, 2, axis=0)[::2],  # a strided view
    ):
        got = partisim.neighbour_lists(like, np.float64(0.15))
        assert all(np.array_equal(a, b) for a, b in zip(got, expected))
    for like in (grid, grid.astype(np.int32), grid.astype(np.uint16), grid.tolist()):
        got = partisim.neighbour_lists(like, np.int64(1) + 0.5)
        assert all(np.array_equal(a, b) for a, b in zip(got, as_float))
    # float16 is widened to float64, float32 searched as float32 (as before).
    half = partisim.neighbour_lists(p.astype(np.float16), 0.15)
    assert all(np.array_equal(a, b) for a, b in
               zip(half, partisim.neighbour_lists(p.astype(np.float16).astype(np.float64), 0.15)))


def test_numpy_integers_are_accepted_for_max_pairs():
    p = np.zeros((5, 3))
    offsets, indices = partisim.neighbour_lists(p, 0.1, max_pairs=np.int64(20))
    assert len(indices) == 20 and offsets[-1] == 20
    with pytest.raises(partisim.PartisimError, match="more than 19 pairs"):
        partisim.neighbour_lists(p, 0.1, max_pairs=np.uint8(19))


def test_empty_positions_give_empty_lists():
    offsets, indices = partisim.neighbour_lists(np.zeros((0, 3)), 0.1)
    assert offsets.tolist() == [0] and len(indices) == 0


def test_bad_input_raises_clear_errors():
    p = np.zeros((10, 3))
    with pytest.raises(ValueError, match=r"positions: expected shape \(N, 3\), got \[10, 2\]"):
        partisim.neighbour_lists(np.zeros((10, 2)), 0.1)
    with pytest.raises(TypeError, match="positions: expected real numbers.*got dtype complex128"):
        partisim.neighbour_lists(np.zeros((10, 3), dtype=complex), 0.1)
    with pytest.raises(partisim.PartisimError, match="radius h = -0.1 must be finite and > 0"):
        partisim.neighbour_lists(p, -0.1)
    q = p.copy()
    q[4, 1] = np.nan
    with pytest.raises(partisim.PartisimError, match="particle 4: position component y is not finite"):
        partisim.neighbour_lists(q, 0.1)
    with pytest.raises(ValueError, match="unknown neighbour-search method"):
        partisim.neighbour_lists(p, 0.1, method="octree")


def test_pairs_beyond_the_limit_are_refused_with_both_sizes():
    # 2000 coincident points: 2000 · 1999 = 3,998,000 ordered pairs, all within any radius.
    p = np.zeros((2000, 3))
    offsets, indices = partisim.neighbour_lists(p, 0.1, max_pairs=3_998_000)
    assert len(indices) == 3_998_000
    with pytest.raises(partisim.PartisimError) as e:
        partisim.neighbour_lists(p, 0.1, max_pairs=3_997_999)
    msg = str(e.value)
    assert "more than 3997999 pairs (15991996 bytes" in msg and "max_pairs = 3997999" in msg
