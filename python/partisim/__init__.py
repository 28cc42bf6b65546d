"""partisim: particle simulation from four papers, in Python.

Thin bindings (pyo3 + numpy) over the Rust crates of the workspace; the Rust crates do all
the work, with the GIL released during long calls:

- :func:`neighbour_lists` (crate ``neighbour-search``): CSR neighbour lists.
- :func:`kernel` (crate ``sph-kernels``): SPH smoothing kernels, vectorised.
- :class:`Simulation` (crate ``sph-sim``): a scene file run frame by frame.
- :func:`render` (crate ``ssfr-render``): screen-space fluid images of particles.
- :class:`Population`, :func:`outer_solar_system` (crate ``symplectic``): comet populations;
  :func:`partisim.dask.run_population_dask` spreads one over a Dask cluster.

Units are SI for fluids (m, s, kg) and AU, days, degrees for comets (years for spans).
Every error reported by the Rust side is raised as :class:`PartisimError` with its message.
"""

from ._partisim import PartisimError, Simulation, kernel, Kernel, read_png
from .neighbours import neighbour_lists
from .render import render
from .comets import Population, PopulationSpec, outer_solar_system, Planets

__all__ = [
    "PartisimError",
    "neighbour_lists",
    "kernel",
    "Kernel",
    "Simulation",
    "render",
    "read_png",
    "Population",
    "PopulationSpec",
    "Planets",
    "outer_solar_system",
]
