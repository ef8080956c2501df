"""Signatures of the Cython extension built from ``compiled.pyx``, for type checkers.

Type checkers cannot read a compiled module: this stub states what it offers, the signatures of
its twin :mod:`contactqp.kernels.pure_numpy` (the extension takes any float64 or int64 buffer of
the shapes those document; numpy arrays are what its callers pass).
"""

import numpy as np

__all__ = [
    "project_rows",
    "natural_map_rows",
    "alart_curnier_rows",
    "sparse_newton_matrix",
    "planar_gauss_seidel",
    "planar_blocks",
    "row_products",
    "abs_row_sums",
]

SMALL_REASONS: tuple[str, ...]
SMALL_CONSTANTS: dict[str, float]
PLANAR_REASONS: tuple[str, ...]
SPATIAL_REASONS: tuple[str, ...]
PLANAR_EVERY: int
PLANAR_SPAN: int

def small_newton(
    W: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    shift: np.ndarray,
    r: np.ndarray,
    tol: float,
    max_iter: int,
    per_contact: bool,
    floor: float,
    iterations: np.ndarray,
    reasons: np.ndarray,
    errors: np.ndarray,
) -> None: ...
def small_certificate(
    W: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    shift: np.ndarray,
    r: np.ndarray,
    per_contact: bool,
    floor: float,
    rtol: float,
    u: np.ndarray,
    measures: np.ndarray,
    status: np.ndarray,
) -> None: ...
def small_semidefinite(W: np.ndarray, shift: float, passed: np.ndarray) -> None: ...
def local_arrays_valid(
    W_values: np.ndarray, q: np.ndarray, mu: np.ndarray, cohesion: np.ndarray | None
) -> bool: ...
def small_solve(
    W: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    cohesion: np.ndarray,
    r: np.ndarray,
    tol: float,
    max_iter: int,
    per_contact: bool,
    floor: float,
    rtol: float,
    u: np.ndarray,
    status: np.ndarray,
) -> tuple[int, int, float, float, float, float, float]: ...
def planar_solve(
    W: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    shift: np.ndarray,
    r: np.ndarray,
    u: np.ndarray,
    status: np.ndarray,
    measures: np.ndarray,
    tol: float,
    max_sweeps: int,
    first: int,
    check_blocks: bool,
    psd_shift: float,
    stall_test: bool,
    per_contact: bool,
    floor: float,
    rtol: float,
) -> tuple[int, int]: ...
def spatial_solve(
    W: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    shift: np.ndarray,
    r: np.ndarray,
    u: np.ndarray,
    status: np.ndarray,
    measures: np.ndarray,
    tol: float,
    max_sweeps: int,
    first: int,
    check_blocks: bool,
    psd_shift: float,
    stall_test: bool,
    per_contact: bool,
    floor: float,
    rtol: float,
) -> tuple[int, int]: ...
def project_rows(X: np.ndarray, mu: np.ndarray, P: np.ndarray) -> None: ...
def natural_map_rows(
    R: np.ndarray, U: np.ndarray, mu: np.ndarray, squares: np.ndarray
) -> float: ...
def alart_curnier_rows(
    R: np.ndarray,
    U: np.ndarray,
    mu: np.ndarray,
    rho: np.ndarray,
    Phi: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
) -> None: ...
def sparse_newton_matrix(
    A: np.ndarray,
    B: np.ndarray,
    W_blocks: np.ndarray,
    block_row: np.ndarray,
    block_col: np.ndarray,
    entries: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    renumber: np.ndarray,
    data: np.ndarray,
    new_indices: np.ndarray,
    new_indptr: np.ndarray,
) -> int: ...
def planar_gauss_seidel(
    W: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    blocks: np.ndarray,
    q: np.ndarray,
    mu: np.ndarray,
    r: np.ndarray,
    u: np.ndarray,
    tol: float,
    max_sweeps: int,
    every: int,
    project: bool,
) -> tuple[int, float]: ...
def planar_blocks(
    W: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, blocks: np.ndarray
) -> None: ...
def row_products(
    W: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    data: np.ndarray,
    x: np.ndarray,
    product: np.ndarray,
    magnitude: np.ndarray,
) -> None: ...
def abs_row_sums(W: np.ndarray, rows: np.ndarray, sums: np.ndarray) -> None: ...

GLOBAL_CODES: tuple[str, ...]
GLOBAL_MEASURES: tuple[str, ...]

def global_small(
    M_indptr: np.ndarray,
    M_indices: np.ndarray,
    M_data: np.ndarray,
    H_indptr: np.ndarray,
    H_indices: np.ndarray,
    H_data: np.ndarray,
    f: np.ndarray,
    w: np.ndarray,
    mu: np.ndarray,
    r: np.ndarray,
    tol: float,
    max_iter: int,
    per_contact: bool,
    floor: float,
    check_psd: bool,
    psd_shift: float,
    digits: np.ndarray,
    rtol: float,
    solve: bool,
    max_unknowns: int,
    max_dense: int,
    max_block: int,
    max_group: int,
    u: np.ndarray,
    v: np.ndarray,
    status: np.ndarray,
    measures: np.ndarray,
) -> int: ...
