"""Build of the compiled part: the per-contact loops of :mod:`contactqp.kernels` (Cython).

Everything else is declared in ``pyproject.toml``.
"""

from setuptools import Extension, setup

setup(ext_modules=[Extension("contactqp.kernels", ["src/contactqp/kernels.pyx"])])
