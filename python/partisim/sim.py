"""Scene simulations (crate ``sph-sim``): :class:`Simulation`'s pure-Python helpers."""

from __future__ import annotations

from ._partisim import Simulation

__all__ = ["Simulation"]


def _simulation_from_bytes(data: bytes, volume_map_cache: bool = False) -> Simulation:
    """Unpickles a :class:`Simulation` (the bytes of ``Simulation.save``)."""
    return Simulation._from_bytes(data, volume_map_cache)
