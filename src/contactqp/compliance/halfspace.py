"""Normal influence coefficients of a linear elastic half-space.

A point force ``F`` normal to the surface of an isotropic linear elastic half-space (Young's
modulus ``E``, Poisson's ratio ``nu``) displaces the surface, at a distance ``r`` from the force,
by the Boussinesq value

.. math::

    w(r) = \\frac{1 - \\nu^2}{\\pi E} \\frac{F}{r}

along the force. A uniform pressure ``p`` on a rectangle displaces a surface point ``(X, Y)``
(relative to the rectangle's centre) by the integral of this kernel over the rectangle, which Love
(1929) gave in closed form:

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

References
----------
.. [Love1929] A. E. H. Love, "The stress produced in a semi-infinite solid by pressure on part of
   the boundary", Phil. Trans. R. Soc. London A 228, 377-420, 1929.
.. [Johnson1985] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, ch. 3.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..errors import InvalidInputError

__all__ = ["grid", "normal_influence", "rectangle_potential"]

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
    xs = np.asarray(x, dtype=float)
    ys = np.asarray(y, dtype=float)
    if xs.ndim != 1 or xs.size == 0:
        raise InvalidInputError(
            f"x must be a non-empty 1-D array of cell centres (m), got shape {xs.shape}")
    if ys.shape != xs.shape:
        raise InvalidInputError(f"y must have the shape of x {xs.shape}, got shape {ys.shape}")
    if not np.all(np.isfinite(xs)):
        raise InvalidInputError(f"x contains NaN or inf (shape {xs.shape})")
    if not np.all(np.isfinite(ys)):
        raise InvalidInputError(f"y contains NaN or inf (shape {ys.shape})")
    return xs, ys


def rectangle_potential(u, v) -> np.ndarray:
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
    return (phi(X + half_x, Y + half_y) - phi(X - half_x, Y + half_y)
            - phi(X + half_x, Y - half_y) + phi(X - half_x, Y - half_y))


def _lattice_indices(coordinate: np.ndarray, pitch: float):
    """Integer indices of ``coordinate`` on a lattice of spacing ``pitch``, or None if off it."""
    steps = (coordinate - coordinate.min()) / pitch
    indices = np.rint(steps)
    tolerance = _LATTICE_RTOL * max(1.0, float(indices.max()))
    if np.max(np.abs(steps - indices), initial=0.0) > tolerance:
        return None
    return indices.astype(np.int64)


def _overlap_message(i: int, j: int, xs, ys) -> str:
    return (f"x, y: cells {i} and {j} overlap (centres ({xs[i]:.6g}, {ys[i]:.6g}) and "
            f"({xs[j]:.6g}, {ys[j]:.6g}) m are closer than one cell dx, dy)")


def normal_influence(x, y, dx, dy, young, poisson) -> np.ndarray:
    """Normal flexibility matrix of an elastic half-space discretised into uniformly loaded cells.

    Entry ``(i, j)`` is the normal surface displacement (m) at the centre of cell ``i`` caused by
    a unit total force (1 N) spread uniformly, as a pressure ``1 / (dx dy)`` (Pa), over cell
    ``j`` (Love's closed form of the Boussinesq solution integrated over a rectangle):

    .. math::

        R_{ij} = \\frac{1 - \\nu^2}{\\pi E\\, dx\\, dy}
            \\iint_{\\text{cell } j} \\frac{d\\xi\\, d\\eta}{\\sqrt{(x_i - \\xi)^2 + (y_i - \\eta)^2}}

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
    scale = (1.0 - nu * nu) / (np.pi * E * dx * dy)
    half_x, half_y = 0.5 * dx, 0.5 * dy
    n = xs.size
    result = np.empty((n, n))

    ix, iy = _lattice_indices(xs, dx), _lattice_indices(ys, dy)
    if ix is not None and iy is not None:
        keys = ix * (int(iy.max()) + 1) + iy
        unique, first, counts = np.unique(keys, return_index=True, return_counts=True)
        if unique.size < n:
            i = int(first[np.argmax(counts > 1)])
            j = int(np.flatnonzero(keys == keys[i])[1])
            raise InvalidInputError(_overlap_message(i, j, xs, ys))
        # One evaluation per distinct offset: a (max ix + 1) x (max iy + 1) table.
        offsets_x = np.arange(int(ix.max()) + 1) * dx
        offsets_y = np.arange(int(iy.max()) + 1) * dy
        table = scale * _rectangle_integral(offsets_x[:, None], offsets_y[None, :], half_x, half_y)
        flat = table.ravel()
        index_type = np.int32 if flat.size < 2**31 else np.int64
        ix, iy = ix.astype(index_type), iy.astype(index_type)
        width = index_type(table.shape[1])
        for start in range(0, n, _BLOCK_ROWS):
            stop = min(start + _BLOCK_ROWS, n)
            # Flat gather (much faster than 2-D fancy indexing): k = |dix| * width + |diy|.
            flat_index = np.abs(ix[start:stop, None] - ix[None, :])
            flat_index *= width
            flat_index += np.abs(iy[start:stop, None] - iy[None, :])
            np.take(flat, flat_index, out=result[start:stop])
        return result

    overlap_x, overlap_y = dx * (1.0 - 1e-9), dy * (1.0 - 1e-9)
    for start in range(0, n, _BLOCK_ROWS):
        stop = min(start + _BLOCK_ROWS, n)
        X = np.abs(xs[start:stop, None] - xs[None, :])
        Y = np.abs(ys[start:stop, None] - ys[None, :])
        overlapping = (X < overlap_x) & (Y < overlap_y)
        overlapping[np.arange(stop - start), np.arange(start, stop)] = False
        if overlapping.any():
            i, j = np.argwhere(overlapping)[0]
            raise InvalidInputError(_overlap_message(int(i) + start, int(j), xs, ys))
        result[start:stop] = scale * _rectangle_integral(X, Y, half_x, half_y)
    return result


def grid(nx, ny, dx, dy) -> tuple[np.ndarray, np.ndarray]:
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
    counts = []
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
