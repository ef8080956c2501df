"""Influence coefficients of a linear elastic half-space: normal, tangential and coupling.

A point force ``F`` normal to the surface of an isotropic linear elastic half-space (Young's
modulus ``E``, Poisson's ratio ``nu``) displaces the surface, at a distance ``r`` from the force,
by the Boussinesq value

.. math::

    w(r) = \\frac{1 - \\nu^2}{\\pi E} \\frac{F}{r}

along the force. A uniform pressure ``p`` on a rectangle displaces a surface point ``(X, Y)``
(relative to the rectangle's centre) by the integral of this kernel over the rectangle, which Love
(1929) gave in closed form [Love1929]_:

.. math::

    w(X, Y) = \\frac{(1 - \\nu^2)\\, p}{\\pi E} \\sum_{\\pm,\\pm} \\pm \\Phi(X \\pm a, Y \\pm b),
    \\qquad
    \\Phi(u, v) = u \\operatorname{asinh}\\frac{v}{|u|} + v \\operatorname{asinh}\\frac{u}{|v|},

with ``2a x 2b`` the rectangle and ``Phi`` a primitive of the kernel
(``d^2 Phi / du dv = 1 / sqrt(u^2 + v^2)``); the four corners carry the signs
``Phi(X+a, Y+b) - Phi(X-a, Y+b) - Phi(X+a, Y-b) + Phi(X-a, Y-b)``.

Discretising the contact zone into rectangular cells carrying uniform pressure and collocating at
the cell centres gives a symmetric flexibility matrix for the total force of each cell. Both the
displacement and the force are measured along the same axis (the outward normal of the
half-space, say): a force pulling the surface out lifts it, a force pressing in sinks it, and the
matrix entries are positive.

A point force ``Q`` tangential to the surface (along x) displaces the surface by Cerruti's
solution ([Johnson1985]_, eq. 2.19 at z = 0; G = E / (2 (1 + nu)) the shear modulus):

.. math::

    u_x = \\frac{Q}{2 \\pi G}
          \\left(\\frac{1 - \\nu}{\\rho} + \\frac{\\nu x^2}{\\rho^3}\\right), \\quad
    u_y = \\frac{Q}{2 \\pi G} \\frac{\\nu x y}{\\rho^3}, \\quad
    u_z = -\\frac{(1 - 2\\nu) Q}{4 \\pi G} \\frac{x}{\\rho^2},

with ``z`` the outward normal (the surface sinks ahead of the force), and a normal force ``F``
(outward) moves the surface radially by ``(1 - 2 nu) F / (4 pi G rho)`` away from it (Boussinesq);
the two coupling terms are reciprocal, so the 3 x 3 per cell flexibility is symmetric. Each kernel
is homogeneous of degree -1 and has an elementary primitive ``d^2 F / du dv = f`` (see
:func:`influence_matrix`), which gives the uniform-traction rectangle in closed form.

References
----------
.. [Love1929] A. E. H. Love, "The stress produced in a semi-infinite solid by pressure on part of
   the boundary", Phil. Trans. R. Soc. London A 228, 377-420, 1929.
.. [Johnson1985] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, ch. 3.
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike

from ..core.model import true_or_false
from ..errors import InvalidInputError

__all__ = ["grid", "influence_matrix", "normal_influence", "rectangle_potential"]

#: Rows of the influence matrix computed at once (bounds the temporary memory, not the result).
_BLOCK_ROWS = 256
#: Relative tolerance for recognising cell centres on a regular lattice of pitch ``dx, dy``.
_LATTICE_RTOL = 1e-9


def _finite_float(value, name: str, expected: str) -> float:
    """``value`` as a finite float, or an InvalidInputError naming ``name`` and what is expected."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = np.nan
    if not np.isfinite(number):
        raise InvalidInputError(f"{name} must be {expected}, got {value!r}")
    return number


def _positive_length(value, name: str) -> float:
    expected = "a positive finite length in m"
    number = _finite_float(value, name, expected)
    if not number > 0.0:
        raise InvalidInputError(f"{name} must be {expected}, got {value!r}")
    return number


