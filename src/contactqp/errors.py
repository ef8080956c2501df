"""The exception and warning tree of contactqp: every class the library raises or issues is here.

Every error the library raises on purpose derives from :class:`ContactError`; errors about bad
input also derive from :class:`ValueError` so that generic callers can catch them as such.

Which error, or a result, when a solve goes wrong:

* :class:`InvalidInputError` (exit status 2 on the command line): the input is wrong, whatever
  the method: a shape, a non-finite value, a matrix that is not positive semidefinite, an
  unknown option or backend name, a setting the backend refuses. It is raised before any work
  is done where it can be.
* :class:`MissingDependencyError` (exit 2): an optional package is not installed; the message,
  written by :func:`contactqp.optional.require`, says which ``pip install`` fixes it.
* :class:`SolverError` (exit 1): the input is valid but the method produced no answer: a
  backend raised, reported no solution, or returned no point or a non-finite one; a
  factorisation the method cannot do without failed. Nothing is returned then, in particular
  no result filled with NaN.
* A result with ``success`` (``converged``) False (exit 1): the method produced a finite
  answer that does not meet its tolerance or its certificate (an iteration cap, a stall, an
  inexact backend status). Its message says why; the answer is there to be examined.
* :class:`UnsupportedProblemError` (exit 2): the input is valid but asks for what this version
  cannot do.
"""

__all__ = [
    "ContactError",
    "InvalidInputError",
    "NotPositiveDefiniteError",
    "RigidBodyModeError",
    "FileFormatError",
    "FileLayoutError",
    "UnsupportedProblemError",
    "MissingDependencyError",
    "SolverError",
    "ReferenceSolveError",
    "LayersError",
    "ContactWarning",
    "SymmetrizedWarning",
    "PureNumpyKernelsWarning",
]


class ContactError(Exception):
    """Base of every error raised by contactqp."""


class InvalidInputError(ContactError, ValueError):
    """An argument has the wrong shape, a non-finite value or an inconsistent content."""


class NotPositiveDefiniteError(InvalidInputError):
    """A matrix that must be symmetric positive (semi)definite is not."""


class RigidBodyModeError(NotPositiveDefiniteError):
    """The stiffness matrix is singular: the model can move without deforming."""


class FileFormatError(InvalidInputError):
    """A file is missing, unreadable or not in the expected format."""


class FileLayoutError(FileFormatError):
    """A part of a file breaks its layout; the message names the part, the reader adds the file.

    The FCLIB readers raise it while they read and give it to the caller as a
    :class:`FileFormatError` that names the file.
    """


class UnsupportedProblemError(ContactError):
    """The problem is valid but asks for something this version cannot solve."""


class MissingDependencyError(ContactError, ImportError):
    """An optional backend is not installed; the message says which ``pip install`` fixes it."""


class SolverError(ContactError):
    """A method produced no answer to valid input (a backend failed or found no solution)."""


class ReferenceSolveError(SolverError):
    """The finite-element reference contact solve failed or could not be verified."""


class LayersError(SolverError):
    """A step of the load history was not solved."""


class ContactWarning(UserWarning):
    """Base of every warning issued by contactqp."""


class SymmetrizedWarning(ContactWarning):
    """A nearly symmetric matrix was replaced by its symmetric part."""


class PureNumpyKernelsWarning(ContactWarning):
    """The compiled kernels are not built: the slower pure-numpy ones are used instead."""
