"""Bad inputs run in a child interpreter: each must raise its named exception, within a time
bound, with memory bounded, and leave the interpreter alive.

A case is a snippet of Python run in a fresh ``python`` process (``np``, ``partisim`` and
``tmp``, a fresh temporary directory as a :class:`pathlib.Path`, are in its namespace). The
child limits its own address space (``RLIMIT_AS``) to what it uses after importing partisim
plus the case's memory budget, so that an unguarded allocation fails at once instead of
eating the machine; a failed allocation the library does not catch then aborts the child,
which the parent reports as a dead interpreter. The child times the snippet alone (not the
imports), catches what it raises, checks that it can still run Python and call the library
afterwards, and writes its findings to a file the parent reads.

Usage, in a test module::

    from _bad_input import BadInput, check, params

    CASES = [
        BadInput("radius nan", "partisim.neighbour_lists(np.zeros((4, 3)), float('nan'))",
                 words=("radius", "nan")),
    ]

    @pytest.mark.parametrize("case", params(CASES))
    def test_bad_input(case):
        check(case)

``raises`` names the exception class; a subclass of it (by name, anywhere in the raised
type's MRO) also passes, so that a named subclass of ``PartisimError`` satisfies a case that
asks for ``PartisimError``. ``words`` must all appear in ``str(exception)``, compared without
regard to case. ``interrupt_after`` sends the child a real SIGINT that many seconds into the
snippet (Ctrl-C), for cases that must stop with ``KeyboardInterrupt``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import textwrap
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Iterable, Optional, Sequence

import pytest

#: Seconds the child may take to start and import partisim, on top of a case's own bound.
STARTUP_SECONDS = 60.0


@dataclass(frozen=True)
class BadInput:
    """One bad input and what it must do.

    - ``name``: the test id.
    - ``code``: the snippet (dedented); it should raise.
    - ``raises``: the exception class name expected (``PartisimError``, ``ValueError``,
      ``TypeError``, ``KeyboardInterrupt``, ...); subclasses pass.
    - ``words``: words that must all appear in the message (case-insensitive).
    - ``seconds``: wall-clock bound on the snippet (imports excluded).
    - ``memory_mb``: address space the snippet may add to what the child had after its
      imports (``RLIMIT_AS``), and bound on the growth of its peak resident size.
    - ``interrupt_after``: if set, a real SIGINT is sent to the child this many seconds after
      the snippet starts.
    - ``setup``: code run before the snippet and outside its time bound (building inputs).
    """

    name: str
    code: str
    raises: str = "PartisimError"
    words: Sequence[str] = field(default_factory=tuple)
    seconds: float = 30.0
    memory_mb: int = 1024
    interrupt_after: Optional[float] = None
    setup: str = ""


@dataclass
class Outcome:
    """What the child reported (or why it reported nothing)."""

    returncode: Optional[int]
    raised: Optional[str] = None  # the raised type's qualified name
    mro: Sequence[str] = ()
    message: str = ""
    seconds: float = 0.0
    peak_rss_growth_mb: float = 0.0
    alive: bool = False
    timed_out: bool = False
    stderr: str = ""


_CHILD = r'''
import faulthandler, json, os, resource, signal, sys, threading, time, traceback
faulthandler.enable()
case = json.loads(sys.argv[1])
report_path = sys.argv[2]

def vm_size_bytes():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmSize in /proc/self/status")

import pathlib, tempfile
import numpy as np
import partisim
import partisim._partisim
tmp = pathlib.Path(tempfile.mkdtemp(prefix="bad-input-"))
namespace = {"np": np, "partisim": partisim, "tmp": tmp, "pathlib": pathlib}
exec(compile(case["setup"], "<setup>", "exec"), namespace)

# The budget starts from what the process holds now (interpreter, numpy, the extension,
# the setup's inputs), so that it measures the snippet alone.
budget = case["memory_mb"] * 1024 * 1024
limit = vm_size_bytes() + budget
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
rss_before_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

signal.signal(signal.SIGINT, signal.default_int_handler)
if case["interrupt_after"] is not None:
    timer = threading.Timer(case["interrupt_after"], os.kill, (os.getpid(), signal.SIGINT))
    timer.daemon = True
    timer.start()

report = {"raised": None, "mro": [], "message": ""}
start = time.perf_counter()
try:
    exec(compile(case["code"], "<bad input>", "exec"), namespace)
except BaseException as e:  # KeyboardInterrupt and MemoryError included
    report["raised"] = f"{type(e).__module__}.{type(e).__qualname__}"
    report["mro"] = [c.__name__ for c in type(e).__mro__]
    report["message"] = str(e)
    report["traceback"] = traceback.format_exc()
report["seconds"] = time.perf_counter() - start
if case["interrupt_after"] is not None:
    timer.cancel()
rss_after_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
report["peak_rss_growth_mb"] = max(0, rss_after_kb - rss_before_kb) / 1024.0

# Alive: the interpreter and the library still work after the error.
x = np.arange(10.0).reshape(-1, 1) * np.ones((1, 3))
offsets, _ = partisim.neighbour_lists(x, 1.5)
report["alive"] = bool(len(offsets) == 11 and sum(range(10)) == 45)
with open(report_path, "w") as f:
    json.dump(report, f)
'''


def run(case: BadInput) -> Outcome:
    """Runs `case` in a child interpreter and returns what it reported."""
    payload = asdict(case)
    payload["code"] = textwrap.dedent(case.code)
    payload["setup"] = textwrap.dedent(case.setup)
    payload["words"] = list(case.words)
    env = {
        **os.environ,
        # Fewer threads and malloc arenas: less address space reserved that the budget would
        # otherwise have to cover (each glibc arena reserves 64 MB).
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MALLOC_ARENA_MAX": "2",
        "PYTHONFAULTHANDLER": "1",
    }
    with tempfile.TemporaryDirectory(prefix="bad-input-report-") as d:
        report_path = Path(d) / "report.json"
        try:
            proc = subprocess.run(
                [sys.executable, "-c", _CHILD, json.dumps(payload), str(report_path)],
                capture_output=True,
                text=True,
                timeout=case.seconds + STARTUP_SECONDS,
                env=env,
            )
        except subprocess.TimeoutExpired as e:
            err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
            return Outcome(returncode=None, timed_out=True, stderr=err)
        if not report_path.exists():
            return Outcome(returncode=proc.returncode, stderr=proc.stderr)
        r = json.loads(report_path.read_text())
    return Outcome(
        returncode=proc.returncode,
        raised=r["raised"],
        mro=tuple(r["mro"]),
        message=r["message"],
        seconds=r["seconds"],
        peak_rss_growth_mb=r["peak_rss_growth_mb"],
        alive=r["alive"],
        stderr=proc.stderr,
    )


def check(case: BadInput) -> Outcome:
    """Runs `case` and asserts everything it promises; returns the outcome."""
    out = run(case)
    tail = out.stderr[-3000:]
    assert not out.timed_out, (
        f"{case.name}: still running after {case.seconds + STARTUP_SECONDS:.0f} s (a hang)\n{tail}"
    )
    assert out.raised is not None or out.returncode == 0, (
        f"{case.name}: the interpreter died (exit status {out.returncode}; "
        f"a negative status is the signal, -6 an abort)\n{tail}"
    )
    assert out.raised is not None, f"{case.name}: nothing raised (expected {case.raises})\n{tail}"
    assert case.raises in out.mro, (
        f"{case.name}: raised {out.raised}: {out.message!r}, expected {case.raises}"
    )
    missing = [w for w in case.words if w.lower() not in out.message.lower()]
    assert not missing, f"{case.name}: message {out.message!r} lacks {missing}"
    assert out.seconds <= case.seconds, (
        f"{case.name}: took {out.seconds:.1f} s, bound {case.seconds} s"
    )
    assert out.peak_rss_growth_mb <= case.memory_mb, (
        f"{case.name}: peak resident size grew by {out.peak_rss_growth_mb:.0f} MB, "
        f"bound {case.memory_mb} MB"
    )
    assert out.alive and out.returncode == 0, (
        f"{case.name}: the interpreter did not carry on after the error "
        f"(exit status {out.returncode})\n{tail}"
    )
    return out


def params(cases: Iterable[BadInput]) -> list:
    """`cases` as `pytest.param`s with their names as ids (names must be unique)."""
    cases = list(cases)
    names = [c.name for c in cases]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"bad-input case names repeated: {dup}")
    return [pytest.param(c, id=c.name) for c in cases]