def _material(young, poisson) -> tuple[float, float]:
    E = _finite_float(young, "young", "a positive finite modulus in Pa")
    if not E > 0.0:
        raise InvalidInputError(f"young must be a positive finite modulus in Pa, got {young!r}")
    nu = _finite_float(poisson, "poisson", "a finite number in (-1, 0.5)")
    if not -1.0 < nu < 0.5:
        raise InvalidInputError(f"poisson must be a finite number in (-1, 0.5), got {poisson!r}")
    return E, nu


def _centres(x, y) -> tuple[np.ndarray, np.ndarray]:
    try:
        xs = np.asarray(x, dtype=float)
        ys = np.asarray(y, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(
            "x and y must be 1-D arrays of cell centres (m), as numbers"
        ) from None
    if xs.ndim != 1 or xs.size == 0:
        raise InvalidInputError(
            f"x must be a non-empty 1-D array of cell centres (m), got shape {xs.shape}"
        )
    if ys.shape != xs.shape:
        raise InvalidInputError(f"y must have the shape of x {xs.shape}, got shape {ys.shape}")
    if not np.all(np.isfinite(xs)):
        raise InvalidInputError(f"x contains NaN or inf (shape {xs.shape})")
    if not np.all(np.isfinite(ys)):
        raise InvalidInputError(f"y contains NaN or inf (shape {ys.shape})")
    return xs, ys


def rectangle_potential(u: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Primitive of the Boussinesq kernel, ``d^2 Phi / du dv = 1 / sqrt(u^2 + v^2)``.

    .. math::

        \\Phi(u, v) = u \\operatorname{asinh}\\frac{v}{|u|} + v \\operatorname{asinh}\\frac{u}{|v|},
        \\qquad \\Phi(0, v) = \\Phi(u, 0) = 0

    Parameters
    ----------
    u, v : array_like
        Coordinates (m), broadcast together.

    Returns
    -------
    ndarray
        ``Phi`` (m); odd in ``u`` and in ``v``. The integral of ``1 / r`` over the rectangle
        ``[u1, u2] x [v1, v2]`` (m) is ``Phi(u2, v2) - Phi(u1, v2) - Phi(u2, v1) + Phi(u1, v1)``.
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    au = np.abs(u)
    av = np.abs(v)
    # u * asinh(v / |u|) -> 0 as u -> 0 (like u log|u|); dividing by 1 there keeps it finite.
    first = u * np.arcsinh(v / np.where(au > 0.0, au, 1.0))
    second = v * np.arcsinh(u / np.where(av > 0.0, av, 1.0))
    return first + second


def _rectangle_integral(X, Y, half_x: float, half_y: float) -> np.ndarray:
    """Integral (m) of ``1 / r`` over ``|xi| <= half_x, |eta| <= half_y``, seen from ``(X, Y)``.

    ``X`` and ``Y`` should be non-negative (the integral is even in each): then the largest corner
    terms are formed from the same operands in every call, and the result is exactly symmetric.
    """
    phi = rectangle_potential
    return (
        phi(X + half_x, Y + half_y)
        - phi(X - half_x, Y + half_y)
        - phi(X + half_x, Y - half_y)
        + phi(X - half_x, Y - half_y)
    )


def _lattice_indices(coordinate: np.ndarray, pitch: float):
    """Integer indices of ``coordinate`` on a lattice of spacing ``pitch``, or None if off it."""
    steps = (coordinate - coordinate.min()) / pitch
    indices = np.rint(steps)
    tolerance = _LATTICE_RTOL * max(1.0, float(indices.max()))
    if np.max(np.abs(steps - indices), initial=0.0) > tolerance:
        return None
    return indices.astype(np.int64)


def _overlap_message(i: int, j: int, xs, ys) -> str:
    return (
        f"x, y: cells {i} and {j} overlap (centres ({xs[i]:.6g}, {ys[i]:.6g}) and "
        f"({xs[j]:.6g}, {ys[j]:.6g}) m are closer than one cell dx, dy)"
    )


def normal_influence(
    x: ArrayLike, y: ArrayLike, dx: float, dy: float, young: float, poisson: float
) -> np.ndarray:
    """Normal flexibility matrix of an elastic half-space discretised into uniformly loaded cells.

    Entry ``(i, j)`` is the normal surface displacement (m) at the centre of cell ``i`` caused by
    a unit total force (1 N) spread uniformly, as a pressure ``1 / (dx dy)`` (Pa), over cell
    ``j`` (Love's closed form of the Boussinesq solution integrated over a rectangle):

    .. math::

        R_{ij} = \\frac{1 - \\nu^2}{\\pi E\\, dx\\, dy}
            \\iint_{\\text{cell } j}
            \\frac{d\\xi\\, d\\eta}{\\sqrt{(x_i - \\xi)^2 + (y_i - \\eta)^2}}

    Displacements and forces are measured along the same normal axis, so ``U = R P`` with ``R``
    symmetric and positive definite. For a distant cell ``R_ij`` tends to the point-load value
    ``(1 - nu^2) / (pi E r_ij)``; the diagonal is
    ``(2 (1 - nu^2) / (pi E)) (asinh(dy/dx) / dy + asinh(dx/dy) / dx)``.

    Parameters
    ----------
    x, y : array_like, shape (n,)
        Cell centres (m). All cells have the same size ``dx`` by ``dy`` and must not overlap;
        centres on a regular lattice of pitch ``dx, dy`` (as from :func:`grid`) take a faster
        path that evaluates each distinct offset once.
    dx, dy : float
        Cell size along x and y (m), > 0.
    young : float
        Young's modulus ``E`` of the half-space (Pa), > 0.
    poisson : float
        Poisson's ratio ``nu``, in (-1, 0.5).

    Returns
    -------
    ndarray, shape (n, n)
        Flexibility ``R`` (m/N) for the total force of each cell.

    Raises
    ------
    InvalidInputError
        An argument is non-finite, out of range, of the wrong shape, or two cells overlap.

    Notes
    -----
    For a rigid obstacle on the half-space the combined modulus is ``E* = E / (1 - nu^2)``; two
    elastic half-spaces in contact are modelled by the sum of their two matrices (same grid).
    The displacement is evaluated at cell centres only; a pressure varying within a cell is
    represented by its mean, which bounds the accuracy by the cell size.

    References
    ----------
    .. [1] A. E. H. Love, Phil. Trans. R. Soc. London A 228, 377-420, 1929.
    .. [2] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, ch. 3.

    Examples
    --------
    >>> from contactqp.compliance import grid, normal_influence
    >>> x, y = grid(4, 4, 1e-4, 1e-4)
    >>> R = normal_influence(x, y, 1e-4, 1e-4, young=210e9, poisson=0.3)
    >>> R.shape
    (16, 16)
    """
    xs, ys = _centres(x, y)
    dx = _positive_length(dx, "dx")
    dy = _positive_length(dy, "dy")
    E, nu = _material(young, poisson)
    result = np.empty((xs.size, xs.size))
    for rows, (integral,), _, _ in _pairwise(
        xs, ys, dx, dy, lambda X, Y: (_normal_kernel(X, Y, dx, dy, E, nu),), signs=False
    ):
        result[rows] = integral
    return result


def _normal_kernel(X, Y, dx: float, dy: float, E: float, nu: float) -> np.ndarray:
    """The entries of :func:`normal_influence` (m/N) at offsets ``(X, Y) >= 0`` of the centres."""
    scale = (1.0 - nu * nu) / (np.pi * E * dx * dy)
    return scale * _rectangle_integral(X, Y, 0.5 * dx, 0.5 * dy)


def _pairwise(xs, ys, dx, dy, evaluate, signs: bool = True):
    """Evaluate kernels of the offsets ``|x_i - x_j|, |y_i - y_j|`` between cells, by row blocks.

    ``evaluate(X, Y)`` (X, Y >= 0, broadcast) returns a tuple of arrays. Yields
    ``(rows, values, sign_x, sign_y)``: a slice of rows ``i``, the tuple evaluated for those rows
    against every cell ``j`` (each array of shape (rows, n)), and the signs of ``x_i - x_j`` and
    ``y_i - y_j`` (for the kernels odd in an offset; None when ``signs`` is False). Centres on a
    regular lattice of pitch ``dx, dy`` evaluate each distinct offset once (a table gathered by
    a flat index, which keeps ``value(i, j) == value(j, i)`` exactly); other arrangements
    evaluate every pair.

    Raises
    ------
    InvalidInputError
        Two cells overlap.
    """
    n = xs.size
    ix, iy = _lattice_indices(xs, dx), _lattice_indices(ys, dy)
    if ix is not None and iy is not None:
        keys = ix * (int(iy.max()) + 1) + iy
        unique, first, counts = np.unique(keys, return_index=True, return_counts=True)
        if unique.size < n:
            i = int(first[np.argmax(counts > 1)])
            j = int(np.flatnonzero(keys == keys[i])[1])
            raise InvalidInputError(_overlap_message(i, j, xs, ys))
        # One evaluation per distinct offset: (max ix + 1) x (max iy + 1) tables.
        offsets_x = np.arange(int(ix.max()) + 1) * dx
        offsets_y = np.arange(int(iy.max()) + 1) * dy
        tables = [table.ravel() for table in evaluate(offsets_x[:, None], offsets_y[None, :])]
        width = offsets_y.size
        index_type = np.int32 if tables[0].size < 2**31 else np.int64
        ix, iy = ix.astype(index_type), iy.astype(index_type)
        for start in range(0, n, _BLOCK_ROWS):
            stop = min(start + _BLOCK_ROWS, n)
            steps_x = ix[start:stop, None] - ix[None, :]
            steps_y = iy[start:stop, None] - iy[None, :]
            # Flat gather (much faster than 2-D fancy indexing): k = |dix| * width + |diy|.
            flat_index = np.abs(steps_x)
            flat_index *= index_type(width)
            flat_index += np.abs(steps_y)
            yield (
                slice(start, stop),
                tuple(np.take(table, flat_index) for table in tables),
                np.sign(steps_x) if signs else None,
                np.sign(steps_y) if signs else None,
            )
        return

    overlap_x, overlap_y = dx * (1.0 - 1e-9), dy * (1.0 - 1e-9)
    for start in range(0, n, _BLOCK_ROWS):
        stop = min(start + _BLOCK_ROWS, n)
        X = xs[start:stop, None] - xs[None, :]
        Y = ys[start:stop, None] - ys[None, :]
        overlapping = (np.abs(X) < overlap_x) & (np.abs(Y) < overlap_y)
        overlapping[np.arange(stop - start), np.arange(start, stop)] = False
        if overlapping.any():
            i, j = np.argwhere(overlapping)[0]
            raise InvalidInputError(_overlap_message(int(i) + start, int(j), xs, ys))
        yield (
            slice(start, stop),
            evaluate(np.abs(X), np.abs(Y)),
            np.sign(X) if signs else None,
            np.sign(Y) if signs else None,
        )


def _cerruti_integrals(X, Y, half_x: float, half_y: float):
    """Integrals (m) of the degree -1 kernels over a ``2 half_x`` by ``2 half_y`` rectangle.

    Seen from ``(X, Y) >= 0`` relative to the centre, with ``(u, v)`` the offset from a source
    point and ``rho = sqrt(u^2 + v^2)``, returns the integrals of ``1 / rho``, ``u^2 / rho^3``,
    ``v^2 / rho^3``, ``u v / rho^3``, ``u / rho^2`` and ``v / rho^2``, from the primitives

    .. math::

        \\frac{u^2}{\\rho^3}: v \\operatorname{asinh}\\frac{u}{|v|}, \\quad
        \\frac{v^2}{\\rho^3}: u \\operatorname{asinh}\\frac{v}{|u|}, \\quad
        \\frac{u v}{\\rho^3}: -\\rho, \\quad
        \\frac{u}{\\rho^2}: \\tfrac12 v \\ln \\rho^2 + u \\arctan\\frac{v}{u}

    (``v / rho^2`` by exchanging ``u`` and ``v``), each evaluated at the four corners like
    :func:`rectangle_potential`. The last three are odd in the offsets: multiply by the signs.
    """

    def corners(primitive):
        return (
            primitive(X + half_x, Y + half_y)
            - primitive(X - half_x, Y + half_y)
            - primitive(X + half_x, Y - half_y)
            + primitive(X - half_x, Y - half_y)
        )

    def asinh_term(u, v):  # v asinh(u / |v|), 0 on v = 0
        av = np.abs(v)
        return v * np.arcsinh(u / np.where(av > 0.0, av, 1.0))

    def log_term(u, v):  # 1/2 v ln(u^2 + v^2) + u atan(v / u), 0 on u = 0 and at the origin
        rho2 = u * u + v * v
        half_log = 0.5 * v * np.log(np.where(rho2 > 0.0, rho2, 1.0))
        return half_log + u * np.arctan(v / np.where(u != 0.0, u, 1.0))

    xx = corners(asinh_term)
    yy = corners(lambda u, v: asinh_term(v, u))
    return (
        xx + yy,
        xx,
        yy,
        corners(lambda u, v: -np.hypot(u, v)),
        corners(log_term),
        corners(lambda u, v: log_term(v, u)),
    )


def _cell_kernels(X, Y, dx: float, dy: float, E: float, nu: float, coupling: bool):
    """The six distinct entries of :func:`influence_matrix` at offsets ``(X, Y) >= 0``.

    Returns ``(R_xx, R_yy, R_xy, R_zz, R_xz, R_yz)`` (m/N) for a unit force on a ``dx`` by
    ``dy`` cell, seen from the offset ``(X, Y)`` of the centres (target minus source); the
    last three are odd in the offsets: multiply ``R_xy`` by the signs of both, ``R_xz`` by the
    sign of ``X`` and ``R_yz`` by that of ``Y`` (``R_zx = -R_xz``, ``R_zy = -R_yz``).
    """
    c = (1.0 + nu) / (np.pi * E * dx * dy)
    coupling_scale = 0.5 * c * (1.0 - 2.0 * nu) if coupling else 0.0
    half_x, half_y = 0.5 * dx, 0.5 * dy
    one, xx, yy, xy, along_x, along_y = _cerruti_integrals(X, Y, half_x, half_y)
    return (
        c * ((1.0 - nu) * one + nu * xx),
        c * ((1.0 - nu) * one + nu * yy),
        c * nu * xy,
        _normal_kernel(X, Y, dx, dy, E, nu),
        coupling_scale * along_x,
        coupling_scale * along_y,
    )


def influence_matrix(
    x: ArrayLike,
    y: ArrayLike,
    dx: float,
    dy: float,
    young: float,
    poisson: float,
    coupling: bool = True,
) -> np.ndarray:
    """Full (3 per cell) flexibility of an elastic half-space under uniform cell tractions.

    Entry ``(3 i + a, 3 j + b)`` is the displacement (m) along axis ``a`` of the centre of cell
    ``i`` caused by a unit total force (1 N) along axis ``b`` spread uniformly over cell ``j``;
    axes ``0, 1, 2 = x, y, z``, with ``z`` the outward normal of the half-space (the sign
    convention of :func:`normal_influence`, whose matrix is the ``z, z`` part). With
    ``c = (1 + nu) / (pi E dx dy) = 1 / (2 pi G dx dy)`` and the rectangle integrals
    ``I[f] = iint_cell j f(x_i - xi, y_i - eta) dxi deta`` (``rho`` the distance):

    .. math::

        R_{xx} = c \\left((1 - \\nu) I[\\tfrac1\\rho] + \\nu I[\\tfrac{x^2}{\\rho^3}]\\right),\\quad
        R_{xy} = c\\, \\nu I[\\tfrac{x y}{\\rho^3}],\\quad
        R_{zz} = c (1 - \\nu) I[\\tfrac1\\rho],\\quad
        R_{xz} = -R_{zx} = c\\, \\frac{1 - 2\\nu}{2} I[\\tfrac{x}{\\rho^2}],

    ``R_yy``, ``R_yz`` likewise. The tangential entries integrate Cerruti's point-force solution,
    the coupling ones Boussinesq's radial displacement and its reciprocal; both are in closed
    form (elementary primitives, see the module notes). ``R`` is symmetric.

    Parameters
    ----------
    x, y : array_like, shape (n,)
        Cell centres (m); equal, non-overlapping cells (see :func:`normal_influence`).
    dx, dy : float
        Cell size (m), > 0.
    young : float
        Young's modulus ``E`` (Pa), > 0.
    poisson : float
        Poisson's ratio ``nu``, in (-1, 0.5).
    coupling : bool
        False drops the normal-tangential coupling (the ``(1 - 2 nu)`` terms), as for two
        elastically similar bodies in contact, where the terms of the two bodies cancel.

    Returns
    -------
    ndarray, shape (3 n, 3 n)
        Flexibility ``R`` (m/N), rows and columns ordered cell by cell ``(x, y, z)``.

    Raises
    ------
    InvalidInputError
        An argument is non-finite, out of range, of the wrong shape, or two cells overlap.

    Notes
    -----
    The coupling vanishes for an incompressible half-space (``nu = 1/2``) and for identical
    bodies. For a distant cell the entries tend to the point-force values.

    References
    ----------
    .. [1] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, §2.2, §3.6-3.7.
    .. [2] J. J. Kalker, *Three-dimensional elastic bodies in rolling contact*, Kluwer, 1990.

    Examples
    --------
    >>> from contactqp.compliance import grid, influence_matrix
    >>> x, y = grid(3, 3, 1e-4, 1e-4)
    >>> influence_matrix(x, y, 1e-4, 1e-4, young=210e9, poisson=0.3).shape
    (27, 27)
    """
    xs, ys = _centres(x, y)
    dx = _positive_length(dx, "dx")
    dy = _positive_length(dy, "dy")
    E, nu = _material(young, poisson)
    coupling = true_or_false(coupling, "coupling")

    def evaluate(X, Y):
        return _cell_kernels(X, Y, dx, dy, E, nu, coupling)

    n = xs.size
    result = np.empty((3 * n, 3 * n))
    for rows, (rxx, ryy, rxy, rzz, rxz, ryz), sign_x, sign_y in _pairwise(xs, ys, dx, dy, evaluate):
        block = result[3 * rows.start : 3 * rows.stop].reshape(rows.stop - rows.start, 3, n, 3)
        block[:, 0, :, 0] = rxx
        block[:, 1, :, 1] = ryy
        block[:, 0, :, 1] = block[:, 1, :, 0] = sign_x * sign_y * rxy
        block[:, 2, :, 2] = rzz
        block[:, 0, :, 2] = sign_x * rxz
        block[:, 2, :, 0] = -block[:, 0, :, 2]
        block[:, 1, :, 2] = sign_y * ryz
        block[:, 2, :, 1] = -block[:, 1, :, 2]
    return result


def grid(nx: int, ny: int, dx: float, dy: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres of an ``nx`` by ``ny`` grid of ``dx`` by ``dy`` cells, centred on the origin.

    Parameters
    ----------
    nx, ny : int
        Cells along x and along y, >= 1.
    dx, dy : float
        Cell size (m), > 0.

    Returns
    -------
    x, y : ndarray, shape (nx * ny,)
        Cell centres (m), x varying fastest: cell ``k = j * nx + i`` is at
        ``((i - (nx - 1) / 2) dx, (j - (ny - 1) / 2) dy)``.

    Raises
    ------
    InvalidInputError
        A count is not a positive integer, or a size is not a positive finite length.
    """
    counts: list[int] = []
    for name, value in (("nx", nx), ("ny", ny)):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
            raise InvalidInputError(f"{name} must be a positive integer, got {value!r}")
        counts.append(int(value))
    dx = _positive_length(dx, "dx")
    dy = _positive_length(dy, "dy")
    nx, ny = counts
    along_x = (np.arange(nx) - 0.5 * (nx - 1)) * dx
    along_y = (np.arange(ny) - 0.5 * (ny - 1)) * dy
    X, Y = np.meshgrid(along_x, along_y, indexing="xy")
    return X.ravel(), Y.ravel()
