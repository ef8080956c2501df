"""Rigid-body motions left free by the fixations of one connected body.

A rigid motion ``u(x) = t + w x (x - c)`` (3D; in 2D one rotation in the plane) is blocked when
it moves some fixed freedom. The fixed freedoms block every motion exactly when the matrix ``T``
of the rigid motions evaluated at them (one row per fixed freedom, one column per translation or
rotation) has full column rank; its null space is the set of motions left free. This check is
exact, unlike a pivot threshold, and names the motions.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rigid_motions", "free_rigid_motions"]

_AXES = "xyz"
#: Singular values of ``T`` (coordinates scaled to the body's size) below this are zero.
_RANK_RTOL = 1e-8


def rigid_motions(
    points: np.ndarray, components: np.ndarray, centre: np.ndarray, scale: float
) -> np.ndarray:
    """Rigid-body displacements at freedoms.

    Parameters
    ----------
    points : ndarray, shape (dim, m)
        Locations of the freedoms (m).
    components : ndarray of int, shape (m,)
        Direction (0 = x, 1 = y, 2 = z) of each freedom.
    centre : ndarray, shape (dim,)
        Centre of the rotations (m).
    scale : float
        Length (m) dividing the lever arms, so that rotations and translations compare.

    Returns
    -------
    ndarray, shape (m, 3) in 2D or (m, 6) in 3D
        Columns: translations along each axis, then rotations (about ``z`` in 2D; about ``x``,
        ``y``, ``z`` in 3D).
    """
    dim = points.shape[0]
    arm = (points - centre[:, None]) / scale
    columns = [(components == axis).astype(float) for axis in range(dim)]
    if dim == 2:
        columns.append(np.where(components == 0, -arm[1], arm[0]))
    else:
        arm3 = arm.T
        for axis in range(3):
            moved = np.cross(np.eye(3)[axis], arm3)
            columns.append(moved[np.arange(arm3.shape[0]), components])
    return np.column_stack(columns)


def _direction(vector: np.ndarray) -> str:
    unit = vector / np.linalg.norm(vector)
    axis = int(np.argmax(np.abs(unit)))
    if abs(unit[axis]) > 1 - 1e-6:
        return _AXES[axis]
    return "(" + ", ".join(f"{c:.2f}" for c in unit) + ")"


def free_rigid_motions(
    points: np.ndarray, components: np.ndarray, centre: np.ndarray, scale: float
) -> list[str]:
    """Names of the rigid motions that the fixed freedoms at ``points`` leave free.

    Parameters are those of :func:`rigid_motions`, for the fixed freedoms of one body.

    Returns
    -------
    list of str
        Empty when the body is held; otherwise one name per free motion, e.g.
        ``"translation along y"`` or ``"rotation about an axis along z"``.
    """
    dim = points.shape[0]
    n_modes = 3 if dim == 2 else 6
    T = rigid_motions(points, components, centre, scale)
    square = np.zeros((n_modes, n_modes))  # T's triangular factor: same singular values
    if T.shape[0]:
        # numpy's stubs type every mode as QRResult, but mode="r" returns the array R alone
        triangle: np.ndarray = np.linalg.qr(T, mode="r")  # type: ignore[assignment]
        square[: triangle.shape[0]] = triangle
    _, sigma, vt = np.linalg.svd(square)
    null = vt[sigma <= _RANK_RTOL * max(1.0, sigma[0])]
    names = []
    inside = np.linalg.norm(null, axis=0) > 1 - 1e-6  # canonical motions lying in the null space
    for mode in np.flatnonzero(inside):
        if mode < dim:
            names.append(f"translation along {_AXES[mode]}")
        else:
            names.append(
                "rotation in the plane" if dim == 2 else f"rotation about {_AXES[mode - dim]}"
            )
    if len(names) < null.shape[0]:
        canonical = np.eye(n_modes)[inside]
        rest = null - (null @ canonical.T) @ canonical
        _, sigma, vt = np.linalg.svd(rest, full_matrices=False)
        for vector in vt[sigma > 1e-6]:
            rotation = vector[dim:]
            if np.linalg.norm(rotation) > 1e-6:
                names.append(
                    "rotation in the plane"
                    if dim == 2
                    else f"rotation about an axis along {_direction(rotation)}"
                )
            else:
                names.append(f"translation along {_direction(vector[:dim])}")
    return names
