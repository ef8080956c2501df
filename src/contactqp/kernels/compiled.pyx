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

from libc.math cimport log, sqrt
from libc.stdint cimport int64_t

__all__ = [
    "project_rows",
    "natural_map_rows",
    "alart_curnier_rows",
    "sparse_newton_matrix",
    "planar_gauss_seidel",
    "planar_blocks",
    "row_products",
]


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


# ---- 2-D contacts: the exact local solver and the Gauss-Seidel sweeps of methods.planar ----

cdef inline void _planar_local(double a00, double a01, double a10, double a11, double bn,
                               double bt, double mu, double rn0, double rt0,
                               double* out) noexcept nogil:
    """Exact solution ``out = (r_N, r_T)`` of one 2-D contact's problem ``u = A r + b``.

    The four cases of the 2-D Coulomb law in turn: open (``r = 0``, ``b_N >= 0``), stick
    (``u = 0``, ``r`` inside the cone), slip along either edge (``r = r_N (1, -s mu)``,
    ``u_N = 0``, ``s u_T >= 0``); the first that holds. If none does (a block that is not
    positive definite), one projected step from ``(rn0, rt0)``.
    """
    cdef double det, rn, rt, denominator, ut, s, step, xn, xt, t, a
    cdef int side
    if bn >= 0.0:
        out[0] = 0.0
        out[1] = 0.0
        return
    if mu == 0.0:
        if a00 > 0.0:
            out[0] = -bn / a00
            out[1] = 0.0
            return
    else:
        det = a00 * a11 - a01 * a10
        if det != 0.0:
            rn = (-a11 * bn + a01 * bt) / det
            rt = (a10 * bn - a00 * bt) / det
            if rn > 0.0 and (rt if rt >= 0.0 else -rt) <= mu * rn:
                out[0] = rn
                out[1] = rt
                return
        for side in range(2):
            s = 1.0 - 2.0 * side
            denominator = a00 - s * mu * a01
            if denominator > 0.0:
                rn = -bn / denominator
                ut = (a10 - s * mu * a11) * rn + bt
                if s * ut >= 0.0:
                    out[0] = rn
                    out[1] = -s * mu * rn
                    return
    step = 1.0 / (a00 if a00 > a11 else a11) if (a00 > 0.0 or a11 > 0.0) else 1.0
    xn = rn0 - step * (a00 * rn0 + a01 * rt0 + bn)
    xt = rt0 - step * (a10 * rn0 + a11 * rt0 + bt)
    t = xt if xt >= 0.0 else -xt
    if t <= mu * xn and xn >= 0.0:
        out[0] = xn
        out[1] = xt
        return
    a = max(xn + mu * t, 0.0) / (1.0 + mu * mu)
    out[0] = a
    out[1] = (mu * a * xt / t) if t > 0.0 else 0.0


cdef inline double _planar_residual(double rn, double rt, double un, double ut,
                                    double mu) noexcept nogil:
    """Squared natural-map residual of one 2-D contact (as :func:`natural_map_rows`)."""
    cdef double x[2]
    cdef double p[2]
    x[0] = rn - un - mu * (ut if ut >= 0.0 else -ut)
    x[1] = rt - ut
    _project(x, 2, mu, p)
    return (rn - p[0]) ** 2 + (rt - p[1]) ** 2


