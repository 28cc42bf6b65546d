"""Type stubs of the extension module (the Rust side of partisim)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Float = Union[npt.NDArray[np.float64], npt.NDArray[np.float32]]

class PartisimError(Exception):
    """An error reported by the Rust crates; the message is the Rust error's."""

__version__: str

def neighbour_lists(
    positions: npt.ArrayLike,
    radius: float,
    method: str = "cell-start-grid",
    max_pairs: Optional[int] = None,
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.uint32]]:
    """CSR neighbour lists of (N, 3) positions within radius (same length unit), at most
    max_pairs pairs (default: what the memory available holds); see
    partisim.neighbour_lists."""

class Kernel:
    """A smoothing kernel W(r, h) of support radius h (m)."""
    @property
    def name(self) -> str: ...
    @property
    def support_radius(self) -> float:
        """h (m)."""
    def value(self, r: npt.ArrayLike) -> _Float:
        """W(r) (1/m³) for distances r (m), any shape."""
    def derivative(self, r: npt.ArrayLike) -> _Float:
        """dW/dr (1/m⁴) for distances r (m), any shape."""
    def gradient(self, r_vectors: npt.ArrayLike) -> _Float:
        """∇W (1/m⁴) for difference vectors x_i - x_j (m), shape (..., 3)."""

def kernel(name: str, support_radius: float) -> Kernel:
    """poly6, spiky, viscosity, cubic-spline or wendland-c2 with support radius h (m)."""

class Simulation:
    """A scene file run frame by frame (sph-sim's SceneSim and frame loop)."""
    @staticmethod
    def from_scene(path: _Path, quick: bool = False) -> Simulation:
        """Loads, checks and builds a scene (quick: its [quick] overrides)."""
    def step(self) -> Dict[str, Any]:
        """Advances one frame; returns its statistics (a blow-up raises PartisimError)."""
    def run(
        self,
        frames: int,
        progress: bool = True,
        callback: Optional[Callable[[Dict[str, Any]], Any]] = None,
    ) -> Dict[str, Any]:
        """Advances `frames` frames (progress bar on stderr). `callback(stats)` after each
        frame: False or a string (the reason) stops the run. Returns how it ended:
        {"ending": "completed" | "stopped" | "diverged", "frame", "time_s", "reason"}.
        Ctrl-C stops between frames with KeyboardInterrupt (the frames done are kept)."""
    @property
    def positions(self) -> _Float:
        """(N, 3) positions (m), in the scene's particle order and precision."""
    @property
    def velocities(self) -> _Float:
        """(N, 3) velocities (m/s), in the scene's particle order and precision."""
    @property
    def densities(self) -> _Float:
        """(N,) densities (kg/m³), in the scene's particle order and precision."""
    @property
    def time(self) -> float:
        """Simulated time (s)."""
    @property
    def frame(self) -> int:
        """Frames done."""
    @property
    def precision(self) -> str:
        """"f32" or "f64" (the scene's)."""
    @property
    def stats(self) -> Optional[Dict[str, Any]]:
        """The last frame's record as a dict (frame, time_s, particles, density ratios,
        iterations, kinetic_energy_j, max_speed_m_s, phases_s, total_s ...; times in s)."""
    def write_vtk(self, path: _Path) -> None:
        """Writes a legacy VTK particle frame (the format of `cargo xtask run`)."""
    def render(self) -> npt.NDArray[np.uint8]:
        """(H, W, 3) image with the scene's [render] settings."""

def render_options(
    positions: npt.ArrayLike,
    radius: float,
    options: Dict[str, Any],
    tank: Optional[Tuple[Sequence[float], Sequence[float]]] = None,
) -> npt.NDArray[np.uint8]:
    """(H, W, 3) image of spheres of radius (m) at positions (N, 3) with the other
    [render] options as a dict; see partisim.render."""
def read_png(path: _Path) -> npt.NDArray[np.uint8]:
    """An 8-bit RGB PNG as an (H, W, 3) uint8 array."""
def write_png(path: _Path, image: npt.ArrayLike) -> None:
    """An (H, W, 3) uint8 image written as an 8-bit RGB PNG, atomically."""
def outer_solar_system_table(frame: str = "ecliptic_j2000") -> Dict[str, Any]: ...

class Population:
    """symplectic::Population (see partisim.Population for the Python interface)."""
    @staticmethod
    def from_spec_json(
        spec_json: str, particles: npt.NDArray[np.float64], ids: Optional[npt.NDArray[np.uint64]] = None
    ) -> Population: ...
    @staticmethod
    def from_spec_file(path: _Path) -> Population: ...
    def advance_to_days(
        self, t_days: float, callback: Optional[Callable[[Dict[str, Any]], Any]] = None
    ) -> bool: ...
    @property
    def time_days(self) -> float: ...
    @property
    def particle_steps(self) -> int: ...
    def __len__(self) -> int: ...
    @property
    def status(self) -> List[str]: ...
    def table(self) -> Dict[str, Any]: ...
    def write_parquet(self, path: _Path) -> None: ...
    def shard(self, start: int, stop: int) -> Population: ...
    @staticmethod
    def merge(shards: List[Population]) -> Population: ...
    def save(self, path: _Path) -> None: ...
    @staticmethod
    def load(path: _Path) -> Population: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> Population: ...
    @property
    def states(self) -> npt.NDArray[np.float64]: ...
    def elements(self, at_days: Optional[float] = None) -> Dict[str, npt.NDArray[np.float64]]: ...
    def states_at_days(
        self, at_days: Optional[float] = None
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
    @property
    def ids(self) -> npt.NDArray[np.uint64]: ...
