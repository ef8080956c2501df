# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
"""Per-contact loops of the friction solvers, compiled by Cython when the package is built.

:mod:`contactqp.kernels.pure_numpy` is the same in numpy: the fallback where this extension
could not be built, and its test oracle; :mod:`contactqp.kernels` chooses between the two.

The Newton and Gauss-Seidel solvers evaluate the same small maps of every contact at each
iteration: the projection on a Coulomb cone, the natural map and the Alart-Curnier function
with its generalised Jacobian. Written with numpy, each evaluation is some twenty array calls
whose fixed cost (about a microsecond each) outweighs the arithmetic on problems of a few
dozen contacts; compiled, one loop over the contacts does it. The sparse Newton matrix is
likewise filled block by block straight into compressed storage. The functions here take
validated float64 arrays (one row per contact, of dimension 2 or 3, normal component first;
index arrays int64), write into the arrays they are given and check nothing beyond the buffer
types and the row length (2 or 3: a ``ValueError`` otherwise, not a buffer overrun):
:mod:`contactqp.core.local_problem` and :mod:`contactqp.methods.coulomb` are their callers.
"""

from libc.math cimport sqrt
from libc.stdint cimport int64_t

__all__ = ["project_rows", "natural_map_rows", "alart_curnier_rows", "sparse_newton_matrix"]


cdef inline void _check_dimension(Py_ssize_t d) except *:
    """Rows of 2 or 3 components only: the per-contact buffers hold 3."""
    if d < 2 or d > 3:
        raise ValueError(f"contact rows must have 2 or 3 components, got {d}")


cdef inline void _project(const double* x, Py_ssize_t d, double mu, double* out) noexcept nogil:
    """``out`` = projection of one contact's ``x`` (length ``d``) on ``||x_T|| <= mu x_N``."""
    cdef Py_ssize_t k
    cdef double xn = x[0], t = 0.0, a, scale
    for k in range(1, d):
        t += x[k] * x[k]
    t = sqrt(t)
    if t <= mu * xn and xn >= 0.0:  # inside
        for k in range(d):
            out[k] = x[k]
        return
    a = max(xn + mu * t, 0.0) / (1.0 + mu * mu)  # 0 in the polar cone
    scale = mu * a / t if t > 0.0 else 0.0
    out[0] = a
    for k in range(1, d):
        out[k] = scale * x[k]


def project_rows(const double[:, :] X, const double[:] mu, double[:, :] P):
    """``P[i]`` = projection of ``X[i]`` on the Coulomb cone of ``mu[i]``."""
    cdef Py_ssize_t i, k, d = X.shape[1]
    _check_dimension(d)
    cdef double x[3]
    cdef double p[3]
    for i in range(X.shape[0]):
        for k in range(d):
            x[k] = X[i, k]
        _project(x, d, mu[i], p)
        for k in range(d):
            P[i, k] = p[k]


def natural_map_rows(const double[:, :] R, const double[:, :] U, const double[:] mu,
                     double[:] squares):
    """Squared natural-map residual of each contact into ``squares``; returns their sum.

    Contact ``i``: ``||R_i - P_K(R_i - U_i - mu_i ||U_iT|| e_N)||^2`` (De Saxce's modified
    velocity; ``R`` measured from the cone apex).
    """
    cdef Py_ssize_t i, k, d = R.shape[1]
    _check_dimension(d)
    cdef double slip, square, total = 0.0
    cdef double x[3]
    cdef double p[3]
    for i in range(R.shape[0]):
        slip = 0.0
        for k in range(1, d):
            slip += U[i, k] * U[i, k]
        for k in range(d):
            x[k] = R[i, k] - U[i, k]
        x[0] -= mu[i] * sqrt(slip)
        _project(x, d, mu[i], p)
        square = 0.0
        for k in range(d):
            square += (R[i, k] - p[k]) ** 2
        squares[i] = square
        total += square
    return total


