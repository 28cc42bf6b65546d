"""Neighbour lists (crate ``neighbour-search``)."""

from __future__ import annotations

from typing import Tuple

import numpy as np

from . import _partisim

METHODS = ("cell-start-grid", "relation-table", "hashed-grid", "brute-force")


def neighbour_lists(
    positions: np.ndarray, radius: float, method: str = "cell-start-grid"
) -> Tuple[np.ndarray, np.ndarray]:
    """Every particle's neighbours within ``radius``, as CSR arrays.

    Parameters
    ----------
    positions : ndarray, shape (N, 3), float64 or float32
        Particle positions (m, or any length unit shared with ``radius``).
    radius : float
        Search radius (same unit), finite and > 0. Pairs with ``|x_i - x_j| < radius``
        are neighbours (the crate's rule, with its round-off margin); a particle is not its
        own neighbour.
    method : str
        ``"cell-start-grid"`` (default), ``"relation-table"``, ``"hashed-grid"`` or
        ``"brute-force"``.

    Returns
    -------
    offsets : ndarray, shape (N + 1,), int64
        Particle ``i``'s neighbours are ``indices[offsets[i]:offsets[i + 1]]``.
    indices : ndarray, shape (offsets[-1],), uint32
        Neighbour indices into ``positions`` (order within a list is the method's).

    Raises
    ------
    TypeError, ValueError
        Not a float64/float32 array of shape (N, 3).
    PartisimError
        A bad radius, a non-finite position (named by index and axis), or a domain too
        large for the method.
    """
    return _partisim.neighbour_lists(positions, float(radius), method)
