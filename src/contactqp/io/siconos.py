"""Reader of the Siconos ``.dat`` text format for frictional-contact problems.

Layout (whitespace-separated tokens; only the sparse dumps are line-oriented)::

    local :  d  nc  <matrix W>  q (d*nc values)  mu (nc values)  [flag]
    global:  d  nc  <matrix M>  <matrix H>  f (ndof values)  w (d*nc values)  mu (nc values)  [flag]

Some Siconos versions end the file with one more integer (0 or 1); it is ignored.

A matrix block is ``storage rows cols`` followed by

* storage 0, dense: ``rows cols`` again, then ``rows*cols`` values in column-major order;
* storage 1, sparse-block (SBM): ``nbblocks``; if non-zero, ``blocknumber0 blocknumber1``
  (numbers of block rows and columns), the cumulative row ends of the block rows
  (``blocknumber0`` ints) and column ends of the block columns (``blocknumber1`` ints),
  ``filled1 filled2``, ``filled1`` block-row pointers, ``filled2`` block-column indices, then
  for every block in row order its number and its values (column-major). Blocks need not be
  square (the ``H`` of global problems);
* storage 2, sparse: an origin code (1 triplet, 2 compressed columns, 3 compressed rows) on its
  own line, then the text dump of CSparse's ``cs_print`` (``%g``: about 6 significant digits).

Precision: the problem is the one written, digit for digit. Each array's significant digits
(those of its longest non-integer value; a value without a decimal point or exponent is exact) are
recorded in the problem's ``digits`` when from 4 to 15 (e.g. ``{"W": 6}`` for a ``cs_print``
dump, 7 for ``%e``; an array whose values all have at most 3 digits, such as ``0.5 1.25``, is
taken as written by hand, exactly), so that a solution can say how far the rounding of the data
limits its meaning for the problem the file was written from
(:func:`contactqp.core.local_problem.accuracy_limits`).

Local or global is decided by content, not by the file name: the tokens are first read as a
local problem, which is accepted only if ``W`` is ``(d*nc) x (d*nc)`` and at most one integer
token is left over; otherwise they are read as a global problem under the same end rule.
A global file can never pass as local: after ``M`` it still holds ``H`` and ``f``, many more
than one token.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ..core.local_problem import GlobalProblem, LocalProblem
from ..errors import ContactError, FileFormatError, FileLayoutError

__all__ = ["read_dat", "parse_dat"]


_CS_COMPRESSED = re.compile(r"^\s*(\d+)-by-(\d+),\s*nzmax:\s*(-?\d+)\s+nnz:\s*(-?\d+)")
_CS_TRIPLET = re.compile(r"^\s*triplet:\s*(\d+)-by-(\d+),\s*nzmax:\s*(-?\d+)\s+nnz:\s*(-?\d+)")
_CS_COL = re.compile(r"^\s*col\s+(\d+)\s*:\s*locations\s+(-?\d+)\s+to\s+(-?\d+)\s*$")
_CS_ENTRY = re.compile(r"^\s*(\d+)\s*:\s*(\S+)\s*$")
_CS_TRIPLET_ENTRY = re.compile(r"^\s*(\d+)\s+(\d+)\s*:\s*(\S+)\s*$")


#: Arrays written with at least this many significant digits are exact doubles; with fewer than
#: SHORT_DIGITS everywhere, exact hand-written values.
FULL_DIGITS, SHORT_DIGITS = 16, 4


def _significant_digits(tokens) -> int:
    """Largest number of significant digits among the non-integer number tokens (0 if none)."""
    most = 0
    for tok in tokens:
        mantissa = tok.split("e")[0].split("E")[0]
        if mantissa == tok and "." not in tok:
            continue  # an integer is exact
        most = max(most, len(mantissa.lstrip("+-").replace(".", "").lstrip("0")))
    return most


class _Tokens:
    """Whitespace tokens of a text, read in order, with line-level access for CSparse dumps.

    ``digits`` is the largest :func:`_significant_digits` of the numbers read by
    :meth:`floats` (or noted by :meth:`note_digits`) since it was last reset to 0.
    """

    def __init__(self, text):
        self.lines = text.splitlines()
        self.li = 0  # index of the next line to split
        self.toks = []  # tokens of the current line
        self.ti = 0  # next token in self.toks
        self.digits = 0

    def note_digits(self, tokens):
        self.digits = max(self.digits, _significant_digits(tokens))

    def state(self):
        return (self.li, self.toks, self.ti)

    def restore(self, state):
        self.li, self.toks, self.ti = state

    def where(self):
        return f"line {self.li}"

    def _fill(self, what):
        while self.ti >= len(self.toks):
            if self.li >= len(self.lines):
                raise FileLayoutError(f"unexpected end of file while reading {what}")
            self.toks = self.lines[self.li].split()
            self.ti = 0
            self.li += 1

    def word(self, what):
        self._fill(what)
        tok = self.toks[self.ti]
        self.ti += 1
        return tok

    def int(self, what, minimum=0):
        tok = self.word(what)
        try:
            value = int(tok)
        except ValueError:
            raise FileLayoutError(
                f"expected an integer ({what}) at {self.where()}, got {tok!r}"
            ) from None
        if value < minimum:
            raise FileLayoutError(f"{what} must be >= {minimum} at {self.where()}, got {value}")
        return value

    def ints(self, count, what):
        return np.array([self.int(what) for _ in range(count)], dtype=np.int64)

    def floats(self, count, what):
        out = []
        need = count
        while need > 0:
            self._fill(what)
            chunk = self.toks[self.ti : self.ti + need]
            self.ti += len(chunk)
            need -= len(chunk)
            out.extend(chunk)
        self.note_digits(out)
        try:
            return np.array(out, dtype=float)
        except ValueError:
            bad = next(t for t in out if not _is_float(t))
            raise FileLayoutError(
                f"expected a number ({what}) near {self.where()}, got {bad!r}"
            ) from None

    def rest_of_line_empty(self):
        return self.ti >= len(self.toks)

    def next_line(self):
        """Return the next whole line (the current one must be fully consumed)."""
        if self.li >= len(self.lines):
            return None
        line = self.lines[self.li]
        self.li += 1
        self.toks, self.ti = [], 0
        return line

    def peek_line(self):
        return self.lines[self.li] if self.li < len(self.lines) else None

    def remaining(self):
        rest = self.toks[self.ti :]
        for line in self.lines[self.li :]:
            rest.extend(line.split())
            if len(rest) > 8:
                break
        return rest


def _is_float(tok):
    try:
        float(tok)
    except ValueError:
        return False
    return True


def _read_dense(tk, rows, cols, what):
    r2 = tk.int(f"{what} dense row count")
    c2 = tk.int(f"{what} dense column count")
    if (r2, c2) != (rows, cols):
        raise FileLayoutError(
            f"{what}: dense header {r2}x{c2} differs from the block size {rows}x{cols}"
        )
    values = tk.floats(rows * cols, f"{what} dense values")
    return values.reshape(cols, rows).T.copy()  # column-major


def _read_sbm(tk, rows, cols, what):
    import scipy.sparse as sp

    nbblocks = tk.int(f"{what} SBM number of blocks")
    if nbblocks == 0:
        return sp.csr_matrix((rows, cols))
    nbr = tk.int(f"{what} SBM number of block rows", 1)
    nbc = tk.int(f"{what} SBM number of block columns", 1)
    row_ends = tk.ints(nbr, f"{what} SBM block-row ends")
    col_ends = tk.ints(nbc, f"{what} SBM block-column ends")
    filled1 = tk.int(f"{what} SBM filled1", 1)
    filled2 = tk.int(f"{what} SBM filled2")
    rowptr = tk.ints(filled1, f"{what} SBM block-row pointers")
    colidx = tk.ints(filled2, f"{what} SBM block-column indices")
    if row_ends[-1] != rows or col_ends[-1] != cols:
        raise FileLayoutError(
            f"{what}: SBM block sizes end at {row_ends[-1]}x{col_ends[-1]}, "
            f"not at the matrix size {rows}x{cols}"
        )
    if (
        np.any(np.diff(row_ends) <= 0)
        or np.any(np.diff(col_ends) <= 0)
        or row_ends[0] <= 0
        or col_ends[0] <= 0
    ):
        raise FileLayoutError(f"{what}: SBM block-row or block-column ends are not increasing")
    if (
        filled1 - 1 > nbr
        or rowptr[0] != 0
        or rowptr[-1] != filled2
        or np.any(np.diff(rowptr) < 0)
        or filled2 != nbblocks
        or (filled2 and colidx.max() >= nbc)
    ):
        raise FileLayoutError(f"{what}: inconsistent SBM index arrays")
    row_start = np.concatenate(([0], row_ends[:-1]))
    col_start = np.concatenate(([0], col_ends[:-1]))
    rr, cc, X = [], [], []
    for brow in range(filled1 - 1):
        r0, nr = row_start[brow], row_ends[brow] - row_start[brow]
        for blk in range(rowptr[brow], rowptr[brow + 1]):
            number = tk.int(f"{what} SBM block number")
            if number != blk:
                raise FileLayoutError(
                    f"{what}: SBM block number {number} found where {blk} was expected"
                )
            bcol = colidx[blk]
            c0, nc = col_start[bcol], col_ends[bcol] - col_start[bcol]
            vals = tk.floats(nr * nc, f"{what} SBM block {blk}")
            jj, ii = np.meshgrid(np.arange(nc), np.arange(nr), indexing="ij")  # column-major
            rr.append(r0 + ii.ravel())
            cc.append(c0 + jj.ravel())
            X.append(vals)
    if not X:
        return sp.csr_matrix((rows, cols))
    return sp.csr_matrix(
        (np.concatenate(X), (np.concatenate(rr), np.concatenate(cc))), shape=(rows, cols)
    )


def _read_cs_dump(tk, rows, cols, what):
    import scipy.sparse as sp

    origin = tk.int(f"{what} sparse origin code")
    if origin not in (1, 2, 3):
        raise FileLayoutError(f"{what}: unknown sparse origin code {origin} (expected 1, 2 or 3)")
    if not tk.rest_of_line_empty():
        raise FileLayoutError(f"{what}: unexpected text after the sparse origin code")
    line = tk.next_line()
    if line is not None and line.lstrip().startswith("CSparse"):
        line = tk.next_line()
    if line is None:
        raise FileLayoutError(f"{what}: unexpected end of file in the CSparse header")
    head = (_CS_TRIPLET if origin == 1 else _CS_COMPRESSED).match(line)
    if not head:
        raise FileLayoutError(f"{what}: cannot read the CSparse header {line.strip()!r}")
    m, n, _, nnz = (int(g) for g in head.groups())
    if (m, n) != (rows, cols):
        raise FileLayoutError(
            f"{what}: CSparse size {m}x{n} differs from the block size {rows}x{cols}"
        )
    rr, cc, X = [], [], []
    outer = -1
    while True:
        line = tk.peek_line()
        if line is None:
            break
        if origin == 1:
            mt = _CS_TRIPLET_ENTRY.match(line)
            if not mt:
                break
            rr.append(int(mt.group(1)))
            cc.append(int(mt.group(2)))
            X.append(mt.group(3))
        else:
            mc = _CS_COL.match(line)
            if mc:
                outer = int(mc.group(1))
            else:
                me = _CS_ENTRY.match(line)
                if not me or outer < 0:
                    break
                rr.append(outer)
                cc.append(int(me.group(1)))
                X.append(me.group(2))
        tk.next_line()
    if len(X) != nnz:
        raise FileLayoutError(f"{what}: CSparse dump holds {len(X)} entries, its header says {nnz}")
    if origin == 2:  # compressed columns: the outer index is the column
        rr, cc = cc, rr
    try:
        x = np.array(X, dtype=float)
    except ValueError:
        raise FileLayoutError(f"{what}: a CSparse entry value is not a number") from None
    tk.note_digits(X)
    row_index = np.asarray(rr, dtype=np.int64)
    column_index = np.asarray(cc, dtype=np.int64)
    if nnz and (row_index.max() >= rows or column_index.max() >= cols):
        raise FileLayoutError(f"{what}: a CSparse index is outside the {rows}x{cols} matrix")
    return sp.csr_matrix((x, (row_index, column_index)), shape=(rows, cols))


def _read_matrix(tk, what):
    storage = tk.int(f"{what} storage type")
    rows = tk.int(f"{what} row count")
    cols = tk.int(f"{what} column count")
    if storage == 0:
        return _read_dense(tk, rows, cols, what)
    if storage == 1:
        return _read_sbm(tk, rows, cols, what)
    if storage == 2:
        return _read_cs_dump(tk, rows, cols, what)
    raise FileLayoutError(f"{what}: unknown storage type {storage} (expected 0, 1 or 2)")


def _read(tk, digits, name, read):
    """``read()``'s array, recording in ``digits[name]`` its significant digits if limited."""
    tk.digits = 0
    value = read()
    if SHORT_DIGITS <= tk.digits < FULL_DIGITS:
        digits[name] = tk.digits
    return value


