"""Side by side: our PBF and IISPH against SPlisHSPlasH 2.19's on its dam break.

SPlisHSPlasH's `DamBreakModel` scene at particle radius 0.0125 m (59,319 fluid particles,
tank 4 x 3 x 1.5 m), fixed time step 2 ms, volume maps (`boundaryHandlingMethod` 2), no
viscosity, iterating to 0.1 % average density error (2-100 iterations), 100 steps from
rest. Ours: the examples `pbf_dambreak` (`STEPS tol=0.001 pbf unilateral volume-map`:
SPlisHSPlasH's stopping rule and constraint form) and `iisph_dambreak` (`STEPS`), built
beforehand:

    cargo build --release -p benches --example pbf_dambreak --example iisph_dambreak

The peer runs in a throwaway virtual environment, never a dependency of the workspace:

    python3 -m venv /tmp/splish && /tmp/splish/bin/pip install pysplishsplash==2.19.0
    /tmp/splish/bin/python benches/scripts/water_vs_splishsplash.py --threads 1 2

Each run is a fresh process (OpenMP threads for the peer, rayon threads for ours). The
peer's time per step is the wall time between the callbacks after its steps (the step and
its bookkeeping, as in a run without output) over the last STEPS of STEPS + 1 steps; ours is the examples' printed mean over all steps. Both
exclude the set-up (scene, sampling, volume map). The peer's import needs the system's
`libGLdispatch.so.0` preloaded; the script sets `LD_PRELOAD` for the peer's processes.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import time

GL_DISPATCH = "/usr/lib/x86_64-linux-gnu/libGLdispatch.so.0"
# SPlisHSPlasH's simulation methods (Simulation::SIMULATION_METHOD's enum).
METHODS = {"pbf": 2, "iisph": 3}


def peer_scene(method, out_dir):
    """Writes the peer's scene for `method` and returns its path."""
    import pysplishsplash  # noqa: F401  (locates the installed data)

    data = os.path.join(os.path.dirname(sys.executable), "data")
    with open(os.path.join(data, "Scenes", "DamBreakModel.json")) as f:
        scene = json.load(f)
    iterations = {"minIterations": 2, "maxIterations": 100, "maxError": 0.1}
    config = scene["Configuration"]
    config.pop("DFSPH", None)
    config.update(
        {
            "particleRadius": 0.0125,
            "simulationMethod": METHODS[method],
            "timeStepSize": 0.002,
            "cflMethod": 0,
            "boundaryHandlingMethod": 2,
        }
    )
    # The method's parameters sit in a block of the configuration named after it (as the
    # shipped scene's "DFSPH"); the peer reads them back into the JSON line.
    config[method.upper()] = dict(iterations)
    scene["Materials"] = [{"id": "Fluid", "density0": 1000, "viscosityMethod": 0}]
    for body in scene["RigidBodies"]:
        body["geometryFile"] = os.path.join(data, "models", "UnitBox.obj")
    path = os.path.join(out_dir, f"DamBreakModel_{method}.json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
    return path


def run_peer(method, steps, out_dir):
    """Runs the peer in this process; prints one JSON line with its figures.

    Its own loop runs the steps (`runSimulation`, which finishes the set-up first), up to
    `stopAt` = `steps + 1.5` time steps; a callback after every step records the wall clock
    and the step's iterations, and the time per step is that of the last `steps` steps.
    """
    import pysplishsplash as sph

    dt = 0.002
    base = sph.Exec.SimulatorBase()
    base.init(
        useGui=False,
        sceneFile=peer_scene(method, out_dir),
        useCache=False,
        outputDir=out_dir,
        initialPause=False,
        stopAt=(steps + 1.5) * dt,
    )
    clock = []
    iterations = []

    def after_step():
        clock.append(time.perf_counter())
        ts = sph.Simulation.getCurrent().getTimeStep()
        iterations.append(ts.getValueInt(ts.SOLVER_ITERATIONS))

    base.setTimeStepCB(after_step)
    base.initSimulation()
    base.runSimulation()
    sim = sph.Simulation.getCurrent()
    ts = sim.getTimeStep()
    clock, iterations = clock[-(steps + 1) :], iterations[-steps:]
    print(
        json.dumps(
            {
                "ms_per_step": 1e3 * (clock[-1] - clock[0]) / steps,
                "steps": len(clock) - 1,
                "iterations": sum(iterations) / len(iterations),
                "particles": sim.getFluidModel(0).numActiveParticles(),
                "max_error_percent": ts.getValueFloat(ts.MAX_ERROR),
                "min_iterations": ts.getValueInt(ts.MIN_ITERATIONS),
                "dt": sph.TimeManager.getCurrent().getTimeStepSize(),
            }
        )
    )
    base.cleanup()


def peer(method, steps, threads, out_dir):
    """The peer's figures from a fresh process on `threads` OpenMP threads."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), LD_PRELOAD=GL_DISPATCH)
    cmd = [sys.executable, __file__, "--peer", method, "--steps", str(steps), "--out", out_dir]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    # The peer prints its timers after the JSON line.
    return json.loads(next(line for line in out.splitlines() if line.startswith("{")))


def ours(method, steps, threads, examples):
    """Our figures from the example binary on `threads` rayon threads."""
    args = {
        "pbf": ["pbf_dambreak", str(steps), "tol=0.001", "pbf", "unilateral", "volume-map"],
        "iisph": ["iisph_dambreak", str(steps)],
    }[method]
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    cmd = [os.path.join(examples, args[0])] + args[1:]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    ms = float(re.search(r"mean wall time per step: ([0-9.]+) ms", out).group(1))
    it = re.search(r"mean iterations per step: ([0-9.]+)", out)
    return {"ms_per_step": ms, "iterations": float(it.group(1)) if it else float("nan")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--methods", nargs="+", default=["pbf", "iisph"], choices=list(METHODS))
    ap.add_argument("--examples", default="target/release/examples")
    ap.add_argument("--out", default="/tmp/water_vs_splishsplash")
    ap.add_argument("--peer", choices=list(METHODS), help=argparse.SUPPRESS)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.peer:
        run_peer(a.peer, a.steps, a.out)
        return
    print(time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), "load", os.getloadavg())
    print("| solver | threads | SPlisHSPlasH 2.19 | ours | ratio |")
    print("| --- | --- | --- | --- | --- |")
    for method in a.methods:
        for threads in a.threads:
            p = peer(method, a.steps, threads, a.out)
            o = ours(method, a.steps, threads, a.examples)
            print(
                f"| {method.upper()} | {threads} | {p['ms_per_step']:.1f} ms "
                f"({p['iterations']:.2f} it., {p['particles']} particles, "
                f"maxError {p['max_error_percent']} %, dt {p['dt']}) | "
                f"{o['ms_per_step']:.2f} ms ({o['iterations']:.2f} it.) | "
                f"{p['ms_per_step'] / o['ms_per_step']:.2f}x |",
                flush=True,
            )
    print(time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), "load", os.getloadavg())


if __name__ == "__main__":
    main()
