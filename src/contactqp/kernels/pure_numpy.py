"""The per-contact kernels in vectorised numpy: the compiled loops' fallback and test oracle.

Each function has the signature and the contract of its twin in :mod:`contactqp.kernels.compiled`
(float64 rows of 2 or 3 components, normal first; int64 index arrays; results written into the
arrays given; a ``ValueError`` for rows of another length) and computes the same numbers up to
rounding: sums may be taken in another order, so results agree to a few ulps, not bit for bit.
Whole-array expressions replace the loops over contacts; only the 2 or 3 components of a row are
looped over where that keeps the compiled loop's order of operations.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "project_rows",
    "natural_map_rows",
    "alart_curnier_rows",
    "sparse_newton_matrix",
    "planar_gauss_seidel",
    "planar_blocks",
    "row_products",
    "abs_row_sums",
]


def _check_dimension(d: int) -> None:
    """Rows of 2 or 3 components only, as the compiled loops accept."""
    if d < 2 or d > 3:
        raise ValueError(f"contact rows must have 2 or 3 components, got {d}")


def _tangential_norms(X: np.ndarray) -> np.ndarray:
    """``||X[i, 1:]||`` of each row."""
    T = X[:, 1:]
    return np.sqrt(np.einsum("ij,ij->i", T, T))


def _projected(X: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Projection of each row of ``X`` on the Coulomb cone ``||x_T|| <= mu x_N`` (a new array)."""
    xn, t = X[:, 0], _tangential_norms(X)
    inside = (t <= mu * xn) & (xn >= 0.0)
    a = np.maximum(xn + mu * t, 0.0) / (1.0 + mu * mu)  # 0 in the polar cone
    scale = np.divide(mu * a, t, out=np.zeros_like(t), where=t > 0.0)
    P = np.empty_like(X)
    P[:, 0] = np.where(inside, xn, a)
    P[:, 1:] = np.where(inside[:, None], X[:, 1:], scale[:, None] * X[:, 1:])
    return P


def project_rows(X: np.ndarray, mu: np.ndarray, P: np.ndarray) -> None:
    """``P[i]`` = projection of ``X[i]`` on the Coulomb cone of ``mu[i]``."""
    _check_dimension(X.shape[1])
    P[...] = _projected(np.asarray(X), np.asarray(mu))


def natural_map_rows(R: np.ndarray, U: np.ndarray, mu: np.ndarray, squares: np.ndarray) -> float:
    """Squared natural-map residual of each contact into ``squares``; returns their sum.

    Contact ``i``: ``||R_i - P_K(R_i - U_i - mu_i ||U_iT|| e_N)||^2`` (De Saxce's modified
    velocity; ``R`` measured from the cone apex).
    """
    _check_dimension(R.shape[1])
    R, U, mu = np.asarray(R), np.asarray(U), np.asarray(mu)
    X = R - U
    X[:, 0] -= mu * _tangential_norms(U)
    difference = R - _projected(X, mu)
    squares[...] = np.einsum("ij,ij->i", difference, difference)
    return float(np.sum(squares))


def alart_curnier_rows(
    R: np.ndarray,
    U: np.ndarray,
    mu: np.ndarray,
    rho: np.ndarray,
    Phi: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
) -> None:
    """Alart-Curnier function of each contact into ``Phi``; with ``A``, ``B`` its Jacobian.

    ``X = R - rho U``; ``Phi_N = R_N - max(0, X_N)`` and
    ``Phi_T = R_T - P_{B(0, mu max(0, X_N))}(X_T)``. When ``A`` and ``B`` have a row per
    contact they receive ``dPhi/dr = I - C`` and ``dPhi/du = rho C``, ``C`` the derivative of
    the projection (see :func:`contactqp.kernels.compiled.alart_curnier_rows`); zero-row ``A``
    and ``B`` skip it.
    """
    d = R.shape[1]
    _check_dimension(d)
    R, U, mu, rho = np.asarray(R), np.asarray(U), np.asarray(mu), np.asarray(rho)
    xn = R[:, 0] - rho * U[:, 0]
    pressed = xn > 0.0
    radius = np.where(pressed, mu * xn, 0.0)
    y = R[:, 1:] - rho[:, None] * U[:, 1:]  # the trial point's tangential part
    norm = np.sqrt(np.einsum("ij,ij->i", y, y))
    outside = norm > radius
    s = np.divide(radius, norm, out=np.ones_like(norm), where=outside)
    Phi[:, 0] = R[:, 0] - np.where(pressed, xn, 0.0)
    Phi[:, 1:] = R[:, 1:] - s[:, None] * y
    if A.shape[0] == 0:
        return
    inverse = np.divide(1.0, norm, out=np.zeros_like(norm), where=outside)
    C = np.zeros((R.shape[0], d, d))
    C[:, 0, 0] = pressed
    C[:, 1:, 0] = np.where(pressed, mu, 0.0)[:, None] * y * inverse[:, None]
    outer = y[:, :, None] * y[:, None, :] * inverse[:, None, None] * inverse[:, None, None]
    C[:, 1:, 1:] = s[:, None, None] * (np.eye(d - 1) - outer)
    A[...] = np.eye(d) - C
    B[...] = rho[:, None, None] * C


