"""Bad inputs to neighbour lists, kernels, rendering, PNG files and array conversion: each
raises its named exception with a message naming the argument, within a time bound, with
memory bounded, and leaves the interpreter working (see _bad_input.py: each case runs in a
child interpreter limited to 1 GB of address space beyond what it holds after importing,
so that an unguarded allocation aborts it there instead of eating the machine).

Categories for every entry point: NaN, infinity, negative, zero, wrong shapes, wrong
dtypes, empty, huge (sizes that would need far more memory than there is), and Ctrl-C in
the calls that can run long.
"""

import pytest

from _bad_input import BadInput, check, params

# A 10¹⁰-row view of one point (zero strides): 240 GB if copied.
HUGE_VIEW = "np.broadcast_to(np.zeros(3), (10**10, 3))"
P = "np.random.default_rng(1).random((50, 3))"

NEIGHBOURS = [
    BadInput("neighbours radius nan", f"partisim.neighbour_lists({P}, float('nan'))", words=("radius", "NaN")),
    BadInput("neighbours radius inf", f"partisim.neighbour_lists({P}, float('inf'))", words=("radius", "inf")),
    BadInput("neighbours radius negative", f"partisim.neighbour_lists({P}, -0.1)", words=("radius", "-0.1")),
    BadInput("neighbours radius zero", f"partisim.neighbour_lists({P}, 0)", words=("radius", "> 0")),
    BadInput("neighbours radius tiny", f"partisim.neighbour_lists({P} * 1e9, 1e-30)", words=("radius",)),
    BadInput("neighbours radius not a number", f"partisim.neighbour_lists({P}, 'big')", raises="ValueError", words=("big",)),
    BadInput("neighbours position nan", "p = np.zeros((9, 3)); p[4, 1] = np.nan\npartisim.neighbour_lists(p, 0.1)", words=("particle 4", "y", "not finite")),
    BadInput("neighbours position inf", "p = np.zeros((9, 3)); p[7, 2] = -np.inf\npartisim.neighbour_lists(p, 0.1)", words=("particle 7", "z", "not finite")),
    BadInput("neighbours position 1e30", "p = np.zeros((9, 3)); p[2, 0] = 1e30\npartisim.neighbour_lists(p, 0.1)", words=("particle 2", "x", "overflows")),
    BadInput("neighbours shape (N, 2)", "partisim.neighbour_lists(np.zeros((10, 2)), 0.1)", raises="ValueError", words=("positions", "(N, 3)", "[10, 2]")),
    BadInput("neighbours shape (3,)", "partisim.neighbour_lists(np.zeros(3), 0.1)", raises="ValueError", words=("positions", "(N, 3)")),
    BadInput("neighbours shape (N, 3, 1)", "partisim.neighbour_lists(np.zeros((4, 3, 1)), 0.1)", raises="ValueError", words=("positions", "(N, 3)")),
    BadInput("neighbours scalar", "partisim.neighbour_lists(3.0, 0.1)", raises="ValueError", words=("positions", "(N, 3)")),
    BadInput("neighbours dtype complex", "partisim.neighbour_lists(np.zeros((4, 3), complex), 0.1)", raises="TypeError", words=("positions", "complex128")),
    BadInput("neighbours dtype str", "partisim.neighbour_lists(np.full((4, 3), 'a'), 0.1)", raises="TypeError", words=("positions", "<U1")),
    BadInput("neighbours dtype object", "partisim.neighbour_lists(np.full((4, 3), None), 0.1)", raises="TypeError", words=("positions", "object")),
    BadInput("neighbours ragged list", "partisim.neighbour_lists([[0, 0, 0], [1, 2]], 0.1)", raises="ValueError", words=("positions", "list")),
    BadInput("neighbours empty shape (0,)", "partisim.neighbour_lists([], 0.1)", raises="ValueError", words=("positions", "(N, 3)")),
    BadInput("neighbours unknown method", f"partisim.neighbour_lists({P}, 0.1, method='octree')", raises="ValueError", words=("octree", "cell-start-grid")),
    BadInput("neighbours max_pairs negative", f"partisim.neighbour_lists({P}, 0.1, max_pairs=-1)", raises="ValueError", words=("max_pairs", "-1")),
    BadInput("neighbours max_pairs float", f"partisim.neighbour_lists({P}, 0.1, max_pairs=1.5)", raises="TypeError", words=("float",)),
    BadInput("neighbours huge broadcast view", f"partisim.neighbour_lists({HUGE_VIEW}, 0.1)", words=("positions", "10000000000", "available")),
    BadInput("neighbours huge broadcast int view", "partisim.neighbour_lists(np.broadcast_to(np.zeros(3, int), (10**10, 3)), 0.1)", words=("positions", "available")),
    # 10⁵ coincident points: 10¹⁰ pairs, 40 GB of indices.
    BadInput("neighbours 1e5 identical points", "partisim.neighbour_lists(np.zeros((10**5, 3)), 0.1)", words=("bytes",), seconds=60),
    BadInput("neighbours 1e5 identical points max_pairs", "partisim.neighbour_lists(np.zeros((10**5, 3)), 0.1, max_pairs=10**7)", words=("more than 10000000 pairs", "max_pairs = 10000000"), seconds=60),
    # Positions in metres, radius meant in millimetres: every pair a neighbour (4·10⁸).
    BadInput("neighbours radius in wrong units", "partisim.neighbour_lists(np.random.default_rng(2).random((20000, 3)), 25.0)", words=("bytes",), seconds=60),
    *[
        BadInput(f"neighbours 1e5 identical points {m}", f"partisim.neighbour_lists(np.zeros((10**5, 3)), 0.1, method='{m}', max_pairs=10**7)", words=("more than 10000000 pairs",), seconds=60)
        for m in ("relation-table", "hashed-grid", "brute-force")
    ],
    # O(N²) on 2·10⁵ points: minutes if not interrupted.
    BadInput("neighbours ctrl-c", "partisim.neighbour_lists(np.random.default_rng(3).random((200000, 3)), 0.01, method='brute-force')", raises="KeyboardInterrupt", interrupt_after=1.0, seconds=10),
]

