"""Projected (nonsmooth) Gauss-Seidel for the local Coulomb problem ``u = W r + q``.

Contact ``i`` is updated by solving its one-contact problem ``u_i = W_ii r_i + b_i`` with the
other reactions frozen (``b_i = q_i + sum_{j != i} W_ij r_j``). Contacts whose blocks do not
couple (``W_ij = 0``) do not see each other's update, so a greedy colouring of the block graph
groups them and each colour is updated at once, vectorised: the sweep is exactly Gauss-Seidel in
colour order, with one sparse row-block product and one batched local solve per colour.

The one-contact problem is solved by the projected fixed point of the De Saxce formulation,
``r_i <- P_K(r_i - rho_i (u_i + mu_i ||u_iT|| e_N))`` with ``rho_i = 1 / ||W_ii||_F``
(Jourdan, Alart and Jean, CMAME 155, 1998; Acary, Bremond and Huber, INRIA RR-9118, 2018).

This is the robust, linearly convergent fallback of :func:`contactqp.methods.coulomb.solve_coulomb`
and works on the FCLIB form (no cohesion: the caller translates a cohesive problem first).
"""

from __future__ import annotations

import numpy as np

from ..core.local_problem import project_rows
from ..core.operators import as_operator

__all__ = ["GaussSeidel"]


def _block_graph(W, nc, d):
    """CSR adjacency (nc x nc) of the contacts whose blocks ``W_ij`` are nonzero."""
    import scipy.sparse as sp  # the graph is CSR, W dense or not

    if isinstance(W, np.ndarray):
        pattern = sp.csr_matrix(np.any(W.reshape(nc, d, nc, d) != 0, axis=(1, 3)))
    else:
        coo = sp.coo_matrix(W)
        nz = coo.data != 0
        pattern = sp.csr_matrix(
            (np.ones(int(nz.sum())), (coo.row[nz] // d, coo.col[nz] // d)), shape=(nc, nc)
        )
    pattern = pattern + pattern.T
    pattern.sort_indices()
    return pattern


def _greedy_colours(graph):
    """Smallest-free-colour greedy colouring of a CSR graph, in contact order."""
    n = graph.shape[0]
    colour = np.full(n, -1)
    for i in range(n):
        taken = colour[graph.indices[graph.indptr[i] : graph.indptr[i + 1]]]
        used = np.zeros(taken.size + 2, dtype=bool)
        used[taken[(taken >= 0) & (taken < used.size)]] = True
        colour[i] = int(np.argmin(used))
    return colour


class GaussSeidel:
    """Colour-ordered nonsmooth Gauss-Seidel sweeps for ``u = W r + q``, Coulomb cones ``mu``.

    Parameters
    ----------
    W : csr_matrix or ndarray, shape (m, m), or an Operator that forms its matrix
        (:attr:`~contactqp.core.operators.Operator.matrix`).
    q : ndarray, shape (m,)
    mu : ndarray, shape (n_contacts,)
    dim : int
        2 or 3.
    local_iterations : int
        Cap on the fixed-point iterations of each one-contact solve.
    """

    def __init__(self, W, q, mu, dim, local_iterations: int = 50):
        import scipy.sparse as sp

        operator = as_operator(W)
        W = operator.matrix  # the colouring and the row blocks are built on the stored entries
        nc = mu.shape[0]
        d = dim
        self.dim, self.mu, self.local_iterations = d, mu, local_iterations
        colour = _greedy_colours(_block_graph(W, nc, d))
        self.groups = [np.flatnonzero(colour == c) for c in range(colour.max() + 1)] if nc else []
        rows = [(g[:, None] * d + np.arange(d)).ravel() for g in self.groups]
        Wr = W if isinstance(W, np.ndarray) else sp.csr_matrix(W)
        self.row_blocks = [Wr[rw] for rw in rows]
        self.q_blocks = [q[rw] for rw in rows]
        idx = np.arange(nc)
        if not isinstance(W, np.ndarray):
            bsr = sp.bsr_matrix(W, blocksize=(d, d))
            self.diag_blocks = np.zeros((nc, d, d))
            # block rows of a BSR matrix: pick each row's diagonal block if it is stored
            br = np.repeat(idx, np.diff(bsr.indptr))
            on_diag = bsr.indices == br
            self.diag_blocks[br[on_diag]] = bsr.data[on_diag]
        else:
            self.diag_blocks = operator.diagonal_blocks(d)
        norms = np.sqrt(np.sum(self.diag_blocks**2, axis=(1, 2)))
        self.rho = 1.0 / np.where(norms > 0, norms, 1.0)

    def _local_solve(self, Wb, b, mu, rho, R):
        """Batched one-contact solves ``u = Wb r + b`` by the projected fixed point, from R."""
        for _ in range(self.local_iterations):
            U = np.einsum("nij,nj->ni", Wb, R) + b
            U[:, 0] += mu * np.sqrt(np.sum(U[:, 1:] ** 2, axis=1))
            new = project_rows(R - rho[:, None] * U, mu)
            change = np.max(np.abs(new - R))
            R = new
            if change <= 1e-15 * (np.max(np.abs(R)) + 1e-300):
                break
        return R

    def sweep(self, r):
        """One sweep over every colour; returns the updated reactions (shape (m,))."""
        d = self.dim
        R = r.reshape(-1, d).copy()
        for g, Wrows, qg in zip(self.groups, self.row_blocks, self.q_blocks, strict=True):
            U = (Wrows @ R.reshape(-1) + qg).reshape(-1, d)
            Wb = self.diag_blocks[g]
            b = U - np.einsum("nij,nj->ni", Wb, R[g])
            R[g] = self._local_solve(Wb, b, self.mu[g], self.rho[g], R[g])
        return R.reshape(-1)