def sparse_newton_matrix(
    A: np.ndarray,
    B: np.ndarray,
    W_blocks: np.ndarray,
    block_row: np.ndarray,
    block_col: np.ndarray,
    entries: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    renumber: np.ndarray,
    data: np.ndarray,
    new_indices: np.ndarray,
    new_indptr: np.ndarray,
) -> int:
    """CSC storage of ``A + B W`` on the kept unknowns; returns its number of entries.

    The arguments are those of :func:`contactqp.kernels.compiled.sparse_newton_matrix`: entry
    ``p`` of the CSC pattern ``(indptr, indices)`` of ``W`` is element ``entries[p, 1:]`` of
    block ``entries[p, 0]``; unknown ``i`` becomes row and column ``renumber[i]`` or is left out
    where that is negative, and zeros are left out too.
    """
    d = A.shape[1]
    n_columns = indptr.shape[0] - 1
    column = np.repeat(np.arange(n_columns), np.diff(indptr))
    row = renumber[indices]
    kept = (row >= 0) & (renumber[:n_columns][column] >= 0)
    block, a, b = entries[kept].T
    i = block_row[block]
    value = np.where(i == block_col[block], A[i, a, b], 0.0)
    for c in range(d):  # the compiled loop's order of the products
        value = value + B[i, a, c] * W_blocks[block, c, b]
    nonzero = value != 0.0
    count = int(np.count_nonzero(nonzero))
    data[:count] = value[nonzero]
    new_indices[:count] = row[kept][nonzero]
    per_column = np.bincount(column[kept][nonzero], minlength=n_columns)
    new_indptr[0] = 0
    new_indptr[1:] = np.cumsum(per_column[renumber[:n_columns] >= 0])
    return count


def planar_local(A: np.ndarray, b: np.ndarray, mu: float, r0: np.ndarray) -> tuple[float, float]:
    """Exact solution ``(r_N, r_T)`` of one 2-D contact's problem ``u = A r + b``.

    The four cases of the 2-D Coulomb law in turn: open (``r = 0``, ``b_N >= 0``), stick
    (``u = 0``, ``r`` inside the cone), slip along either edge (``r = r_N (1, -s mu)``,
    ``u_N = 0``, ``s u_T >= 0``); the first that holds. If none does (a block that is not
    positive definite), one projected step from ``r0``.
    """
    (a00, a01), (a10, a11) = A
    bn, bt = b
    if bn >= 0.0:
        return 0.0, 0.0
    if mu == 0.0:
        if a00 > 0.0:
            return -bn / a00, 0.0
    else:
        det = a00 * a11 - a01 * a10
        if det != 0.0:
            rn = (-a11 * bn + a01 * bt) / det
            rt = (a10 * bn - a00 * bt) / det
            if rn > 0.0 and abs(rt) <= mu * rn:
                return rn, rt
        for s in (1.0, -1.0):
            denominator = a00 - s * mu * a01
            if denominator > 0.0:
                rn = -bn / denominator
                if s * ((a10 - s * mu * a11) * rn + bt) >= 0.0:
                    return rn, -s * mu * rn
    largest = max(a00, a11)
    step = 1.0 / largest if largest > 0.0 else 1.0
    x = np.asarray(r0, dtype=float) - step * (A @ r0 + b)
    projected = _projected(x[None, :], np.array([mu]))[0]
    return float(projected[0]), float(projected[1])


