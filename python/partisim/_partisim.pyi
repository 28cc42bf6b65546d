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
    """A scene file run frame by frame (sph-sim's SceneSim and frame loop).

    Units are SI (m, s, kg); arrays are in the scene's particle order and precision
    (``precision``: float32 or float64). ``time`` is simulated time (s); wall-clock times
    appear only in ``stats`` (``*_s`` phase timings). Picklable; ``save``/``load`` continue
    bit for bit."""
    @staticmethod
    def from_scene(
        path: _Path,
        quick: bool = False,
        overrides: Optional[Dict[str, Any]] = None,
        volume_map_cache: Union[bool, _Path, None] = True,
    ) -> Simulation:
        """Loads, checks and builds a scene (quick: its [quick] overrides). `overrides`:
        values of the file's keys by dotted path ({"solver.friction_angle_deg": 33.0,
        "fluid[0].max": [...]}), checked as the file's ("given as an override" in messages).
        `volume_map_cache`: True (default: the command line's target/cache/volume-maps under
        the current directory), a directory, or None/False for none."""
    @staticmethod
    def load(path: _Path, volume_map_cache: Union[bool, _Path, None] = True) -> Simulation:
        """The simulation saved by `save`, continuing bit for bit."""
    def save(self, path: _Path) -> None:
        """Writes the scene text, overrides, quick mode and the whole state, atomically."""
    @staticmethod
    def _from_bytes(data: bytes, volume_map_cache: Union[bool, _Path, None] = True) -> Simulation: ...
    def __reduce__(self) -> Any: ...
    def step(self) -> Dict[str, Any]:
        """Advances one frame; returns its statistics (a blow-up raises PartisimError)."""
    def run(
        self,
        frames: Optional[int] = None,
        progress: Optional[bool] = None,
        callback: Optional[Callable[[Dict[str, Any]], Any]] = None,
        until_rest: Optional[Dict[str, Any]] = None,
    ) -> Dict[str, Any]:
        """Runs to the scene's last frame (frames=None) or `frames` more (numpy integers
        accepted), never past the scene's last frame (as `particles run --frames`); huge
        counts are clamped. Progress through partisim.progress (None: on for a terminal or
        Jupyter). `callback(stats)` after each frame: something true (True, a non-empty
        string: the reason) stops the run, None or anything false goes on.
        `until_rest={"speed_m_s", "hold_s", "region", "below_since_s"}` stops at rest
        (below_since_s: an earlier run's rest_below_since_s, continuing its hold). Returns
        {"ending", "frame", "time_s", "reason", "frames_run", "scene_frames",
        "at_scene_end"} (+ "at_rest", "rest_from_s", "rest_below_since_s",
        "max_speed_m_s" with until_rest).
        Ctrl-C stops between frames with KeyboardInterrupt (the frames done are kept)."""
    def repose(
        self,
        shape: str = "planar",
        floor_y: Optional[float] = None,
        bin_width_m: Optional[float] = None,
        fit_band: Tuple[float, float] = (0.2, 0.8),
        min_fit_points: int = 4,
        steepest_run_m: Optional[float] = None,
    ) -> Dict[str, Any]:
        """The angle of repose of the current particles (granular-measure), degrees, with
        its resolution, flanks, profile and the at-rest verdict of the last run watched
        with until_rest (None if none, or if frames were run since)."""
    @property
    def volume_maps(self) -> List[str]:
        """Per solid: "built", "loaded", "stored", "replaced", "write-failed" or
        "uncacheable" (empty for the collision boundary)."""
    @property
    def scene_frames(self) -> int:
        """The scene's last frame, ceil(duration / frame_dt)."""
    @property
    def solver(self) -> str:
        """The scene's solver kind: "pbf", "pcisph", "iisph" or "granular"."""
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
    def events_table(self) -> Dict[str, Any]: ...
    def write_events_parquet(self, path: _Path) -> None: ...
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
