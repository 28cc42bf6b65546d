"""Screen-space fluid rendering (crate ``ssfr-render``)."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional, Sequence, Tuple

import numpy as np

from . import _partisim


def render(
    positions: np.ndarray,
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
    positions : ndarray, shape (N, 3), float64 or float32
        Particle centres (m), y up.
    radius : float
        Radius of each particle's sphere (m), > 0.
    camera : dict, optional
        ``eye`` and ``target`` (m, 3 numbers each), ``up`` (3 numbers) and ``fov_deg``
        (vertical field of view, degrees). Missing entries default to a view framing
        ``tank`` or else the particles' bounding box.
    width, height : int
        Image size (pixels).
    tank : (min, max), optional
        Corners of a tank (m) drawn as walls and framed by the default camera.
    **options
        The other tables of a scene's ``[render]`` section, as dicts: ``light``,
        ``background``, ``smoothing``, ``refraction``, ``material``, ``noise``,
        ``anisotropy``, and ``thickness_blur_px`` (int). Unknown keys are errors naming them.

    Returns
    -------
    ndarray, shape (height, width, 3), uint8
        The sRGB image.
    """
    config = {
        "width": int(width),
        "height": int(height),
        "particle_radius": float(radius),
    }
    if camera is not None:
        config["camera"] = dict(camera)
    config.update(options)
    tank_arg = None
    if tank is not None:
        lo, hi = tank
        tank_arg = (tuple(float(x) for x in lo), tuple(float(x) for x in hi))
    return _partisim.render_json(positions, json.dumps(config), tank_arg)
