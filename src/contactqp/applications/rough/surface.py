r"""Self-affine random surfaces, generated spectrally, and their spectral rms height and slope.

Construction
------------
A periodic grid of ``nx x ny`` square cells of side ``cell`` (m) is one period
``L_x x L_y = nx cell x ny cell`` of the surface. Its discrete Fourier modes have the
wavenumbers :math:`q = 2\pi \sqrt{(k_x / L_x)^2 + (k_y / L_y)^2}` with ``k_x, k_y`` the signed
integer frequencies of :func:`numpy.fft.fftfreq`. Wavenumbers are given here in multiples of
the fundamental :math:`q_0 = 2\pi / L` (``L`` the longer side), i.e. as mode numbers. The power
spectral density is the isotropic power law with a plateau (Persson's self-affine model):

.. math::

   C(q) \propto \begin{cases}
       q_r^{-2(1+H)} & q_L \le q < q_r \quad\text{(roll-off plateau)}\\
       q^{-2(1+H)}   & q_r \le q \le q_s\\
       0             & \text{otherwise (and at } q = 0\text{: zero mean)}
   \end{cases}

with ``H`` the Hurst exponent, ``q_L`` the long-wavelength cut-off, ``q_r`` the roll-off and
``q_s`` the short-wavelength cut-off. Each mode has the amplitude :math:`\sqrt{C(q)}` exactly
and a random phase: the phases are those of the real FFT of white noise drawn from
``numpy.random.default_rng(seed)``, which have the Hermitian symmetry of a real field by
construction (the self-conjugate modes get a real sign), so :func:`numpy.fft.irfft2` returns
the surface without projecting anything away. The surface is then scaled to the requested rms
height or rms slope, so that value holds to rounding and the discrete PSD is :math:`C(q)` up to
one constant factor.

Discrete definitions
--------------------
With :math:`\hat h_k` the discrete Fourier transform (:func:`numpy.fft.fft2`) of the
``N = nx ny`` heights, Parseval's identity gives

.. math::

   h_\mathrm{rms}^2 = \frac{1}{N} \sum_i (h_i - \bar h)^2
       = \frac{1}{N^2} \sum_{k \ne 0} |\hat h_k|^2, \qquad
   h'^2_\mathrm{rms} = \frac{1}{N^2} \sum_k |q_k|^2 |\hat h_k|^2,

the second being the mean of :math:`|\nabla h|^2` of the trigonometric interpolant of the
heights (the spectral gradient), exact for a band-limited surface; at the Nyquist
frequencies :math:`|q|` is :math:`\pi / \text{cell}`. Finite differences would give less:
:math:`\sin(q\,\text{cell}) / \text{cell}` instead of ``q`` for each mode.

References
----------
B. N. J. Persson, O. Albohr, U. Tartaglino, A. I. Volokitin and E. Tosatti, "On the nature of
surface roughness with application to contact mechanics, sealing, rubber friction and
adhesion", J. Phys.: Condens. Matter 17 (2005) R1-R62.
T. D. B. Jacobs, T. Junge and L. Pastewka, "Quantitative characterization of surface
topography using spectral analysis", Surf. Topogr.: Metrol. Prop. 5 (2017) 013001.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InvalidInputError

__all__ = ["self_affine_surface", "rms_height", "rms_slope", "wavenumbers"]


def wavenumbers(nx: int, ny: int, cell: float) -> np.ndarray:
    """The magnitude :math:`|q|` (rad/m) of each mode of :func:`numpy.fft.fft2`, shape (ny, nx).

    Parameters
    ----------
    nx, ny : int
        Cells along x (columns) and y (rows).
    cell : float
        Side of a square cell (m).
    """
    qx = 2 * np.pi * np.fft.fftfreq(nx, d=cell)
    qy = 2 * np.pi * np.fft.fftfreq(ny, d=cell)
    return np.hypot(qx[np.newaxis, :], qy[:, np.newaxis])


def rms_height(heights: np.ndarray) -> float:
    """Root mean square of the heights about their mean (m), of a 2-D grid of heights."""
    return _rms_height(_grid(heights))


def rms_slope(heights: np.ndarray, cell: float) -> float:
    r"""Spectral rms slope :math:`h'_\mathrm{rms}` of a periodic grid of heights (see the
    module's discrete definition).

    Parameters
    ----------
    heights : ndarray, shape (ny, nx)
        One period, ``heights[j, i]`` at ``x = i cell``, ``y = j cell`` (m).
    cell : float
        Side of a square cell (m).

    Returns
    -------
    float
        :math:`\sqrt{\langle |\nabla h|^2 \rangle}` (dimensionless).
    """
    return _rms_slope(_grid(heights), _positive("cell", cell))


def self_affine_surface(
    nx: int,
    cell: float,
    *,
    hurst: float,
    rms_height: float | None = None,
    rms_slope: float | None = None,
    ny: int | None = None,
    long_cutoff: float = 1.0,
    rolloff: float | None = None,
    short_cutoff: float | None = None,
    seed: int | np.random.Generator | None = None,
) -> np.ndarray:
    """A periodic self-affine random surface with the power spectrum of the module's model.

    Parameters
    ----------
    nx : int
        Cells along x (columns), at least 2.
    cell : float
        Side of a square cell (m).
    hurst : float
        Hurst exponent ``H``, in (0, 1]; the PSD falls as ``q^{-2(1+H)}``.
    rms_height, rms_slope : float
        Exactly one: the rms height (m) or the spectral rms slope (dimensionless) of the result.
    ny : int, optional
        Cells along y (rows); default ``nx``.
    long_cutoff, rolloff, short_cutoff : float
        ``q_L <= q_r <= q_s`` in multiples of the fundamental wavenumber ``2 pi / L`` (``L``
        the longer side): modes below ``q_L`` or above ``q_s`` are empty, those between ``q_L``
        and ``q_r`` have the plateau's power. Defaults: ``q_L = 1``, ``q_r = q_L`` (no
        plateau) and the Nyquist mode number ``max(nx, ny) / 2`` (the wavenumber
        ``pi / cell``).
    seed : int or numpy.random.Generator, optional
        The phases' random source; the same seed gives the same surface.

    Returns
    -------
    ndarray, shape (ny, nx)
        Heights (m) of zero mean, ``heights[j, i]`` at ``x = i cell``, ``y = j cell``; row
        ``j`` is cell ``k = j nx + i`` of :func:`contactqp.compliance.grid`'s order when raveled.

    Raises
    ------
    InvalidInputError
        A size, exponent, wavenumber or rms out of range, both or neither rms given, or a band
        ``[q_L, q_s]`` that holds no mode of the grid.
    """
    nx = _size("nx", nx)
    ny = nx if ny is None else _size("ny", ny)
    cell = _positive("cell", cell)
    if not (isinstance(hurst, int | float) and 0 < hurst <= 1):
        raise InvalidInputError(f"hurst must be in (0, 1], got {hurst!r}")
    if (rms_height is None) == (rms_slope is None):
        raise InvalidInputError("give exactly one of rms_height and rms_slope")
    target = _positive(
        "rms_height" if rms_slope is None else "rms_slope",
        rms_height if rms_slope is None else rms_slope,
    )
    length = max(nx, ny) * cell
    fundamental = 2 * np.pi / length
    nyquist = max(nx, ny) / 2  # pi / cell in units of 2 pi / L
    q_s = nyquist if short_cutoff is None else _positive("short_cutoff", short_cutoff)
    q_l = _positive("long_cutoff", long_cutoff)
    q_r = q_l if rolloff is None else _positive("rolloff", rolloff)
    if not q_l <= q_r <= q_s:
        raise InvalidInputError(
            f"need long_cutoff <= rolloff <= short_cutoff, got {q_l:g}, {q_r:g}, {q_s:g}"
        )
    if q_s > nyquist * (1 + 1e-12):
        raise InvalidInputError(
            f"short_cutoff {q_s:g} is above the grid's Nyquist mode number {nyquist:g}"
        )
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    noise = np.fft.rfft2(rng.standard_normal((ny, nx)))
    magnitude = np.abs(noise)
    phases = np.divide(noise, magnitude, out=np.ones_like(noise), where=magnitude > 0)
    qx = 2 * np.pi * np.fft.rfftfreq(nx, d=cell)
    qy = 2 * np.pi * np.fft.fftfreq(ny, d=cell)
    mode = np.hypot(qx[np.newaxis, :], qy[:, np.newaxis]) / fundamental  # mode numbers
    tol = 1e-9  # mode numbers are exact integers (or their hypot) up to rounding
    band = (mode >= q_l * (1 - tol)) & (mode <= q_s * (1 + tol))
    if not band.any():
        raise InvalidInputError(
            f"no mode of the {nx} x {ny} grid lies between long_cutoff {q_l:g} and "
            f"short_cutoff {q_s:g}"
        )
    power = np.zeros_like(mode)
    power[band] = np.maximum(mode[band], q_r) ** (-2 * (1 + hurst))
    heights = np.fft.irfft2(np.sqrt(power) * phases, s=(ny, nx))
    achieved = _rms_height(heights) if rms_slope is None else _rms_slope(heights, cell)
    return heights * (target / achieved)


def _rms_height(heights: np.ndarray) -> float:
    return float(np.sqrt(np.mean((heights - heights.mean()) ** 2)))


def _rms_slope(heights: np.ndarray, cell: float) -> float:
    q = wavenumbers(heights.shape[1], heights.shape[0], cell)
    return float(np.sqrt(np.sum(q**2 * np.abs(np.fft.fft2(heights)) ** 2)) / heights.size)


def _grid(heights: np.ndarray) -> np.ndarray:
    h = np.asarray(heights, dtype=float)
    if h.ndim != 2 or min(h.shape) < 2:
        raise InvalidInputError(f"heights must be a 2-D grid of at least 2 x 2, got {h.shape}")
    if not np.isfinite(h).all():
        raise InvalidInputError("heights must be finite")
    return h


def _size(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 2:
        raise InvalidInputError(f"{name} must be an integer of at least 2, got {value!r}")
    return int(value)


def _positive(name: str, value: float | None) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
        raise InvalidInputError(f"{name} must be a positive number, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise InvalidInputError(f"{name} must be positive and finite, got {value!r}")
    return float(value)
