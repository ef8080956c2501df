"""Build of the compiled part: the per-contact loops of :mod:`contactqp.kernels` (Cython).

The extension is optional: where it cannot be compiled (no C compiler, say) the build warns and
goes on, and the package uses its pure-numpy kernels (:mod:`contactqp.kernels.pure_numpy`).
Everything else is declared in ``pyproject.toml``.
"""

import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.errors import CCompilerError, ExecError, PlatformError

KERNELS = Extension("contactqp.kernels.compiled", ["src/contactqp/kernels/compiled.pyx"])

#: What a failed compilation raises: no compiler, a compiler that fails, no build tools.
BUILD_FAILURES = (CCompilerError, ExecError, PlatformError, OSError)


class OptionalBuildExt(build_ext):
    """``build_ext`` that leaves out an extension it cannot build, with a warning on stderr.

    The extensions left out are dropped from :attr:`extensions`, so that the steps after the
    build (copies into the source tree for an editable install, the list of outputs) do not look
    for them.
    """

    def run(self):
        try:
            super().run()
        except BUILD_FAILURES as exc:  # e.g. no compiler found while setting one up
            self.skipped("the compiled extensions", exc)
            self.extensions = []

    def build_extensions(self):
        self.check_extensions_list(self.extensions)
        built = []
        for ext in self.extensions:
            try:
                self.build_extension(ext)
            except BUILD_FAILURES as exc:
                self.skipped(ext.name, exc)
            else:
                built.append(ext)
        self.extensions = built

    @staticmethod
    def skipped(name: str, exc: Exception) -> None:
        """Say on stderr which extension is left out and why."""
        print(
            f"WARNING: {name} not built ({type(exc).__name__}: {exc}); contactqp will use "
            f"its pure-numpy kernels (slower on small problems)",
            file=sys.stderr,
        )


if __name__ == "__main__":
    setup(ext_modules=[KERNELS], cmdclass={"build_ext": OptionalBuildExt})
