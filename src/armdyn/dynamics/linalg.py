"""The kernels' small dense linear algebra: Cholesky and LU factorizations in place and their
triangular solves (Golub and Van Loan, Matrix Computations, 4th ed., 2013, 4.2 and 3.4), inlined
into the kernels that call them.

A Cholesky factor A = L L^T is kept as ``cholesky`` leaves it: L in A's lower triangle, its
diagonal included; the solves divide by L_jj (correctly rounded, where multiplying by a stored
reciprocal would round twice). The solves run row by
row with every right-hand side at once (the inner loops run along X's rows, contiguous); each
value is updated in the order k = 0, 1, ... whatever the loop order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from armdyn.dynamics.spatial import NUMBA_OPTIONS


@njit(inline="always", **NUMBA_OPTIONS)
def cholesky(A: np.ndarray, floor: float = 0.0) -> int:
    """A = L L^T in place (only A's lower triangle is read and written).
    Returns -1, or the first column j whose pivot L_jj^2 is not above ``floor`` (A is not positive
    definite, or nearly singular; the columns from j on are then not factored)."""
    m = A.shape[0]
    for j in range(m):
        d = A[j, j]
        for k in range(j):
            d -= A[j, k] * A[j, k]
        if not d > floor:
            return j
        pivot = math.sqrt(d)
        A[j, j] = pivot
        for i in range(j + 1, m):
            s = A[i, j]
            for k in range(j):
                s -= A[i, k] * A[j, k]
            A[i, j] = s / pivot
    return -1


@njit(inline="always", **NUMBA_OPTIONS)
def solve_lower(L: np.ndarray, X: np.ndarray) -> None:
    """X <- L^-1 X in place, X (m, k), for L from ``cholesky``."""
    width = X.shape[1]
    for r in range(L.shape[0]):
        for k in range(r):
            weight = L[r, k]
            for c in range(width):
                X[r, c] -= weight * X[k, c]
        pivot = L[r, r]
        for c in range(width):
            X[r, c] /= pivot


@njit(inline="always", **NUMBA_OPTIONS)
def solve_lower_transpose(L: np.ndarray, X: np.ndarray) -> None:
    """X <- L^-T X in place, X (m, k), for L from ``cholesky``."""
    m, width = L.shape[0], X.shape[1]
    for r in range(m - 1, -1, -1):
        for k in range(r + 1, m):
            weight = L[k, r]
            for c in range(width):
                X[r, c] -= weight * X[k, c]
        pivot = L[r, r]
        for c in range(width):
            X[r, c] /= pivot


@njit(inline="always", **NUMBA_OPTIONS)
def cholesky_solve(L: np.ndarray, X: np.ndarray) -> None:
    """X <- A^-1 X in place for A = L L^T factored by ``cholesky``: L Y = X, then L^T X = Y."""
    solve_lower(L, X)
    solve_lower_transpose(L, X)


@njit(inline="always", **NUMBA_OPTIONS)
def cholesky_solve_vector(L: np.ndarray, x: np.ndarray) -> None:
    """x <- A^-1 x in place for one right-hand side x (m,), A = L L^T factored by ``cholesky``: the same
    substitutions as ``cholesky_solve`` without the loop over columns (the simulation's every stage)."""
    m = L.shape[0]
    for r in range(m):
        total = x[r]
        for k in range(r):
            total -= L[r, k] * x[k]
        x[r] = total / L[r, r]
    for r in range(m - 1, -1, -1):
        total = x[r]
        for k in range(r + 1, m):
            total -= L[k, r] * x[k]
        x[r] = total / L[r, r]


@njit(inline="always", **NUMBA_OPTIONS)
def lu(A: np.ndarray, pivots: np.ndarray) -> bool:
    """P A = L U in place with partial pivoting (row k swapped with pivots[k]); False when singular."""
    n = A.shape[0]
    for k in range(n):
        p, big = k, abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                p, big = i, abs(A[i, k])
        if not big > 0.0:
            return False
        pivots[k] = p
        if p != k:
            for c in range(n):
                A[k, c], A[p, c] = A[p, c], A[k, c]
        inverse = 1.0 / A[k, k]
        for i in range(k + 1, n):
            factor = A[i, k] * inverse
            A[i, k] = factor
            for c in range(k + 1, n):
                A[i, c] -= factor * A[k, c]
    return True


@njit(inline="always", **NUMBA_OPTIONS)
def lu_solve(A: np.ndarray, pivots: np.ndarray, x: np.ndarray) -> None:
    """x <- A^-1 x for A factored by ``lu``."""
    n = A.shape[0]
    for k in range(n):
        p = int(pivots[k])
        x[k], x[p] = x[p], x[k]
    for i in range(n):
        for k in range(i):
            x[i] -= A[i, k] * x[k]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            x[i] -= A[i, k] * x[k]
        x[i] /= A[i, i]


@njit(inline="always", **NUMBA_OPTIONS)
def lu_solve_transpose(A: np.ndarray, pivots: np.ndarray, x: np.ndarray) -> None:
    """x <- A^-T x for A factored by ``lu``: A^T = U^T L^T P, solved in that order."""
    n = A.shape[0]
    for i in range(n):
        for k in range(i):
            x[i] -= A[k, i] * x[k]
        x[i] /= A[i, i]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            x[i] -= A[k, i] * x[k]
    for k in range(n - 1, -1, -1):
        p = int(pivots[k])
        x[k], x[p] = x[p], x[k]