def alart_curnier_rows(const double[:, :] R, const double[:, :] U, const double[:] mu,
                       const double[:] rho, double[:, :] Phi, double[:, :, :] A,
                       double[:, :, :] B):
    """Alart-Curnier function of each contact into ``Phi``; with ``A``, ``B`` its Jacobian.

    ``X = R - rho U``; ``Phi_N = R_N - max(0, X_N)`` and
    ``Phi_T = R_T - P_{B(0, mu max(0, X_N))}(X_T)``. When ``A`` and ``B`` have a row per
    contact they receive ``dPhi/dr = I - C`` and ``dPhi/du = rho C``, ``C`` the derivative of
    the projection (``C_NN = 1`` when ``X_N > 0``; on a slipping contact, with
    ``y = X_T / ||X_T||``: ``C_TT = s (I - y y^T)``, ``s = radius / ||X_T||``, and
    ``C_TN = mu y``); zero-row ``A`` and ``B`` skip it.
    """
    cdef Py_ssize_t i, k, a, b, d = R.shape[1]
    _check_dimension(d)
    cdef bint jacobian = A.shape[0] > 0, pressed, outside
    cdef double xn, radius, norm, s, inverse, c, identity
    cdef double y[3]  # the trial point X_i (its tangential part)
    for i in range(R.shape[0]):
        xn = R[i, 0] - rho[i] * U[i, 0]
        pressed = xn > 0.0
        radius = mu[i] * xn if pressed else 0.0
        norm = 0.0
        for k in range(1, d):
            y[k] = R[i, k] - rho[i] * U[i, k]
            norm += y[k] * y[k]
        norm = sqrt(norm)
        outside = norm > radius
        s = radius / norm if outside else 1.0
        Phi[i, 0] = R[i, 0] - (xn if pressed else 0.0)
        for k in range(1, d):
            Phi[i, k] = R[i, k] - s * y[k]
        if not jacobian:
            continue
        inverse = 1.0 / norm if outside else 0.0  # y / ||y|| is the slip direction
        for a in range(d):
            for b in range(d):
                identity = 1.0 if a == b else 0.0
                if a == 0:
                    c = 1.0 if (b == 0 and pressed) else 0.0
                elif b == 0:
                    c = mu[i] * y[a] * inverse if pressed else 0.0
                else:
                    c = s * (identity - y[a] * y[b] * inverse * inverse)
                A[i, a, b] = identity - c
                B[i, a, b] = rho[i] * c


def sparse_newton_matrix(const double[:, :, :] A, const double[:, :, :] B,
                         const double[:, :, :] W_blocks, const int64_t[:] block_row,
                         const int64_t[:] block_col, const int64_t[:, :] entries,
                         const int64_t[:] indptr, const int64_t[:] indices,
                         const int64_t[:] renumber, double[:] data, int64_t[:] new_indices,
                         int64_t[:] new_indptr):
    """CSC storage of ``A + B W`` on the kept unknowns; returns its number of entries.

    ``W_blocks[k]`` is the block of contacts ``(block_row[k], block_col[k])``; entry ``p`` of
    the CSC pattern ``(indptr, indices)`` of ``W`` (diagonal blocks always stored) is element
    ``entries[p, 1:]`` of block ``entries[p, 0]``. Unknown ``i`` of that pattern becomes row
    and column ``renumber[i]`` of the result, or is left out where ``renumber[i] < 0``; zeros
    are left out too. The result is written to ``data``, ``new_indices`` and ``new_indptr``.
    """
    cdef Py_ssize_t column, p, c, d = A.shape[1]
    cdef int64_t count = 0, columns = 0, row, k, a, b, i
    cdef double value
    new_indptr[0] = 0
    for column in range(indptr.shape[0] - 1):
        if renumber[column] < 0:
            continue
        for p in range(indptr[column], indptr[column + 1]):
            row = renumber[indices[p]]
            if row < 0:
                continue
            k, a, b = entries[p, 0], entries[p, 1], entries[p, 2]
            i = block_row[k]
            value = A[i, a, b] if i == block_col[k] else 0.0
            for c in range(d):
                value += B[i, a, c] * W_blocks[k, c, b]
            if value != 0.0:
                data[count] = value
                new_indices[count] = row
                count += 1
        columns += 1
        new_indptr[columns] = count
    return count