def _check_end(tk):
    rest = tk.remaining()
    if len(rest) > 1 or (rest and not re.fullmatch(r"[+-]?\d+", rest[0])):
        shown = " ".join(rest[:3])
        raise FileLayoutError(f"unexpected extra content at the end: {shown!r}...")


def _parse_local(tk: _Tokens, d: int, nc: int, title: str) -> LocalProblem:
    m = d * nc
    digits: dict[str, int] = {}
    W = _read(tk, digits, "W", lambda: _read_matrix(tk, "W"))
    if W.shape != (m, m):
        raise FileLayoutError(
            f"W is {W.shape[0]}x{W.shape[1]}, expected {m}x{m} for d={d}, nc={nc}"
        )
    q = _read(tk, digits, "q", lambda: tk.floats(m, "q"))
    mu = tk.floats(nc, "mu")
    _check_end(tk)
    return LocalProblem(W, q, mu, d, title, digits=digits)


def _parse_global(tk: _Tokens, d: int, nc: int, title: str) -> GlobalProblem:
    m = d * nc
    digits: dict[str, int] = {}
    M = _read(tk, digits, "M", lambda: _read_matrix(tk, "M"))
    ndof = M.shape[0]
    if M.shape != (ndof, ndof):
        raise FileLayoutError(f"M is {M.shape[0]}x{M.shape[1]}, not square")
    H = _read(tk, digits, "H", lambda: _read_matrix(tk, "H"))
    if H.shape != (ndof, m):
        raise FileLayoutError(f"H is {H.shape[0]}x{H.shape[1]}, expected {ndof}x{m}")
    f = _read(tk, digits, "f", lambda: tk.floats(ndof, "f"))
    w = _read(tk, digits, "w", lambda: tk.floats(m, "w"))
    mu = tk.floats(nc, "mu")
    _check_end(tk)
    return GlobalProblem(M, H, f, w, mu, d, title, digits=digits)


