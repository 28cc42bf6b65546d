"""Neighbour lists (crate ``neighbour-search``)."""

from __future__ import annotations

import operator
from typing import Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike

from . import _partisim

METHODS = ("cell-start-grid", "relation-table", "hashed-grid", "brute-force")


def neighbour_lists(
    positions: ArrayLike,
    radius: float,
    method: str = "cell-start-grid",
    max_pairs: Optional[int] = None,
) -> Tuple[np.ndarray, np.ndarray]:
    """Every particle's neighbours within ``radius``, as CSR arrays.

    Parameters
    ----------
    positions : array_like, shape (N, 3)
        Particle positions (m, or any length unit shared with ``radius``). float64 and
        float32 arrays are searched in their own precision (views and non-contiguous
        arrays included); lists, integer arrays and other real dtypes are converted to
        float64 as ``numpy.asarray`` would. Copied once; refused before the copy when it
        would not fit in the memory available.
    radius : float
        Search radius (same unit), finite and > 0. Pairs with ``|x_i - x_j| < radius``
        are neighbours (the crate's rule, with its round-off margin); a particle is not its
        own neighbour.
    method : str
        ``"cell-start-grid"`` (default), ``"relation-table"``, ``"hashed-grid"`` or
        ``"brute-force"``.
    max_pairs : int, optional
        Most (ordered) pairs the lists may hold; the search stops as soon as it finds
        more. Default: as many as the memory available when called holds (12 bytes a
        pair, for the index and the search's buffers; ``MemAvailable`` on Linux, no limit
        but the allocator's elsewhere). A radius in the wrong units or many coincident
        particles then raise instead of exhausting memory.

    Returns
    -------
    offsets : ndarray, shape (N + 1,), int64
        Particle ``i``'s neighbours are ``indices[offsets[i]:offsets[i + 1]]``.
    indices : ndarray, shape (offsets[-1],), uint32
        Neighbour indices into ``positions`` (order within a list is the method's).

    Raises
    ------
    TypeError, ValueError
        ``positions`` not of shape (N, 3), not real numbers; an unknown method; a
        negative or non-integer ``max_pairs``.
    PartisimError
        A bad radius; a non-finite position (named by index and axis); a domain too large
        for the method; more pairs than ``max_pairs`` (the message gives the pairs found
        and the limit, with their sizes in bytes); memory exhausted (the size asked for).
    KeyboardInterrupt
        Ctrl-C during the search (it stops within one grid cell).
    """
    if max_pairs is not None:
        max_pairs = operator.index(max_pairs)
        if max_pairs < 0:
            raise ValueError(f"max_pairs: must be >= 0, got {max_pairs}")
    return _partisim.neighbour_lists(positions, float(radius), method, max_pairs)
