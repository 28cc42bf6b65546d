"""partisim: particle simulation from four papers, in Python.

Thin bindings (pyo3 + numpy) over the Rust crates of the workspace; the Rust crates do all
the work, with the GIL released during long calls:

- :func:`neighbour_lists` (crate ``neighbour-search``): CSR neighbour lists.
- :func:`kernel` (crate ``sph-kernels``): SPH smoothing kernels, vectorised.
- :class:`Simulation` (crate ``sph-sim``): a scene file run frame by frame.
- :func:`render` (crate ``ssfr-render``): screen-space fluid images of particles;
  :func:`write_png` and :func:`read_png` save and load them.
- :class:`Population`, :func:`outer_solar_system` (crate ``symplectic``): comet populations;
  :func:`partisim.dask.run_population_dask` spreads one over a Dask cluster.

Units are SI for fluids (m, s, kg) and AU, days, degrees for comets (years for spans).
Every error reported by the Rust side is raised as :class:`PartisimError` with its message.
Arrays are taken as numpy takes them (lists, integer arrays and views converted), checked
for shape and size before they are copied; long calls stop on Ctrl-C.

``__version__`` is the version of the Rust crates the extension was built from (the
package's own version: maturin takes it from the same place).
"""

from ._partisim import PartisimError, Simulation, kernel, Kernel, __version__
from .neighbours import neighbour_lists
from .render import render, read_png, write_png
from .comets import Population, PopulationSpec, outer_solar_system, Planets

__all__ = [
    "PartisimError",
    "neighbour_lists",
    "kernel",
    "Kernel",
    "Simulation",
    "render",
    "read_png",
    "write_png",
    "__version__",
    "Population",
    "PopulationSpec",
    "Planets",
    "outer_solar_system",
]
