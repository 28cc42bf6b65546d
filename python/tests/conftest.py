"""Shared helpers: the repository root, two small scenes (a PBF column and a granular wedge
of known slope), `cargo xtask run` and a reader of its VTK frames."""

import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]

# A scene of a few hundred particles and 5 frames (0.1 s of 0.02 s), walls as volume maps.
PBF = """
name = "tiny"
[simulation]
precision = "f64"
particle_spacing = 0.05
duration = 0.1
frame_dt = 0.02
[solver]
kind = "pbf"
substeps = 2
solver_iterations = 3
[boundary]
model = "volume-map"
[tank]
min = [0.0, 0.0, 0.0]
max = [0.5, 0.5, 0.5]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.2, 0.3, 0.2]
"""

# A planar heap of known slope: a prism whose cross-section is an isosceles triangle with
# base 1 m (x) and flanks at 30°, 0.2 m deep (z), filled with particles at 0.02 m.
H = float(0.5 * np.tan(np.radians(30.0)))
WEDGE_OBJ = f"""v 0 0 0
v 1 0 0
v 0.5 {H!r} 0
v 0 0 0.2
v 1 0 0.2
v 0.5 {H!r} 0.2
f 1 3 2
f 4 5 6
f 1 2 5
f 1 5 4
f 1 4 6
f 1 6 3
f 2 3 6
f 2 6 5
"""

WEDGE = """
name = "wedge"
[simulation]
particle_spacing = 0.02
duration = 0.04
frame_dt = 0.02
gravity = [0.0, 0.0, 0.0]
[solver]
kind = "granular"
substeps = 2
friction_angle_deg = 30.0
[boundary]
model = "collision"
[tank]
min = [-0.01, -0.01, -0.01]
max = [1.01, 0.5, 0.21]
[[fluid]]
kind = "mesh"
path = "wedge.obj"
"""


def xtask_run(scene: Path, out: Path, frames: int, render: bool = False) -> Path:
    """Runs `cargo xtask run SCENE --quick --frames N` (the Rust front end) into `out`."""
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not on PATH: the comparison with `cargo xtask run` needs it")
    cmd = ["cargo", "xtask", "run", str(scene), "--quick", "--frames", str(frames), "--out", str(out)]
    if render:
        cmd.append("--render")
    subprocess.run(cmd, cwd=REPO, check=True, env={**os.environ, "CARGO_TERM_COLOR": "never"})
    return out


def read_vtk_frame(path: Path) -> dict:
    """A particle frame of `sph_sim::vtk` (legacy VTK, binary, big-endian POLYDATA): the
    points, the point data `velocity`, `density` and `id`, as numpy arrays."""
    data = Path(path).read_bytes()
    if not data.startswith(b"# vtk DataFile Version"):
        raise ValueError(f"{path}: not a legacy VTK file")

    def block(header: bytes, dtype: str, count_per_point: int) -> np.ndarray:
        m = re.search(re.escape(header) + rb"[^\n]*\n(LOOKUP_TABLE default\n)?", data)
        if m is None:
            raise ValueError(f"{path}: no {header!r}")
        n = int(re.search(rb"POINTS (\d+)", data).group(1))
        count = n * count_per_point
        size = np.dtype(dtype).itemsize * count
        return np.frombuffer(data[m.end() : m.end() + size], dtype=dtype, count=count)

    n = int(re.search(rb"POINTS (\d+)", data).group(1))
    return {
        "positions": block(b"POINTS ", ">f4", 3).reshape(n, 3),
        "velocities": block(b"VECTORS velocity float", ">f4", 3).reshape(n, 3),
        "densities": block(b"SCALARS density float 1", ">f4", 1),
        "ids": block(b"SCALARS id int 1", ">i4", 1),
    }
