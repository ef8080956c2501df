"""The exception and warning tree of contactqp.

Every error the library raises on purpose derives from :class:`ContactError`; errors about bad
input also derive from :class:`ValueError` so that generic callers can catch them as such.
"""

__all__ = [
    "ContactError",
    "InvalidInputError",
    "NotPositiveDefiniteError",
    "FileFormatError",
    "UnsupportedProblemError",
    "MissingDependencyError",
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


class FileFormatError(InvalidInputError):
    """A file is missing, unreadable or not in the expected format."""


class UnsupportedProblemError(ContactError):
    """The problem is valid but asks for something this version cannot solve."""


class MissingDependencyError(ContactError, ImportError):
    """An optional backend is not installed; the message says which ``pip install`` fixes it."""


class ContactWarning(UserWarning):
    """Base of every warning issued by contactqp."""


class SymmetrizedWarning(ContactWarning):
    """A nearly symmetric matrix was replaced by its symmetric part."""


class PureNumpyKernelsWarning(ContactWarning):
    """The compiled kernels are not built: the slower pure-numpy ones are used instead."""
