"""Gaps of an assembly file: the nominal gap of every pair and the variation around it.

A measured point cloud (CSV ``x, y[, z], gap``) is interpolated to the pairs' positions (the
mean of each pair's two nodes) with scipy:

* ``"linear"``: :class:`scipy.interpolate.LinearNDInterpolator`, piecewise linear on the
  Delaunay triangulation of the measured points;
* ``"thin-plate"``: :class:`scipy.interpolate.RBFInterpolator` with the thin-plate-spline
  kernel and a linear polynomial, through every measured point.

Both reproduce a linear gap field exactly. A cloud with ``z`` is first projected onto its
least-squares plane (its two principal directions), pairs included. Pairs outside the cloud's
convex hull are refused unless ``extrapolate = true``: then ``"linear"`` gives them the nearest
measured gap and ``"thin-plate"`` its spline's value. The interpolation error is measured by
leave-one-out at up to :data:`MAX_CHECKED` measured points: each is predicted from the others.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator, RBFInterpolator
from scipy.spatial import Delaunay, QhullError

from ...errors import InvalidInputError

__all__ = ["InterpolationError", "Cloud", "MAX_CHECKED"]

#: Measured points the leave-one-out check predicts at most (evenly spread over the file).
MAX_CHECKED = 200


@dataclass(frozen=True)
class InterpolationError:
    """How well the interpolant predicts each measured point from the others (leave-one-out).

    Attributes
    ----------
    interpolant : str
    max_abs, rms : float
        Largest and root-mean-square error (m) over the checked points.
    n_points : int
        Measured points checked.
    n_skipped : int
        Checked points outside the hull of the others (``"linear"`` cannot predict them).
    """

    interpolant: str
    max_abs: float
    rms: float
    n_points: int
    n_skipped: int

    def describe(self) -> str:
        """One line for the command line."""
        skipped = f", {self.n_skipped} on the hull skipped" if self.n_skipped else ""
        return (
            f"gap interpolation ({self.interpolant}, leave-one-out at {self.n_points} measured "
            f"points{skipped}): max {self.max_abs:.3g} m, rms {self.rms:.3g} m"
        )


class Cloud:
    """Measured points in the plane they are interpolated in.

    Parameters
    ----------
    points : ndarray, shape (n, 2) or (n, 3)
        Measured positions (m).
    """

    def __init__(self, points: np.ndarray) -> None:
        self.dim = points.shape[1]
        if self.dim == 3:
            self.centre = points.mean(axis=0)
            _, _, vt = np.linalg.svd(points - self.centre, full_matrices=False)
            self.axes = vt[:2]
        self.points = self.project(points)
        if len(self.points) < 3:
            raise InvalidInputError(f"needs at least 3 measured points, got {len(self.points)}")
        try:
            self.hull = Delaunay(self.points)
        except QhullError:
            raise InvalidInputError(
                "the measured points lie on a line: no surface to interpolate on"
            ) from None

    def project(self, positions: np.ndarray) -> np.ndarray:
        """Positions in the interpolation plane: ``(x, y)``, or along the cloud's principal
        directions when it has ``z``."""
        if self.dim == 2:
            return positions[:, :2]
        return (positions - self.centre) @ self.axes.T

    def outside(self, positions: np.ndarray) -> np.ndarray:
        """Indices of ``positions`` (m, shape (k, 3)) outside the cloud's convex hull."""
        return np.flatnonzero(self.hull.find_simplex(self.project(positions), tol=1e-9) < 0)

    def interpolate(
        self, values: np.ndarray, positions: np.ndarray, interpolant: str
    ) -> np.ndarray:
        """``values`` measured at the cloud's points, at ``positions`` (m, shape (k, 3))."""
        return _fit(self.points, values, interpolant)(self.project(positions))

    def leave_one_out(self, values: np.ndarray, interpolant: str) -> InterpolationError:
        """The interpolation error at up to :data:`MAX_CHECKED` measured points."""
        n = len(self.points)
        checked = np.unique(np.linspace(0, n - 1, min(n, MAX_CHECKED)).round().astype(int))
        errors, skipped = [], 0
        for index in checked:
            keep = np.arange(n) != index
            try:
                predicted = _fit(self.points[keep], values[keep], interpolant, nearest=False)(
                    self.points[index : index + 1]
                )[0]
            except (QhullError, ValueError, np.linalg.LinAlgError):
                predicted = np.nan
            if np.isnan(predicted):
                skipped += 1
            else:
                errors.append(predicted - values[index])
        error = np.abs(np.asarray(errors))
        return InterpolationError(
            interpolant,
            float(error.max()) if error.size else float("nan"),
            float(np.sqrt(np.mean(error**2))) if error.size else float("nan"),
            int(checked.size - skipped),
            int(skipped),
        )


def _fit(points: np.ndarray, values: np.ndarray, interpolant: str, nearest: bool = True):
    """A function of (m, 2) positions; ``"linear"`` fills NaN with the nearest measured value
    when ``nearest``."""
    if interpolant == "thin-plate":
        return RBFInterpolator(points, values, kernel="thin_plate_spline", degree=1)
    linear = LinearNDInterpolator(points, values)
    if not nearest:
        return linear
    closest = NearestNDInterpolator(points, values)

    def evaluate(positions: np.ndarray) -> np.ndarray:
        result = linear(positions)
        missing = np.isnan(result)
        if np.any(missing):
            result[missing] = closest(positions[missing])
        return result

    return evaluate
