"""One product of the FFT half-space operator: scipy.fft against pyFFTW, one thread.

The product of :class:`contactqp.compliance.HalfSpaceOperator` (normal, non-periodic) is one
real forward transform of the zero-padded grid, a multiplication by the kernel's (real)
transform and one real inverse transform, cropped. Timed three ways on the same padded sizes:

* ``scipy``: ``W @ f`` with ``fft="scipy"`` (``scipy.fft.rfftn`` with ``s=``, padding
  included, ``irfftn``, crop and copy);
* ``pyfftw``: ``W @ f`` with ``fft="pyfftw"`` (the library's default when pyFFTW is
  installed: ``FFTW_ESTIMATE`` plans on aligned buffers, made with the operator);
* ``measure``: bare pyFFTW ``FFTW`` objects planned with ``FFTW_MEASURE`` (about 1 s of
  planning per size), the best case for FFTW.

CPU time (``time.process_time``), runs alternated between the contenders, median of the
repetitions. Run from the repository root::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_fft.py [--sizes 256,512,1024]

pyFFTW is not a dependency: install it (``pip install pyfftw``) to time it; without it the
``pyfftw`` column says so.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import scipy.fft

from contactqp.compliance import HalfSpaceOperator

try:
    import pyfftw
except ImportError:  # pragma: no cover - optional
    pyfftw = None


def _pyfftw_product(padded_shape):
    real = pyfftw.empty_aligned(padded_shape, dtype="float64")
    half = pyfftw.empty_aligned((padded_shape[0], padded_shape[1] // 2 + 1), dtype="complex128")
    out = pyfftw.empty_aligned(padded_shape, dtype="float64")
    forward = pyfftw.FFTW(real, half, axes=(0, 1), flags=("FFTW_MEASURE",), threads=1)
    inverse = pyfftw.FFTW(
        half, out, axes=(0, 1), direction="FFTW_BACKWARD", flags=("FFTW_MEASURE",), threads=1
    )
    real[:] = 0.0

    def product(f, kernel, n):
        real[:n, :n] = f
        forward()
        half[:] *= kernel
        inverse()  # normalised by pyFFTW (1 / N), like irfft2
        return out[:n, :n]

    return product


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="256,512,1024", help="padded grid sides")
    parser.add_argument("--repeat", type=int, default=0, help="repetitions (0: by size)")
    args = parser.parse_args()
    print(f"scipy {scipy.__version__}, numpy {np.__version__}, ", end="")
    print(f"pyfftw {pyfftw.__version__}" if pyfftw else "pyfftw not installed")
    print(f"{'padded':>8} {'scipy':>10} {'pyfftw':>10} {'measure':>10} {'pyfftw/scipy':>13}")
    for side in (int(s) for s in args.sizes.split(",")):
        n = side // 2  # grid n x n pads to 2n - 1, whose fast real length is 2n for these
        W = HalfSpaceOperator(n, n, 1e-5, 1e-5, 210e9, 0.3, fft="scipy")
        padded_shape = W._fft_shape
        kernel = W._spectra[0]
        f = np.random.default_rng(0).random((n, n))
        reference = (W @ f.ravel()).reshape(n, n)
        contenders = {"scipy": lambda f=f, W=W: W @ f.ravel()}
        if pyfftw is not None:
            V = HalfSpaceOperator(n, n, 1e-5, 1e-5, 210e9, 0.3, fft="pyfftw")
            product = _pyfftw_product(padded_shape)
            contenders["pyfftw"] = lambda f=f, V=V: V @ f.ravel()
            contenders["measure"] = lambda f=f, k=kernel, n=n, product=product: product(f, k, n)
        for name, run in contenders.items():  # the same answer, and warm
            answer = np.asarray(run()).reshape(n, n)
            error = np.max(np.abs(answer - reference)) / np.max(np.abs(reference))
            assert error < 1e-12, (name, error)
        repeat = args.repeat or max(5, int(2e7 / side**2))
        times: dict[str, list[float]] = {name: [] for name in contenders}
        for _ in range(repeat):
            for name, run in contenders.items():
                start = time.process_time()
                run()
                times[name].append(time.process_time() - start)
        median = {name: statistics.median(values) * 1e3 for name, values in times.items()}
        if pyfftw is None:
            print(f"{padded_shape[0]:>5}^2 {median['scipy']:>8.2f}ms {'-':>10} {'-':>10}")
            continue
        print(
            f"{padded_shape[0]:>5}^2 {median['scipy']:>8.2f}ms {median['pyfftw']:>8.2f}ms "
            f"{median['measure']:>8.2f}ms {median['pyfftw'] / median['scipy']:>13.2f}"
        )


if __name__ == "__main__":
    main()
