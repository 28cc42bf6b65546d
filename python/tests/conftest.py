"""Shared helpers: the repository root, `cargo xtask run` and a reader of its VTK frames."""

import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


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