def planar_gauss_seidel(
    W: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    blocks: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    r: np.ndarray,
    u: np.ndarray,
    tol: float,
    max_sweeps: int,
    every: int,
    project: bool,
) -> tuple[int, float]:
    """Gauss-Seidel sweeps with the exact 2-D local solver; returns ``(sweeps, error)``.

    ``W`` is a dense (m, m) array, or, when it has no rows, the CSR arrays
    ``(indptr, indices, data)`` of ``W`` are used; ``blocks`` holds its diagonal blocks
    (:func:`planar_blocks`). Each sweep updates the contacts in order,
    ``r_i`` the exact solution of contact ``i``'s problem with the others held. Every ``every``
    sweeps ``u = W r + q`` and the natural-map error
    ``||r - P_K(r - u - mu |u_T| e_N)|| / max(||q||, ||r||, ||u||)`` are computed; the sweeps
    stop when it is at most ``tol``, after ``max_sweeps``, or, with ``project``, from the third
    evaluation on, when the rate of the last two (``(e_k / e_{k-2})^(1/2)`` per ``every``
    sweeps) would not reach ``tol`` within ``max_sweeps`` (a stall). ``r`` is updated in
    place, ``u`` holds ``W r + q`` of the last evaluation.
    """
    m = q.shape[0]
    matrix = _matrix(W, indptr, indices, data, m)
    dense = matrix if isinstance(matrix, np.ndarray) else matrix.toarray()
    own_blocks = np.asarray(blocks).reshape(-1, 2, 2)
    sweep, checks, error = 0, 0, np.inf
    before = last = np.inf
    scale_q = float(q @ q)
    while sweep < max_sweeps:
        for i, A in enumerate(own_blocks):
            own = r[2 * i : 2 * i + 2].copy()
            b = q[2 * i : 2 * i + 2] + dense[2 * i : 2 * i + 2] @ r - A @ own
            r[2 * i], r[2 * i + 1] = planar_local(A, b, float(mu[i]), own)
        sweep += 1
        if sweep % every and sweep < max_sweeps:
            continue
        u[...] = dense @ r + q
        squares = np.empty(m // 2)
        residual = natural_map_rows(r.reshape(-1, 2), u.reshape(-1, 2), mu, squares)
        scale = np.sqrt(max(scale_q, float(r @ r), float(u @ u)))
        error = float(np.sqrt(residual) / (scale if scale > 0.0 else 1.0))
        if error <= tol:
            break
        checks += 1
        if project and checks >= 3:
            rate = np.sqrt(error / before)
            if rate >= 1.0 or sweep + every * np.log(tol / error) / np.log(rate) > max_sweeps:
                break
        before, last = last, error
    return sweep, error


def _matrix(
    W: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, n: int
) -> Any:
    """A dense ``W``, or (no rows) the (n, n) CSR matrix of the arrays (no index pointer
    either: a problem without contacts, dense)."""
    if W.shape[0] or indptr.size == 0:
        return np.asarray(W)
    import scipy.sparse as sp

    return sp.csr_matrix((data, indices, indptr), shape=(n, n))


def planar_blocks(
    W: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, blocks: np.ndarray
) -> None:
    """``blocks[i] = (a00, a01, a10, a11)``, contact ``i``'s diagonal 2x2 block of ``W``.

    ``W`` dense, or (no rows) its CSR arrays, as :func:`planar_gauss_seidel`; entries not
    stored are 0.
    """
    matrix = _matrix(W, indptr, indices, data, 2 * blocks.shape[0])
    blocks[:, 0] = matrix.diagonal()[::2]
    blocks[:, 1] = matrix.diagonal(1)[::2]
    blocks[:, 2] = matrix.diagonal(-1)[::2]
    blocks[:, 3] = matrix.diagonal()[1::2]


def row_products(
    W: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    x: np.ndarray,
    product: np.ndarray,
    magnitude: np.ndarray,
) -> None:
    """``product = W x`` and ``magnitude = |W| |x|``, ``W`` dense or (no rows) its CSR arrays."""
    matrix = _matrix(W, indptr, indices, data, x.shape[0])
    product[...] = np.asarray(matrix @ x).ravel()
    magnitude[...] = np.asarray(abs(matrix) @ np.abs(x)).ravel()


#: Rows of ``|W|`` :func:`abs_row_sums` forms at a time (a buffer of a few hundred kB).
_ABS_ROWS = 32


def abs_row_sums(W: np.ndarray, rows: np.ndarray, sums: np.ndarray) -> None:
    """``sums[k] = sum_j |W[rows[k], j]|``, a few rows at a time in one reused buffer."""
    buffer = np.empty((min(_ABS_ROWS, rows.size), W.shape[1]))
    for start in range(0, rows.size, _ABS_ROWS):
        chunk = rows[start : start + _ABS_ROWS]
        block = W.take(chunk, axis=0, out=buffer[: chunk.size])
        np.abs(block, out=block)
        sums[start : start + chunk.size] = block.sum(axis=1)
