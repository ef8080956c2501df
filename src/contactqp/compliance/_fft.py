"""Real FFT convolutions on a (padded) lattice, by scipy.fft or by pyFFTW.

:func:`transforms` returns an object with three methods, the whole of what the FFT operators
ask of an FFT library:

* ``convolve(field, kernel)``: the cropped inverse transform of ``kernel`` times the
  transform of ``field`` (zero padded to the transform's shape);
* ``forward(field)``: the padded real transform (a new array);
* ``inverse(spectrum)``: the cropped real inverse transform (a new array; ``spectrum`` may be
  overwritten).

``field`` has the lattice's shape, or that shape followed by one axis of columns (each column
transformed on its own). A 2-D lattice zero padded along y is transformed along x on its own
rows only, then along y, and back along x on the rows kept (a fifth less work than a 2-D
transform, and 1.7 times faster than ``scipy.fft.rfftn`` with ``s=`` measured here).

Which library (:func:`transforms` with ``fft=None``), by measurement (see
:mod:`contactqp.compliance.fft_halfspace`): pyFFTW (the ``fft`` extra), planned with
``FFTW_ESTIMATE`` (milliseconds) on aligned buffers owned by the object, takes 0.6 to 0.9 of
scipy.fft's time on periodic grids and 0.5 to 0.8 on padded grids up to 512 x 512, but 1.0
to 1.2 on padded grids from 1024 x 1024, where scipy.fft is chosen. Its buffers make a
product not re-entrant: a lock serialises products from several threads, and a pickled copy
plans afresh.
"""

from __future__ import annotations

import math
import os
import threading

import numpy as np
import scipy.fft

from ..errors import InvalidInputError
from ..optional import require

__all__ = ["FFT_LIBRARIES", "transforms"]

#: The accepted names of the ``fft`` argument.
FFT_LIBRARIES = ("scipy", "pyfftw")
#: Padded 2-D grids of this many points or more are transformed by scipy.fft by default.
_SCIPY_FROM = 1024 * 1024


def _pyfftw_installed() -> bool:
    try:
        import pyfftw  # noqa: F401
    except ImportError:
        return False
    return True


def transforms(shape: tuple[int, ...], crop: tuple[int, ...], workers: int | None, fft):
    """FFT convolutions of fields of shape ``crop`` padded to ``shape``.

    Parameters
    ----------
    shape, crop : tuple of int
        The transform's shape and the lattice's (``crop <= shape`` per axis).
    workers : int or None
        Threads (scipy.fft's convention: None one, negative counts from the CPU count).
    fft : {None, "scipy", "pyfftw"}
        The library; None: the faster one measured for this transform (see the module
        notes), scipy.fft if pyFFTW is not installed.

    Raises
    ------
    InvalidInputError
        ``fft`` is none of these.
    MissingDependencyError
        ``fft="pyfftw"`` and pyFFTW is not installed.
    """
    if fft is None:
        pruned = len(shape) == 2 and crop[0] < shape[0]
        large = math.prod(shape) >= _SCIPY_FROM
        fft = "pyfftw" if _pyfftw_installed() and not (pruned and large) else "scipy"
    if fft not in FFT_LIBRARIES:
        raise InvalidInputError(f'fft must be None, "scipy" or "pyfftw", got {fft!r}')
    if fft == "pyfftw":
        require("pyfftw", "the pyFFTW transforms", "fft")
        return _FFTW(shape, crop, workers)
    return _Scipy(shape, crop, workers)


class _Scipy:
    name = "scipy"

    def __init__(self, shape, crop, workers):
        self.shape = tuple(shape)
        self.axes = tuple(range(len(shape)))
        self.crop = tuple(slice(0, n) for n in crop)
        self.workers = workers
        # zero padded along y: transform along x the lattice's rows only, and back the rows kept
        self.pruned = len(shape) == 2 and crop[0] < shape[0]

    def forward(self, field):
        if self.pruned:
            rows = scipy.fft.rfft(field, n=self.shape[1], axis=1, workers=self.workers)
            return scipy.fft.fft(
                rows, n=self.shape[0], axis=0, workers=self.workers, overwrite_x=True
            )
        return scipy.fft.rfftn(field, s=self.shape, axes=self.axes, workers=self.workers)

    def inverse(self, spectrum):
        if self.pruned:
            rows = scipy.fft.ifft(spectrum, axis=0, workers=self.workers, overwrite_x=True)
            rows = rows[self.crop[0]]
            field = scipy.fft.irfft(rows, n=self.shape[1], axis=1, workers=self.workers)
            return field[:, self.crop[1]]
        field = scipy.fft.irfftn(
            spectrum, s=self.shape, axes=self.axes, workers=self.workers, overwrite_x=True
        )
        return field[self.crop]

    def convolve(self, field, kernel):
        spectrum = self.forward(field)
        spectrum *= kernel if field.ndim == len(self.shape) else kernel[..., None]
        return self.inverse(spectrum)


