"""Small 3-vector helpers for the compiled kernels (numba, no BLAS): a handful of flops each, called per car,
wheel and contact."""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def vdot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, nogil=True)
def vcross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(cache=True, nogil=True)
def vcross_into(a, b, out):
    """out = a x b without a new array (``out`` must not be ``a`` or ``b``)."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, nogil=True)
def mat_vec(M, x):
    """M @ x for a 3x3 matrix."""
    return np.array([M[0, 0] * x[0] + M[0, 1] * x[1] + M[0, 2] * x[2],
                     M[1, 0] * x[0] + M[1, 1] * x[1] + M[1, 2] * x[2],
                     M[2, 0] * x[0] + M[2, 1] * x[1] + M[2, 2] * x[2]])


@njit(cache=True, nogil=True)
def mat_t_vec(M, x):
    """M.T @ x for a 3x3 matrix."""
    return np.array([M[0, 0] * x[0] + M[1, 0] * x[1] + M[2, 0] * x[2],
                     M[0, 1] * x[0] + M[1, 1] * x[1] + M[2, 1] * x[2],
                     M[0, 2] * x[0] + M[1, 2] * x[1] + M[2, 2] * x[2]])