KERNELS = [
    BadInput("kernel unknown name", "partisim.kernel('gaussian', 0.1)", words=("gaussian", "poly6")),
    BadInput("kernel h nan", "partisim.kernel('poly6', float('nan'))", words=("support radius", "NaN")),
    BadInput("kernel h inf", "partisim.kernel('spiky', float('inf'))", words=("support radius", "inf")),
    BadInput("kernel h negative", "partisim.kernel('cubic-spline', -1.0)", words=("support radius", "-1")),
    BadInput("kernel h zero", "partisim.kernel('wendland-c2', 0)", words=("support radius", "0")),
    BadInput("kernel h huge", "partisim.kernel('poly6', 1e300)", words=("support radius",)),
    BadInput("kernel h not a number", "partisim.kernel('poly6', 'h')", raises="TypeError"),
    BadInput("kernel r dtype complex", "partisim.kernel('poly6', 0.1).value(np.zeros(4, complex))", raises="TypeError", words=("r", "complex128")),
    BadInput("kernel r dtype str", "partisim.kernel('poly6', 0.1).value(['a', 'b'])", raises="TypeError", words=("r", "<U1")),
    BadInput("kernel r ragged", "partisim.kernel('poly6', 0.1).derivative([[0.1], [0.1, 0.2]])", raises="ValueError", words=("r",)),
    BadInput("kernel r huge broadcast view", "partisim.kernel('poly6', 0.1).value(np.broadcast_to(0.1, (10**11,)))", words=("r", "available")),
    BadInput("kernel gradient shape (N, 2)", "partisim.kernel('spiky', 0.1).gradient(np.zeros((5, 2)))", raises="ValueError", words=("r_vectors", "(..., 3)")),
    BadInput("kernel gradient scalar", "partisim.kernel('spiky', 0.1).gradient(0.5)", raises="ValueError", words=("r_vectors", "(..., 3)")),
    BadInput("kernel gradient huge broadcast view", "partisim.kernel('spiky', 0.1).gradient(np.broadcast_to(np.zeros(3), (10**10, 3)))", words=("r_vectors", "available")),
]

BLOCK = "np.random.default_rng(4).random((200, 3)) * 0.2"
R = "partisim.render"

