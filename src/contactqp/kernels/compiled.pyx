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

from libc.math cimport INFINITY, copysign, cos, fabs, isfinite, log, sin, sqrt
from libc.stdlib cimport free, malloc
from cpython.buffer cimport (
    PyBUF_C_CONTIGUOUS, PyBUF_FORMAT, PyBUF_WRITABLE, PyBuffer_Release, PyObject_GetBuffer
)
from libc.stdint cimport int64_t
from cpython.pycapsule cimport PyCapsule_GetName, PyCapsule_GetPointer

__all__ = [
    "project_rows",
    "natural_map_rows",
    "alart_curnier_rows",
    "sparse_newton_matrix",
    "planar_gauss_seidel",
    "planar_blocks",
    "row_products",
    "abs_row_sums",
    "small_newton",
    "small_certificate",
    "small_semidefinite",
    "SMALL_REASONS",
    "planar_solve",
    "PLANAR_REASONS",
    "PLANAR_EVERY",
    "PLANAR_SPAN",
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


cdef inline double _natural_row(const double* r, const double* u, Py_ssize_t d,
                                double mu) noexcept nogil:
    """Squared natural-map residual of one contact (``r`` from the cone apex, ``u`` its
    velocity): ``||r - P_K(r - u - mu ||u_T|| e_N)||^2``."""
    cdef Py_ssize_t k
    cdef double slip = 0.0, square = 0.0
    cdef double x[3]
    cdef double p[3]
    for k in range(1, d):
        slip += u[k] * u[k]
    for k in range(d):
        x[k] = r[k] - u[k]
    x[0] -= mu * sqrt(slip)
    _project(x, d, mu, p)
    for k in range(d):
        square += (r[k] - p[k]) ** 2
    return square


def natural_map_rows(const double[:, :] R, const double[:, :] U, const double[:] mu,
                     double[:] squares):
    """Squared natural-map residual of each contact into ``squares``; returns their sum.

    Contact ``i``: ``||R_i - P_K(R_i - U_i - mu_i ||U_iT|| e_N)||^2`` (De Saxce's modified
    velocity; ``R`` measured from the cone apex).
    """
    cdef Py_ssize_t i, k, d = R.shape[1]
    _check_dimension(d)
    cdef double square, total = 0.0
    cdef double r[3]
    cdef double u[3]
    for i in range(R.shape[0]):
        for k in range(d):
            r[k] = R[i, k]
            u[k] = U[i, k]
        square = _natural_row(r, u, d, mu[i])
        squares[i] = square
        total += square
    return total


cdef inline void _alart_curnier(const double* r, const double* u, Py_ssize_t d, double mu,
                                double rho, double* phi, double* A, double* B) noexcept nogil:
    """Alart-Curnier function of one contact into ``phi``; its Jacobian blocks ``A``, ``B``
    (row-major ``d x d``) too unless ``A`` is NULL (see :func:`alart_curnier_rows`)."""
    cdef Py_ssize_t k, a, b
    cdef bint pressed, outside
    cdef double xn, radius, norm = 0.0, s, inverse, c, identity
    cdef double y[3]  # the trial point X_i (its tangential part)
    xn = r[0] - rho * u[0]
    pressed = xn > 0.0
    radius = mu * xn if pressed else 0.0
    for k in range(1, d):
        y[k] = r[k] - rho * u[k]
        norm += y[k] * y[k]
    norm = sqrt(norm)
    outside = norm > radius
    s = radius / norm if outside else 1.0
    phi[0] = r[0] - (xn if pressed else 0.0)
    for k in range(1, d):
        phi[k] = r[k] - s * y[k]
    if A == NULL:
        return
    inverse = 1.0 / norm if outside else 0.0  # y / ||y|| is the slip direction
    for a in range(d):
        for b in range(d):
            identity = 1.0 if a == b else 0.0
            if a == 0:
                c = 1.0 if (b == 0 and pressed) else 0.0
            elif b == 0:
                c = mu * y[a] * inverse if pressed else 0.0
            else:
                c = s * (identity - y[a] * y[b] * inverse * inverse)
            A[a * d + b] = identity - c
            B[a * d + b] = rho * c


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
    cdef bint jacobian = A.shape[0] > 0
    cdef double r[3]
    cdef double u[3]
    cdef double phi[3]
    cdef double a_block[9]
    cdef double b_block[9]
    for i in range(R.shape[0]):
        for k in range(d):
            r[k] = R[i, k]
            u[k] = U[i, k]
        _alart_curnier(r, u, d, mu[i], rho[i], phi, a_block if jacobian else NULL, b_block)
        for k in range(d):
            Phi[i, k] = phi[k]
        if not jacobian:
            continue
        for a in range(d):
            for b in range(d):
                A[i, a, b] = a_block[a * d + b]
                B[i, a, b] = b_block[a * d + b]


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


ctypedef double (*_asum_t)(int* n, double* x, int* incx) noexcept nogil
cdef _asum_t _dasum = NULL


def abs_row_sums(const double[:, ::1] W, const int64_t[:] rows, double[:] sums):
    """``sums[k] = sum_j |W[rows[k], j]|`` by BLAS ``dasum`` (scipy's) on each row asked for:
    one read of each, no temporary."""
    global _dasum
    cdef Py_ssize_t k, i
    cdef int n = <int> W.shape[1], one = 1
    if sums.shape[0] != rows.shape[0]:
        raise ValueError("sums must hold one value per row")
    if _dasum == NULL:
        from scipy.linalg import cython_blas
        capsule = cython_blas.__pyx_capi__["dasum"]
        _dasum = <_asum_t> PyCapsule_GetPointer(capsule, PyCapsule_GetName(capsule))
    for k in range(rows.shape[0]):
        i = rows[k]
        if i < 0 or i >= W.shape[0]:
            raise IndexError(f"row {i} out of range 0..{W.shape[0] - 1}")
        sums[k] = _dasum(&n, <double*> &W[i, 0], &one) if n else 0.0


# ---------------------------------------------------------------------------------------------
# Small dense problems: the whole Newton run, the certificate and the PSD check in C.

#: Why :func:`small_newton` stopped, by the code it returns (the reasons of coulomb's Newton run).
SMALL_REASONS = (
    "converged", "stalled", "singular Newton matrix", "line search failed", "iteration limit"
)
cdef enum:
    _CONVERGED = 0
    _STALLED = 1
    _SINGULAR = 2
    _NO_STEP = 3
    _LIMIT = 4

# the constants of contactqp.methods.coulomb's Newton run (passed by the caller would cost more
# than it says: tests/test_kernels.py checks that the two agree)
cdef double REGULARISATION = 1e-2
cdef Py_ssize_t MEMORY = 5
cdef double ARMIJO = 1e-4
cdef Py_ssize_t MAX_HALVINGS = 30
cdef Py_ssize_t STALL = 20
SMALL_CONSTANTS = {
    "REGULARISATION": REGULARISATION,
    "MEMORY": MEMORY,
    "ARMIJO": ARMIJO,
    "MAX_HALVINGS": MAX_HALVINGS,
    "STALL": STALL,
}


cdef struct Small:
    # one problem u = W r + q (W row-major m x m), nc contacts of dimension d, apex shift
    Py_ssize_t m, nc, d
    const double* W
    const double* q
    const double* mu
    const double* shift
    bint per_contact
    double floor  # CONTACT_FLOOR
    double qq  # q . q
    double rr  # r . r and u . u at the point last measured
    double uu
    # one group of a larger problem that W does not couple: the rest's q . q, r . r and u . u,
    # by which its Newton steps are regularised as the whole problem's run would regularise them
    bint grouped
    double rest_qq
    double rest_rr
    double rest_uu
    double* qt  # q - W shift: the problem from the cone apex
    double* rho
    double* scale  # mean diagonal of each contact block (1 where not positive)
    # work
    double* u
    double* phi
    double* A
    double* B
    double* step
    double* rhs
    double* trial
    double* trial_u
    double* trial_phi
    double* best
    double* react
    double* J
    double* squares
    Py_ssize_t* rows
    Py_ssize_t* pivots
    double* errors
    double* history


cdef inline double _dot(const double* x, const double* y, Py_ssize_t n) noexcept nogil:
    cdef Py_ssize_t i
    cdef double total = 0.0
    for i in range(n):
        total += x[i] * y[i]
    return total


cdef inline void _product(const Small* S, const double* r, const double* q,
                          double* u) noexcept nogil:
    """``u = W r + q``."""
    cdef Py_ssize_t i, j, m = S.m
    cdef double total
    for i in range(m):
        total = 0.0
        for j in range(m):
            total += S.W[i * m + j] * r[j]
        u[i] = total + q[i]


cdef void _natural_error(Small* S, const double* r, const double* u, double* residual,
                         double* error) noexcept nogil:
    """Natural-map residual and error of reactions ``r`` and velocities ``u``
    (:func:`contactqp.core.local_problem.natural_map_residual`: ``r + shift`` is measured)."""
    cdef Py_ssize_t i, k, d = S.d, m = S.m
    cdef double total = 0.0, rr = 0.0, uu = 0.0, scale, own, a, b, c, worst = 0.0, floor
    cdef double x[3]
    for i in range(S.nc):
        for k in range(d):
            x[k] = r[i * d + k] + S.shift[i * d + k]
        S.squares[i] = _natural_row(x, u + i * d, d, S.mu[i])
        total += S.squares[i]
    for i in range(m):
        rr += r[i] * r[i]
        uu += u[i] * u[i]
    residual[0] = sqrt(total)
    S.rr, S.uu = rr, uu
    scale = sqrt(max(S.qq, max(rr, uu)))
    if scale == 0.0:
        scale = 1.0
    error[0] = residual[0] / scale
    if S.per_contact and S.nc:
        floor = (S.floor * scale) ** 2
        for i in range(S.nc):
            a = 0.0
            b = 0.0
            c = 0.0
            for k in range(d):
                a += S.q[i * d + k] ** 2
                b += r[i * d + k] ** 2
                c += u[i * d + k] ** 2
            own = max(max(a, b), max(c, floor))
            worst = max(worst, S.squares[i] / own)
        error[0] = max(error[0], sqrt(worst))


cdef void _measure(Small* S, const double* r, const double* u, double* residual,
                   double* error) noexcept nogil:
    """:func:`_natural_error` of ``r`` from the apex: of the reactions ``r - shift``."""
    cdef Py_ssize_t i
    for i in range(S.m):
        S.react[i] = r[i] - S.shift[i]
    _natural_error(S, S.react, u, residual, error)


cdef void _residual(const Small* S, const double* r, double* u, double* phi) noexcept nogil:
    """``u = W r + q~`` and the Alart-Curnier function ``phi`` of ``(r, u)``."""
    cdef Py_ssize_t i, d = S.d
    _product(S, r, S.qt, u)
    for i in range(S.nc):
        _alart_curnier(r + i * d, u + i * d, d, S.mu[i], S.rho[i], phi + i * d, NULL, NULL)


cdef bint _lu_solve(double* J, Py_ssize_t n, double* b, Py_ssize_t* pivots) noexcept nogil:
    """Solve ``J x = b`` in place (``b`` becomes ``x``) by LU with partial pivoting (LAPACK's
    ``getrf``/``getrs`` unblocked); False when a pivot is exactly zero (``numpy.linalg.solve``'s
    LinAlgError)."""
    cdef Py_ssize_t i, j, k, p
    cdef double big, value, pivot
    for k in range(n):
        p = k
        big = fabs(J[k * n + k])
        for i in range(k + 1, n):
            value = fabs(J[i * n + k])
            if value > big:
                big = value
                p = i
        pivots[k] = p
        if J[p * n + k] == 0.0:
            return False
        if p != k:
            for j in range(n):
                value = J[k * n + j]
                J[k * n + j] = J[p * n + j]
                J[p * n + j] = value
        pivot = 1.0 / J[k * n + k]
        for i in range(k + 1, n):
            J[i * n + k] *= pivot
        for i in range(k + 1, n):
            value = J[i * n + k]
            if value != 0.0:
                for j in range(k + 1, n):
                    J[i * n + j] -= value * J[k * n + j]
    for k in range(n):
        p = pivots[k]
        if p != k:
            value = b[k]
            b[k] = b[p]
            b[p] = value
    for i in range(n):
        value = b[i]
        for j in range(i):
            value -= J[i * n + j] * b[j]
        b[i] = value
    for i in range(n - 1, -1, -1):
        value = b[i]
        for j in range(i + 1, n):
            value -= J[i * n + j] * b[j]
        b[i] = value / J[i * n + i]
    return True


cdef bint _direction(Small* S, const double* r, const double* u, double eta) noexcept nogil:
    """``S.step`` = the Newton step ``(A + B (W + eta D)) dr = -Phi`` (coulomb's
    ``_Newton.direction``, dense); False if the matrix is singular or the step not finite."""
    cdef Py_ssize_t i, j, a, b, c, k, kk, d = S.d, m = S.m, dd = S.d * S.d, n = 0, ni, nj
    cdef Py_ssize_t kept = 0
    cdef double value, factor
    cdef double* Ai
    cdef double* Bi
    for i in range(S.nc):
        Ai = S.A + i * dd
        Bi = S.B + i * dd
        _alart_curnier(r + i * d, u + i * d, d, S.mu[i], S.rho[i], S.phi + i * d, Ai, Bi)
        factor = eta * S.scale[i]
        c = 0
        for k in range(dd):
            Ai[k] += factor * Bi[k]
            if Bi[k] != 0.0:
                c = 1
        if c:  # kept: the contact's rows enter the factored block
            for a in range(d):
                S.rows[n + a] = i * d + a
            n += d
            kept += 1
    for k in range(m):
        S.step[k] = -S.phi[k]
    if kept == 0:
        return True
    for k in range(n):
        S.rhs[k] = S.step[S.rows[k]]
    if kept < S.nc:  # rhs -= B W (the released contacts' steps)
        for k in range(m):
            S.trial[k] = S.step[k]
        for k in range(n):
            S.trial[S.rows[k]] = 0.0
        for k in range(m):  # coupling, in trial_u
            value = 0.0
            for j in range(m):
                value += S.W[k * m + j] * S.trial[j]
            S.trial_u[k] = value
        for kk in range(n // d):
            ni = kk * d
            i = S.rows[ni] // d
            Bi = S.B + i * dd
            for a in range(d):
                value = 0.0
                for c in range(d):
                    value += Bi[a * d + c] * S.trial_u[i * d + c]
                S.rhs[ni + a] -= value
    # J = B_kept W[kept, kept] + blockdiag(A_kept)
    for kk in range(n // d):
        ni = kk * d
        i = S.rows[ni] // d
        Bi = S.B + i * dd
        Ai = S.A + i * dd
        for a in range(d):
            for nj in range(n):
                value = 0.0
                for c in range(d):
                    value += Bi[a * d + c] * S.W[(i * d + c) * m + S.rows[nj]]
                S.J[(ni + a) * n + nj] = value
            for b in range(d):
                S.J[(ni + a) * n + ni + b] += Ai[a * d + b]
    if not _lu_solve(S.J, n, S.rhs, S.pivots):
        return False
    for k in range(n):
        S.step[S.rows[k]] = S.rhs[k]
    for k in range(m):
        if not isfinite(S.step[k]):
            return False
    return True


cdef inline double _regulariser(const Small* S, double residual, double error) noexcept nogil:
    """The relative size of a Newton step's regularisation (capped at REGULARISATION by the
    caller): the error; for one group of a larger problem, once its own error is below the cap,
    its residual on the whole problem's scale (the rest's sizes as last known), as the whole
    problem's run would regularise it."""
    cdef double whole
    if not S.grouped or error >= REGULARISATION:
        return error
    whole = sqrt(max(S.qq + S.rest_qq, max(S.rr + S.rest_rr, S.uu + S.rest_uu)))
    return residual / whole if whole > 0.0 else error


cdef int _run(Small* S, double* r, double tol, Py_ssize_t max_iter, Py_ssize_t* iterations,
              double* out_error) noexcept nogil:
    """Coulomb's Newton run (``_Newton.run``, ``adaptive=False``) from ``r`` (apex coordinates,
    overwritten by the point returned); the reason code, ``iterations`` and the error."""
    cdef Py_ssize_t k, i, count = 1, tries, first
    cdef double residual, error, best_error, merit, reference, t, trial_residual, trial_error
    cdef double low_recent, low_before
    cdef bint found
    cdef Py_ssize_t m = S.m
    _residual(S, r, S.u, S.phi)
    _measure(S, r, S.u, &residual, &error)
    for i in range(m):
        S.best[i] = r[i]
    best_error = error
    S.errors[0] = error
    for k in range(max_iter):
        if error <= tol:
            iterations[0] = k
            out_error[0] = error
            return _CONVERGED
        if count > STALL:
            low_recent = S.errors[count - STALL]
            for i in range(count - STALL, count):
                low_recent = min(low_recent, S.errors[i])
            low_before = S.errors[0]
            for i in range(count - STALL):
                low_before = min(low_before, S.errors[i])
            if low_recent > 0.5 * low_before:
                break  # stalled
        merit = 0.5 * _dot(S.phi, S.phi, m)
        S.history[k] = merit
        first = k - MEMORY + 1 if k >= MEMORY else 0
        reference = S.history[first]
        for i in range(first, k + 1):
            reference = max(reference, S.history[i])
        if not _direction(S, r, S.u, min(REGULARISATION, _regulariser(S, residual, error))):
            iterations[0] = k
            out_error[0] = best_error
            for i in range(m):
                r[i] = S.best[i]
            return _SINGULAR
        t = 1.0
        found = False
        for tries in range(MAX_HALVINGS):
            for i in range(m):
                S.trial[i] = r[i] + t * S.step[i]
            _residual(S, S.trial, S.trial_u, S.trial_phi)
            _measure(S, S.trial, S.trial_u, &trial_residual, &trial_error)
            if 0.5 * _dot(S.trial_phi, S.trial_phi, m) <= reference - ARMIJO * t * merit or (
                t == 1.0 and trial_residual < residual
            ):
                found = True
                break
            t *= 0.5
        if not found:
            iterations[0] = k
            out_error[0] = best_error
            for i in range(m):
                r[i] = S.best[i]
            return _NO_STEP
        for i in range(m):
            r[i] = S.trial[i]
            S.u[i] = S.trial_u[i]
            S.phi[i] = S.trial_phi[i]
        residual = trial_residual
        error = trial_error
        S.errors[count] = error
        count += 1
        if error < best_error:
            best_error = error
            for i in range(m):
                S.best[i] = r[i]
    else:
        iterations[0] = max_iter
        out_error[0] = best_error
        for i in range(m):
            r[i] = S.best[i]
        return _LIMIT
    iterations[0] = k
    out_error[0] = best_error
    for i in range(m):
        r[i] = S.best[i]
    return _STALLED


cdef double* _setup(Small* S, Py_ssize_t m, Py_ssize_t nc, Py_ssize_t max_iter) noexcept nogil:
    """Allocate the work arrays of problems of ``m`` unknowns and ``nc`` contacts (one block,
    freed by the caller); NULL when out of memory."""
    cdef Py_ssize_t dd = (m // nc) ** 2 if nc else 0
    cdef Py_ssize_t size = 10 * m + 2 * nc * dd + m * m + 3 * nc + 2 * (max_iter + 1)
    cdef double* block = <double*> malloc(size * sizeof(double))
    cdef Py_ssize_t* indices = <Py_ssize_t*> malloc((2 * m + 1) * sizeof(Py_ssize_t))
    if block == NULL or indices == NULL:
        free(block)
        free(indices)
        return NULL
    S.m, S.nc = m, nc
    S.d = m // nc if nc else 3
    S.qt = block
    S.u = block + m
    S.phi = block + 2 * m
    S.step = block + 3 * m
    S.rhs = block + 4 * m
    S.trial = block + 5 * m
    S.trial_u = block + 6 * m
    S.trial_phi = block + 7 * m
    S.best = block + 8 * m
    S.react = block + 9 * m
    S.J = block + 10 * m
    S.A = S.J + m * m
    S.B = S.A + nc * dd
    S.rho = S.B + nc * dd
    S.scale = S.rho + nc
    S.squares = S.scale + nc
    S.errors = S.squares + nc
    S.history = S.errors + max_iter + 1
    S.rows = indices
    S.pivots = indices + m
    return block


cdef void _problem(Small* S, const double* W, const double* q, const double* mu,
                   const double* shift) noexcept nogil:
    """Point ``S`` at one problem: ``q~``, ``rho`` and the contact scales."""
    cdef Py_ssize_t i, k, d = S.d, m = S.m
    cdef double mean
    S.W, S.q, S.mu, S.shift = W, q, mu, shift
    S.grouped = False
    S.qq = _dot(q, q, m)
    for i in range(m):  # q~ = q - W shift
        S.qt[i] = q[i] - _dot(W + i * m, shift, m)
    for i in range(S.nc):
        mean = 0.0
        for k in range(d):
            mean += W[(i * d + k) * m + i * d + k]
        mean /= d
        S.scale[i] = mean if mean > 0.0 else 1.0
        S.rho[i] = 1.0 / S.scale[i]


cdef void* _buffer(object array, char kind, int ndim, Py_ssize_t* shape, bint writable,
                   str name) except NULL:
    """The data of a C-contiguous array of ``ndim`` dimensions, of float64 (``kind`` ``d``) or
    intp (``n``), its shape written to ``shape``.

    A typed memoryview costs a few thousand instructions to set up, the whole Newton run of a
    one-contact problem: the small-problem functions read their arrays through this. The buffer
    is released at once; the caller holds the arrays for the call.
    """
    cdef Py_buffer view
    cdef int i, flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT
    cdef char code
    cdef bint ok
    if writable:
        flags |= PyBUF_WRITABLE
    PyObject_GetBuffer(array, &view, flags)
    cdef void* data = view.buf
    ok = view.ndim == ndim and view.itemsize == 8 and view.format != NULL
    if ok:
        code = view.format[0]
        if code == b'@' or code == b'=' or code == b'<':
            code = view.format[1]
        ok = code == b'd' if kind == b'd' else (code == b'q' or code == b'l' or code == b'n')
    if ok:
        for i in range(ndim):
            shape[i] = view.shape[i]
    PyBuffer_Release(&view)
    if not ok:
        raise ValueError(
            f"{name} must be a C-contiguous {ndim}-D "
            f"{'float64' if kind == b'd' else 'intp'} array{' (writable)' if writable else ''}"
        )
    return data if data != NULL else <void*> shape  # an empty array's data is never read


def small_newton(W, q, mu, shift, r, double tol, Py_ssize_t max_iter, bint per_contact,
                 double floor, iterations, reasons, errors):
    """Coulomb's first Newton run on each of ``P`` small dense problems, in C.

    Problem ``p``: ``u = W[p] r + q[p]`` (``W[p]`` row-major, ``m`` unknowns), friction
    coefficients ``mu[p]`` (``nc`` contacts, ``d = m / nc`` components each), apex shift
    ``shift[p]`` (:attr:`~contactqp.core.local_problem.LocalProblem.apex_shift`). From the start
    ``r[p]`` (apex coordinates: reactions plus ``shift[p]``) it runs exactly the iterations of
    ``contactqp.methods.coulomb._Newton.run`` with ``adaptive=False`` (the same steps,
    safeguards and stopping rules, up to rounding: sums in another order), measured by the
    natural-map error (``per_contact``: each contact on its own scale too, floored at ``floor``
    times the problem's). ``r[p]`` receives the point returned (the last one when converged,
    else the best), ``iterations[p]`` the iterations, ``reasons[p]`` an index of
    :data:`SMALL_REASONS` and ``errors[p]`` its error.
    """
    cdef Py_ssize_t p, P, m, nc
    cdef Py_ssize_t sw[3]
    cdef Py_ssize_t sq[2]
    cdef Py_ssize_t smu[2]
    cdef Py_ssize_t ss[2]
    cdef Py_ssize_t sr[2]
    cdef Py_ssize_t si[1]
    cdef Py_ssize_t sn[1]
    cdef Py_ssize_t se[1]
    cdef const double* Wd = <const double*> _buffer(W, b'd', 3, sw, False, "W")
    cdef const double* qd = <const double*> _buffer(q, b'd', 2, sq, False, "q")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 2, smu, False, "mu")
    cdef const double* sd = <const double*> _buffer(shift, b'd', 2, ss, False, "shift")
    cdef double* rd = <double*> _buffer(r, b'd', 2, sr, True, "r")
    cdef Py_ssize_t* itd = <Py_ssize_t*> _buffer(iterations, b'n', 1, si, True, "iterations")
    cdef Py_ssize_t* red = <Py_ssize_t*> _buffer(reasons, b'n', 1, sn, True, "reasons")
    cdef double* erd = <double*> _buffer(errors, b'd', 1, se, True, "errors")
    P, m, nc = sw[0], sw[1], smu[1]
    if sw[2] != m or sq[1] != m or ss[1] != m or sr[1] != m:
        raise ValueError("W, q, shift and r must have m = W.shape[1] columns")
    if nc == 0 or m != (m // nc) * nc:
        raise ValueError(f"{m} unknowns do not make rows of {nc} contacts")
    _check_dimension(m // nc)
    if (sq[0] != P or smu[0] != P or ss[0] != P or sr[0] != P or si[0] != P or sn[0] != P
            or se[0] != P):
        raise ValueError("every argument must hold P = W.shape[0] problems")
    if max_iter < 0:
        raise ValueError("max_iter must be >= 0")
    cdef Small S
    cdef double* block
    cdef Py_ssize_t count
    with nogil:
        block = _setup(&S, m, nc, max_iter)
        if block != NULL:
            S.per_contact = per_contact
            S.floor = floor
            for p in range(P):
                _problem(&S, Wd + p * m * m, qd + p * m, mud + p * nc, sd + p * m)
                red[p] = _run(&S, rd + p * m, tol, max_iter, &count, erd + p)
                itd[p] = count
            free(block)
            free(S.rows)
    if block == NULL:
        raise MemoryError()


cdef void _certify(Small* S, const double* rp, double rtol, double* up, double* md,
                   Py_ssize_t* std) noexcept nogil:
    """The certificate of reactions ``rp`` of the problem ``S`` points at (``S.qq`` set):
    ``up = W rp + q``, ``md`` its four measures and ``std`` the contacts' status codes (see
    :func:`small_certificate`)."""
    cdef Py_ssize_t i, j, k, m = S.m, nc = S.nc, d = S.d
    cdef double total, magnitude, product, largest, force, w, apex, size, aa, slip, carry
    cdef double residual, error, value
    product = 0.0
    w = 0.0
    for i in range(m):
        total = 0.0
        magnitude = 0.0
        for j in range(m):
            total += S.W[i * m + j] * rp[j]
            magnitude += fabs(S.W[i * m + j]) * fabs(rp[j])
        up[i] = total + S.q[i]
        if i % d == 0 or S.mu[i // d] != 0.0:  # the certified rows
            product += magnitude * magnitude
        w = max(w, fabs(S.W[i * m + i]))
    if w == 0.0:
        w = 1.0
    _natural_error(S, rp, up, &residual, &error)
    md[0] = error
    md[1] = sqrt(product)
    md[2] = sqrt(S.qq)
    size = 0.0
    aa = 0.0
    value = 0.0
    for i in range(m):
        size += rp[i] * rp[i]
        apex = rp[i] + S.shift[i]
        aa += apex * apex
        value += up[i] * up[i]
    md[3] = sqrt(max(S.qq, max(size, value)))
    largest = max(max(sqrt(size), sqrt(aa)), max(sqrt(S.qq) / w, sqrt(value) / w))
    force = largest if largest > 0.0 else 1.0
    for i in range(nc):
        carry = 0.0
        slip = 0.0
        for k in range(d):
            apex = rp[i * d + k] + S.shift[i * d + k]
            carry += apex * apex
            if k:
                slip += up[i * d + k] ** 2
        if sqrt(carry) > rtol * force:
            std[i] = 2 if sqrt(slip) > rtol * w * force else 1
        else:
            std[i] = 0


def small_certificate(W, q, mu, shift, r, bint per_contact, double floor, double rtol, u,
                      measures, status):
    """The certificate of reactions ``r[p]`` of each small dense problem, from ``r`` alone.

    ``u[p] = W[p] r[p] + q[p]``; ``measures[p]`` = (natural-map error, ``|| |W| |r| ||`` over
    the rows the error depends on, ``||q||``, ``max(||q||, ||r||, ||u||)``), the figures of
    :func:`~contactqp.core.local_problem.natural_map_residual` and
    :func:`~contactqp.core.local_problem.accuracy_limits`; ``status[p]`` the open (0) /
    stick (1) / slip (2) code of each contact by the rule of
    :func:`~contactqp.core.local_problem.contact_status_unchecked` with ``rtol``.
    """
    cdef Py_ssize_t p, i, j, k, P, m, nc, d
    cdef Py_ssize_t sw[3]
    cdef Py_ssize_t sq[2]
    cdef Py_ssize_t smu[2]
    cdef Py_ssize_t ss[2]
    cdef Py_ssize_t sr[2]
    cdef Py_ssize_t su[2]
    cdef Py_ssize_t sm[2]
    cdef Py_ssize_t st[2]
    cdef const double* Wd = <const double*> _buffer(W, b'd', 3, sw, False, "W")
    cdef const double* qd = <const double*> _buffer(q, b'd', 2, sq, False, "q")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 2, smu, False, "mu")
    cdef const double* sd = <const double*> _buffer(shift, b'd', 2, ss, False, "shift")
    cdef const double* rd = <const double*> _buffer(r, b'd', 2, sr, False, "r")
    cdef double* ud = <double*> _buffer(u, b'd', 2, su, True, "u")
    cdef double* md = <double*> _buffer(measures, b'd', 2, sm, True, "measures")
    cdef Py_ssize_t* std = <Py_ssize_t*> _buffer(status, b'n', 2, st, True, "status")
    P, m, nc = sw[0], sw[1], smu[1]
    if nc == 0 or m != (m // nc) * nc:
        raise ValueError(f"{m} unknowns do not make rows of {nc} contacts")
    d = m // nc
    _check_dimension(d)
    if (sw[2] != m or sq[1] != m or ss[1] != m or sr[1] != m or su[1] != m or sm[1] != 4
            or st[1] != nc):
        raise ValueError("inconsistent shapes")
    if (sq[0] != P or smu[0] != P or ss[0] != P or sr[0] != P or su[0] != P or sm[0] != P
            or st[0] != P):
        raise ValueError("every argument must hold P = W.shape[0] problems")
    cdef Small S
    cdef double* squares = <double*> malloc(nc * sizeof(double))
    if squares == NULL:
        raise MemoryError()
    S.m, S.nc, S.d = m, nc, d
    S.per_contact = per_contact
    S.floor = floor
    S.squares = squares
    with nogil:
        for p in range(P):
            S.W, S.q, S.mu, S.shift = Wd + p * m * m, qd + p * m, mud + p * nc, sd + p * m
            S.qq = _dot(S.q, S.q, m)
            _certify(&S, rd + p * m, rtol, ud + p * m, md + p * 4, std + p * nc)
    free(squares)


cdef bint _semidefinite(const double* W, Py_ssize_t m, double shift, double* S,
                        double* scaling, Py_ssize_t* keep) noexcept nogil:
    """The test of :func:`small_semidefinite` on one row-major ``m x m`` matrix ``W``, in the
    work arrays ``S`` (``m * m``), ``scaling`` and ``keep`` (``m`` each)."""
    cdef Py_ssize_t i, j, k, n = 0
    cdef double value
    for i in range(m):
        value = W[i * m + i]
        if value < 0.0 or not (value >= 0.0):
            return False
        elif value > 0.0:
            keep[n] = i
            scaling[n] = 1.0 / sqrt(value)
            n += 1
        else:  # a zero diagonal entry: its row must be zero
            for j in range(m):
                if 0.5 * (W[i * m + j] + W[j * m + i]) != 0.0:
                    return False
    for i in range(n):
        for j in range(n):
            value = 0.5 * (W[keep[i] * m + keep[j]] + W[keep[j] * m + keep[i]])
            S[i * n + j] = scaling[i] * value * scaling[j]
        S[i * n + i] += shift
    for j in range(n):  # lower Cholesky factor in place, by columns
        value = S[j * n + j]
        for k in range(j):
            value -= S[j * n + k] * S[j * n + k]
        if not (value > 0.0):
            return False
        value = sqrt(value)
        S[j * n + j] = value
        for i in range(j + 1, n):
            S[i * n + j] -= _dot(S + i * n, S + j * n, j)
            S[i * n + j] /= value
    return True


def small_semidefinite(W, double shift, passed):
    """``passed[p]`` = 1 when ``W[p]`` passes the test of
    :func:`~contactqp.core.local_problem.check_positive_semidefinite`, else 0.

    With ``S = (W + W^T) / 2``: no diagonal entry negative, a row with a zero diagonal entry
    zero, and a Cholesky factorisation (unblocked, as LAPACK's ``potrf``: a pivot that is not
    positive fails) of the Jacobi-scaled ``S`` on the rows with a positive diagonal, plus
    ``shift`` times the identity.
    """
    cdef Py_ssize_t p, P, m
    cdef Py_ssize_t sw[3]
    cdef Py_ssize_t sp[1]
    cdef const double* Wd = <const double*> _buffer(W, b'd', 3, sw, False, "W")
    cdef Py_ssize_t* pd = <Py_ssize_t*> _buffer(passed, b'n', 1, sp, True, "passed")
    P, m = sw[0], sw[1]
    if sw[2] != m or sp[0] != P:
        raise ValueError("W must be (P, m, m) and passed (P,)")
    cdef double* S = <double*> malloc((m * m + m + 1) * sizeof(double))
    cdef Py_ssize_t* keep = <Py_ssize_t*> malloc((m + 1) * sizeof(Py_ssize_t))
    if S == NULL or keep == NULL:
        free(S)
        free(keep)
        raise MemoryError()
    with nogil:
        for p in range(P):
            pd[p] = 1 if _semidefinite(Wd + p * m * m, m, shift, S, S + m * m, keep) else 0
    free(S)
    free(keep)


def local_arrays_valid(W_values, q, mu, cohesion):
    """True when the C-contiguous float64 arrays of a local problem pass its checks: the
    entries ``W_values`` of ``W`` (any number, e.g. a dense ``W`` raveled or a sparse one's
    stored values) and ``q`` finite, ``mu`` finite and ``>= 0``, and ``cohesion`` (same length
    as ``mu``, or None) finite, ``>= 0`` and positive only where ``mu > 0``: the checks of
    :class:`~contactqp.core.local_problem.LocalProblem`, in one pass without temporaries.
    False on any failure, which the caller's own checks then name. Shapes are the caller's.
    """
    cdef Py_ssize_t sw[1]
    cdef Py_ssize_t sq[1]
    cdef Py_ssize_t smu[1]
    cdef Py_ssize_t sc[1]
    cdef const double* Wd = <const double*> _buffer(W_values, b'd', 1, sw, False, "W_values")
    cdef const double* qd = <const double*> _buffer(q, b'd', 1, sq, False, "q")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 1, smu, False, "mu")
    cdef const double* cd = NULL
    cdef Py_ssize_t i, nc = smu[0]
    if cohesion is not None:
        cd = <const double*> _buffer(cohesion, b'd', 1, sc, False, "cohesion")
        if sc[0] != nc:
            return False
    cdef bint ok = True
    with nogil:
        for i in range(sw[0]):
            if not isfinite(Wd[i]):
                ok = False
                break
        for i in range(sq[0]):
            if not isfinite(qd[i]):
                ok = False
        for i in range(nc):
            if not (mud[i] >= 0.0 and isfinite(mud[i])):
                ok = False
            elif cd != NULL and not (
                    isfinite(cd[i]) and (cd[i] == 0.0 or (cd[i] > 0.0 and mud[i] > 0.0))):
                ok = False
    return ok


def small_solve(W, q, mu, cohesion, r, double tol, Py_ssize_t max_iter, bint per_contact,
                double floor, double rtol, u, status):
    """One small dense problem solved in one call: Coulomb's first Newton run and the
    certificate of its answer (:func:`small_newton` and :func:`small_certificate` on a batch of
    one, with the apex shift computed here from ``mu`` and ``cohesion``).

    ``W`` (m, m), ``q`` and ``r`` (m,), ``mu``, ``cohesion`` and ``status`` (k,). ``r`` holds
    the start (reactions) and receives the reactions returned, ``u`` their ``W r + q`` and
    ``status`` their contact codes. Returns ``(iterations, reason, run error, error, product,
    size_q, scale)``: ``reason`` an index of :data:`SMALL_REASONS`, the run error that of the
    Newton run's point (its own measure) and the last four the certificate's measures
    (:func:`small_certificate`).
    """
    cdef Py_ssize_t sw[2]
    cdef Py_ssize_t sq[1]
    cdef Py_ssize_t smu[1]
    cdef Py_ssize_t sc[1]
    cdef Py_ssize_t sr[1]
    cdef Py_ssize_t su[1]
    cdef Py_ssize_t st[1]
    cdef const double* Wd = <const double*> _buffer(W, b'd', 2, sw, False, "W")
    cdef const double* qd = <const double*> _buffer(q, b'd', 1, sq, False, "q")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 1, smu, False, "mu")
    cdef const double* cd = <const double*> _buffer(cohesion, b'd', 1, sc, False, "cohesion")
    cdef double* rd = <double*> _buffer(r, b'd', 1, sr, True, "r")
    cdef double* ud = <double*> _buffer(u, b'd', 1, su, True, "u")
    cdef Py_ssize_t* std = <Py_ssize_t*> _buffer(status, b'n', 1, st, True, "status")
    cdef Py_ssize_t i, m = sw[0], nc = smu[0], count = 0, d
    if nc == 0 or m != (m // nc) * nc:
        raise ValueError(f"{m} unknowns do not make rows of {nc} contacts")
    d = m // nc
    _check_dimension(d)
    if sw[1] != m or sq[0] != m or sr[0] != m or su[0] != m or sc[0] != nc or st[0] != nc:
        raise ValueError("inconsistent shapes")
    if max_iter < 0:
        raise ValueError("max_iter must be >= 0")
    cdef Small S
    cdef double md[4]
    cdef double run_error = 0.0
    cdef int reason = _CONVERGED
    cdef double* block
    cdef double* work = <double*> malloc((2 * m + 1) * sizeof(double))
    if work == NULL:
        raise MemoryError()
    cdef double* shift = work
    cdef double* x = work + m
    with nogil:
        for i in range(m):
            shift[i] = 0.0
        for i in range(nc):
            if cd[i] > 0.0:
                shift[i * d] = cd[i] / mud[i]
        block = _setup(&S, m, nc, max_iter)
        if block != NULL:
            S.per_contact = per_contact
            S.floor = floor
            _problem(&S, Wd, qd, mud, shift)
            for i in range(m):
                x[i] = rd[i] + shift[i]
            reason = _run(&S, x, tol, max_iter, &count, &run_error)
            for i in range(m):
                rd[i] = x[i] - shift[i]
            _certify(&S, rd, rtol, ud, md, std)
            free(block)
            free(S.rows)
    free(work)
    if block == NULL:
        raise MemoryError()
    return (count, reason, run_error, md[0], md[1], md[2], md[3])


# ---------------------------------------------------------------------------------------------
# 2-D contacts: the whole Gauss-Seidel solve of methods.planar, its certificate included.

#: Why :func:`planar_solve` stopped, by the code it returns.
PLANAR_REASONS = ("converged", "stalled", "sweep budget spent", "diagonal block not semidefinite")
cdef enum:
    _PLANAR_EVERY = 10
    _PLANAR_SPAN = 20
#: Most sweeps between two evaluations of the error in :func:`planar_solve`.
PLANAR_EVERY = _PLANAR_EVERY
#: Fewest sweeps over which :func:`planar_solve`'s stall test measures the rate.
PLANAR_SPAN = _PLANAR_SPAN


cdef struct Checks:
    # the evaluations of the error during a Gauss-Seidel solve: count of them, the sweep of
    # each (history) and its error, the sweep of the last, and the ratio of the last error to
    # the change of that sweep (which says, from a sweep's change, when tol may be met)
    Py_ssize_t* history
    double* errors
    Py_ssize_t count
    Py_ssize_t last
    double ratio


cdef Py_ssize_t _judge(Checks* C, Py_ssize_t sweep, double error, double relative, double tol,
                       Py_ssize_t max_sweeps, bint stall_test) noexcept nogil:
    """Record the ``error`` after ``sweep`` sweeps (whose relative change was ``relative``);
    the code to stop with (:data:`PLANAR_REASONS`: 0 converged, 1 stalled, where the rate over
    at least ``_PLANAR_SPAN`` sweeps would not reach ``tol`` within ``max_sweeps``, 2 the
    budget spent), or -1 to go on."""
    cdef Py_ssize_t k
    cdef double rate
    C.history[C.count] = sweep
    C.errors[C.count] = error
    C.count += 1
    C.last = sweep
    if error <= tol:
        return 0
    if sweep >= max_sweeps:
        return 2
    if relative > 0.0:
        C.ratio = error / relative
    if stall_test:
        for k in range(C.count - 2, -1, -1):
            if C.history[k] <= sweep - _PLANAR_SPAN:
                rate = (error / C.errors[k]) ** (1.0 / (sweep - C.history[k]))
                if rate >= 1.0 or sweep + log(tol / error) / log(rate) > max_sweeps:
                    return 1
                break
    return -1


cdef inline bint _due(const Checks* C, Py_ssize_t sweep, Py_ssize_t first, double relative,
                      double tol, Py_ssize_t max_sweeps) noexcept nogil:
    """Whether the error is evaluated after ``sweep`` sweeps: each of the ``first``, when the
    sweep's change says ``tol`` may be met, at least every ``_PLANAR_EVERY``, and the last."""
    return (sweep <= first or C.ratio * relative <= tol or sweep - C.last >= _PLANAR_EVERY
            or sweep >= max_sweeps)


cdef struct Blocks:
    # W by 2x2 contact blocks: diag[4 i:4 i + 4] the diagonal block of contact i (row-major),
    # the off-diagonal blocks of block row i at slots ptr[i] .. ptr[i + 1] - 1, col[s] their
    # block column and val[4 s:4 s + 4] their entries (row-major)
    Py_ssize_t nc
    double* diag
    Py_ssize_t* ptr
    Py_ssize_t* col
    double* val


cdef inline void _block_row(const Blocks* B, Py_ssize_t i, const double* x, double* bn,
                            double* bt) noexcept nogil:
    """``(bn, bt) += sum over the off-diagonal blocks of row i of W_ij x_j``."""
    cdef Py_ssize_t s, j
    cdef double n = bn[0], t = bt[0], xn, xt
    cdef const double* v
    for s in range(B.ptr[i], B.ptr[i + 1]):
        j = B.col[s]
        v = B.val + 4 * s
        xn = x[2 * j]
        xt = x[2 * j + 1]
        n += v[0] * xn + v[1] * xt
        t += v[2] * xn + v[3] * xt
    bn[0] = n
    bt[0] = t


cdef void _block_product(const Blocks* B, const double* x, const double* q,
                         double* u) noexcept nogil:
    """``u = W x + q`` by blocks."""
    cdef Py_ssize_t i
    cdef double bn, bt
    cdef const double* a
    for i in range(B.nc):
        a = B.diag + 4 * i
        bn = q[2 * i] + a[0] * x[2 * i] + a[1] * x[2 * i + 1]
        bt = q[2 * i + 1] + a[2] * x[2 * i] + a[3] * x[2 * i + 1]
        _block_row(B, i, x, &bn, &bt)
        u[2 * i] = bn
        u[2 * i + 1] = bt


cdef inline void _planar_factors(const double* a, double mu, double* f) noexcept nogil:
    """``f`` (10 values): what :func:`_planar_local` computes of contact block ``a`` alone.

    ``f[0:4]`` the map ``b -> -a^-1 b`` (row-major; ``f[8]`` is 1 when ``a`` is invertible,
    else 0), and for either edge ``s = +1, -1`` (``k = 0, 1``): ``f[4 + 2k]`` the inverse of
    ``a00 - s mu a01`` when that is positive (else -1), ``f[5 + 2k] = a10 - s mu a11``;
    ``f[9] = 1 / (1 + mu^2)`` (the projection on the cone, :func:`_planar_error`).
    """
    f[9] = 1.0 / (1.0 + mu * mu)
    cdef double det = a[0] * a[3] - a[1] * a[2], s, denominator
    cdef int side
    if det != 0.0:
        f[0] = -a[3] / det
        f[1] = a[1] / det
        f[2] = a[2] / det
        f[3] = -a[0] / det
        f[8] = 1.0
    else:
        f[0] = f[1] = f[2] = f[3] = 0.0
        f[8] = 0.0
    for side in range(2):
        s = 1.0 - 2.0 * side
        denominator = a[0] - s * mu * a[1]
        f[4 + 2 * side] = 1.0 / denominator if denominator > 0.0 else -1.0
        f[5 + 2 * side] = a[2] - s * mu * a[3]


cdef double _planar_error(const Blocks* B, const double* x, const double* q, const double* mu,
                          const double* f, double qq) noexcept nogil:
    """The natural-map error of reactions ``x`` (no apex shift) with ``u = W x + q``, by
    blocks, in one pass: :func:`_natural_error` without ``per_contact``, the 2-D projection
    written out (``|u_T|`` and ``|x_T|`` need no square root)."""
    cdef Py_ssize_t i
    cdef double total = 0.0, rr = 0.0, uu = 0.0, un, ut, rn, rt, yn, yt, t, a, pn, pt, c
    cdef double scale
    cdef const double* d
    for i in range(B.nc):
        d = B.diag + 4 * i
        rn = x[2 * i]
        rt = x[2 * i + 1]
        un = q[2 * i] + d[0] * rn + d[1] * rt
        ut = q[2 * i + 1] + d[2] * rn + d[3] * rt
        _block_row(B, i, x, &un, &ut)
        c = mu[i]
        yn = rn - un - c * fabs(ut)
        yt = rt - ut
        t = fabs(yt)
        if t <= c * yn and yn >= 0.0:  # inside
            pn = yn
            pt = yt
        else:
            a = max(yn + c * t, 0.0) * f[10 * i + 9]  # 0 in the polar cone
            pn = a
            pt = copysign(c * a, yt) if t > 0.0 else 0.0
        total += (rn - pn) ** 2 + (rt - pt) ** 2
        rr += rn * rn + rt * rt
        uu += un * un + ut * ut
    scale = sqrt(max(qq, max(rr, uu)))
    return sqrt(total) / (scale if scale > 0.0 else 1.0)


cdef inline void _planar_local_factored(const double* a, const double* f, double bn, double bt,
                                        double mu, double rn0, double rt0,
                                        double* out) noexcept nogil:
    """:func:`_planar_local` with the block's divisions done once (:func:`_planar_factors`)."""
    cdef double rn, rt, ut, s
    cdef int side
    if bn >= 0.0:
        out[0] = 0.0
        out[1] = 0.0
        return
    if mu == 0.0:
        if f[4] > 0.0:  # 1 / a00
            out[0] = -bn * f[4]
            out[1] = 0.0
            return
    else:
        if f[8] != 0.0:
            rn = f[0] * bn + f[1] * bt
            rt = f[2] * bn + f[3] * bt
            if rn > 0.0 and (rt if rt >= 0.0 else -rt) <= mu * rn:
                out[0] = rn
                out[1] = rt
                return
        for side in range(2):
            if f[4 + 2 * side] > 0.0:
                s = 1.0 - 2.0 * side
                rn = -bn * f[4 + 2 * side]
                ut = f[5 + 2 * side] * rn + bt
                if s * ut >= 0.0:
                    out[0] = rn
                    out[1] = -s * mu * rn
                    return
    _planar_local(a[0], a[1], a[2], a[3], bn, bt, mu, rn0, rt0, out)  # none holds: its step


cdef void _block_certificate(Small* S, Py_ssize_t d, bint dense, const double* Wd,
                            const Py_ssize_t* ip, const Py_ssize_t* ix, const double* dv,
                            const double* diag, const double* x, Py_ssize_t* loaded,
                            double rtol, double* rd, double* ud, double* md,
                            Py_ssize_t* std) noexcept nogil:
    """The certificate of the reactions ``rd = x - shift`` (written) of the sweeps' point ``x``
    (from the apex), from ``W`` as given: dense ``Wd`` (read over the columns where ``rd`` is
    not zero, in ``loaded``: the other terms are zero exactly) or CSR ``(ip, ix, dv)``. ``S``
    points at the problem (``m``, ``nc``, ``d``, ``q``, ``mu``, ``shift``, ``qq`` and the
    error's settings); ``diag`` holds each contact's ``d x d`` diagonal block. Writes ``ud``,
    ``md`` and ``std`` as :func:`small_certificate` does."""
    cdef Py_ssize_t k, j, p, row, i, count = 0, m = S.m, dd = d * d
    cdef double product = 0.0, w = 0.0, total, magnitude, value, residual, error, size, aa
    cdef double apex, largest, force, carry, slip
    for k in range(m):
        rd[k] = x[k] - S.shift[k]
        if rd[k] != 0.0:
            loaded[count] = k
            count += 1
    for row in range(m):
        total = 0.0
        magnitude = 0.0
        if dense:
            for k in range(count):
                j = loaded[k]
                value = Wd[row * m + j] * rd[j]
                total += value
                magnitude += fabs(value)
        else:
            for p in range(ip[row], ip[row + 1]):
                value = dv[p] * rd[ix[p]]
                total += value
                magnitude += fabs(value)
        ud[row] = total + S.q[row]
        if row % d == 0 or S.mu[row // d] != 0.0:  # the certified rows
            product += magnitude * magnitude
        w = max(w, fabs(diag[dd * (row // d) + (d + 1) * (row % d)]))
    if w == 0.0:
        w = 1.0
    _natural_error(S, rd, ud, &residual, &error)
    md[0] = error
    md[1] = sqrt(product)
    md[2] = sqrt(S.qq)
    size = 0.0
    aa = 0.0
    value = 0.0
    for k in range(m):
        size += rd[k] * rd[k]
        apex = rd[k] + S.shift[k]
        aa += apex * apex
        value += ud[k] * ud[k]
    md[3] = sqrt(max(S.qq, max(size, value)))
    largest = max(max(sqrt(size), sqrt(aa)), max(sqrt(S.qq) / w, sqrt(value) / w))
    force = largest if largest > 0.0 else 1.0
    for i in range(S.nc):
        carry = 0.0
        slip = 0.0
        for k in range(d):
            apex = rd[d * i + k] + S.shift[d * i + k]
            carry += apex * apex
            if k:
                slip += ud[d * i + k] * ud[d * i + k]
        if sqrt(carry) > rtol * force:
            std[i] = 2 if sqrt(slip) > rtol * w * force else 1
        else:
            std[i] = 0


def planar_solve(W, indptr, indices, data, q, mu, shift, r, u, status, measures, double tol,
                 Py_ssize_t max_sweeps, Py_ssize_t first, bint check_blocks, double psd_shift,
                 bint stall_test, bint per_contact, double floor, double rtol):
    """The Gauss-Seidel solve of a 2-D local problem and its certificate, in one call.

    ``W`` is a dense (m, m) array, or, when it has no rows, the CSR arrays
    ``(indptr, indices, data)`` of ``W`` (intp indices) are used; ``q`` (m), ``mu`` (nc),
    ``shift`` (m, the apex shift of
    :attr:`~contactqp.core.local_problem.LocalProblem.apex_shift`, or empty: none), ``r``
    (m: the start in, the reactions out), ``u`` (m, out), ``status`` (nc, intp, out),
    ``measures`` (4, out).

    ``W`` is read once into 2x2 contact blocks (those that hold a nonzero entry). With
    ``check_blocks``, each diagonal block's symmetric part is tested as
    :func:`contactqp.methods.planar.check_contact_blocks` does (with ``psd_shift``); the first
    that fails stops the call with code 3 and its contact as the count. The sweeps are those of
    :func:`planar_gauss_seidel` on the reactions from the apex, ``r + shift``; the natural-map
    error of :func:`~contactqp.core.local_problem.natural_map_residual` (``per_contact``:
    each contact on its own scale too, floored at ``floor`` times the problem's) is evaluated
    at the start when that is zero (``u = q``), after each of the ``first`` sweeps, then when
    the relative change of a sweep, times the ratio of error to change at the last evaluation,
    reaches ``tol``, and at least every ``PLANAR_EVERY`` (10) sweeps and after the last. The
    sweeps stop when it is at most ``tol`` (code 0), with ``stall_test`` when the rate over the
    last ``PLANAR_SPAN`` (20) or more sweeps would not reach ``tol`` within ``max_sweeps``
    (code 1), or after ``max_sweeps`` (code 2).

    Then, from the reactions ``r`` alone and ``W`` as given (a dense one over the columns
    where ``r`` is not zero), the certificate of :func:`small_certificate`: ``u = W r + q``,
    ``measures`` = (natural-map error, ``|| |W| |r| ||`` over the rows the error depends on,
    ``||q||``, ``max(||q||, ||r||, ||u||)``) and ``status`` (open 0, stick 1, slip 2 with
    ``rtol``).
    Returns ``(sweeps, code)``: the index :data:`PLANAR_REASONS`.
    """
    cdef Py_ssize_t sw[2]
    cdef Py_ssize_t sp_[1]
    cdef Py_ssize_t si[1]
    cdef Py_ssize_t sd_[1]
    cdef Py_ssize_t sq[1]
    cdef Py_ssize_t smu[1]
    cdef Py_ssize_t ss[1]
    cdef Py_ssize_t sr[1]
    cdef Py_ssize_t su[1]
    cdef Py_ssize_t sst[1]
    cdef Py_ssize_t sm[1]
    cdef const double* Wd = <const double*> _buffer(W, b'd', 2, sw, False, "W")
    cdef const Py_ssize_t* ip = <const Py_ssize_t*> _buffer(indptr, b'n', 1, sp_, False, "indptr")
    cdef const Py_ssize_t* ix = <const Py_ssize_t*> _buffer(indices, b'n', 1, si, False,
                                                            "indices")
    cdef const double* dv = <const double*> _buffer(data, b'd', 1, sd_, False, "data")
    cdef const double* qd = <const double*> _buffer(q, b'd', 1, sq, False, "q")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 1, smu, False, "mu")
    cdef const double* sh = <const double*> _buffer(shift, b'd', 1, ss, False, "shift")
    cdef double* rd = <double*> _buffer(r, b'd', 1, sr, True, "r")
    cdef double* ud = <double*> _buffer(u, b'd', 1, su, True, "u")
    cdef Py_ssize_t* std = <Py_ssize_t*> _buffer(status, b'n', 1, sst, True, "status")
    cdef double* md = <double*> _buffer(measures, b'd', 1, sm, True, "measures")
    cdef Py_ssize_t m = sq[0], nc = smu[0], most, nb = 0, i, j, k, l, p, s, c
    cdef bint dense = sw[0] > 0 or m == 0  # no contacts: nothing to read either way
    if (m != 2 * nc or (ss[0] != m and ss[0] != 0) or sr[0] != m or su[0] != m
            or sst[0] != nc or sm[0] != 4):
        raise ValueError("inconsistent shapes")
    if dense and (sw[0] != m or sw[1] != m) and m > 0:
        raise ValueError("a dense W must be (m, m)")
    if not dense and (sp_[0] != m + 1 or si[0] < ip[m] or sd_[0] < ip[m]):
        raise ValueError("indptr must have m + 1 entries, indices and data indptr[m]")
    most = nc * nc if dense else (ip[m] if m else 0)
    cdef double* work = <double*> malloc((14 * nc + 4 * most + 6 * m + 1) * sizeof(double))
    cdef Py_ssize_t* index = <Py_ssize_t*> malloc((2 * nc + most + m + 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t* history = <Py_ssize_t*> malloc((max_sweeps + 2) * sizeof(Py_ssize_t))
    cdef double* errors = <double*> malloc((max_sweeps + 2) * sizeof(double))
    if work == NULL or index == NULL or history == NULL or errors == NULL:
        free(work)
        free(index)
        free(history)
        free(errors)
        raise MemoryError()
    cdef Blocks B
    B.nc = nc
    B.diag = work
    B.val = work + 4 * nc
    cdef double* x = B.val + 4 * most  # reactions from the apex
    cdef double* qa = x + m  # q - W shift
    cdef double* react = qa + m  # x - shift
    cdef double* squares = react + m
    cdef double* factors = squares + nc + m  # after the zero shift
    cdef Py_ssize_t kk
    if ss[0] == 0:  # no shift: zeros
        sh = squares + nc
        for kk in range(m):
            (squares + nc)[kk] = 0.0
    B.ptr = index
    B.col = index + nc + 1
    cdef Py_ssize_t* mark = B.col + most
    cdef Py_ssize_t* loaded = mark + nc  # the columns where r is not zero
    cdef Small S
    cdef double bn, bt, a00, a01, a10, a11, coupling, change, size, relative, residual, error
    cdef double out[2]
    cdef double* a
    cdef bint shifted = False, zero = True, check
    cdef Py_ssize_t sweep = 0, code = 2, bad = -1
    cdef Checks C
    C.history, C.errors, C.count, C.last, C.ratio = history, errors, 0, 0, 1.0
    with nogil:
        # W by contact blocks
        for i in range(nc):
            mark[i] = -1
        for i in range(nc):
            B.ptr[i] = nb
            a = B.diag + 4 * i
            a[0] = a[1] = a[2] = a[3] = 0.0
            if dense:
                for j in range(nc):
                    a00 = Wd[2 * i * m + 2 * j]
                    a01 = Wd[2 * i * m + 2 * j + 1]
                    a10 = Wd[(2 * i + 1) * m + 2 * j]
                    a11 = Wd[(2 * i + 1) * m + 2 * j + 1]
                    if j == i:
                        a[0], a[1], a[2], a[3] = a00, a01, a10, a11
                    elif a00 != 0.0 or a01 != 0.0 or a10 != 0.0 or a11 != 0.0:
                        B.col[nb] = j
                        B.val[4 * nb] = a00
                        B.val[4 * nb + 1] = a01
                        B.val[4 * nb + 2] = a10
                        B.val[4 * nb + 3] = a11
                        nb += 1
            else:
                for k in range(2):
                    for p in range(ip[2 * i + k], ip[2 * i + k + 1]):
                        c = ix[p]
                        j = c // 2
                        l = c - 2 * j
                        if j == i:
                            a[2 * k + l] += dv[p]
                            continue
                        s = mark[j]
                        if s < B.ptr[i]:  # no block of j in this row yet
                            s = nb
                            mark[j] = nb
                            B.col[nb] = j
                            B.val[4 * nb] = B.val[4 * nb + 1] = 0.0
                            B.val[4 * nb + 2] = B.val[4 * nb + 3] = 0.0
                            nb += 1
                        B.val[4 * s + 2 * k + l] += dv[p]
        B.ptr[nc] = nb
        if check_blocks:
            for i in range(nc):
                a = B.diag + 4 * i
                coupling = 0.5 * (a[1] + a[2])
                if (a[0] < 0.0 or a[3] < 0.0
                        or coupling * coupling > (1.0 + psd_shift) ** 2 * a[0] * a[3]):
                    bad = i
                    break
    if bad >= 0:
        free(work)
        free(index)
        free(history)
        free(errors)
        return bad, 3
    S.m, S.nc, S.d = m, nc, 2
    S.q, S.mu, S.shift = qd, mud, sh
    S.per_contact = per_contact
    S.floor = floor
    S.squares = squares
    with nogil:
        S.qq = _dot(qd, qd, m)
        for i in range(nc):
            _planar_factors(B.diag + 4 * i, mud[i], factors + 10 * i)
        for k in range(m):
            x[k] = rd[k] + sh[k]
            if sh[k] != 0.0:
                shifted = True
            if x[k] != 0.0:
                zero = False
        if shifted:  # q - W shift
            _block_product(&B, sh, qd, qa)
            for k in range(m):
                qa[k] = 2.0 * qd[k] - qa[k]
        else:
            for k in range(m):
                qa[k] = qd[k]
        check = zero
        relative = 0.0
        while True:
            if check:
                if not shifted and not per_contact:  # the FCLIB error, in one pass
                    error = _planar_error(&B, x, qa, mud, factors, S.qq)
                else:
                    if zero and sweep == 0:
                        for k in range(m):
                            ud[k] = qa[k]
                    else:
                        _block_product(&B, x, qa, ud)
                    for k in range(m):
                        react[k] = x[k] - sh[k]
                    _natural_error(&S, react, ud, &residual, &error)
                code = _judge(&C, sweep, error, relative, tol, max_sweeps, stall_test)
                if code >= 0:
                    break
            elif sweep >= max_sweeps:
                code = 2
                break
            change = 0.0
            size = 0.0
            for i in range(nc):
                a = B.diag + 4 * i
                bn = qa[2 * i]
                bt = qa[2 * i + 1]
                _block_row(&B, i, x, &bn, &bt)
                _planar_local_factored(a, factors + 10 * i, bn, bt, mud[i], x[2 * i],
                                       x[2 * i + 1], out)
                change += (out[0] - x[2 * i]) ** 2 + (out[1] - x[2 * i + 1]) ** 2
                size += out[0] * out[0] + out[1] * out[1]
                x[2 * i] = out[0]
                x[2 * i + 1] = out[1]
            sweep += 1
            size = sqrt(max(size, S.qq))
            relative = sqrt(change) / (size if size > 0.0 else 1.0)
            check = _due(&C, sweep, first, relative, tol, max_sweeps)
        _block_certificate(&S, 2, dense, Wd, ip, ix, dv, B.diag, x, loaded, rtol, rd, ud, md,
                           std)
    free(work)
    free(index)
    free(history)
    free(errors)
    return sweep, code


# ---------------------------------------------------------------------------------------------
# 3-D contacts: Gauss-Seidel sweeps with a local solver by cases, its certificate included.

#: Why :func:`spatial_solve` stopped, by the code it returns (those of :data:`PLANAR_REASONS`).
SPATIAL_REASONS = PLANAR_REASONS
cdef enum:
    _LOCAL_ITERATIONS = 30  # largest Newton run of one contact's slip
cdef double _LOCAL_SHARE = 1e-2  # its target: this share of the sweeps' (at least 1e-15)


cdef struct Blocks3:
    # W by 3x3 contact blocks, as Blocks by 2x2 ones: diag[9 i:9 i + 9] contact i's diagonal
    # block (row-major), the off-diagonal blocks of block row i at slots ptr[i] .. ptr[i + 1] - 1,
    # col[s] their block column and val[9 s:9 s + 9] their entries
    Py_ssize_t nc
    double* diag
    Py_ssize_t* ptr
    Py_ssize_t* col
    double* val


cdef inline void _row3(const Blocks3* B, Py_ssize_t i, const double* x, double* b) noexcept nogil:
    """``b += sum over the off-diagonal blocks of row i of W_ij x_j``."""
    cdef Py_ssize_t s, j
    cdef double b0 = b[0], b1 = b[1], b2 = b[2], x0, x1, x2
    cdef const double* v
    for s in range(B.ptr[i], B.ptr[i + 1]):
        j = B.col[s]
        v = B.val + 9 * s
        x0 = x[3 * j]
        x1 = x[3 * j + 1]
        x2 = x[3 * j + 2]
        b0 += v[0] * x0 + v[1] * x1 + v[2] * x2
        b1 += v[3] * x0 + v[4] * x1 + v[5] * x2
        b2 += v[6] * x0 + v[7] * x1 + v[8] * x2
    b[0] = b0
    b[1] = b1
    b[2] = b2


cdef void _product3(const Blocks3* B, const double* x, const double* q, double* u) noexcept nogil:
    """``u = W x + q`` by blocks."""
    cdef Py_ssize_t i, k
    cdef const double* a
    for i in range(B.nc):
        a = B.diag + 9 * i
        for k in range(3):
            u[3 * i + k] = (q[3 * i + k] + a[3 * k] * x[3 * i] + a[3 * k + 1] * x[3 * i + 1]
                            + a[3 * k + 2] * x[3 * i + 2])
        _row3(B, i, x, u + 3 * i)


cdef void _inverse3(const double* a, double* f) noexcept nogil:
    """``f[0:9]`` the inverse of the 3x3 block ``a`` (row-major), ``f[9]`` 1 when it exists
    (a nonzero determinant), else 0."""
    cdef double det
    f[0] = a[4] * a[8] - a[5] * a[7]
    f[1] = a[2] * a[7] - a[1] * a[8]
    f[2] = a[1] * a[5] - a[2] * a[4]
    f[3] = a[5] * a[6] - a[3] * a[8]
    f[4] = a[0] * a[8] - a[2] * a[6]
    f[5] = a[2] * a[3] - a[0] * a[5]
    f[6] = a[3] * a[7] - a[4] * a[6]
    f[7] = a[1] * a[6] - a[0] * a[7]
    f[8] = a[0] * a[4] - a[1] * a[3]
    det = a[0] * f[0] + a[1] * f[3] + a[2] * f[6]
    if det != 0.0 and isfinite(1.0 / det):
        for k in range(9):
            f[k] /= det
        f[9] = 1.0
    else:
        f[9] = 0.0


cdef enum:
    _SLIP_SAMPLES = 96  # slip directions sampled by _slip3 (its residual has at most 4 roots)


cdef inline double _slip_residual(const double* a, const double* b, double mu, double c,
                                  double s, double* normal, double* speed) noexcept nogil:
    """:func:`_slip3`'s residual at the slip direction ``d = (c, s)``, with the normal reaction
    ``normal`` and the slip speed ``speed`` that the normal law gives there."""
    cdef double g0 = a[0] - mu * (a[1] * c + a[2] * s)
    cdef double g1 = a[3] - mu * (a[4] * c + a[5] * s)
    cdef double g2 = a[6] - mu * (a[7] * c + a[8] * s)
    cdef double along = g1 * c + g2 * s, across = g2 * c - g1 * s
    cdef double b_along = b[1] * c + b[2] * s, b_across = b[2] * c - b[1] * s
    normal[0] = -b[0] / g0 if g0 != 0.0 else -1.0
    speed[0] = normal[0] * along + b_along
    return g0 * b_across - b[0] * across


cdef bint _slip3(const double* a, const double* b, double mu, double* x) noexcept nogil:
    """One contact's slip ``u = a x + b`` exactly, by its direction: ``x`` becomes the slip
    nearest to it, and True, when there is one.

    A slip in the direction ``d = (cos t, sin t)`` has ``x = x_N (1, -mu d)``, ``u_N = 0``
    and ``u_T = lambda d``: given ``t``, the normal row fixes ``x_N`` and ``u_T . d`` gives
    ``lambda``; the slip holds where ``u_T`` has no component across ``d``, which (times the
    normal row's coefficient) is a trigonometric polynomial in ``t`` of degree 2. Its sign changes
    over :data:`_SLIP_SAMPLES` directions are bisected to rounding; a root is a slip when
    ``x_N > 0`` and ``lambda >= 0``. Roots closer than the sampling are missed (then the caller
    keeps its point)."""
    cdef double step = 6.283185307179586 / _SLIP_SAMPLES, low, high, mid, f_low, f_mid
    cdef double normal, speed, best = INFINITY, distance, c, s
    cdef double found[3]
    cdef Py_ssize_t k, n
    f_low = _slip_residual(a, b, mu, 1.0, 0.0, &normal, &speed)
    for k in range(_SLIP_SAMPLES):
        low = k * step
        high = low + step
        f_mid = _slip_residual(a, b, mu, cos(high), sin(high), &normal, &speed)
        if (f_low < 0.0) == (f_mid < 0.0) and f_mid != 0.0:
            f_low = f_mid
            continue
        f_mid, f_low = f_low, f_mid  # f_mid: at low; f_low: at high, for the next interval
        for n in range(60):
            mid = 0.5 * (low + high)
            if mid == low or mid == high:
                break
            if (_slip_residual(a, b, mu, cos(mid), sin(mid), &normal, &speed) < 0.0) == (
                f_mid < 0.0
            ):
                low = mid
            else:
                high = mid
        c = cos(0.5 * (low + high))
        s = sin(0.5 * (low + high))
        _slip_residual(a, b, mu, c, s, &normal, &speed)
        if normal > 0.0 and speed >= 0.0 and isfinite(normal):
            distance = ((normal - x[0]) ** 2 + (mu * normal * c + x[1]) ** 2
                        + (mu * normal * s + x[2]) ** 2)
            if distance < best:
                best = distance
                found[0] = normal
                found[1] = -mu * normal * c
                found[2] = -mu * normal * s
    if best == INFINITY:
        return False
    x[0] = found[0]
    x[1] = found[1]
    x[2] = found[2]
    return True


cdef void _spatial_local(Small* L, const double* a, const double* f, const double* b,
                         const double* mu, const double* zeros, double tol,
                         double* x) noexcept nogil:
    """Contact ``i``'s problem ``u = a x + b`` (its block ``a``, ``f`` = :func:`_inverse3` of
    it, the others' reactions in ``b``, its coefficient ``mu[0]``), solved in place from ``x``,
    by its cases:

    * open, ``x = 0``, when ``b_N >= 0`` (then ``u = b`` is in the dual cone);
    * without friction, ``x = (-b_N / a_NN, 0, 0)``;
    * stick, ``x = -a^-1 b``, when that lies in the cone (``u = 0``);
    * otherwise a slip: coulomb's Newton run on the one-contact problem from ``x``
      (:func:`_run` on ``L``, work arrays of one contact, at most ``_LOCAL_ITERATIONS``
      iterations to the one-contact natural-map error ``tol``), whose best point is kept;
      where it stops short, the slip found by its direction (:func:`_slip3`).
    """
    cdef double r0, r1, r2, error
    cdef Py_ssize_t count
    if b[0] >= 0.0:
        x[0] = x[1] = x[2] = 0.0
        return
    if mu[0] == 0.0:
        if a[0] > 0.0:
            x[0] = -b[0] / a[0]
            x[1] = x[2] = 0.0
        return
    if f[9] != 0.0:
        r0 = -(f[0] * b[0] + f[1] * b[1] + f[2] * b[2])
        r1 = -(f[3] * b[0] + f[4] * b[1] + f[5] * b[2])
        r2 = -(f[6] * b[0] + f[7] * b[1] + f[8] * b[2])
        if r0 > 0.0 and sqrt(r1 * r1 + r2 * r2) <= mu[0] * r0:
            x[0] = r0
            x[1] = r1
            x[2] = r2
            return
    _problem(L, a, b, mu, zeros)
    if _run(L, x, tol, _LOCAL_ITERATIONS, &count, &error) != _CONVERGED:
        _slip3(a, b, mu[0], x)  # Newton stopped short: the slip by its direction


def spatial_solve(W, indptr, indices, data, q, mu, shift, r, u, status, measures, double tol,
                  Py_ssize_t max_sweeps, Py_ssize_t first, bint check_blocks, double psd_shift,
                  bint stall_test, bint per_contact, double floor, double rtol):
    """The Gauss-Seidel solve of a 3-D local problem and its certificate, in one call.

    The arguments, the evaluations of the error, the stopping rules, the codes and the
    certificate are those of :func:`planar_solve`, for 3x3 contact blocks; each contact's
    problem is solved by :func:`_spatial_local` (open, stick or a slip found by a one-contact
    Newton run). With ``check_blocks`` each diagonal block must pass the test of
    :func:`small_semidefinite` (with ``psd_shift``), else code 3 with its contact as the count.
    Returns ``(sweeps, code)``: the index :data:`SPATIAL_REASONS`.
    """
    cdef Py_ssize_t sw[2]
    cdef Py_ssize_t sp_[1]
    cdef Py_ssize_t si[1]
    cdef Py_ssize_t sd_[1]
    cdef Py_ssize_t sq[1]
    cdef Py_ssize_t smu[1]
    cdef Py_ssize_t ss[1]
    cdef Py_ssize_t sr[1]
    cdef Py_ssize_t su[1]
    cdef Py_ssize_t sst[1]
    cdef Py_ssize_t sm[1]
    cdef const double* Wd = <const double*> _buffer(W, b'd', 2, sw, False, "W")
    cdef const Py_ssize_t* ip = <const Py_ssize_t*> _buffer(indptr, b'n', 1, sp_, False, "indptr")
    cdef const Py_ssize_t* ix = <const Py_ssize_t*> _buffer(indices, b'n', 1, si, False,
                                                            "indices")
    cdef const double* dv = <const double*> _buffer(data, b'd', 1, sd_, False, "data")
    cdef const double* qd = <const double*> _buffer(q, b'd', 1, sq, False, "q")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 1, smu, False, "mu")
    cdef const double* sh = <const double*> _buffer(shift, b'd', 1, ss, False, "shift")
    cdef double* rd = <double*> _buffer(r, b'd', 1, sr, True, "r")
    cdef double* ud = <double*> _buffer(u, b'd', 1, su, True, "u")
    cdef Py_ssize_t* std = <Py_ssize_t*> _buffer(status, b'n', 1, sst, True, "status")
    cdef double* md = <double*> _buffer(measures, b'd', 1, sm, True, "measures")
    cdef Py_ssize_t m = sq[0], nc = smu[0], most, nb = 0, i, j, k, l, p, s, c, e
    cdef bint dense = sw[0] > 0 or m == 0
    if (m != 3 * nc or (ss[0] != m and ss[0] != 0) or sr[0] != m or su[0] != m
            or sst[0] != nc or sm[0] != 4):
        raise ValueError("inconsistent shapes")
    if dense and (sw[0] != m or sw[1] != m) and m > 0:
        raise ValueError("a dense W must be (m, m)")
    if not dense and (sp_[0] != m + 1 or si[0] < ip[m] or sd_[0] < ip[m]):
        raise ValueError("indptr must have m + 1 entries, indices and data indptr[m]")
    most = nc * nc if dense else (ip[m] if m else 0)
    cdef double* work = <double*> malloc((30 * nc + 9 * most + 6 * m + 40) * sizeof(double))
    cdef Py_ssize_t* index = <Py_ssize_t*> malloc((2 * nc + most + m + 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t* history = <Py_ssize_t*> malloc((max_sweeps + 2) * sizeof(Py_ssize_t))
    cdef double* errors = <double*> malloc((max_sweeps + 2) * sizeof(double))
    cdef Small L  # one contact's work arrays, for the slips
    cdef double* local = _setup(&L, 3, 1, _LOCAL_ITERATIONS)
    if work == NULL or index == NULL or history == NULL or errors == NULL or local == NULL:
        free(work)
        free(index)
        free(history)
        free(errors)
        free(local)
        if local != NULL:
            free(L.rows)
        raise MemoryError()
    L.per_contact = False
    L.floor = floor
    cdef Blocks3 B
    B.nc = nc
    B.diag = work
    B.val = work + 9 * nc
    cdef double* x = B.val + 9 * most  # reactions from the apex
    cdef double* qa = x + m  # q - W shift
    cdef double* react = qa + m  # x - shift
    cdef double* squares = react + m
    cdef double* zeros = squares + nc  # m + 3 zeros: the shift when none is given
    cdef double* factors = zeros + m + 3  # 10 per contact: the inverse of its block
    cdef double* b = factors + 10 * nc  # 3
    cdef double* scaled = b + 3  # 9 + 3 + 3: the PSD test of one block
    cdef Py_ssize_t kk
    for kk in range(m + 3):
        zeros[kk] = 0.0
    if ss[0] == 0:
        sh = zeros
    B.ptr = index
    B.col = index + nc + 1
    cdef Py_ssize_t* mark = B.col + most
    cdef Py_ssize_t* loaded = mark + nc
    cdef Py_ssize_t keep[3]
    cdef Small S
    cdef double change, size, relative, residual, error, value
    cdef double* a
    cdef double old[3]
    cdef bint shifted = False, zero = True, check
    cdef Py_ssize_t sweep = 0, code = 2, bad = -1
    cdef Checks C
    C.history, C.errors, C.count, C.last, C.ratio = history, errors, 0, 0, 1.0
    cdef double local_tol = max(_LOCAL_SHARE * tol, 1e-15)
    with nogil:
        for i in range(nc):
            mark[i] = -1
        for i in range(nc):  # W by contact blocks
            B.ptr[i] = nb
            a = B.diag + 9 * i
            for e in range(9):
                a[e] = 0.0
            if dense:
                for j in range(nc):
                    c = 0
                    for k in range(3):
                        for l in range(3):
                            if Wd[(3 * i + k) * m + 3 * j + l] != 0.0:
                                c = 1
                    if j == i:
                        for k in range(3):
                            for l in range(3):
                                a[3 * k + l] = Wd[(3 * i + k) * m + 3 * j + l]
                    elif c:
                        B.col[nb] = j
                        for k in range(3):
                            for l in range(3):
                                B.val[9 * nb + 3 * k + l] = Wd[(3 * i + k) * m + 3 * j + l]
                        nb += 1
            else:
                for k in range(3):
                    for p in range(ip[3 * i + k], ip[3 * i + k + 1]):
                        c = ix[p]
                        j = c // 3
                        l = c - 3 * j
                        if j == i:
                            a[3 * k + l] += dv[p]
                            continue
                        s = mark[j]
                        if s < B.ptr[i]:  # no block of j in this row yet
                            s = nb
                            mark[j] = nb
                            B.col[nb] = j
                            for e in range(9):
                                B.val[9 * nb + e] = 0.0
                            nb += 1
                        B.val[9 * s + 3 * k + l] += dv[p]
        B.ptr[nc] = nb
        if check_blocks:
            for i in range(nc):
                if not _semidefinite(B.diag + 9 * i, 3, psd_shift, scaled, scaled + 9, keep):
                    bad = i
                    break
    if bad >= 0:
        free(work)
        free(index)
        free(history)
        free(errors)
        free(local)
        free(L.rows)
        return bad, 3
    S.m, S.nc, S.d = m, nc, 3
    S.q, S.mu, S.shift = qd, mud, sh
    S.per_contact = per_contact
    S.floor = floor
    S.squares = squares
    with nogil:
        S.qq = _dot(qd, qd, m)
        for i in range(nc):
            _inverse3(B.diag + 9 * i, factors + 10 * i)
        for k in range(m):
            x[k] = rd[k] + sh[k]
            if sh[k] != 0.0:
                shifted = True
            if x[k] != 0.0:
                zero = False
        if shifted:  # q - W shift
            _product3(&B, sh, qd, qa)
            for k in range(m):
                qa[k] = 2.0 * qd[k] - qa[k]
        else:
            for k in range(m):
                qa[k] = qd[k]
        check = zero
        relative = 0.0
        while True:
            if check:
                if zero and sweep == 0:
                    for k in range(m):
                        ud[k] = qa[k]
                else:
                    _product3(&B, x, qa, ud)
                for k in range(m):
                    react[k] = x[k] - sh[k]
                _natural_error(&S, react, ud, &residual, &error)
                code = _judge(&C, sweep, error, relative, tol, max_sweeps, stall_test)
                if code >= 0:
                    break
            elif sweep >= max_sweeps:
                code = 2
                break
            change = 0.0
            size = 0.0
            for i in range(nc):
                a = B.diag + 9 * i
                for k in range(3):
                    old[k] = x[3 * i + k]
                    b[k] = qa[3 * i + k]
                _row3(&B, i, x, b)
                _spatial_local(&L, a, factors + 10 * i, b, mud + i, zeros, local_tol,
                               x + 3 * i)
                for k in range(3):
                    value = x[3 * i + k]
                    change += (value - old[k]) ** 2
                    size += value * value
            sweep += 1
            size = sqrt(max(size, S.qq))
            relative = sqrt(change) / (size if size > 0.0 else 1.0)
            check = _due(&C, sweep, first, relative, tol, max_sweeps)
        _block_certificate(&S, 3, dense, Wd, ip, ix, dv, B.diag, x, loaded, rtol, rd, ud, md,
                           std)
    free(work)
    free(index)
    free(history)
    free(errors)
    free(local)
    free(L.rows)
    return sweep, code


# ---------------------------------------------------------------------------------------------
# Small global problems M v = H r + f, u = H^T v + w: the factorisation of M, the condensation
# W = H^T M^-1 H, the Newton runs on the condensed problem and the certificate on the global
# equations as written, in one call (contactqp.methods.global_route.solve_compiled).

__all__ += ["global_small", "GLOBAL_CODES", "GLOBAL_MEASURES"]

#: What :func:`global_small` returns, by code: "solved" (the certificate is in ``measures``),
#: else why the caller must take the general route instead.
GLOBAL_CODES = ("solved", "not handled", "singular M", "not semidefinite", "not converged")
cdef enum:
    _G_SOLVED = 0
    _G_NOT_HANDLED = 1
    _G_SINGULAR = 2
    _G_NOT_PSD = 3
    _G_NOT_CONVERGED = 4

#: The entries of :func:`global_small`'s ``measures``, in order.
GLOBAL_MEASURES = (
    "error", "equilibrium", "rounding", "data", "condition", "local_error", "local_product",
    "local_size_q", "local_scale", "iterations", "groups", "positive_definite",
)
cdef Py_ssize_t _G_MEASURES = 12

ctypedef void (*_getrf_t)(int* m, int* n, double* a, int* lda, int* ipiv,
                          int* info) noexcept nogil
ctypedef void (*_getrs_t)(char* trans, int* n, int* nrhs, double* a, int* lda, int* ipiv,
                          double* b, int* ldb, int* info) noexcept nogil
ctypedef void (*_potrf_t)(char* uplo, int* n, double* a, int* lda, int* info) noexcept nogil
ctypedef void (*_potrs_t)(char* uplo, int* n, int* nrhs, double* a, int* lda, double* b,
                          int* ldb, int* info) noexcept nogil
ctypedef void (*_gecon_t)(char* norm, int* n, double* a, int* lda, double* anorm,
                          double* rcond, double* work, int* iwork, int* info) noexcept nogil

cdef _getrf_t _dgetrf = NULL
cdef _getrs_t _dgetrs = NULL
cdef _potrf_t _dpotrf = NULL
cdef _potrs_t _dpotrs = NULL
cdef _gecon_t _dgecon = NULL
cdef _gecon_t _dpocon = NULL  # the same argument types as gecon's (uplo for norm)
ctypedef void (*_gbtrf_t)(int* m, int* n, int* kl, int* ku, double* ab, int* ldab, int* ipiv,
                          int* info) noexcept nogil
ctypedef void (*_gbtrs_t)(char* trans, int* n, int* kl, int* ku, int* nrhs, double* ab,
                          int* ldab, int* ipiv, double* b, int* ldb, int* info) noexcept nogil
ctypedef void (*_gbcon_t)(char* norm, int* n, int* kl, int* ku, double* ab, int* ldab,
                          int* ipiv, double* anorm, double* rcond, double* work, int* iwork,
                          int* info) noexcept nogil
ctypedef void (*_pbtrf_t)(char* uplo, int* n, int* kd, double* ab, int* ldab,
                          int* info) noexcept nogil
ctypedef void (*_pbtrs_t)(char* uplo, int* n, int* kd, int* nrhs, double* ab, int* ldab,
                          double* b, int* ldb, int* info) noexcept nogil
ctypedef void (*_pbcon_t)(char* uplo, int* n, int* kd, double* ab, int* ldab, double* anorm,
                          double* rcond, double* work, int* iwork, int* info) noexcept nogil
cdef _gbtrf_t _dgbtrf = NULL
cdef _gbtrs_t _dgbtrs = NULL
cdef _gbcon_t _dgbcon = NULL
cdef _pbtrf_t _dpbtrf = NULL
cdef _pbtrs_t _dpbtrs = NULL
cdef _pbcon_t _dpbcon = NULL
cdef double _G_EPS = 2.220446049250313e-16


cdef void* _lapack_function(dict capi, str name) except NULL:
    capsule = capi[name]
    return PyCapsule_GetPointer(capsule, PyCapsule_GetName(capsule))


cdef int _load_lapack() except -1:
    """Point at scipy's LAPACK (:mod:`scipy.linalg.cython_lapack`, read at run time: no build
    dependency on scipy), the library that ``scipy.linalg`` calls."""
    global _dgetrf, _dgetrs, _dpotrf, _dpotrs, _dgecon, _dpocon
    global _dgbtrf, _dgbtrs, _dgbcon, _dpbtrf, _dpbtrs, _dpbcon
    if _dgetrf != NULL:
        return 0
    from scipy.linalg import cython_lapack
    capi = cython_lapack.__pyx_capi__
    _dgetrs = <_getrs_t> _lapack_function(capi, "dgetrs")
    _dpotrf = <_potrf_t> _lapack_function(capi, "dpotrf")
    _dpotrs = <_potrs_t> _lapack_function(capi, "dpotrs")
    _dgecon = <_gecon_t> _lapack_function(capi, "dgecon")
    _dpocon = <_gecon_t> _lapack_function(capi, "dpocon")
    _dgbtrf = <_gbtrf_t> _lapack_function(capi, "dgbtrf")
    _dgbtrs = <_gbtrs_t> _lapack_function(capi, "dgbtrs")
    _dgbcon = <_gbcon_t> _lapack_function(capi, "dgbcon")
    _dpbtrf = <_pbtrf_t> _lapack_function(capi, "dpbtrf")
    _dpbtrs = <_pbtrs_t> _lapack_function(capi, "dpbtrs")
    _dpbcon = <_pbcon_t> _lapack_function(capi, "dpbcon")
    _dgetrf = <_getrf_t> _lapack_function(capi, "dgetrf")
    return 0


cdef struct Mass:
    # an exact factorisation of M (n x n), as contactqp.methods.global_route's factors
    Py_ssize_t n, k  # freedoms; diagonal block size (0: dense)
    double* s  # Jacobi scaling |diag M|^-1/2 (1 on zeros)
    double* inverse  # k > 0: the n / k blocks of M^-1, row-major
    double* factor  # k == 0: Cholesky (upper) or LU factor of S M S, column-major
    int* pivots  # LU pivots (LAPACK's, 1-based)
    bint cholesky
    bint band  # factor in LAPACK's band storage (kl, ku diagonals, leading dimension ld)
    Py_ssize_t kl, ku, ld
    bint positive_definite
    double condition  # 1-norm condition number of S M S (LAPACK's estimate when dense)


cdef inline double _scale_of(double diagonal) noexcept nogil:
    return 1.0 / sqrt(fabs(diagonal)) if diagonal != 0.0 else 1.0


cdef bint _invert(double* a, Py_ssize_t k, double* inv) noexcept nogil:
    """``inv = a^-1`` (row-major k x k) by Gauss-Jordan with partial pivoting (``a`` is
    overwritten); False when a pivot is exactly zero (numpy.linalg.inv's LinAlgError)."""
    cdef Py_ssize_t i, j, c, p
    cdef double big, value, pivot
    for i in range(k):
        for j in range(k):
            inv[i * k + j] = 1.0 if i == j else 0.0
    for c in range(k):
        p = c
        big = fabs(a[c * k + c])
        for i in range(c + 1, k):
            if fabs(a[i * k + c]) > big:
                big = fabs(a[i * k + c])
                p = i
        if a[p * k + c] == 0.0:
            return False
        if p != c:
            for j in range(k):
                value = a[c * k + j]
                a[c * k + j] = a[p * k + j]
                a[p * k + j] = value
                value = inv[c * k + j]
                inv[c * k + j] = inv[p * k + j]
                inv[p * k + j] = value
        pivot = 1.0 / a[c * k + c]
        for j in range(k):
            a[c * k + j] *= pivot
            inv[c * k + j] *= pivot
        for i in range(k):
            if i != c and a[i * k + c] != 0.0:
                value = a[i * k + c]
                for j in range(k):
                    a[i * k + j] -= value * a[c * k + j]
                    inv[i * k + j] -= value * inv[c * k + j]
    return True


cdef bint _cholesky_ok(const double* a, Py_ssize_t k, double* work) noexcept nogil:
    """Whether the symmetric row-major ``a`` (k x k) has a Cholesky factorisation (every
    pivot positive, LAPACK's test)."""
    cdef Py_ssize_t i, j, c
    cdef double value
    for i in range(k * k):
        work[i] = a[i]
    for j in range(k):
        value = work[j * k + j]
        for c in range(j):
            value -= work[j * k + c] * work[j * k + c]
        if not (value > 0.0):
            return False
        value = sqrt(value)
        work[j * k + j] = value
        for i in range(j + 1, k):
            work[i * k + j] = (work[i * k + j] - _dot(work + i * k, work + j * k, j)) / value
    return True


cdef Py_ssize_t _mass_structure(const Py_ssize_t* Mp, const Py_ssize_t* Mi, const double* Mx,
                                Py_ssize_t n, Py_ssize_t max_block) noexcept nogil:
    """The smallest ``k <= max_block`` dividing ``n`` such that the nonzero entries of ``M``
    lie in its diagonal ``k x k`` blocks (1: diagonal), else 0 (global_route.block_size)."""
    cdef Py_ssize_t i, p, j, k, spread = 0
    cdef bint fits
    for i in range(n):
        for p in range(Mp[i], Mp[i + 1]):
            if Mx[p] != 0.0:
                spread = max(spread, i - Mi[p] if i > Mi[p] else Mi[p] - i)
    if spread == 0:
        return 1
    for k in range(max(2, spread + 1), max_block + 1):
        if n % k:
            continue
        fits = True
        for i in range(n):
            for p in range(Mp[i], Mp[i + 1]):
                if Mx[p] != 0.0 and i // k != Mi[p] // k:
                    fits = False
                    break
            if not fits:
                break
        if fits:
            return k
    return 0


cdef int _mass_factor(Mass* F, const Py_ssize_t* Mp, const Py_ssize_t* Mi, const double* Mx,
                      double* work) noexcept nogil:
    """Factor ``M`` as :func:`contactqp.methods.global_route.factor_mass` does (``F.k`` set by
    the caller; arrays allocated by it); ``_G_SOLVED`` or ``_G_SINGULAR``. ``work``: at
    least ``4 n + 2 k^2`` doubles (dense: ``n^2 + 6 n``)."""
    cdef Py_ssize_t n = F.n, k = F.k, i, j, p, b, nb, c
    cdef double value, norm, inverse_norm, column, low, high
    cdef double* block
    cdef double* scaled
    cdef int info, size, one = 1
    cdef int* iwork
    cdef double rcond
    cdef char uplo = b'U'
    cdef char which = b'1'
    F.positive_definite = True
    if k == 1:
        for i in range(n):
            value = 0.0
            for p in range(Mp[i], Mp[i + 1]):
                if Mi[p] == i:
                    value += Mx[p]
            if value == 0.0:
                return _G_SINGULAR
            F.s[i] = _scale_of(value)
            F.inverse[i] = 1.0 / value
            if not (value > 0.0):
                F.positive_definite = False
        F.condition = 1.0
        return _G_SOLVED
    if k > 1:
        nb = n // k
        for i in range(n * k):
            F.inverse[i] = 0.0
        for i in range(n):  # the blocks, row-major, into F.inverse first
            b = i // k
            for p in range(Mp[i], Mp[i + 1]):
                if Mi[p] // k == b:
                    F.inverse[b * k * k + (i % k) * k + Mi[p] % k] += Mx[p]
        for i in range(n):
            F.s[i] = _scale_of(F.inverse[(i // k) * k * k + (i % k) * (k + 1)])
        norm = 0.0
        inverse_norm = 0.0
        scaled = work
        block = work + k * k
        for b in range(nb):
            for i in range(k):
                for j in range(k):
                    scaled[i * k + j] = (F.s[b * k + i] * F.inverse[b * k * k + i * k + j]
                                         * F.s[b * k + j])
                    if F.inverse[b * k * k + i * k + j] != F.inverse[b * k * k + j * k + i]:
                        F.positive_definite = False
            for j in range(k):
                column = 0.0
                for i in range(k):
                    column += fabs(scaled[i * k + j])
                norm = max(norm, column)
            if F.positive_definite and not _cholesky_ok(scaled, k, block):
                F.positive_definite = False
            if not _invert(scaled, k, block):
                return _G_SINGULAR
            for j in range(k):
                column = 0.0
                for i in range(k):
                    column += fabs(block[i * k + j])
                inverse_norm = max(inverse_norm, column)
            for i in range(k):
                for j in range(k):
                    F.inverse[b * k * k + i * k + j] = (F.s[b * k + i] * block[i * k + j]
                                                        * F.s[b * k + j])
        F.condition = norm * inverse_norm
        if not isfinite(F.condition) or F.condition * n * _G_EPS >= 1.0:
            return _G_SINGULAR
        return _G_SOLVED
    # dense: Cholesky of S M S when M is exactly symmetric, else LU with partial pivoting, in
    # LAPACK's band storage when M's nonzeros lie in a narrow band (the same factors: the
    # pivots are looked for among the same rows, the others being zero) and full otherwise
    _dense_factor(F, Mp, Mi, Mx, work)
    if F.condition < 0.0:
        return _G_SINGULAR
    return _G_SOLVED


cdef void _dense_factor(Mass* F, const Py_ssize_t* Mp, const Py_ssize_t* Mi, const double* Mx,
                        double* work) noexcept nogil:
    """The dense branch of :func:`_mass_factor`; ``F.condition`` < 0 when ``M`` is singular.
    ``work``: ``n^2 + 6 n`` doubles."""
    cdef Py_ssize_t n = F.n, i, j, p, kl = 0, ku = 0, kd, ld, row, step
    cdef double value, norm, low, high, rcond
    cdef double* A = work  # M (then S M S) in full or band storage
    cdef double* column_sums = work + n * n
    cdef double* lapack_work = column_sums + n  # 4 n
    cdef int* iwork = <int*> (lapack_work + 4 * n)  # n ints
    cdef int info, size = <int> n, lower, upper, diagonals, lead
    cdef char uplo = b'U'
    cdef char which = b'1'
    F.condition = -1.0
    for i in range(n):
        F.s[i] = 0.0
        column_sums[i] = 0.0
        for p in range(Mp[i], Mp[i + 1]):
            if Mx[p] != 0.0:
                j = Mi[p]
                kl = max(kl, i - j)
                ku = max(ku, j - i)
            if Mi[p] == i:
                F.s[i] += Mx[p]
    for i in range(n):
        F.s[i] = _scale_of(F.s[i])
    F.band = 2 * (2 * kl + ku + 1) <= n
    F.kl, F.ku = kl, ku
    ld = 2 * kl + ku + 1 if F.band else n
    F.ld = ld
    for i in range(ld * n):
        A[i] = 0.0
    for i in range(n):  # A(i, j) at A[i + j n], or at A[kl + ku + i - j + j ld] in a band
        for p in range(Mp[i], Mp[i + 1]):
            if Mx[p] != 0.0:
                j = Mi[p]
                A[(kl + ku + i - j if F.band else i) + j * ld] += Mx[p]
    row = kl + ku if F.band else 0  # A(i, j) = A[row + i - j + j step]
    step = ld if F.band else n + 1
    F.positive_definite = kl == ku
    if F.positive_definite:
        for j in range(n):
            for i in range(max(0, j - ku), j):
                if A[row + i - j + j * step] != A[row + j - i + i * step]:
                    F.positive_definite = False
                    break
            if not F.positive_definite:
                break
    for j in range(n):
        for i in range(max(0, j - ku), min(n, j + kl + 1)):
            value = F.s[i] * A[row + i - j + j * step] * F.s[j]
            A[row + i - j + j * step] = value
            column_sums[j] += fabs(value)
    norm = 0.0
    for j in range(n):
        norm = max(norm, column_sums[j])
    F.cholesky = False
    kd = ku
    if F.positive_definite:
        if F.band:  # the upper triangle, row kd the diagonal
            for j in range(n):
                for i in range(max(0, j - kd), j + 1):
                    F.factor[kd + i - j + j * (kd + 1)] = A[row + i - j + j * step]
            diagonals = <int> kd
            lead = <int> (kd + 1)
            _dpbtrf(&uplo, &size, &diagonals, F.factor, &lead, &info)
        else:
            for i in range(n * n):
                F.factor[i] = A[i]
            _dpotrf(&uplo, &size, F.factor, &size, &info)
        F.cholesky = info == 0
    F.positive_definite = F.cholesky
    if not F.cholesky:
        for i in range(ld * n):
            F.factor[i] = A[i]
        if F.band:
            lower = <int> kl
            upper = <int> ku
            lead = <int> ld
            _dgbtrf(&size, &size, &lower, &upper, F.factor, &lead, F.pivots, &info)
        else:
            _dgetrf(&size, &size, F.factor, &size, F.pivots, &info)
        if info < 0:
            return
    low = INFINITY
    high = 0.0
    for i in range(n):
        if F.cholesky:
            value = F.factor[(kd + i * (kd + 1)) if F.band else i + i * n] ** 2
        else:
            value = fabs(F.factor[(kl + ku + i * ld) if F.band else i + i * n])
        if not isfinite(value):
            return
        low = min(low, value)
        high = max(high, value)
    if low <= n * _G_EPS * high:
        return
    if F.cholesky and F.band:
        _dpbcon(&uplo, &size, &diagonals, F.factor, &lead, &norm, &rcond, lapack_work, iwork,
                &info)
    elif F.cholesky:
        _dpocon(&uplo, &size, F.factor, &size, &norm, &rcond, lapack_work, iwork, &info)
    elif F.band:
        _dgbcon(&which, &size, &lower, &upper, F.factor, &lead, F.pivots, &norm, &rcond,
                lapack_work, iwork, &info)
    else:
        _dgecon(&which, &size, F.factor, &size, &norm, &rcond, lapack_work, iwork, &info)
    F.condition = 1.0 / rcond if rcond > 0.0 else INFINITY


cdef void _mass_solve(const Mass* F, double* x, Py_ssize_t nrhs, double* work) noexcept nogil:
    """``x = M^-1 x`` in place, ``x`` column-major n x nrhs; ``work``: n doubles."""
    cdef Py_ssize_t n = F.n, k = F.k, c, b, i, j
    cdef double value
    cdef int size = <int> n, count = <int> nrhs, info
    cdef char uplo = b'U'
    cdef char trans = b'N'
    cdef double* column
    if k > 0:
        for c in range(nrhs):
            column = x + c * n
            if k == 1:
                for i in range(n):
                    column[i] *= F.inverse[i]
                continue
            for b in range(n // k):
                for i in range(k):
                    value = 0.0
                    for j in range(k):
                        value += F.inverse[b * k * k + i * k + j] * column[b * k + j]
                    work[i] = value
                for i in range(k):
                    column[b * k + i] = work[i]
        return
    for c in range(nrhs):
        for i in range(n):
            x[c * n + i] *= F.s[i]
    cdef int lower = <int> F.kl, upper = <int> F.ku, lead = <int> F.ld
    cdef int diagonals = <int> F.ku, lead_cholesky = <int> (F.ku + 1)
    if F.cholesky and F.band:
        _dpbtrs(&uplo, &size, &diagonals, &count, F.factor, &lead_cholesky, x, &size, &info)
    elif F.cholesky:
        _dpotrs(&uplo, &size, &count, F.factor, &size, x, &size, &info)
    elif F.band:
        _dgbtrs(&trans, &size, &lower, &upper, &count, F.factor, &lead, F.pivots, x, &size,
                &info)
    else:
        _dgetrs(&trans, &size, &count, F.factor, &size, F.pivots, x, &size, &info)
    for c in range(nrhs):
        for i in range(n):
            x[c * n + i] *= F.s[i]


cdef Py_ssize_t _root(Py_ssize_t* parent, Py_ssize_t i) noexcept nogil:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


cdef void _join(Py_ssize_t* parent, Py_ssize_t i, Py_ssize_t j) noexcept nogil:
    """Put the groups of contacts ``i`` and ``j`` together (the smaller root stays)."""
    i = _root(parent, i)
    j = _root(parent, j)
    if i != j:
        parent[max(i, j)] = min(i, j)


cdef void _group_by_blocks(Py_ssize_t* parent, const Py_ssize_t* Hp, const Py_ssize_t* Hi,
                           Py_ssize_t n, Py_ssize_t k, Py_ssize_t d, Py_ssize_t nc) noexcept nogil:
    """Join the contacts that ``H`` puts on one ``k x k`` block of a block-diagonal ``M``
    (``W = H^T M^-1 H`` is zero between the others)."""
    cdef Py_ssize_t i, b, p, first
    for i in range(nc):
        parent[i] = i
    for b in range(n // k):
        first = -1
        for i in range(b * k, b * k + k):
            for p in range(Hp[i], Hp[i + 1]):
                if first < 0:
                    first = Hi[p] // d
                else:
                    _join(parent, first, Hi[p] // d)


cdef void _group_by_entries(Py_ssize_t* parent, const double* W, Py_ssize_t m, Py_ssize_t d,
                            Py_ssize_t nc) noexcept nogil:
    """Join the contacts that a nonzero entry of the dense row-major ``W`` couples."""
    cdef Py_ssize_t i, a, b
    for i in range(nc):
        parent[i] = i
    for a in range(m):
        for b in range(m):
            if W[a * m + b] != 0.0 and a // d != b // d:
                _join(parent, a // d, b // d)


cdef inline double* _group_row(double* packed, const Py_ssize_t* parent,
                               const Py_ssize_t* start, const Py_ssize_t* offset,
                               const Py_ssize_t* place, Py_ssize_t d, Py_ssize_t a) noexcept nogil:
    """Row of unknown ``a`` in its group's block of the packed ``W`` (:func:`_group_layout`)."""
    cdef Py_ssize_t root = parent[a // d]
    return packed + offset[root] + place[a] * (start[root + 1] - start[root]) * d


cdef inline double _group_product(double* packed, const Py_ssize_t* parent,
                                  const Py_ssize_t* start, const Py_ssize_t* offset,
                                  const Py_ssize_t* place, const Py_ssize_t* members,
                                  Py_ssize_t d, Py_ssize_t a, const double* r,
                                  double* magnitude) noexcept nogil:
    """``(W r)_a`` over the columns of ``a``'s group (``W`` is zero elsewhere), and
    ``(|W| |r|)_a`` in ``magnitude``."""
    cdef Py_ssize_t root = parent[a // d], p, j, c
    cdef const double* row = _group_row(packed, parent, start, offset, place, d, a)
    cdef double value = 0.0, size = 0.0, entry
    for p in range(start[root], start[root + 1]):
        j = members[p] * d
        for c in range(d):
            entry = row[(p - start[root]) * d + c]
            value += entry * r[j + c]
            size += fabs(entry) * fabs(r[j + c])
    magnitude[0] = size
    return value


cdef Py_ssize_t _group_layout(Py_ssize_t* parent, Py_ssize_t* start, Py_ssize_t* members,
                              Py_ssize_t* cursor, Py_ssize_t* offset, Py_ssize_t* place,
                              Py_ssize_t nc, Py_ssize_t d, Py_ssize_t* groups,
                              Py_ssize_t* widest) noexcept nogil:
    """Each contact's root in ``parent``, each group's contacts (in increasing order) in
    ``members[start[root]:start[root + 1]]``, and where the group's block of ``W`` (its
    unknowns in that order, row-major) starts in the packed array: ``offset[root]``; ``place``
    gives each unknown's row in its block. Returns the packed array's size; ``groups`` and
    ``widest`` (the most unknowns of a group) are written."""
    cdef Py_ssize_t i, c, p, width, packed = 0
    groups[0] = 0
    widest[0] = 0
    for i in range(nc):
        parent[i] = _root(parent, i)
        if parent[i] == i:
            groups[0] += 1
    for i in range(nc + 1):
        start[i] = 0
    for i in range(nc):
        start[parent[i] + 1] += 1
    for i in range(nc):
        start[i + 1] += start[i]
    for i in range(nc):
        cursor[i] = start[i]
    for i in range(nc):
        members[cursor[parent[i]]] = i
        cursor[parent[i]] += 1
    for i in range(nc):
        if parent[i] != i:
            continue
        width = (start[i + 1] - start[i]) * d
        widest[0] = max(widest[0], width)
        offset[i] = packed
        packed += width * width
        for p in range(start[i], start[i + 1]):
            for c in range(d):
                place[members[p] * d + c] = (p - start[i]) * d + c
    return packed


cdef const void* _int_view(object array, str name, Py_ssize_t* size, int* itemsize) except NULL:
    """The data of a C-contiguous 1-D array of 32- or 64-bit ints (scipy's index arrays are
    either), its length written to ``size`` and its item size to ``itemsize``; the buffer is
    released at once (the caller holds the array for the call)."""
    cdef Py_buffer view
    PyObject_GetBuffer(array, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT)
    cdef char code = 0
    cdef const void* data = view.buf
    if view.format != NULL:
        code = view.format[0]
        if code == b'@' or code == b'=' or code == b'<':
            code = view.format[1]
    cdef bint ok = view.ndim == 1 and (
        (view.itemsize == 4 and code == b'i')
        or (view.itemsize == 8 and (code == b'q' or code == b'l' or code == b'n'))
    )
    if ok:
        size[0] = view.shape[0]
        itemsize[0] = <int> view.itemsize
    PyBuffer_Release(&view)
    if not ok:
        raise ValueError(f"{name} must be a C-contiguous 1-D array of 32- or 64-bit ints")
    return data if data != NULL else <const void*> size


cdef void _copy_ints(const void* source, int itemsize, Py_ssize_t n,
                     Py_ssize_t* target) noexcept nogil:
    cdef Py_ssize_t i
    if itemsize == 4:
        for i in range(n):
            target[i] = (<const int*> source)[i]
    else:
        for i in range(n):
            target[i] = (<const int64_t*> source)[i]


cdef int _condense(const Mass* F, const Py_ssize_t* Hp, const Py_ssize_t* Hi, const double* Hx,
                   const double* f, const double* w, Py_ssize_t m, Py_ssize_t d, double* W,
                   Py_ssize_t n_w, const Py_ssize_t* parent, const Py_ssize_t* start,
                   const Py_ssize_t* offset, const Py_ssize_t* place, double* q, double* B,
                   double* work) noexcept nogil:
    """``W = H^T M^-1 H`` and ``q = H^T M^-1 f + w``; ``B``: n (m + 1) doubles (dense M) or
    n. A dense ``M`` gives ``W`` dense (row-major m x m, ``n_w = m^2``); a block-diagonal one
    gives the blocks of the groups of :func:`_group_by_blocks` only, packed as
    :func:`_group_layout` lays them out (``n_w`` numbers; W is zero elsewhere).
    ``_G_SINGULAR`` when ``q`` is not finite (``W``'s entries are checked by the caller)."""
    cdef Py_ssize_t n = F.n, k = F.k, i, i1, i2, p1, p2, b, a
    cdef double value
    cdef const double* inverse
    cdef double* row
    for i in range(n_w):
        W[i] = 0.0
    for i in range(m):
        q[i] = 0.0
    if k == 0:
        for i in range(n * (m + 1)):
            B[i] = 0.0
        for i in range(n):
            for p1 in range(Hp[i], Hp[i + 1]):
                B[i + Hi[p1] * n] += Hx[p1]
            B[i + m * n] = f[i]
        _mass_solve(F, B, m + 1, work)
        for i in range(n):
            for p1 in range(Hp[i], Hp[i + 1]):
                a = Hi[p1]
                value = Hx[p1]
                for b in range(m):
                    W[a * m + b] += value * B[i + b * n]
                q[a] += value * B[i + m * n]
    else:
        for b in range(n // k):
            inverse = F.inverse + b * k * k
            for i1 in range(b * k, b * k + k):
                for p1 in range(Hp[i1], Hp[i1 + 1]):
                    row = _group_row(W, parent, start, offset, place, d, Hi[p1])
                    for i2 in range(b * k, b * k + k):
                        value = Hx[p1] * inverse[(i1 - b * k) * k + i2 - b * k]
                        for p2 in range(Hp[i2], Hp[i2 + 1]):
                            row[place[Hi[p2]]] += value * Hx[p2]
        for i in range(n):
            B[i] = f[i]
        _mass_solve(F, B, 1, work)
        for i in range(n):
            for p1 in range(Hp[i], Hp[i + 1]):
                q[Hi[p1]] += Hx[p1] * B[i]
    for i in range(m):
        q[i] += w[i]
        if not isfinite(q[i]):
            return _G_SINGULAR
    return _G_SOLVED


def global_small(M_indptr, M_indices, M_data, H_indptr, H_indices, H_data, f, w, mu, r,
                 double tol, Py_ssize_t max_iter, bint per_contact, double floor,
                 bint check_psd, double psd_shift, digits, double rtol, bint solve,
                 Py_ssize_t max_unknowns, Py_ssize_t max_dense, Py_ssize_t max_block,
                 Py_ssize_t max_group, u, v, status, measures):
    """A small global problem ``M v = H r + f``, ``u = H^T v + w`` solved and certified in C.

    ``M`` (n x n) and ``H`` (n x m) in compressed rows (int64 ``indptr``, ``indices``; float64
    ``data``), ``mu`` (nc,), ``m = d nc``. ``M`` is factored as
    :func:`contactqp.methods.global_route.factor_mass` does: block diagonal (blocks of at most
    ``max_block``, inverted exactly) or, up to ``max_dense`` freedoms, dense (LAPACK: Cholesky
    of the Jacobi-scaled ``M`` when it is exactly symmetric, else LU). The contacts fall into
    the groups that ``W = H^T M^-1 H`` couples: with a dense ``M`` (then ``m <= max_unknowns``)
    those of its nonzero entries, ``W`` formed dense; with a block-diagonal one those that ``H``
    puts on one block, found before ``M`` is factored, and only the groups' blocks of ``W`` are
    formed (at most ``max(max_unknowns**2, m max_group)`` numbers in all).
    ``q = H^T M^-1 f + w``. With ``solve`` every group must have at most ``max_group``
    unknowns, and each group is solved from ``r`` by coulomb's first Newton run (that of
    :func:`small_newton`, to ``tol`` for one group, else ``tol / sqrt(3)``, which bounds the
    whole problem's error by ``tol``; but once a group's own error is below the
    regularisation's cap, its steps are regularised by its residual on the whole problem's
    scale, as one run on the whole problem would regularise them), after the semidefiniteness
    test of
    :func:`small_semidefinite` on each group's ``W`` (``check_psd``, unless ``M`` was found
    symmetric positive definite). ``r`` receives the reactions.

    The certificate of ``r`` is that of
    :meth:`~contactqp.core.local_problem.GlobalProblem.certify`: ``v`` solves ``M v = H r + f``,
    ``u = H^T v + w``, ``measures`` the figures named by :data:`GLOBAL_MEASURES` (``digits``:
    the relative roundings of ``M``, ``H``, ``f``, ``w``), ``status`` the open / stick / slip
    code of each contact by the rule of
    :func:`~contactqp.core.local_problem.contact_status_unchecked` (``rtol``) on the condensed
    problem. Returns the index of :data:`GLOBAL_CODES`: 0 when all this was done, else why not
    (the structure or sizes are not the small route's, ``M`` is singular, a group's ``W``
    fails the test, a Newton run did not converge); the outputs are then not to be read, but
    for "not converged": ``r`` then holds the reactions of the groups whose runs converged (the
    others' are left as given), ``status`` is -1 on the contacts of the groups whose runs
    stopped short (0 elsewhere), and ``measures`` holds the iterations (the most of the
    converged groups') and the number of groups.
    """
    cdef Py_ssize_t smp[1]
    cdef Py_ssize_t smi[1]
    cdef Py_ssize_t smx[1]
    cdef Py_ssize_t shp[1]
    cdef Py_ssize_t shi[1]
    cdef Py_ssize_t shx[1]
    cdef Py_ssize_t sf[1]
    cdef Py_ssize_t sw[1]
    cdef Py_ssize_t smu[1]
    cdef Py_ssize_t sr[1]
    cdef Py_ssize_t sdg[1]
    cdef Py_ssize_t su[1]
    cdef Py_ssize_t sv[1]
    cdef Py_ssize_t sst[1]
    cdef Py_ssize_t sme[1]
    cdef int imp, imi, ihp, ihi
    cdef const void* vmp = _int_view(M_indptr, "M_indptr", smp, &imp)
    cdef const void* vmi = _int_view(M_indices, "M_indices", smi, &imi)
    cdef const void* vhp = _int_view(H_indptr, "H_indptr", shp, &ihp)
    cdef const void* vhi = _int_view(H_indices, "H_indices", shi, &ihi)
    cdef const double* Mx = <const double*> _buffer(M_data, b'd', 1, smx, False, "M_data")
    cdef const double* Hx = <const double*> _buffer(H_data, b'd', 1, shx, False, "H_data")
    cdef const double* fd = <const double*> _buffer(f, b'd', 1, sf, False, "f")
    cdef const double* wd = <const double*> _buffer(w, b'd', 1, sw, False, "w")
    cdef const double* mud = <const double*> _buffer(mu, b'd', 1, smu, False, "mu")
    cdef double* rd = <double*> _buffer(r, b'd', 1, sr, True, "r")
    cdef const double* dg = <const double*> _buffer(digits, b'd', 1, sdg, False, "digits")
    cdef double* ud = <double*> _buffer(u, b'd', 1, su, True, "u")
    cdef double* vd = <double*> _buffer(v, b'd', 1, sv, True, "v")
    cdef Py_ssize_t* std = <Py_ssize_t*> _buffer(status, b'n', 1, sst, True, "status")
    cdef double* md = <double*> _buffer(measures, b'd', 1, sme, True, "measures")
    cdef Py_ssize_t n = sf[0], m = sw[0], nc = smu[0], d, i
    if smp[0] != n + 1 or shp[0] != n + 1 or sv[0] != n:
        raise ValueError("M_indptr and H_indptr must have n + 1 entries and v n, n = len(f)")
    if sr[0] != m or su[0] != m or sst[0] != nc or sme[0] != _G_MEASURES or sdg[0] != 4:
        raise ValueError("inconsistent shapes")
    cdef Py_ssize_t* indices = <Py_ssize_t*> malloc(
        (smp[0] + smi[0] + shp[0] + shi[0] + 1) * sizeof(Py_ssize_t)
    )
    if indices == NULL:
        raise MemoryError()
    cdef Py_ssize_t* Mp = indices
    cdef Py_ssize_t* Mi = Mp + smp[0]
    cdef Py_ssize_t* Hp = Mi + smi[0]
    cdef Py_ssize_t* Hi = Hp + shp[0]
    _copy_ints(vmp, imp, smp[0], Mp)
    _copy_ints(vmi, imi, smi[0], Mi)
    _copy_ints(vhp, ihp, shp[0], Hp)
    _copy_ints(vhi, ihi, shi[0], Hi)
    try:
        return _global_small(
            Mp, Mi, Mx, Hp, Hi, Hx, fd, wd, mud, rd, tol, max_iter, per_contact, floor,
            check_psd, psd_shift, dg, rtol, solve, max_unknowns, max_dense, max_block,
            max_group, ud, vd, std, md, n, m, nc, smi[0], smx[0], shi[0], shx[0]
        )
    finally:
        free(indices)


cdef int _global_small(
    const Py_ssize_t* Mp, const Py_ssize_t* Mi, const double* Mx, const Py_ssize_t* Hp,
    const Py_ssize_t* Hi, const double* Hx, const double* fd, const double* wd,
    const double* mud, double* rd, double tol, Py_ssize_t max_iter, bint per_contact,
    double floor, bint check_psd, double psd_shift, const double* dg, double rtol, bint solve,
    Py_ssize_t max_unknowns, Py_ssize_t max_dense, Py_ssize_t max_block, Py_ssize_t max_group,
    double* ud, double* vd, Py_ssize_t* std, double* md, Py_ssize_t n, Py_ssize_t m,
    Py_ssize_t nc, Py_ssize_t n_mi, Py_ssize_t n_mx, Py_ssize_t n_hi, Py_ssize_t n_hx,
) except -2:
    """:func:`global_small` on its arrays' data (the index arrays as Py_ssize_t)."""
    cdef Py_ssize_t d, i
    if n_mi != n_mx or n_mi < Mp[n] or n_hi != n_hx or n_hi < Hp[n] or Mp[0] != 0 or Hp[0] != 0:
        raise ValueError("indices and data must hold indptr[-1] entries")
    for i in range(n):
        if Mp[i] > Mp[i + 1] or Hp[i] > Hp[i + 1]:
            raise ValueError("indptr must not decrease")
    for i in range(Mp[n]):
        if Mi[i] < 0 or Mi[i] >= n:
            raise ValueError("M_indices out of range")
    for i in range(Hp[n]):
        if Hi[i] < 0 or Hi[i] >= m:
            raise ValueError("H_indices out of range")
    if n == 0 or nc == 0:
        return _G_NOT_HANDLED
    d = m // nc
    if d * nc != m:
        raise ValueError(f"{m} unknowns do not make rows of {nc} contacts")
    _check_dimension(d)
    _load_lapack()
    cdef Mass F
    F.n = n
    F.k = _mass_structure(Mp, Mi, Mx, n, max_block)
    if F.k == 0 and (n > max_dense or m > max_unknowns):
        return _G_NOT_HANDLED
    cdef Py_ssize_t k = F.k, g = max_group
    # the groups of contacts that W couples, and where each group's block of W is kept
    cdef Py_ssize_t* index = <Py_ssize_t*> malloc((5 * nc + 1 + g + m) * sizeof(Py_ssize_t))
    if index == NULL:
        raise MemoryError()
    cdef Py_ssize_t* parent = index
    cdef Py_ssize_t* start = index + nc  # nc + 1
    cdef Py_ssize_t* members = start + nc + 1
    cdef Py_ssize_t* keep = members + nc  # g
    cdef Py_ssize_t* cursor = keep + g  # nc
    cdef Py_ssize_t* offset = cursor + nc  # nc
    cdef Py_ssize_t* place = offset + nc  # m
    cdef Py_ssize_t groups = 0, widest = 0, packed = 0
    if k > 0:  # with a block-diagonal M, from H alone: W is formed on the groups' blocks only
        _group_by_blocks(parent, Hp, Hi, n, k, d, nc)
        packed = _group_layout(parent, start, members, cursor, offset, place, nc, d, &groups,
                               &widest)
        if (solve and widest > g) or packed > max(max_unknowns * max_unknowns, m * g):
            free(index)
            return _G_NOT_HANDLED
    cdef Py_ssize_t n_w = m * m if k == 0 else packed
    cdef Py_ssize_t n_work = n * n + 6 * n if k == 0 else 4 * n + 2 * k * k
    cdef Py_ssize_t n_b = n * (m + 1) if k == 0 else n
    cdef Py_ssize_t total = (n + (n * n if k == 0 else n * k) + n_work + n_w + m + n_b
                             + 5 * n + 3 * m + 3 * g * g + 4 * g + nc)
    cdef double* block = <double*> malloc(total * sizeof(double))
    cdef int* pivots = <int*> malloc((n + 1) * sizeof(int))
    if block == NULL or pivots == NULL:
        free(block)
        free(index)
        free(pivots)
        raise MemoryError()
    F.s = block
    F.inverse = block + n
    F.factor = F.inverse
    F.pivots = pivots
    cdef double* work = F.inverse + (n * n if k == 0 else n * k)
    cdef double* W = work + n_work  # dense (M dense) or the groups' blocks (block diagonal)
    cdef double* Wg = W if k > 0 else NULL  # the groups' blocks, packed
    cdef double* q = W + n_w
    cdef double* B = q + m
    cdef double* Hr = B + n_b
    cdef double* Mv = Hr + n
    cdef double* zeros = Mv + n  # m: the apex shift of every contact (no cohesion)
    cdef double* ul = zeros + m
    cdef double* transport = ul + m
    cdef double* Wc = transport + m  # g * g
    cdef double* Sc = Wc + g * g  # 2 g * g
    cdef double* qc = Sc + 2 * g * g
    cdef double* rc = qc + g
    cdef double* scaling = rc + g
    cdef double* muc = scaling + g  # g (of at most g contacts)
    cdef double* squares = muc + g  # nc
    cdef double* v_scaled = squares + nc  # n
    cdef double* forcing = v_scaled + n  # n
    cdef double* row
    cdef int code = _G_SOLVED, reason
    cdef Py_ssize_t a, c, p, j, mg, ncg, iterations = 0, count, root
    cdef double tol_group, value, error, residual, eq, sizes, product, magnitude, rr, uu, qq
    cdef double size_h, size_y, transported, scale, largest, force, wdiag, carry, slip
    cdef double rel_m = dg[0], rel_h = dg[1], rel_f = dg[2], rel_w = dg[3], data = 0.0
    cdef double sm, shr, sf2, whole_qq = 0.0, whole_rr = 0.0, whole_uu = 0.0
    cdef double group_qq, group_rr, group_uu
    cdef Small S
    cdef Small L
    cdef double* work_newton
    try:
        with nogil:
            for i in range(m):
                zeros[i] = 0.0
            code = _mass_factor(&F, Mp, Mi, Mx, work)
            if code == _G_SOLVED:
                code = _condense(&F, Hp, Hi, Hx, fd, wd, m, d, W, n_w, parent, start, offset,
                                 place, q, B, work)
            if code == _G_SOLVED and k == 0:
                # with a dense M, the groups are those of W's nonzero entries; their blocks
                # are copied out of the dense W, packed
                _group_by_entries(parent, W, m, d, nc)
                packed = _group_layout(parent, start, members, cursor, offset, place, nc, d,
                                       &groups, &widest)
                if solve and widest > g:
                    code = _G_NOT_HANDLED
                else:
                    Wg = <double*> malloc(packed * sizeof(double))
                    if Wg == NULL:
                        code = -1
                    else:
                        for a in range(m):
                            root = parent[a // d]
                            row = _group_row(Wg, parent, start, offset, place, d, a)
                            for p in range(start[root], start[root + 1]):
                                j = members[p] * d
                                for c in range(d):
                                    row[(p - start[root]) * d + c] = W[a * m + j + c]
            if code == _G_SOLVED:
                for i in range(packed):  # W is zero outside its groups' blocks: the rest finite?
                    if not isfinite(Wg[i]):
                        code = _G_SINGULAR
                        break
            if code == _G_SOLVED and solve:
                tol_group = tol if groups == 1 else tol / sqrt(3.0)
                for i in range(nc):
                    std[i] = 0  # -1: a contact of a group whose Newton run stopped short
                for a in range(m):  # the whole problem's sizes at the start, u = W r + q
                    ul[a] = _group_product(Wg, parent, start, offset, place, members, d, a, rd,
                                           &magnitude) + q[a]
                    whole_qq += q[a] * q[a]
                    whole_rr += rd[a] * rd[a]
                    whole_uu += ul[a] * ul[a]
                for root in range(nc):
                    if parent[root] != root:
                        continue
                    ncg = start[root + 1] - start[root]
                    mg = ncg * d
                    for a in range(mg * mg):
                        Wc[a] = Wg[offset[root] + a]
                    group_qq = 0.0
                    group_rr = 0.0
                    group_uu = 0.0
                    for a in range(mg):
                        i = members[start[root] + a // d] * d + a % d
                        qc[a] = q[i]
                        rc[a] = rd[i]
                        group_qq += q[i] * q[i]
                        group_rr += rd[i] * rd[i]
                        group_uu += ul[i] * ul[i]
                    for a in range(ncg):
                        muc[a] = mud[members[start[root] + a]]
                    if check_psd and not F.positive_definite and not _semidefinite(
                        Wc, mg, psd_shift, Sc, scaling, keep
                    ):
                        code = _G_NOT_PSD
                        break
                    work_newton = _setup(&S, mg, ncg, max_iter)
                    if work_newton == NULL:
                        code = -1
                        break
                    S.per_contact = per_contact
                    S.floor = floor
                    _problem(&S, Wc, qc, muc, zeros)
                    S.grouped = groups > 1
                    S.rest_qq = max(whole_qq - group_qq, 0.0)
                    S.rest_rr = max(whole_rr - group_rr, 0.0)  # the groups solved before at
                    S.rest_uu = max(whole_uu - group_uu, 0.0)  # their answers, the rest as given
                    reason = _run(&S, rc, tol_group, max_iter, &count, &error)
                    free(work_newton)
                    free(S.rows)
                    if reason == _CONVERGED:
                        iterations = max(iterations, count)
                        whole_rr += S.rr - group_rr
                        whole_uu += S.uu - group_uu
                        for a in range(mg):
                            rd[members[start[root] + a // d] * d + a % d] = rc[a]
                    else:  # the other groups are still solved; the caller takes this one on
                        code = _G_NOT_CONVERGED
                        for a in range(ncg):
                            std[members[start[root] + a]] = -1
                if code == _G_NOT_CONVERGED:
                    md[9] = <double> iterations
                    md[10] = <double> groups
            if code == _G_SOLVED:
                L.m, L.nc, L.d = m, nc, d
                L.q, L.mu, L.shift, L.squares = q, mud, zeros, squares
                L.floor = floor
                L.qq = _dot(q, q, m)
                qq = L.qq
                # the condensed problem's certificate (the route's local message)
                product = 0.0
                wdiag = 0.0
                for a in range(m):
                    ul[a] = _group_product(Wg, parent, start, offset, place, members, d, a, rd,
                                           &magnitude) + q[a]
                    if a % d == 0 or mud[a // d] != 0.0:
                        product += magnitude * magnitude
                    row = _group_row(Wg, parent, start, offset, place, d, a)
                    wdiag = max(wdiag, fabs(row[place[a]]))
                L.per_contact = per_contact
                _natural_error(&L, rd, ul, &residual, &error)
                md[5] = error
                md[6] = sqrt(product)
                md[7] = sqrt(qq)
                rr = _dot(rd, rd, m)
                md[8] = sqrt(max(qq, max(rr, _dot(ul, ul, m))))
                # the global certificate: v solves M v = H r + f, u = H^T v + w
                for i in range(n):
                    value = 0.0
                    magnitude = 0.0
                    for p in range(Hp[i], Hp[i + 1]):
                        value += Hx[p] * rd[Hi[p]]
                        magnitude += fabs(Hx[p]) * fabs(rd[Hi[p]])
                    Hr[i] = value
                    forcing[i] = rel_h * magnitude + rel_f * fabs(fd[i])
                    vd[i] = value + fd[i]
                _mass_solve(&F, vd, 1, work)
                sm = 0.0
                shr = 0.0
                sf2 = 0.0
                eq = 0.0
                size_h = 0.0
                size_y = 0.0
                for i in range(n):
                    value = 0.0
                    magnitude = 0.0
                    for p in range(Mp[i], Mp[i + 1]):
                        value += Mx[p] * vd[Mi[p]]
                        magnitude += fabs(Mx[p]) * fabs(vd[Mi[p]])
                    forcing[i] += rel_m * magnitude
                    sm += (F.s[i] * value) ** 2
                    shr += (F.s[i] * Hr[i]) ** 2
                    sf2 += (F.s[i] * fd[i]) ** 2
                    eq += (F.s[i] * (value - Hr[i] - fd[i])) ** 2
                    size_y += (vd[i] / F.s[i]) ** 2
                    for p in range(Hp[i], Hp[i + 1]):
                        size_h += (F.s[i] * Hx[p]) ** 2
                sizes = sqrt(max(sm, max(shr, sf2)))
                md[1] = sqrt(eq) / (sizes if sizes > 0.0 else 1.0)
                for a in range(m):
                    ud[a] = 0.0
                    transport[a] = 0.0
                for i in range(n):
                    for p in range(Hp[i], Hp[i + 1]):
                        ud[Hi[p]] += Hx[p] * vd[i]
                        transport[Hi[p]] += fabs(Hx[p]) * fabs(vd[i])
                for a in range(m):
                    ud[a] += wd[a]
                L.per_contact = False
                _natural_error(&L, rd, ud, &residual, &error)
                md[0] = error
                uu = _dot(ud, ud, m)
                scale = sqrt(max(qq, max(rr, uu)))
                if scale == 0.0:
                    scale = 1.0
                transported = sqrt(_dot(transport, transport, m)) + sqrt(_dot(wd, wd, m))
                md[2] = (F.condition * _G_EPS * sqrt(size_h) * sqrt(size_y)
                         + _G_EPS * transported) / scale
                if rel_m != 0.0 or rel_h != 0.0 or rel_f != 0.0 or rel_w != 0.0:
                    _mass_solve(&F, forcing, 1, work)
                    for a in range(m):
                        ul[a] = 0.0
                    for i in range(n):
                        for p in range(Hp[i], Hp[i + 1]):
                            ul[Hi[p]] += Hx[p] * forcing[i]
                    data = (sqrt(_dot(ul, ul, m))
                            + rel_h * sqrt(_dot(transport, transport, m))
                            + rel_w * sqrt(_dot(wd, wd, m))) / scale
                md[3] = data
                md[4] = F.condition
                md[9] = <double> iterations
                md[10] = <double> groups
                md[11] = 1.0 if F.positive_definite else 0.0
                # status, on the condensed problem (contact_status_unchecked)
                if wdiag == 0.0:
                    wdiag = 1.0
                largest = max(sqrt(rr), max(sqrt(qq) / wdiag, sqrt(uu) / wdiag))
                force = largest if largest > 0.0 else 1.0
                for i in range(nc):
                    carry = 0.0
                    slip = 0.0
                    for c in range(d):
                        carry += rd[i * d + c] ** 2
                        if c:
                            slip += ud[i * d + c] ** 2
                    if sqrt(carry) > rtol * force:
                        std[i] = 2 if sqrt(slip) > rtol * wdiag * force else 1
                    else:
                        std[i] = 0
    finally:
        if k == 0:
            free(Wg)
        free(block)
        free(index)
        free(pivots)
    if code == -1:
        raise MemoryError()
    return code
