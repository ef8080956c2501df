"""Half-space and half-plane flexibilities applied by FFT, without forming ``W``.

The flexibility of a regular grid of equal cells on an elastic half-space is a convolution: the
displacement of cell ``i`` under a force on cell ``j`` depends on their offset only. The
operators here hold the kernel's transform and apply ``W`` with real FFTs (see "Which FFT"), in
``O(n log n)`` time and ``O(n)`` memory, where the dense matrix of
:func:`~contactqp.compliance.normal_influence` takes ``O(n^2)`` of both.

Non-periodic (a finite grid on an infinite half-space)
    The kernel is the one of :func:`~contactqp.compliance.normal_influence` and
    :func:`~contactqp.compliance.influence_matrix` (Love's uniform pressure on a rectangle,
    Cerruti's tangential terms and the coupling), evaluated once on the ``nx x ny`` lattice of
    offsets and convolved with the forces after zero padding to at least ``2 n - 1`` per axis
    (a fast length from :func:`scipy.fft.next_fast_len`). The product equals the dense
    matrix's to rounding; it costs one forward and one inverse real transform of the padded
    grid per component.

Periodic (the grid is one period of the surface, as for rough surfaces)
    The periodic sum of the cell kernel diverges (it decays as ``1 / r``). The operator uses
    the spectral (Westergaard) kernel instead, as Stanley & Kato [Stanley1997]_ and Tamaas
    do: a traction mode of wave vector ``q`` displaces the surface by the half-space's surface
    Green's function at ``q`` (below), the tractions being the forces of the cells divided by
    the cell area and the displacements collocated at the cell centres. A mode of the grid
    (``p0 cos(q x)`` sampled at the centres) is then displaced by exactly Westergaard's
    ``2 p0 cos(q x) / (E* |q|)`` [Westergaard1939]_. The mean (``q = 0``) mode of the
    displacement is undetermined (a periodic half-space under a net force sinks without
    limit): it is set to 0, so ``W`` is positive semidefinite with the constant vector in its
    null space, and a periodic contact problem is posed with a fixed load, the mean approach
    being the unknown that balances it. With ``G = E / (2 (1 + nu))``, ``E* = E / (1 - nu^2)``:

    .. math::

        \\hat u_z = \\frac{2}{E^* |q|} \\hat p_z, \\quad
        \\hat u_x = \\frac{1}{G |q|}\\left(1 - \\frac{\\nu q_x^2}{|q|^2}\\right) \\hat p_x
            - \\frac{\\nu q_x q_y}{G |q|^3} \\hat p_y
            - \\frac{i (1 - 2\\nu) q_x}{2 G |q|^2} \\hat p_z, \\quad
        \\hat u_z \\mathrel{+}= \\frac{i (1 - 2\\nu)}{2 G |q|^2} (q_x \\hat p_x + q_y \\hat p_y)

    (``u_y`` by exchanging ``x`` and ``y``): the transforms of Cerruti's and Boussinesq's
    point-force solutions [Johnson1985b]_ (``z`` the outward normal, the convention of
    :func:`~contactqp.compliance.influence_matrix`). The odd terms vanish on a grid's Nyquist
    frequencies, where ``q`` and ``-q`` are the same mode, which keeps ``W`` real and symmetric.

The half-plane (:class:`HalfPlaneOperator`) is the same in one dimension, in plane strain.

An elastic layer on a rigid base (periodic, normal component)
    ``thickness=h`` replaces the half-space by a layer of thickness ``h`` on a rigid base,
    ``base="bonded"`` (no displacement at the interface) or ``"frictionless"`` (no normal
    displacement, no shear). A traction mode of a periodic surface is a plane-strain problem in
    the plane of ``q`` and the normal; its Airy stress function
    ``((A + B z) cosh qz + (C + D z) sinh qz) cos qx`` meets the four boundary conditions, and
    the surface displacement is the half-space's times (``t = |q| h``, ``kappa = 3 - 4 nu``)

    .. math::

        \\text{bonded: } \\frac{\\kappa \\sinh(2t) / 2 - t}
            {\\kappa \\sinh^2 t + t^2 + 4 (1 - \\nu)^2}, \\qquad
        \\text{frictionless: } \\frac{2 \\sinh^2 t}{2 t + \\sinh(2 t)}

    (derived symbolically for this module; both tend to 1 as ``t`` grows, and as ``t -> 0``
    to the thin layer's ``h (1 + nu)(1 - 2 nu) / ((1 - nu) E)`` per unit pressure, the
    oedometric compliance, when bonded, and to ``(1 - nu^2) h / E`` when frictionless).
    Non-periodic grids and the tangential components of a layer are not implemented (refused).

Two bodies in contact
    The normal flexibility depends on the material through ``E* = E / (1 - nu^2)`` only. For
    two elastic bodies ``1 / E* = (1 - nu1^2) / E1 + (1 - nu2^2) / E2``
    (:func:`composite_modulus`); the normal operator of the pair is the operator of one body of
    modulus ``E*`` and Poisson's ratio 0::

        HalfSpaceOperator(nx, ny, dx, dy, composite_modulus(E1, nu1, E2, nu2), 0.0)

    Tangential flexibilities do not combine that way: for ``components="full"`` add the two
    bodies' products (with ``coupling=False`` for elastically similar bodies, whose coupling
    terms cancel).

Which FFT
    Measured for one product of the normal operator, one thread, median CPU time of
    alternating runs, on the project's 2-core machine under load (load average 8-10; two runs,
    ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_fft.py --sizes
    256,512,1024,2048``, scipy 1.17.1, pyFFTW 0.15.1, ``FFTW_ESTIMATE`` plans). Non-periodic
    grids are zero padded, transformed along x on their rows only (both libraries):

    ==================  ===============  ===============  ==============
    transformed grid    scipy.fft        pyFFTW           pyFFTW / scipy
    ==================  ===============  ===============  ==============
    padded 256 x 256    0.75 / 1.01 ms   0.59 / 0.86 ms   0.78 / 0.85
    padded 512 x 512    3.54 / 4.12 ms   3.08 / 3.31 ms   0.87 / 0.80
    padded 1024 x 1024  17.4 / 21.5 ms   18.4 / 22.2 ms   1.06 / 1.03
    padded 2048 x 2048  71.4 / 93.2 ms   83.2 / 94.4 ms   1.17 / 1.01
    periodic 256 x 256  0.67 / 0.80 ms   0.45 / 0.56 ms   0.68 / 0.69
    periodic 512 x 512  3.40 / 4.19 ms   2.67 / 3.23 ms   0.78 / 0.77
    periodic 1024^2     19.7 / 19.8 ms   15.4 / 17.7 ms   0.78 / 0.89
    periodic 2048^2     118 / 131 ms     73.9 / 93.9 ms   0.62 / 0.72
    ==================  ===============  ===============  ==============

    pyFFTW is faster on periodic grids and on small padded ones, not on padded grids from
    1024 x 1024 (pyFFTW's ``FFTW_MEASURE`` plans, about 1 s of planning per size, were no
    faster than scipy.fft there either). So by default (``fft=None``) the operators use
    pyFFTW when it is installed (the ``fft`` extra), except on padded grids of 1024 x 1024
    points or more, which use :mod:`scipy.fft`; ``fft="scipy"`` or ``"pyfftw"`` chooses. The
    two agree to rounding.

References
----------
.. [Stanley1997] H. M. Stanley and T. Kato, "An FFT-based method for rough surface contact",
   J. Tribol. 119, 481-485, 1997.
.. [Westergaard1939] H. M. Westergaard, "Bearing pressures and cracks", J. Appl. Mech. 6,
   A49-A53, 1939.
.. [Johnson1985b] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985,
   ch. 2-3 (line and point loads, sinusoidal pressure).
"""