RENDER = [
    BadInput("render radius nan", f"{R}({BLOCK}, float('nan'), width=32, height=32)", words=("radius", "NaN", "finite")),
    BadInput("render radius inf", f"{R}({BLOCK}, float('inf'), width=32, height=32)", words=("radius", "inf")),
    BadInput("render radius negative", f"{R}({BLOCK}, -0.01, width=32, height=32)", words=("radius", "-0.01")),
    BadInput("render radius zero", f"{R}({BLOCK}, 0.0, width=32, height=32)", words=("radius", "> 0")),
    BadInput("render width zero", f"{R}({BLOCK}, 0.01, width=0, height=32)", words=("image size", "0 x 32")),
    BadInput("render height negative", f"{R}({BLOCK}, 0.01, width=32, height=-5)", words=("height", "-5")),
    BadInput("render width not a number", f"{R}({BLOCK}, 0.01, width='wide', height=32)", words=("width", "string")),
    BadInput("render image huge", f"{R}({BLOCK}, 0.01, width=10**6, height=10**6)", words=("image size", "2^26")),
    # 2^26 pixels, the largest size accepted: 6.2 GB of buffers (93 bytes a pixel), more than
    # the child's 1 GB: refused before any is allocated, naming both sizes.
    BadInput("render image beyond memory", f"{R}({BLOCK}, 0.01, width=8192, height=8192)", words=("image size 8192 x 8192", "6241124352 bytes", "available")),
    BadInput("render unknown option", f"{R}({BLOCK}, 0.01, width=32, height=32, colour=1)", words=("colour",)),
    BadInput("render unknown background field", f"{R}({BLOCK}, 0.01, width=32, height=32, background={{'colour_of_sky': 1}})", words=("background", "colour_of_sky")),
    BadInput("render camera fov nan", f"{R}({BLOCK}, 0.01, camera={{'fov_deg': float('nan')}}, width=32, height=32)", words=("camera.fov_deg", "NaN")),
    BadInput("render camera eye is target", f"{R}({BLOCK}, 0.01, camera={{'eye': [1, 1, 1], 'target': [1, 1, 1]}}, width=32, height=32)", words=("camera",)),
    BadInput("render camera eye wrong length", f"{R}({BLOCK}, 0.01, camera={{'eye': [1, 1]}}, width=32, height=32)", words=("camera.eye",)),
    BadInput("render position nan", f"p = {BLOCK}; p[3, 2] = np.nan\n{R}(p, 0.01, width=32, height=32)", words=("particle 3", "NaN")),
    BadInput("render position 1e30", f"p = {BLOCK}; p[5, 1] = 1e30\n{R}(p, 0.01, width=32, height=32)", words=("positions", "particle 5", "y", "1e30")),
    BadInput("render shape (N, 2)", f"{R}(np.zeros((5, 2)), 0.01, width=32, height=32)", raises="ValueError", words=("positions", "(N, 3)")),
    BadInput("render dtype complex", f"{R}(np.zeros((5, 3), complex), 0.01, width=32, height=32)", raises="TypeError", words=("positions", "complex128")),
    BadInput("render empty", f"{R}(np.zeros((0, 3)), 0.01, width=32, height=32)", words=("none of the 0 particles",)),
    BadInput("render huge broadcast view", f"{R}({HUGE_VIEW}, 0.01, width=32, height=32)", words=("positions", "available")),
    # 10⁶ ellipsoids of 0.01 m on 4096² pixels: over two minutes of work (the ellipsoids'
    # estimate about 100 s, the splatting about 35 s), stopped after 1 s through the
    # renderer's cancellation flag (the interpreter's next call would otherwise wait for it).
    BadInput("render ctrl-c", "p = np.random.default_rng(5).random((10**6, 3))\npartisim.render(p, 0.01, width=4096, height=4096, anisotropy={'support': 0.03})", raises="KeyboardInterrupt", interrupt_after=1.0, seconds=10, memory_mb=2048),
]

PNG = [
    BadInput("read_png missing", "partisim.read_png(tmp / 'none.png')", words=("none.png",)),
    BadInput("read_png directory", "partisim.read_png(tmp)", words=("bad-input-",)),
    BadInput("read_png text file", "(tmp / 'a.png').write_text('not a png')\npartisim.read_png(tmp / 'a.png')", words=("a.png",)),
    BadInput("read_png empty file", "(tmp / 'e.png').write_bytes(b'')\npartisim.read_png(tmp / 'e.png')", words=("e.png",)),
    BadInput("read_png /dev/zero", "partisim.read_png('/dev/zero')", words=("/dev/zero",), seconds=10),
    BadInput("write_png missing directory", "partisim.write_png(tmp / 'no' / 'x.png', np.zeros((4, 4, 3), np.uint8))", words=("x.png",)),
    BadInput("write_png shape (H, W)", "partisim.write_png(tmp / 'x.png', np.zeros((4, 4), np.uint8))", raises="ValueError", words=("image", "(H, W, 3)")),
    BadInput("write_png shape (H, W, 4)", "partisim.write_png(tmp / 'x.png', np.zeros((4, 4, 4), np.uint8))", raises="ValueError", words=("image", "(H, W, 3)")),
    BadInput("write_png empty", "partisim.write_png(tmp / 'x.png', np.zeros((0, 4, 3), np.uint8))", raises="ValueError", words=("image", "zero-size")),
    BadInput("write_png float", "partisim.write_png(tmp / 'x.png', np.zeros((4, 4, 3)))", raises="TypeError", words=("image", "float64")),
    BadInput("write_png out of range", "partisim.write_png(tmp / 'x.png', np.full((4, 4, 3), 300))", raises="ValueError", words=("image", "0..=255")),
    BadInput("write_png negative", "partisim.write_png(tmp / 'x.png', np.full((4, 4, 3), -1))", raises="ValueError", words=("image", "0..=255")),
    BadInput("write_png huge broadcast view", "partisim.write_png(tmp / 'x.png', np.broadcast_to(np.zeros(3, np.uint8), (10**6, 10**6, 3)))", raises="ValueError", words=("image", "2^26")),
]


@pytest.mark.parametrize("case", params(NEIGHBOURS + KERNELS + RENDER + PNG))
def test_bad_input(case):
    check(case)
