"""Problem files: FCLIB HDF5 (:mod:`contactqp.io.fclib`), Siconos text (:mod:`.siconos`)."""

from .fclib import read_problem, write_problem, write_solution

__all__ = ["read_problem", "write_problem", "write_solution"]