from __future__ import annotations

import math
import numbers

import numpy as np
import scipy.fft

from ..core.model import true_or_false
from ..core.operators import Coarsening, Operator
from ..errors import InvalidInputError
from ._fft import transforms
from .halfspace import _cell_kernels, _finite_float, _material, _normal_kernel, _positive_length

__all__ = ["HalfPlaneOperator", "HalfSpaceOperator", "composite_modulus"]

# The 3 x 3 per cell layout of influence_matrix: (kernel kind, sign) for each pair of
# components (x, y, z); the kinds are _cell_kernels' six kernels, in its order.
_FULL_PAIRS = (
    ((0, 1.0), (2, 1.0), (4, 1.0)),
    ((2, 1.0), (1, 1.0), (5, 1.0)),
    ((4, -1.0), (5, -1.0), (3, 1.0)),
)
# Oddness of each kind along the lattice axes (y, x): xx, yy, xy, zz, xz, yz.
_FULL_PARITY = ((0, 0), (0, 0), (1, 1), (0, 0), (0, 1), (1, 0))


def _count(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise InvalidInputError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _workers(value) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value == 0:
        raise InvalidInputError(
            f"workers must be None or a nonzero integer (threads of the FFTs), got {value!r}"
        )
    return int(value)


class _LatticeOperator(Operator):
    """``W`` of a translation-invariant kernel on a regular lattice of cells, applied by FFT.

    The vector holds ``components`` entries per cell, cell by cell, the cells in the C order of
    the lattice's shape ``cells``. Entry ``(a, b)`` of the kernel at an offset ``d`` (target
    minus source, in cells) is ``sign[a][b] * K_k(d)`` with ``k = kind[a][b]``; non-periodic,
    ``K_k(d) = table_k[|d|] * prod(sign(d_axis))`` over the axes along which kind ``k`` is odd.
    """

    def __init__(
        self,
        cells: tuple[int, ...],
        pairs,
        parity,
        workers: int | None,
        fft: str | None,
        *,
        tables: list[np.ndarray] | None = None,
        spectra: list[np.ndarray] | None = None,
    ):
        count = math.prod(cells)
        components = len(pairs)
        super().__init__((components * count, components * count))
        self._cells = cells
        self._count = count
        self._components = components
        self._axes = tuple(range(len(cells)))
        self._kind = np.array([[kind for kind, _ in row] for row in pairs], dtype=np.intp)
        self._sign = np.array([[sign for _, sign in row] for row in pairs], dtype=float)
        self._parity = np.array(parity, dtype=bool)
        self._workers = workers
        self._crop = tuple(slice(0, n) for n in cells)
        self._periodic = tables is None
        self._tables: np.ndarray | None
        if tables is not None:
            self._tables = np.stack(tables)
            self._fft_shape = tuple(scipy.fft.next_fast_len(2 * n - 1, real=True) for n in cells)
            spectra = [self._padded_spectrum(kind) for kind in range(len(tables))]
        else:
            self._tables = None  # the periodic real-space kernels, made when a block asks
            self._fft_shape = cells
        assert spectra is not None
        # a kernel that is zero everywhere (the coupling, switched off) is skipped
        self._spectra = [spectrum if np.any(spectrum) else None for spectrum in spectra]
        self._engine = transforms(self._fft_shape, cells, workers, fft)
        #: The FFT library the products use, ``"scipy"`` or ``"pyfftw"``.
        self.fft = self._engine.name

    def _padded_spectrum(self, kind: int) -> np.ndarray:
        """The transform of kernel ``kind`` laid on the padded grid (offset ``-d`` at ``N - d``)."""
        assert self._tables is not None
        padded = self._tables[kind]
        for axis, (n, size) in enumerate(zip(self._cells, self._fft_shape, strict=True)):
            m = np.arange(size)
            negative = m > size - n
            index = np.where(m < n, m, np.where(negative, size - m, 0))
            odd = self._parity[kind, axis]
            weight = np.where(m < n, 1.0, np.where(negative, -1.0 if odd else 1.0, 0.0))
            if odd:
                weight[0] = 0.0
            shape = [1] * len(self._cells)
            shape[axis] = size
            padded = np.take(padded, index, axis=axis) * weight.reshape(shape)
        spectrum = scipy.fft.rfftn(padded, axes=self._axes, workers=self._workers)
        # an even kernel's transform is real, an odd one's imaginary: drop the rounding
        if self._parity[kind].sum() % 2 == 0:
            return np.ascontiguousarray(spectrum.real)
        return 1j * spectrum.imag

    def __matmul__(self, x):
        x = np.asarray(x)
        if x.ndim not in (1, 2) or x.shape[0] != self.shape[0]:
            raise InvalidInputError(
                f"the operator takes a vector of {self.shape[0]} entries or a 2-D array of "
                f"{self.shape[0]} rows, got shape {x.shape}"
            )
        if np.iscomplexobj(x):
            raise InvalidInputError("the operator takes real vectors, got complex ones")
        columns = x.shape[1:]
        if x.size == 0:  # no columns
            return np.zeros(x.shape)
        engine = self._engine
        c = self._components
        if c == 1:
            kernel = self._spectra[0]
            if kernel is None:
                return np.zeros(x.shape)
            return engine.convolve(x.reshape(self._cells + columns), kernel).reshape(x.shape)
        lattice = (slice(None),) * len(self._cells)
        if columns:
            spectra = [None if k is None else k[..., None] for k in self._spectra]
        else:
            spectra = self._spectra
        fields = x.reshape(self._cells + (c,) + columns)
        # a component that is zero everywhere (the normal forces of a tangential product) is
        # not transformed, nor is an output that only such components would reach
        forward = [
            engine.forward(field) if np.any(field) else None
            for field in (fields[lattice + (b,)] for b in range(c))
        ]
        out = np.empty(self._cells + (c,) + columns)
        for a in range(c):
            total = None
            for b in range(c):
                kernel = spectra[self._kind[a, b]]
                if kernel is None or forward[b] is None:
                    continue
                term = kernel * forward[b]
                if total is None:
                    total = term if self._sign[a, b] > 0 else -term
                elif self._sign[a, b] > 0:
                    total += term
                else:
                    total -= term
            out[lattice + (a,)] = 0.0 if total is None else engine.inverse(total)
        return out.reshape(x.shape)

    def _periodic_tables(self) -> np.ndarray:
        """The periodic kernels in real space, one per kind, indexed by offsets modulo the grid."""
        if self._tables is None:
            zero = np.zeros(self._cells)
            self._tables = np.stack(
                [
                    zero
                    if s is None
                    else scipy.fft.irfftn(s, s=self._cells, axes=self._axes, workers=self._workers)
                    for s in self._spectra
                ]
            )
        return self._tables

    def _selection(self, selection, name: str) -> np.ndarray:
        n = self.shape[0]
        if selection is None:
            return np.arange(n)
        if isinstance(selection, slice):
            return np.arange(n)[selection]
        index = np.asarray(selection)
        if index.dtype == bool:
            if index.shape != (n,):
                raise InvalidInputError(
                    f"{name}: a boolean mask must have shape ({n},), got {index.shape}"
                )
            return np.flatnonzero(index)
        if index.ndim != 1 or (index.size and not np.issubdtype(index.dtype, np.integer)):
            raise InvalidInputError(f"{name} must be None, a slice, a mask or 1-D indices")
        index = index.astype(np.intp, copy=False)
        if index.size and (index.min() < 0 or index.max() >= n):
            raise InvalidInputError(f"{name}: indices must lie in [0, {n}), got {index.min()}..")
        return index

    def _entries(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """``W[rows[:, None], cols[None, :]]`` for integer indices broadcast together."""
        c = self._components
        cell_r, comp_r = np.divmod(rows, c)
        cell_c, comp_c = np.divmod(cols, c)
        kind = self._kind[comp_r, comp_c]
        value = self._sign[comp_r, comp_c]
        offsets = [
            r - s
            for r, s in zip(
                np.unravel_index(cell_r, self._cells),
                np.unravel_index(cell_c, self._cells),
                strict=True,
            )
        ]
        if self._periodic:
            index = tuple(d % n for d, n in zip(offsets, self._cells, strict=True))
            return value * self._periodic_tables()[(kind,) + index]
        assert self._tables is not None
        value = value * self._tables[(kind,) + tuple(np.abs(d) for d in offsets)]
        for axis, d in enumerate(offsets):
            odd = self._parity[kind, axis]
            if np.any(odd):
                value = value * np.where(odd, np.sign(d), 1)
        return value

    def diagonal(self) -> np.ndarray:
        first = np.arange(self._components)
        return np.tile(self._entries(first, first), self._count)

    def block(self, rows=None, cols=None) -> np.ndarray:
        rows = self._selection(rows, "rows")
        cols = self._selection(cols, "cols")
        return np.asarray(self._entries(rows[:, None], cols[None, :]), dtype=float)

    def diagonal_blocks(self, size: int) -> np.ndarray:
        if size != self._components:
            return super().diagonal_blocks(size)
        first = np.arange(size)
        block = self._entries(first[:, None], first[None, :])
        return np.broadcast_to(block, (self._count, size, size)).copy()


class HalfSpaceOperator(_LatticeOperator):
    """Flexibility of an elastic half-space under a grid of uniformly loaded cells, by FFT.

    The operator of :func:`~contactqp.compliance.normal_influence` (``components="normal"``)
    or :func:`~contactqp.compliance.influence_matrix` (``components="full"``) on the grid of
    :func:`~contactqp.compliance.grid`, without forming it: products by FFT (see the module
    notes), dense blocks and diagonals from the kernel's values. :attr:`matrix` refuses.

    Parameters
    ----------
    nx, ny : int
        Cells along x and y, >= 1. Cell ``k = j * nx + i`` is the ``i``-th along x of the
        ``j``-th row, as :func:`~contactqp.compliance.grid` orders them.
    dx, dy : float
        Cell size (m), > 0.
    young : float
        Young's modulus ``E`` (Pa), > 0; for two bodies in contact see
        :func:`composite_modulus`.
    poisson : float
        Poisson's ratio ``nu``, in (-1, 0.5).
    components : {"normal", "full"}
        ``"normal"``: one entry per cell, the normal force (N) and displacement (m) along the
        outward normal. ``"full"``: three per cell ``(x, y, z)`` in
        :func:`~contactqp.compliance.influence_matrix`'s layout.
    coupling : bool
        With ``"full"``: False drops the normal-tangential coupling (``(1 - 2 nu)`` terms).
    periodic : bool
        True: the grid is one period of a periodic surface (the spectral Westergaard kernel,
        displacements of zero mean; see the module notes). False: a finite grid on an infinite
        half-space (the dense matrix's kernel, zero padding).
    thickness : float, optional
        An elastic layer of this thickness (m) on a rigid base instead of the half-space
        (periodic, ``components="normal"`` only; see the module notes).
    base : {"bonded", "frictionless"}
        The layer's interface with the rigid base.
    workers : int or None
        Threads of the FFTs (None: one; negative: counted back from the CPU count, as
        :mod:`scipy.fft` does).
    fft : {None, "scipy", "pyfftw"}
        The FFT library of the products; None: the one measured faster for this grid (see
        the module notes; :mod:`scipy.fft` if pyFFTW, the ``fft`` extra, is not installed).
        The attribute ``fft`` says which.

    Attributes
    ----------
    components : str
        ``"normal"`` or ``"full"``.
    periodic : bool
        Whether the grid is one period.
    grid_shape, cell : tuple
        ``(nx, ny)`` and ``(dx, dy)``.
    fft : str
        The FFT library of the products, ``"scipy"`` or ``"pyfftw"``.

    Raises
    ------
    InvalidInputError
        An argument is of the wrong type or out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from contactqp.compliance import HalfSpaceOperator, grid, normal_influence
    >>> W = HalfSpaceOperator(8, 6, 1e-4, 1e-4, young=210e9, poisson=0.3)
    >>> f = np.ones(48)
    >>> R = normal_influence(*grid(8, 6, 1e-4, 1e-4), 1e-4, 1e-4, 210e9, 0.3)
    >>> bool(np.allclose(W @ f, R @ f, rtol=1e-12, atol=0))
    True
    """

    def __init__(
        self,
        nx: int,
        ny: int,
        dx: float,
        dy: float,
        young: float,
        poisson: float,
        *,
        components: str = "normal",
        coupling: bool = True,
        periodic: bool = False,
        thickness: float | None = None,
        base: str = "bonded",
        workers: int | None = None,
        fft: str | None = None,
    ):
        nx, ny = _count(nx, "nx"), _count(ny, "ny")
        dx, dy = _positive_length(dx, "dx"), _positive_length(dy, "dy")
        E, nu = _material(young, poisson)
        if components not in ("normal", "full"):
            raise InvalidInputError(f'components must be "normal" or "full", got {components!r}')
        coupling = true_or_false(coupling, "coupling")
        periodic = true_or_false(periodic, "periodic")
        layer = _layer(thickness, base, components, periodic)
        self.components = components
        self.periodic = periodic
        self.grid_shape = (nx, ny)
        self.cell = (dx, dy)
        #: ``(thickness, base)`` of the layer, or None for the half-space.
        self.layer = layer
        self._moduli = (E, nu)
        self._coupling = coupling
        self._fft_requested = fft  # None: chosen per grid, the coarse ones' too
        full = components == "full"
        pairs = _FULL_PAIRS if full else (((0, 1.0),),)
        parity = _FULL_PARITY if full else ((0, 0),)
        cells = (ny, nx)
        if periodic:
            spectra = _half_space_spectra(nx, ny, dx, dy, E, nu, full, coupling)
            if layer is not None:
                spectra[0] = spectra[0] * _layer_factor(_wavenumbers(nx, ny, dx, dy), nu, *layer)
            super().__init__(cells, pairs, parity, _workers(workers), fft, spectra=spectra)
            return
        X = (np.arange(nx) * dx)[None, :]
        Y = (np.arange(ny) * dy)[:, None]
        if full:
            tables = [
                np.broadcast_to(t, cells) for t in _cell_kernels(X, Y, dx, dy, E, nu, coupling)
            ]
        else:
            tables = [_normal_kernel(X, Y, dx, dy, E, nu)]
        super().__init__(cells, pairs, parity, _workers(workers), fft, tables=tables)

    def coarsening(self) -> Coarsening | None:
        """The same half-space on cells twice as large (2 x 2 cells merged, each component
        apart), for an even number of cells, at least :data:`COARSEST` per side after merging,
        along each axis; else None."""
        nx, ny = self.grid_shape
        if nx % 2 or ny % 2 or min(nx, ny) < 2 * COARSEST:
            return None
        (dx, dy), (E, nu) = self.cell, self._moduli
        thickness, base = self.layer if self.layer is not None else (None, "bonded")
        coarse = HalfSpaceOperator(
            nx // 2, ny // 2, 2 * dx, 2 * dy, E, nu, components=self.components,
            coupling=self._coupling, periodic=self.periodic, thickness=thickness, base=base,
            workers=self._workers, fft=self._fft_requested,
        )  # fmt: skip
        c = self._components

        def restrict(values: np.ndarray) -> np.ndarray:
            return values.reshape(ny // 2, 2, nx // 2, 2, c).mean(axis=(1, 3)).ravel()

        def prolong(forces: np.ndarray) -> np.ndarray:
            shared = forces.reshape(ny // 2, nx // 2, c) / 4.0
            return np.repeat(np.repeat(shared, 2, axis=0), 2, axis=1).ravel()

        return Coarsening(coarse, restrict, prolong)

    def preconditioner(self):
        """For ``components="normal"``: the inverse of the periodic kernel,
        ``E* |q| dx dy / 2`` (Westergaard's; over the layer's factor with a layer), applied
        by FFT on the whole period (periodic) or on the smallest box of cells around the
        contact, taken as periodic (non-periodic: there it approximates the inverse away from
        the box's edges). Else None."""
        if self.components != "normal":
            return None
        E, nu = self._moduli
        nx, ny = self.grid_shape
        layer = None if self.layer is None else (nu, *self.layer)
        return _SpectralInverse((ny, nx), self.cell, E / (1.0 - nu * nu), self.periodic, layer)


#: Fewest cells per side of the coarsest lattice of :meth:`HalfSpaceOperator.coarsening`.
COARSEST = 16


class _SpectralInverse:
    """``M(x, on)``: the half-space's inverse periodic kernel on the contact's box."""

    def __init__(self, cells: tuple[int, int], cell: tuple[float, float], E_star, periodic, layer):
        self._cells = cells
        self._cell = cell
        self._E_star = float(E_star)
        self._periodic = periodic
        self._layer = layer  # (nu, thickness, base) or None
        self._kernels: dict[tuple[int, int], np.ndarray] = {}

    def _kernel(self, shape: tuple[int, int]) -> np.ndarray:
        kernel = self._kernels.get(shape)
        if kernel is None:
            dx, dy = self._cell
            q = _wavenumbers(shape[1], shape[0], dx, dy)
            q.flat[0] = np.min(q[q > 0], initial=1.0 / max(dx, dy))  # definite on the mean
            kernel = 0.5 * self._E_star * dx * dy * q
            if self._layer is not None:
                kernel /= _layer_factor(q, *self._layer)
            if len(self._kernels) >= 8:
                self._kernels.clear()
            self._kernels[shape] = kernel
        return kernel

    def __call__(self, x: np.ndarray, on: np.ndarray) -> np.ndarray:
        field = np.where(on, x, 0.0).reshape(self._cells)
        mask = on.reshape(self._cells)
        out = np.zeros(self._cells)
        if self._periodic:
            box: tuple[slice, ...] = (slice(None), slice(None))
            shape = self._cells
        else:
            rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
            if rows.size == 0:
                return out.ravel()
            box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
            shape = (
                scipy.fft.next_fast_len(int(rows[-1] + 1 - rows[0]), real=True),
                scipy.fft.next_fast_len(int(cols[-1] + 1 - cols[0]), real=True),
            )
        part = field[box]
        spectrum = scipy.fft.rfft2(part, s=shape)
        spectrum *= self._kernel(shape)
        inverse = scipy.fft.irfft2(spectrum, s=shape, overwrite_x=True)
        out[box] = inverse[: part.shape[0], : part.shape[1]]
        return out.ravel()


_TINY = np.finfo(float).tiny
#: The layer factors are 1 to rounding beyond this ``|q| h`` (they differ by ~t^2 exp(-2 t)).
_THICK = 25.0


def _layer(thickness, base, components: str, periodic: bool) -> tuple[float, str] | None:
    """``(thickness, base)`` checked, or None for the half-space."""
    if thickness is None:
        return None
    thickness = _positive_length(thickness, "thickness")
    if base not in ("bonded", "frictionless"):
        raise InvalidInputError(f'base must be "bonded" or "frictionless", got {base!r}')
    if not periodic or components != "normal":
        raise InvalidInputError(
            "thickness: an elastic layer is implemented for periodic grids and the normal "
            'component only (periodic=True, components="normal")'
        )
    return thickness, base


def _wavenumbers(nx: int, ny: int, dx: float, dy: float) -> np.ndarray:
    """``|q|`` on the ``rfftn`` grid of a ``(ny, nx)`` lattice (rad/m)."""
    qx = 2.0 * np.pi * scipy.fft.rfftfreq(nx, dx)[None, :]
    qy = 2.0 * np.pi * scipy.fft.fftfreq(ny, dy)[:, None]
    return np.hypot(qx, qy)


def _layer_factor(q: np.ndarray, nu: float, thickness: float, base: str) -> np.ndarray:
    """The layer's normal surface compliance over the half-space's, per wavenumber ``q`` (see
    the module notes); at ``q = 0`` its limit 0."""
    t = np.minimum(q * thickness, _THICK)
    if base == "frictionless":
        factor = 2.0 * np.sinh(t) ** 2 / np.maximum(2.0 * t + np.sinh(2.0 * t), _TINY)
    else:
        kappa = 3.0 - 4.0 * nu
        factor = (0.5 * kappa * np.sinh(2.0 * t) - t) / (
            kappa * np.sinh(t) ** 2 + t * t + 4.0 * (1.0 - nu) ** 2
        )
    return np.where(q * thickness >= _THICK, 1.0, factor)


def _half_space_spectra(nx, ny, dx, dy, E, nu, full: bool, coupling: bool) -> list[np.ndarray]:
    """The periodic kernels on the ``rfftn`` grid of a ``(ny, nx)`` lattice, per unit force."""
    qx = 2.0 * np.pi * scipy.fft.rfftfreq(nx, dx)[None, :]
    qy = 2.0 * np.pi * scipy.fft.fftfreq(ny, dy)[:, None]
    q = np.hypot(qx, qy)
    inverse = np.divide(1.0, q, out=np.zeros_like(q), where=q > 0)  # the mean mode: 0
    G = E / (2.0 * (1.0 + nu))
    scale = 1.0 / (G * dx * dy)
    zz = scale * (1.0 - nu) * inverse
    if not full:
        return [zz]
    xx = scale * inverse * (1.0 - nu * (qx * inverse) ** 2)
    yy = scale * inverse * (1.0 - nu * (qy * inverse) ** 2)
    xy = -scale * nu * qx * qy * inverse**3
    c = 0.5 * (1.0 - 2.0 * nu) * scale if coupling else 0.0
    xz = -1j * c * qx * inverse**2
    yz = -1j * c * qy * inverse**2
    # on a Nyquist frequency q and -q are one mode: the odd parts vanish there
    if nx % 2 == 0:
        xy[:, nx // 2] = 0.0
        xz[:, nx // 2] = 0.0
    if ny % 2 == 0:
        xy[ny // 2, :] = 0.0
        yz[ny // 2, :] = 0.0
    return [xx, yy, xy, zz, xz, yz]


class HalfPlaneOperator(_LatticeOperator):
    """Flexibility of an elastic half-plane (plane strain) under a line of strips, by FFT.

    ``n`` strips of width ``dx`` centred at ``(i - (n - 1) / 2) dx`` carry each a uniform
    pressure; entry ``(i, j)`` is the normal displacement (m) at the centre of strip ``i``
    under a unit force per unit length (1 N/m) on strip ``j``, both along the outward normal.
    A line load ``P`` displaces the surface by ``(2 / (pi E*)) P ln(r0 / |x|)`` with
    ``E* = E / (1 - nu^2)``: in two dimensions the displacement is defined up to a rigid
    constant, fixed by the datum ``r0`` (``reference``), the distance from a load at which it
    displaces the surface by nothing. The strip integral is, with ``a = dx / 2`` and ``X`` the
    offset of the centres,

    .. math::

        W(X) = \\frac{2}{\\pi E^* dx}\\left(dx - (X + a) \\ln\\frac{|X + a|}{r_0}
            + (X - a) \\ln\\frac{|X - a|}{r_0}\\right).

    ``W`` is positive definite when ``r0`` exceeds a quarter of the line's length (the
    logarithmic capacity of a segment); the default ``r0`` is the line's length ``n dx``.
    Periodic, the line is one period and the kernel is Westergaard's
    ``u_hat = 2 p_hat / (E* |q|)``, of zero mean (no datum: see the module notes).

    With ``components="full"`` each strip has two entries, ``(x, z)`` (tangential, then normal
    along the outward normal): a tangential line load displaces the surface tangentially by the
    same kernel, and the coupling of Flamant's solution (Johnson 1985, sec. 2.2) adds
    ``c sgn(x_i - x_j)`` to the tangential displacement under an outward normal force, and
    ``-c sgn(x_i - x_j)`` to the outward normal displacement under a tangential one, with
    ``c = (1 - 2 nu)(1 + nu) / (2 E)`` (per N/m; a strip's own centre 0). Periodic, the
    coupling's spectrum is ``-i (1 - 2 nu)(1 + nu) / (E q)`` (zero at the mean and the Nyquist
    frequency), the same as the half-space's along one axis.

    Parameters
    ----------
    n : int
        Strips, >= 1.
    dx : float
        Strip width (m), > 0.
    young : float
        Young's modulus ``E`` (Pa), > 0.
    poisson : float
        Poisson's ratio ``nu``, in (-1, 0.5); plane strain.
    periodic : bool
        True: the line is one period (the spectral kernel); False: a finite line on an infinite
        half-plane (zero padding).
    components : {"normal", "full"}
        One entry per strip (the normal force and displacement), or two, ``(x, z)``.
    coupling : bool
        With ``"full"``: False drops the normal-tangential coupling (the ``(1 - 2 nu)`` terms).
    reference : float or None
        The datum ``r0`` (m), > 0, non-periodic only; None: ``n dx``.
    workers, fft
        As for :class:`HalfSpaceOperator`.

    Raises
    ------
    InvalidInputError
        An argument is of the wrong type or out of range, or ``reference`` is given with
        ``periodic``.
    """

    def __init__(
        self,
        n: int,
        dx: float,
        young: float,
        poisson: float,
        *,
        periodic: bool = False,
        components: str = "normal",
        coupling: bool = True,
        reference: float | None = None,
        workers: int | None = None,
        fft: str | None = None,
    ):
        n = _count(n, "n")
        dx = _positive_length(dx, "dx")
        E, nu = _material(young, poisson)
        periodic = true_or_false(periodic, "periodic")
        if components not in ("normal", "full"):
            raise InvalidInputError(f'components must be "normal" or "full", got {components!r}')
        coupling = true_or_false(coupling, "coupling")
        E_star = E / (1.0 - nu * nu)
        c = 0.5 * (1.0 - 2.0 * nu) * (1.0 + nu) / E if coupling else 0.0
        self.periodic = periodic
        self.components = components
        full = components == "full"
        # (x, z) per strip: the log kernel (kind 0) on both, the odd coupling (kind 1) between
        pairs = (((0, 1.0), (1, 1.0)), ((1, -1.0), (0, 1.0))) if full else (((0, 1.0),),)
        parity = ((0,), (1,)) if full else ((0,),)
        if periodic:
            if reference is not None:
                raise InvalidInputError(
                    "reference is for a non-periodic half-plane; a periodic one has "
                    "displacements of zero mean"
                )
            self.reference = None
            q = 2.0 * np.pi * scipy.fft.rfftfreq(n, dx)
            inverse = np.divide(1.0, q, out=np.zeros_like(q), where=q > 0)
            spectra: list[np.ndarray] = [2.0 / (E_star * dx) * inverse]
            if full:
                odd = -2j * c / dx * inverse
                if n % 2 == 0:
                    odd[n // 2] = 0.0  # q and -q are one mode there
                spectra.append(odd)
            super().__init__((n,), pairs, parity, _workers(workers), fft, spectra=spectra)
            return
        r0 = n * dx if reference is None else _positive_length(reference, "reference")
        self.reference = r0
        tables = [_strip_kernel(np.arange(n) * dx, dx, E_star, r0)]
        if full:  # c sgn(d) at the centres of the other strips, 0 at the strip's own
            tables.append(np.where(np.arange(n) > 0, c, 0.0))
        super().__init__((n,), pairs, parity, _workers(workers), fft, tables=tables)


def _strip_kernel(X: np.ndarray, dx: float, E_star: float, r0: float) -> np.ndarray:
    """Displacement (m) at offsets ``X`` from a strip of width ``dx`` under 1 N/m, datum ``r0``."""
    a = 0.5 * dx

    def t_log(t):  # t ln(|t| / r0), 0 at t = 0
        magnitude = np.abs(t)
        return t * np.log(np.where(magnitude > 0.0, magnitude, r0) / r0)

    return 2.0 / (np.pi * E_star * dx) * (dx - t_log(X + a) + t_log(X - a))


def composite_modulus(young1: float, poisson1: float, young2: float, poisson2: float) -> float:
    """The contact modulus ``E*`` of two elastic bodies, ``1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2``.

    Parameters
    ----------
    young1, young2 : float
        Young's moduli (Pa), > 0; ``math.inf`` for a rigid body (not both).
    poisson1, poisson2 : float
        Poisson's ratios, in (-1, 0.5].

    Returns
    -------
    float
        ``E*`` (Pa). The normal half-space operator of the pair is the one of a single body
        with ``young=E*`` and ``poisson=0`` (see the module notes).

    Raises
    ------
    InvalidInputError
        A modulus is not positive, both are infinite, or a ratio is out of range.

    Examples
    --------
    A steel ball on a rigid flat, and on an aluminium one (GPa):

    >>> round(composite_modulus(210e9, 0.3, float("inf"), 0.0) / 1e9, 2)
    230.77
    >>> round(composite_modulus(210e9, 0.3, 70e9, 0.33) / 1e9, 2)
    58.61
    """
    compliance = 0.0
    for young, poisson, which in ((young1, poisson1, "1"), (young2, poisson2, "2")):
        try:
            E = float(young)
        except (TypeError, ValueError):
            E = math.nan
        if not E > 0.0:  # NaN fails too
            raise InvalidInputError(
                f"young{which} must be a positive modulus in Pa (inf: rigid), got {young!r}"
            )
        nu = _finite_float(poisson, f"poisson{which}", "a finite number in (-1, 0.5]")
        if not -1.0 < nu <= 0.5:
            raise InvalidInputError(
                f"poisson{which} must be a finite number in (-1, 0.5], got {poisson!r}"
            )
        compliance += (1.0 - nu * nu) / E
    if compliance == 0.0:
        raise InvalidInputError("young1 and young2 are both infinite: two rigid bodies")
    return 1.0 / compliance