def parse_dat(text: str, name: str = "<string>", title: str = "") -> LocalProblem | GlobalProblem:
    """Parse the content of a Siconos ``.dat`` file.

    Parameters
    ----------
    text : str
        File content.
    name : str, optional
        Shown in error messages.
    title : str, optional
        Stored as the problem's title.

    Returns
    -------
    LocalProblem or GlobalProblem
        The global form is returned as read, not condensed.

    Raises
    ------
    FileFormatError
        If the text is neither layout (the message gives both reasons) or the content is
        invalid (non-finite values, negative ``mu``, ...).
    """
    tk = _Tokens(text)
    try:
        d = tk.int("space dimension")
        nc = tk.int("number of contacts")
        if d not in (2, 3):
            raise FileLayoutError(f"space dimension must be 2 or 3, got {d}")
    except FileLayoutError as exc:
        raise FileFormatError(f"{name}: not a Siconos .dat problem: {exc}") from None
    start = tk.state()
    try:
        try:
            return _parse_local(tk, d, nc, title)
        except FileLayoutError as exc:
            local_error = exc
        tk.restore(start)
        try:
            return _parse_global(tk, d, nc, title)
        except FileLayoutError as exc:
            raise FileFormatError(
                f"{name}: not a Siconos .dat problem: as local, {local_error}; as global, {exc}"
            ) from None
    except FileFormatError:
        raise
    except ContactError as exc:  # invalid content caught by LocalProblem / GlobalProblem
        raise FileFormatError(f"{name}: {exc}") from None


def read_dat(path: str | os.PathLike[str]) -> LocalProblem | GlobalProblem:
    """Read a Siconos ``.dat`` problem file.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    LocalProblem or GlobalProblem
        The global form (``GFC3D_*`` files) is returned as read; call its
        :meth:`~contactqp.core.local_problem.GlobalProblem.condense` for the local form. The
        title is the file name without its suffix.

    Raises
    ------
    FileFormatError
        If the file is missing, not text, or not in the layout described in this module.
    """
    p = Path(os.fspath(path))
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise FileFormatError(f"{p}: no such file") from None
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    if b"\0" in raw:
        raise FileFormatError(f"{p}: not a text file (Siconos .dat expected)")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise FileFormatError(f"{p}: not a text file (Siconos .dat expected)") from None
    return parse_dat(text, name=str(p), title=p.stem)