def planar_gauss_seidel(const double[:, :] W, const int64_t[:] indptr,
                        const int64_t[:] indices, const double[:] data,
                        const double[:, :] blocks, const double[:] q, const double[:] mu,
                        double[:] r, double[:] u, double tol, Py_ssize_t max_sweeps,
                        Py_ssize_t every, bint project):
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
    cdef Py_ssize_t m = q.shape[0], nc = m // 2, i, j, p, sweep = 0, checks = 0
    cdef bint dense = W.shape[0] > 0
    cdef double bn, bt, a00, a01, a10, a11, residual, rr, uu, scale, rate, qq = 0.0
    cdef double error = 1e300, before = 1e300, last = 1e300
    cdef double out[2]
    for i in range(m):
        qq += q[i] * q[i]
    while sweep < max_sweeps:
        for i in range(nc):
            bn = q[2 * i]
            bt = q[2 * i + 1]
            a00, a01, a10, a11 = blocks[i, 0], blocks[i, 1], blocks[i, 2], blocks[i, 3]
            if dense:
                for j in range(m):
                    bn += W[2 * i, j] * r[j]
                    bt += W[2 * i + 1, j] * r[j]
            else:
                for p in range(indptr[2 * i], indptr[2 * i + 1]):
                    bn += data[p] * r[indices[p]]
                for p in range(indptr[2 * i + 1], indptr[2 * i + 2]):
                    bt += data[p] * r[indices[p]]
            bn -= a00 * r[2 * i] + a01 * r[2 * i + 1]
            bt -= a10 * r[2 * i] + a11 * r[2 * i + 1]
            _planar_local(a00, a01, a10, a11, bn, bt, mu[i], r[2 * i], r[2 * i + 1], out)
            r[2 * i] = out[0]
            r[2 * i + 1] = out[1]
        sweep += 1
        if sweep % every and sweep < max_sweeps:
            continue
        for i in range(m):
            bn = q[i]
            if dense:
                for j in range(m):
                    bn += W[i, j] * r[j]
            else:
                for p in range(indptr[i], indptr[i + 1]):
                    bn += data[p] * r[indices[p]]
            u[i] = bn
        residual = rr = uu = 0.0
        for i in range(nc):
            residual += _planar_residual(r[2 * i], r[2 * i + 1], u[2 * i], u[2 * i + 1], mu[i])
        for i in range(m):
            rr += r[i] * r[i]
            uu += u[i] * u[i]
        scale = sqrt(max(qq, max(rr, uu)))
        error = sqrt(residual) / (scale if scale > 0.0 else 1.0)
        if error <= tol:
            break
        checks += 1
        if project and checks >= 3:
            rate = sqrt(error / before)
            if rate >= 1.0 or sweep + every * log(tol / error) / log(rate) > max_sweeps:
                break
        before = last
        last = error
    return sweep, error


def planar_blocks(const double[:, :] W, const int64_t[:] indptr, const int64_t[:] indices,
                  const double[:] data, double[:, :] blocks):
    """``blocks[i] = (a00, a01, a10, a11)``, contact ``i``'s diagonal 2x2 block of ``W``.

    ``W`` dense, or (no rows) its CSR arrays, as :func:`planar_gauss_seidel`; entries not
    stored are 0.
    """
    cdef Py_ssize_t i, k, p, j, nc = blocks.shape[0]
    for i in range(nc):
        for k in range(2):
            if W.shape[0] > 0:
                blocks[i, 2 * k] = W[2 * i + k, 2 * i]
                blocks[i, 2 * k + 1] = W[2 * i + k, 2 * i + 1]
            else:
                blocks[i, 2 * k] = 0.0
                blocks[i, 2 * k + 1] = 0.0
                for p in range(indptr[2 * i + k], indptr[2 * i + k + 1]):
                    j = indices[p]
                    if j == 2 * i or j == 2 * i + 1:
                        blocks[i, 2 * k + j - 2 * i] = data[p]


def row_products(const double[:, :] W, const int64_t[:] indptr, const int64_t[:] indices,
                 const double[:] data, const double[:] x, double[:] product,
                 double[:] magnitude):
    """``product = W x`` and ``magnitude = |W| |x|``, ``W`` dense or (no rows) its CSR arrays."""
    cdef Py_ssize_t i, j, p, m = x.shape[0]
    cdef double s, a, v
    for i in range(product.shape[0]):
        s = a = 0.0
        if W.shape[0] > 0:
            for j in range(m):
                v = W[i, j] * x[j]
                s += v
                a += v if v >= 0.0 else -v
        else:
            for p in range(indptr[i], indptr[i + 1]):
                v = data[p] * x[indices[p]]
                s += v
                a += v if v >= 0.0 else -v
        product[i] = s
        magnitude[i] = a
