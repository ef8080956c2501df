"""The one set of per-contact status labels, shared by every result, file and plot.

Each result's ``contact_status`` holds one :class:`ContactStatus` code (an integer) per contact:

* ``open`` (0): the contact carries no force (measured from the friction cone's apex);
* ``stick`` (1): closed, with friction, and no slip in the step;
* ``slip`` (2): closed, with friction, and slipping;
* ``closed`` (3): carries force, without a tangential law (frictionless contact);
* ``fastened`` (4): closed by a fastener (a bilateral constraint).

The codes of ``open``, ``stick`` and ``slip`` are those the frictional results and their files
have always used.
"""

from __future__ import annotations

import enum

import numpy as np

__all__ = ["ContactStatus", "STATUS_LABELS", "status_labels", "status_counts"]


class ContactStatus(enum.IntEnum):
    """Status of one contact; the integer is the code stored in ``contact_status`` arrays."""

    OPEN = 0
    STICK = 1
    SLIP = 2
    CLOSED = 3
    FASTENED = 4

    @property
    def label(self) -> str:
        """The lower-case label written in tables, CSV files and plots, e.g. ``"stick"``."""
        return self.name.lower()


#: Label of each code, by index: ``STATUS_LABELS[code]``.
STATUS_LABELS: tuple[str, ...] = tuple(status.label for status in ContactStatus)


def status_labels(codes) -> list[str]:
    """The label of each status code in ``codes`` (array_like of int)."""
    return [STATUS_LABELS[int(code)] for code in np.asarray(codes).reshape(-1)]


def status_counts(codes) -> dict[str, int]:
    """``{label: count}`` of ``codes`` for every label, in code order (zeros included)."""
    counts = np.bincount(np.asarray(codes, dtype=int).reshape(-1), minlength=len(STATUS_LABELS))
    return {label: int(count) for label, count in zip(STATUS_LABELS, counts, strict=True)}