class _FFTW:
    name = "pyfftw"

    def __init__(self, shape, crop, workers):
        self.shape = tuple(shape)
        self.crop_shape = tuple(crop)
        self.workers = workers
        self.crop = tuple(slice(0, n) for n in crop)
        self._plan()

    def _plan(self):
        import pyfftw

        workers = self.workers
        if workers is None:
            threads = 1
        elif workers > 0:
            threads = workers
        else:  # scipy.fft's convention: -1 all CPUs, -2 all but one, ...
            threads = max(1, (os.cpu_count() or 1) + 1 + workers)
        half = self.shape[:-1] + (self.shape[-1] // 2 + 1,)
        flags = ("FFTW_ESTIMATE",)
        destroy = flags + ("FFTW_DESTROY_INPUT",)

        def plan(source, target, axes, backward=False):
            direction = "FFTW_BACKWARD" if backward else "FFTW_FORWARD"
            return pyfftw.FFTW(
                source, target, axes=axes, direction=direction, threads=threads,
                flags=destroy if backward and source is not target else flags,
            )  # fmt: skip

        self._spectrum = pyfftw.empty_aligned(half, dtype="complex128")
        rows = self.crop_shape[0]
        if len(self.shape) == 2 and rows < self.shape[0]:
            # zero padded along y: the x transforms of the padding rows are zero, and only
            # the first rows of the inverse are kept; 20 % less work than a 2-D transform
            self._real = pyfftw.empty_aligned((rows, self.shape[1]), dtype="float64")
            padded = pyfftw.empty_aligned(half, dtype="complex128")
            padded[...] = 0.0  # only its first rows are ever written
            self._out = pyfftw.empty_aligned((rows, self.shape[1]), dtype="float64")
            self._forward = [
                plan(self._real, padded[:rows], (1,)),
                plan(padded, self._spectrum, (0,)),
            ]
            self._inverse = [
                plan(self._spectrum, self._spectrum, (0,), backward=True),
                plan(self._spectrum[:rows], self._out, (1,), backward=True),
            ]
        else:
            self._real = pyfftw.empty_aligned(self.shape, dtype="float64")
            self._out = pyfftw.empty_aligned(self.shape, dtype="float64")
            axes = tuple(range(len(self.shape)))
            self._forward = [plan(self._real, self._spectrum, axes)]
            self._inverse = [plan(self._spectrum, self._out, axes, backward=True)]
        self._real[...] = 0.0  # the padding stays zero: only the crop is ever written
        self._result = self._out[self.crop]
        self._scale = 1.0 / math.prod(self.shape)
        self._lock = threading.Lock()

    def __getstate__(self):
        return {"shape": self.shape, "crop_shape": self.crop_shape, "workers": self.workers}

    def __setstate__(self, state):
        self.shape, self.crop_shape = state["shape"], state["crop_shape"]
        self.workers = state["workers"]
        self.crop = tuple(slice(0, n) for n in self.crop_shape)
        self._plan()

    @staticmethod
    def _transform(plans):
        for plan in plans:
            plan.execute()  # unnormalised: the inverse's 1 / N is applied to the crop only

    def forward(self, field):
        single = field.ndim == len(self.shape)
        out = np.empty(self._spectrum.shape + field.shape[len(self.shape) :], dtype=complex)
        with self._lock:
            for j in range(1 if single else field.shape[-1]):
                self._real[self.crop] = field if single else field[..., j]
                self._transform(self._forward)
                if single:
                    out[...] = self._spectrum
                else:
                    out[..., j] = self._spectrum
        return out

    def inverse(self, spectrum):
        out = np.empty(self.crop_shape + spectrum.shape[len(self.shape) :])
        single = spectrum.ndim == len(self.shape)
        with self._lock:
            for j in range(1 if single else spectrum.shape[-1]):
                self._spectrum[...] = spectrum if single else spectrum[..., j]
                self._transform(self._inverse)
                np.multiply(self._result, self._scale, out=out if single else out[..., j])
        return out

    def convolve(self, field, kernel):
        single = field.ndim == len(self.shape)
        out = np.empty(field.shape)
        with self._lock:
            for j in range(1 if single else field.shape[-1]):
                self._real[self.crop] = field if single else field[..., j]
                self._transform(self._forward)
                np.multiply(self._spectrum, kernel, out=self._spectrum)
                self._transform(self._inverse)
                np.multiply(self._result, self._scale, out=out if single else out[..., j])
        return out
