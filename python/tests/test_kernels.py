"""Kernels against their formulas, written here from the papers (not from the Rust code).

poly6, spiky, viscosity: Müller, Charypar & Gross 2003, eqs. (20)-(22), support h.
cubic spline: Monaghan 1992 M4 in the support-h form of Koschier et al. 2019 (eq. 4):
  W = k (6q³ - 6q² + 1) for q <= 1/2, 2k (1 - q)³ for q <= 1, k = 8/(π h³), q = r/h.
Wendland C2: Wendland 1995 / Dehnen & Aly 2012, 3D: W = 21/(2π h³) (1 - q)⁴ (1 + 4q).
"""

import numpy as np
import pytest

import partisim

H = 0.1


def poly6(r, h):
    return np.where(r < h, 315 / (64 * np.pi * h**9) * (h * h - r * r) ** 3, 0.0)


def spiky(r, h):
    return np.where(r < h, 15 / (np.pi * h**6) * (h - r) ** 3, 0.0)


def viscosity(r, h):
    with np.errstate(divide="ignore", invalid="ignore"):
        w = 15 / (2 * np.pi * h**3) * (-(r**3) / (2 * h**3) + r * r / (h * h) + h / (2 * r) - 1)
    return np.where(r < h, w, 0.0)


def cubic(r, h):
    q = r / h
    k = 8 / (np.pi * h**3)
    return np.where(q <= 0.5, k * (6 * q**3 - 6 * q**2 + 1), np.where(q <= 1, 2 * k * (1 - q) ** 3, 0.0))


def wendland(r, h):
    q = r / h
    return np.where(q < 1, 21 / (2 * np.pi * h**3) * (1 - q) ** 4 * (1 + 4 * q), 0.0)


FORMULAS = {"poly6": poly6, "spiky": spiky, "viscosity": viscosity, "cubic-spline": cubic, "wendland-c2": wendland}


@pytest.mark.parametrize("name", FORMULAS)
def test_values_match_the_formula(name):
    k = partisim.kernel(name, H)
    assert k.name == name and k.support_radius == H
    r = np.linspace(0.001, 1.2 * H, 97).reshape(97, 1)  # any shape comes back as given
    w = k.value(r)
    assert w.shape == r.shape and w.dtype == np.float64
    # 1e-12 relative: two float64 evaluations of one polynomial in different orders.
    np.testing.assert_allclose(w, FORMULAS[name](r, H), rtol=1e-12, atol=1e-12 * FORMULAS[name](np.array(0.001), H))


@pytest.mark.parametrize("name", FORMULAS)
def test_gradient_is_the_radial_derivative_along_r(name):
    k = partisim.kernel(name, H)
    rng = np.random.default_rng(3)
    rv = rng.normal(size=(200, 3))
    rv *= (rng.random((200, 1)) * 1.1 * H + 1e-3) / np.linalg.norm(rv, axis=1, keepdims=True)
    r = np.linalg.norm(rv, axis=1)
    # dW/dr by central differences of the formula (step 1e-7 h: truncation ~1e-14 h² W''',
    # round-off ~1e-9 relative), away from the support edge and the cubic's knot.
    eps = 1e-7 * H
    dwdr = (FORMULAS[name](r + eps, H) - FORMULAS[name](r - eps, H)) / (2 * eps)
    expected = dwdr[:, None] * rv / r[:, None]
    g = k.gradient(rv)
    assert g.shape == rv.shape
    ok = (np.abs(r - H) > 2 * eps) & (np.abs(r - 0.5 * H) > 2 * eps)
    scale = np.abs(expected[ok]).max()
    np.testing.assert_allclose(g[ok], expected[ok], rtol=1e-5, atol=1e-6 * scale)
    assert np.array_equal(k.gradient(np.zeros((1, 3))), np.zeros((1, 3)))


def test_float32_in_float32_out():
    k = partisim.kernel("spiky", H)
    r = np.array([0.0, 0.05, 0.2], dtype=np.float32)
    w = k.value(r)
    assert w.dtype == np.float32
    np.testing.assert_allclose(w, spiky(r.astype(np.float64), H), rtol=1e-6)
    assert k.gradient(np.ones((2, 4, 3), dtype=np.float32) * 0.01).shape == (2, 4, 3)


def test_bad_input_raises_clear_errors():
    with pytest.raises(partisim.PartisimError, match="unknown kernel"):
        partisim.kernel("gaussian", H)
    with pytest.raises(partisim.PartisimError):
        partisim.kernel("poly6", -1.0)
    with pytest.raises(partisim.PartisimError):
        partisim.kernel("poly6", float("nan"))
    k = partisim.kernel("poly6", H)
    with pytest.raises(ValueError, match=r"r_vectors: expected shape \(\.\.\., 3\)"):
        k.gradient(np.zeros((4, 2)))
    with pytest.raises(TypeError, match="r: expected real numbers.*got dtype complex128"):
        k.value(np.arange(3) * 1j)


def test_array_likes_and_numpy_scalars():
    k = partisim.kernel("cubic-spline", np.float32(H))
    r = np.linspace(0, H, 11)
    expected = k.value(r)
    assert np.array_equal(k.value(r.tolist()), expected)
    assert np.array_equal(k.value(np.arange(3)), k.value(np.arange(3.0)))
    assert k.value(0.05).shape == () and k.value(0.05) == k.value(np.array(0.05))
    assert np.array_equal(k.derivative(r[::2]), k.derivative(np.ascontiguousarray(r[::2])))
    v = np.random.default_rng(0).random((5, 3)) * H
    assert np.array_equal(k.gradient(v.tolist()), k.gradient(v))
    assert np.array_equal(k.gradient(v.T.copy().T), k.gradient(v))  # column major
