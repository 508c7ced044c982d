"""Jacobian structure and finite differences of the chain model (docs/model.md section 6).

A segment chain couples only neighbours, so ``d(dy/dt)/dy`` is banded.  :func:`sparsity` gives
its structural pattern (an incomplete pattern is fatal to Radau and BDF, so the tests check it
covers every non-zero of a dense finite-difference Jacobian), :class:`BandedDifferences` a
finite-difference Jacobian in LAPACK packed band format from ONE vectorised kernel call, the
layout ``solve_ivp(method="LSODA", lband=..., uband=...)`` expects, and :func:`to_sparse` the
same as a sparse matrix for BDF and Radau.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import block_diag, dia_matrix

__all__ = ["sparsity", "bandwidths", "BandedDifferences", "to_sparse"]


def _blocks(layout, force_loop: bool, joints: bool):
    """The (own, previous, next) segment blocks of the pattern for one segment's rows."""
    ns, idx = layout.n_s, layout.index
    own = np.ones((ns, ns), bool)
    own[idx["x_m"], :] = False
    own[idx["x_m"], idx["v_mps"]] = True
    prev = np.zeros((ns, ns), bool)  # rows of segment k, columns of segment k-1
    nxt = np.zeros((ns, ns), bool)  # rows of segment k, columns of segment k+1
    ahead_rows = ["v_mps"]  # rows that see link k-1
    behind_rows = ["v_mps"]  # rows that see link k
    if joints:
        behind_rows.append("s_m")
    if force_loop:
        loop_rows = ["q_mps", "omega_front", "omega_rear", "integral_front_Nm", "integral_rear_Nm"]
        ahead_rows += loop_rows
        behind_rows += loop_rows
    for r in ahead_rows:
        for c in ("x_m", "v_mps"):
            prev[idx[r], idx[c]] = True
        if joints:
            prev[idx[r], idx["s_m"]] = True
    for r in behind_rows:
        for c in ("x_m", "v_mps"):
            nxt[idx[r], idx[c]] = True
    return own, prev, nxt


def sparsity(model, member: bool = False):
    """Structural non-zero pattern of the Jacobian ``d(dy/dt)/dy`` of a :class:`~snoworm.dynamics.ChainModel`.

    Within a segment every field may depend on every other (except ``x``, which is the
    integral of ``v``).  Across segments only the link forces couple: the force of link
    ``k-1`` (ahead) depends on ``x, v`` of segments ``k-1, k`` and on ``s_{k-1}``; link ``k``
    (behind) on ``x, v`` of ``k, k+1`` and on ``s_k``.  Rows that see a link force: ``v``;
    ``s`` (its own link, and the mover speed of the link's other segment); with a force
    loop also ``q`` and the wheel states that follow its set-point.

    Returns
    -------
    ndarray of bool or scipy.sparse matrix
        One chain: a dense ``(n_states, n_states)`` array.  Stacked chains: block diagonal,
        one block per member, as a sparse matrix (``member=True``: one member's dense block).
    """
    L = model.layout
    ns, n = L.n_s, L.n
    own, prev, nxt = _blocks(L, model.force_loop, model.has_joints)
    P = np.zeros((n * ns, n * ns), bool)
    for k in range(n):
        P[k * ns : (k + 1) * ns, k * ns : (k + 1) * ns] = own
        if k > 0:
            P[k * ns : (k + 1) * ns, (k - 1) * ns : k * ns] = prev
        if k < n - 1:
            P[k * ns : (k + 1) * ns, (k + 1) * ns : (k + 2) * ns] = nxt
    if member or not L.batch_shape:
        return P
    return block_diag([P] * L.n_batch, format="csr").astype(bool)  # stacked chains


def bandwidths(pattern) -> tuple:
    """``(lband, uband)`` of a dense pattern: the farthest non-zero below and above the diagonal."""
    r, c = np.nonzero(pattern)
    return int(max(0, np.max(r - c))), int(max(0, np.max(c - r)))


class BandedDifferences:
    """Banded finite-difference Jacobian of ``f`` from one vectorised call per Jacobian.

    All ``lband + uband + 1`` column groups of the band are perturbed at once and evaluated as
    a stack (the kernel's leading batch axis), so a Jacobian costs about as much as one or two
    right-hand-side calls instead of one per group.

    Parameters
    ----------
    n : int
        Number of states.
    lband, uband : int
        Bandwidths.
    rel_step : float
        Relative perturbation (floored at ``1e-3`` in absolute value).
    """

    def __init__(self, n: int, lband: int, uband: int, rel_step: float = 1.2e-4):
        self.n, self.lband, self.uband, self.rel_step = n, lband, uband, rel_step
        self.width = min(lband + uband + 1, n)
        cols = np.arange(n)
        self.group = cols % self.width
        r = np.arange(lband + uband + 1)[:, None]
        self.rows = cols[None, :] + r - uband  # row i of packed entry (r, j)
        self.valid = (self.rows >= 0) & (self.rows < n)

    def __call__(self, f_stack, y):
        """``J_packed`` with ``J_packed[uband + i - j, j] = df_i/dy_j``.

        ``f_stack`` maps a stack of states ``(k, n)`` to their derivatives ``(k, n)``.
        """
        n, w, group = self.n, self.width, self.group
        h = self.rel_step * np.maximum(1e-3, np.abs(y))
        Yp = np.tile(y, (w + 1, 1))
        Yp[1 + group, np.arange(n)] += h
        h = Yp[1 + group, np.arange(n)] - y  # the step actually taken (rounding)
        F = f_stack(Yp)
        dF = F[1:] - F[0]
        g = np.broadcast_to(group, self.rows.shape)
        return np.where(self.valid, dF[g, np.where(self.valid, self.rows, 0)], 0.0) / h[None, :]


def to_sparse(packed, lband: int, uband: int):
    """A packed band matrix (LAPACK layout) as a sparse CSC matrix."""
    n = packed.shape[1]
    return dia_matrix((packed, np.arange(uband, -lband - 1, -1)), shape=(n, n)).tocsc()
