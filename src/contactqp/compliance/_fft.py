"""Real FFT convolutions on a (padded) lattice, by scipy.fft or by pyFFTW.

:func:`transforms` returns an object with three methods, the whole of what the FFT operators
ask of an FFT library:

* ``convolve(field, kernel)``: the cropped inverse transform of ``kernel`` times the
  transform of ``field`` (zero padded to the transform's shape);
* ``forward(field)``: the padded real transform (a new array);
* ``inverse(spectrum)``: the cropped real inverse transform (a new array; ``spectrum`` may be
  overwritten).

``field`` has the lattice's shape, or that shape followed by one axis of columns (each column
transformed on its own). pyFFTW (the ``fft`` extra) is used when it is installed: planned with
``FFTW_ESTIMATE`` (a few ms) on aligned buffers owned by the object, it took 0.4 to 0.6 of
scipy.fft's time per product here (see :mod:`contactqp.compliance.fft_halfspace`). Its buffers
make a product not re-entrant: a lock serialises products from several threads, and a pickled
copy plans afresh.
"""

from __future__ import annotations

import os
import threading

import numpy as np
import scipy.fft

from ..errors import InvalidInputError
from ..optional import require

__all__ = ["FFT_LIBRARIES", "transforms"]

#: The accepted names of the ``fft`` argument.
FFT_LIBRARIES = ("scipy", "pyfftw")


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
        The library; None: pyFFTW if it is installed, else scipy.fft.

    Raises
    ------
    InvalidInputError
        ``fft`` is none of these.
    MissingDependencyError
        ``fft="pyfftw"`` and pyFFTW is not installed.
    """
    if fft is None:
        fft = "pyfftw" if _pyfftw_installed() else "scipy"
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

    def forward(self, field):
        return scipy.fft.rfftn(field, s=self.shape, axes=self.axes, workers=self.workers)

    def inverse(self, spectrum):
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
        self._real = pyfftw.empty_aligned(self.shape, dtype="float64")
        self._real[...] = 0.0  # the padding stays zero: only the crop is ever written
        self._half = pyfftw.empty_aligned(half, dtype="complex128")
        self._out = pyfftw.empty_aligned(self.shape, dtype="float64")
        axes = tuple(range(len(self.shape)))
        flags = ("FFTW_ESTIMATE",)
        self._forward = pyfftw.FFTW(self._real, self._half, axes=axes, flags=flags, threads=threads)
        self._inverse = pyfftw.FFTW(
            self._half,
            self._out,
            axes=axes,
            direction="FFTW_BACKWARD",
            flags=flags + ("FFTW_DESTROY_INPUT",),
            threads=threads,
        )
        self._lock = threading.Lock()

    def __getstate__(self):
        return {"shape": self.shape, "crop_shape": self.crop_shape, "workers": self.workers}

    def __setstate__(self, state):
        self.shape, self.crop_shape = state["shape"], state["crop_shape"]
        self.workers = state["workers"]
        self.crop = tuple(slice(0, n) for n in self.crop_shape)
        self._plan()

    def forward(self, field):
        single = field.ndim == len(self.shape)
        out = np.empty(self._half.shape + field.shape[len(self.shape) :], dtype=complex)
        with self._lock:
            for j in range(1 if single else field.shape[-1]):
                self._real[self.crop] = field if single else field[..., j]
                self._forward()
                if single:
                    out[...] = self._half
                else:
                    out[..., j] = self._half
        return out

    def inverse(self, spectrum):
        out = np.empty(self.crop_shape + spectrum.shape[len(self.shape) :])
        single = spectrum.ndim == len(self.shape)
        with self._lock:
            for j in range(1 if single else spectrum.shape[-1]):
                self._half[...] = spectrum if single else spectrum[..., j]
                self._inverse()
                if single:
                    out[...] = self._out[self.crop]
                else:
                    out[..., j] = self._out[self.crop]
        return out

    def convolve(self, field, kernel):
        single = field.ndim == len(self.shape)
        out = np.empty(field.shape)
        with self._lock:
            for j in range(1 if single else field.shape[-1]):
                self._real[self.crop] = field if single else field[..., j]
                self._forward()
                np.multiply(self._half, kernel, out=self._half)
                self._inverse()
                if single:
                    out[...] = self._out[self.crop]
                else:
                    out[..., j] = self._out[self.crop]
        return out
