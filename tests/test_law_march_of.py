"""The march compiled for one law (elements.law_march.march_of: law step inlined, other laws
pruned) against the march generic in the law, and its seedless (P = 0) forces-only path."""
import numpy as np
import pytest

from elements.closure import march_newton
from elements.kernels import march
from elements.laws.registry import JENKINS, CUBIC, FRICTION3D, COULOMB_STATIC_KINETIC, COULOMB_REGULARISED
from elements.law_march import march_of, CLOSE_PLAIN, CLOSE_NEWTON

N = 48
th = 2 * np.pi * np.arange(N) / N

# (kind, params, n_state, n_local, z (N, nz))
LAWS = {
    "jenkins": (JENKINS, [1.0, 0.3], 2, 1, np.c_[np.cos(th) + 0.2 * np.sin(3 * th)]),
    "cubic": (CUBIC, [2.0], 1, 1, np.c_[np.cos(th)]),
    "friction3d": (FRICTION3D, [1e3, 2e3, 0.4, 10.0, 2.0], 5, 3,
                   np.c_[0.02 * np.cos(th), 0.01 * np.sin(th), 0.004 * np.cos(th) - 0.002]),
    "coulomb_sk": (COULOMB_STATIC_KINETIC, [1.0, 1.0, 0.5, 0.3], 3, 1, np.c_[np.cos(th)]),
    "coulomb_reg": (COULOMB_REGULARISED, [1.0, 0.1, 1.0], 1, 1, np.c_[np.cos(th), -np.sin(th)]),
}


@pytest.mark.parametrize("closure", [CLOSE_PLAIN, CLOSE_NEWTON])
@pytest.mark.parametrize("law", sorted(LAWS))
def test_march_of_equals_generic_and_seedless(law, closure, rng):
    kind, p, ns, nl, z = LAWS[law]
    p = np.array(p, dtype=float)
    z = np.ascontiguousarray(z)
    dz = rng.standard_normal(z.shape + (7,))
    start = int(np.argmax(z[:, 0]))
    generic = march_newton if closure == CLOSE_NEWTON else march
    ref = generic(kind, p, ns, nl, z, dz, start, 30, 1e-12)
    got = march_of(kind, closure)(p, ns, nl, z, dz, start, 30, 1e-12)
    assert got[2] == ref[2] and got[2] > 0
    assert np.array_equal(got[0], ref[0]) and np.array_equal(got[1], ref[1])
    assert np.abs(ref[1]).max() > 0.0     # the seeds did propagate
    # forces only: no seed columns at all, same forces as the seeded march
    f0, df0, passes0 = march_of(kind, closure)(p, ns, nl, z, np.zeros(z.shape + (0,)), start, 30, 1e-12)
    assert df0.shape == (N, nl, 0)
    scale = np.abs(ref[0]).max()
    assert np.abs(f0 - ref[0]).max() <= 1e-12 * scale
