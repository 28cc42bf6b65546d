"""Screen-space fluid rendering (crate ``ssfr-render``)."""

from __future__ import annotations

import os
from typing import Any, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _partisim


def render(
    positions: ArrayLike,
    radius: float,
    camera: Optional[Mapping[str, Any]] = None,
    width: int = 1280,
    height: int = 720,
    *,
    tank: Optional[Tuple[Sequence[float], Sequence[float]]] = None,
    **options: Any,
) -> np.ndarray:
    """An image of the liquid the particles make (van der Laan et al. 2009's screen-space
    fluid pipeline with the crate's improvements).

    Parameters
    ----------
    positions : array_like, shape (N, 3)
        Particle centres (m), y up. float64 and float32 arrays are used as they are (views
        and non-contiguous arrays included); lists, integer arrays and other real dtypes
        are converted to float64 as ``numpy.asarray`` would. Each coordinate must be
        finite and within ±1e18 m (the renderer computes in float32).
    radius : float
        Radius of each particle's sphere (m), finite and > 0.
    camera : dict, optional
        ``eye`` and ``target`` (m, 3 numbers each), ``up`` (3 numbers) and ``fov_deg``
        (vertical field of view, degrees). Missing entries default to a view framing
        ``tank`` or else the particles' bounding box.
    width, height : int
        Image size (pixels), each >= 1, at most 2**26 pixels in all, whose buffers (93
        bytes a pixel: 6.2 GB at 2**26) must fit in the memory available (else
        PartisimError with both sizes, before any is allocated).
    tank : (min, max), optional
        Corners of a tank (m) drawn as walls and framed by the default camera.
    **options
        The other tables of a scene's ``[render]`` section, as dicts: ``light``,
        ``background``, ``smoothing``, ``refraction``, ``material``, ``noise``,
        ``anisotropy``, and ``thickness_blur_px`` (int). Entries that are ``None`` take
        their defaults.

    Returns
    -------
    ndarray, shape (height, width, 3), uint8
        The sRGB image (row 0 at the top); :func:`write_png` saves it.

    Raises
    ------
    ValueError, TypeError
        ``positions`` not of shape (N, 3) or not real numbers.
    PartisimError
        An option out of range or unknown, named by its keyword (``radius``,
        ``camera.fov_deg``, ``background``: unknown field ...); a particle with a
        non-finite or out-of-range coordinate, named by its index; no particle in view;
        positions too large to copy in the memory available.
    KeyboardInterrupt
        Ctrl-C while rendering (the call returns at once; the frame being drawn is
        discarded).
    """
    config: dict = {"width": width, "height": height}
    if camera is not None:
        config["camera"] = dict(camera)
    config.update(options)
    tank_arg = None
    if tank is not None:
        lo, hi = tank
        tank_arg = (tuple(float(x) for x in lo), tuple(float(x) for x in hi))
    return _partisim.render_options(positions, float(radius), config, tank_arg)


def read_png(path: Union[str, "os.PathLike[str]"]) -> np.ndarray:
    """Reads an 8-bit RGB or RGBA PNG (alpha dropped), as the renderer writes them.

    Parameters
    ----------
    path : str or path-like
        The file.

    Returns
    -------
    ndarray, shape (height, width, 3), uint8

    Raises
    ------
    PartisimError
        The file is missing, not a PNG, not 8-bit, or larger than the PNG decoder's
        limit on decoded bytes; the message names the file.
    """
    return _partisim.read_png(os.fspath(path))


def write_png(path: Union[str, "os.PathLike[str]"], image: ArrayLike) -> None:
    """Writes an image as an 8-bit RGB PNG, atomically (the file appears complete or not
    at all; an existing file is replaced only once the new one is written).

    Parameters
    ----------
    path : str or path-like
        The file to write (its directory must exist).
    image : array_like, shape (height, width, 3)
        uint8 sRGB values, row 0 at the top (what :func:`render` returns); integer arrays
        are accepted when every value is in 0..255. At most 2**26 pixels.

    Raises
    ------
    ValueError, TypeError
        Not of shape (H, W, 3), an empty image, values outside 0..255 or not integers.
    PartisimError
        The file cannot be written (the message names it and the reason).
    """
    _partisim.write_png(os.fspath(path), image)
