"""Bad inputs of the comet side, each in a child interpreter (``_bad_input``): the named
exception within a time bound, memory bounded, the interpreter alive afterwards."""

import pytest

from _bad_input import BadInput, check, params
from conftest import REPO

# The shipped population file, its particle file swapped for the case's.
SHIPPED = REPO / "populations" / "scattered-disk.toml"

# Scattered-disk elements (a, e, i, node, peri, M) for the cases that need good particles.
ELEMENTS = "np.tile([60.0, 0.4, 10.0, 20.0, 30.0, 40.0], (8, 1))"
PLANETS = "partisim.outer_solar_system()"

CASES = [
    # Files that never end or block: refused from their metadata, before open().
    BadInput("load /dev/zero", "partisim.Population.load('/dev/zero')",
             words=("/dev/zero", "device", "not a regular file"), seconds=5),
    BadInput("from_file /dev/zero", "partisim.Population.from_file('/dev/zero')",
             words=("/dev/zero", "device", "not a regular file"), seconds=5),
    BadInput("from_file fifo", "partisim.Population.from_file(tmp / 'spec.toml')",
             setup="import os; os.mkfifo(tmp / 'spec.toml')",
             words=("named pipe",), seconds=5),
    BadInput("particle file /dev/zero",
             "partisim.Population.from_file(tmp / 'spec.toml')",
             setup=f"""
text = open({str(SHIPPED)!r}).read()
(tmp / 'spec.toml').write_text(text.replace('file = "scattered-disk.csv"', 'file = "/dev/zero"'))
""",
             words=("/dev/zero", "device"), seconds=5),
    # 3·10⁸ rows (a broadcast view: no memory of its own) counted before any copy.
    BadInput("3e8 rows",
             f"partisim.Population({PLANETS}, np.broadcast_to(np.array([60.0, 0.4, 10.0, 20.0, 30.0, 40.0]), (300_000_000, 6)))",
             words=("300000000 particles", "bytes available"), seconds=10, memory_mb=512),
    # Steps: the planets' grid of one particle step, and a step that does not move the clock.
    BadInput("planet step 1e-6 days",
             f"partisim.Population({PLANETS}, {ELEMENTS}, planet_step_days=1e-6)",
             words=("planet_step_days", "MAX_STEP_GRID_BYTES", "take at least"), seconds=10),
    BadInput("initial step 1e-300 days",
             f"partisim.Population({PLANETS}, {ELEMENTS}, initial_step_days=1e-300)",
             words=("initial_step_days", "no progress"), seconds=10),
    # Settings are named as the caller wrote them, with no line or column of JSON or TOML.
    BadInput("unknown scheme",
             f"partisim.Population({PLANETS}, {ELEMENTS}, scheme='s4')",
             words=("PopulationSpec scheme", "s4"), seconds=10),
    BadInput("negative removal rule",
             f"partisim.Population({PLANETS}, {ELEMENTS}, removal={{'min_perihelion': float('nan')}})",
             words=("min_perihelion",), seconds=10),
    BadInput("unknown removal rule",
             f"partisim.Population({PLANETS}, {ELEMENTS}, removal={{'hill_radius': 1.0}})",
             words=("PopulationSpec removal", "hill_radius"), seconds=10),
    BadInput("encounters with a Hill-sphere removal",
             f"partisim.Population({PLANETS}, {ELEMENTS}, removal={{'hill_factor': 1.0}}, encounters={{}})",
             words=("hill_factor", "encounters"), seconds=10),
    BadInput("event perihelion NaN",
             f"partisim.Population({PLANETS}, {ELEMENTS}, events={{'perihelion_below': [2.5, float('nan')]}})",
             words=("PopulationSpec events", "perihelion_below"), seconds=10),
    BadInput("unknown event",
             f"partisim.Population({PLANETS}, {ELEMENTS}, events={{'first_q': 2.5}})",
             words=("PopulationSpec events", "first_q"), seconds=10),
    BadInput("negative min_distance",
             f"partisim.Population({PLANETS}, {ELEMENTS}, removal={{'min_distance': {{'distance': -1.0}}}})",
             words=("PopulationSpec removal", "min_distance", "distance"), seconds=10),
    BadInput("unknown encounter setting",
             f"partisim.Population({PLANETS}, {ELEMENTS}, encounters={{'hill_radii': 3.0}})",
             words=("PopulationSpec encounters", "hill_radii"), seconds=10),
    BadInput("float32 particles",
             f"partisim.Population({PLANETS}, {ELEMENTS}.astype(np.float32))",
             raises="TypeError", words=("float64",), seconds=10),
    BadInput("negative identifiers",
             f"partisim.Population({PLANETS}, {ELEMENTS}, ids=[-1, 0, 1, 2, 3, 4, 5, 6])",
             raises="ValueError", words=("ids", "negative"), seconds=10),
    BadInput("end time not finite",
             f"partisim.Population({PLANETS}, {ELEMENTS}).advance(float('inf'))",
             raises="ValueError", words=("to_years", "finite"), seconds=10),
    BadInput("shards at different times",
             f"""
p = partisim.Population({PLANETS}, {ELEMENTS})
a, b = p.shard(0, 4), p.shard(4, 8)
a.advance(600.0)
partisim.Population.merge([a, b])
""",
             words=("different times", "years"), seconds=30),
    BadInput("shards = 0", """
from partisim.dask import run_population_dask
run_population_dask(None, partisim.PopulationSpec(particles=np.zeros((2, 6))), 1.0, shards=np.int64(0))
""", raises="ValueError", words=("shards", "integer >= 1"), seconds=10),
    # Ctrl-C within a long window (a first step of 10⁻⁸ days: 10¹¹ steps per particle).
    BadInput("Ctrl-C in a window",
             f"partisim.Population({PLANETS}, {ELEMENTS}, initial_step_days=1e-8).advance(1e4)",
             raises="KeyboardInterrupt", interrupt_after=2.0, seconds=20),
]


@pytest.mark.parametrize("case", params(CASES))
def test_bad_input(case):
    check(case)
