"""The draws of an odds study: uniform points (Monte Carlo or quasi-Monte Carlo) and field seeds.

``method``: ``random`` (``numpy.random.default_rng(seed)``), ``sobol`` (scrambled Sobol' points,
``scipy.stats.qmc.Sobol``) or ``lhs`` (Latin hypercube, ``scipy.stats.qmc.LatinHypercube``), all
seeded by ``seed``; the uniforms are mapped through each input's inverse CDF
(:mod:`snoworm.studies.odds.inputs`).  The X_t field is not a quasi-random coordinate (it has one
dimension per grid point): each draw has its own seed, ``SeedSequence([seed, FIELD_STREAM, k])``,
so draw ``k`` has the same field for every strategy and whatever ran before.

With ``sensitivity``, the design is Saltelli's (the one ``scipy.stats.sobol_indices`` evaluates):
two independent blocks A and B of ``n`` points, then for each input group ``i`` the block
``AB_i`` (A with group ``i``'s coordinates, and its field seed if ``i`` is the field, from B):
``n (k + 2)`` draws for ``k`` groups.  P(go) and the percentiles use the ``2 n`` independent draws
of A and B.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from ...config.schema import ScenarioError

__all__ = ["METHODS", "Design", "design", "uniforms", "field_seed", "FIELD_STREAM"]

#: Sampling methods (``--method``).
METHODS = ("random", "sobol", "lhs")

#: Stream number of the field seeds in ``SeedSequence([seed, FIELD_STREAM, k])``.
FIELD_STREAM = 1


def uniforms(method: str, n: int, d: int, seed: int) -> np.ndarray:
    """``n`` points of ``[0, 1)^d`` by ``method`` (:data:`METHODS`), reproducible for ``seed``."""
    if method not in METHODS:
        raise ScenarioError(f"--method: expected one of {', '.join(METHODS)}, got {method!r}.")
    if d == 0:
        return np.zeros((n, 0))
    if method == "random":
        return np.random.default_rng(seed).random((n, d))
    if method == "sobol":
        if n & (n - 1):
            lo = 1 << (n.bit_length() - 1)
            raise ScenarioError(
                f"--samples {n} with --method sobol: Sobol' points keep their balance only in blocks of a power of "
                f"2; use --samples {lo} or {2 * lo} (or --method lhs / random for any number)."
            )
        return qmc.Sobol(d, scramble=True, seed=seed).random(n)
    return qmc.LatinHypercube(d, seed=seed).random(n)


def field_seed(seed: int, k: int) -> int:
    """The X_t field's seed of draw ``k`` (the same for every strategy and run)."""
    return int(np.random.SeedSequence([int(seed), FIELD_STREAM, int(k)]).generate_state(1, np.uint64)[0] >> 1)


@dataclass(frozen=True)
class Design:
    """The draws: ``U`` (n_draws, dim) uniforms, ``field_seeds`` (n_draws,), and for a Saltelli design
    ``n`` (base size) and ``groups`` (names, in block order AB_0, AB_1, ...); ``independent`` is the mask
    of the draws that are independent samples (every draw, or A and B)."""

    U: np.ndarray
    field_seeds: np.ndarray
    n: int
    groups: tuple = ()
    saltelli: bool = False

    @property
    def n_draws(self) -> int:
        return len(self.U)

    @property
    def independent(self) -> np.ndarray:
        mask = np.zeros(self.n_draws, bool)
        mask[: 2 * self.n if self.saltelli else self.n_draws] = True
        return mask

    def block(self, name: str) -> slice:
        """Rows of block ``A``, ``B`` or ``AB:<group>``."""
        n = self.n
        if name == "A":
            return slice(0, n)
        if name == "B":
            return slice(n, 2 * n)
        j = self.groups.index(name[3:])
        return slice((2 + j) * n, (3 + j) * n)


def design(unc, n: int, method: str, seed: int, sensitivity: bool = False) -> Design:
    """The draws of an odds study of the uncertain inputs ``unc`` (:class:`~snoworm.studies.odds.inputs.Uncertainty`)."""
    d = unc.dim
    if not sensitivity:
        U = uniforms(method, n, d, seed)
        return Design(U, np.array([field_seed(seed, k) for k in range(n)], dtype=np.int64), n)
    groups = unc.groups
    if len(groups) < 2:
        raise ScenarioError(
            "--sensitivity: Sobol indices apportion the variance among at least two uncertain inputs; "
            f"this study has {len(groups)}. Add another --vary or --xt-field, or leave --sensitivity out."
        )
    AB = uniforms(method, n, 2 * d, seed)
    A, B = AB[:, :d], AB[:, d:]
    sA = np.array([field_seed(seed, k) for k in range(n)], dtype=np.int64)
    sB = np.array([field_seed(seed, n + k) for k in range(n)], dtype=np.int64)
    blocks, seeds, j = [A, B], [sA, sB], 0
    for g in groups:
        M = A.copy()
        M[:, j : j + g.dim] = B[:, j : j + g.dim]
        j += g.dim
        blocks.append(M)
        seeds.append(sB if g.name == "xt_field" else sA)
    return Design(np.vstack(blocks), np.concatenate(seeds), n, tuple(g.name for g in groups), True)
