"""Estimates of an odds study: P(go) with its Wilson interval, percentiles, Sobol indices.

Wilson's score interval (Wilson 1927; Brown, Cai & DasGupta 2001, Statist. Sci. 16:101) for ``k``
successes in ``n`` independent draws at confidence ``1 - alpha`` (``z`` its normal quantile)::

    centre = (p + z^2 / 2n) / (1 + z^2 / n),   half = z / (1 + z^2 / n) sqrt(p (1 - p) / n + z^2 / 4n^2)

with ``p = k / n``.  Unlike the normal ("Wald") interval it never leaves [0, 1] and keeps close to
its nominal coverage at ``p`` near 0 or 1 and for small ``n``, where an odds study lives.

Sobol indices: first-order ``S_i`` (the share of the output's variance explained by input ``i``
alone) and total ``S_Ti`` (with all its interactions), from Saltelli's design
(:mod:`snoworm.studies.odds.sampling`) by ``scipy.stats.sobol_indices`` (Saltelli et al. 2010's
first-order and Jansen's total estimators) and its bootstrap intervals.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from scipy.stats import bootstrap, norm, sobol_indices

__all__ = ["wilson", "percentiles", "sobol", "PERCENTILES", "draws_for_half_width"]

#: Percentiles reported for time, speed made good and energy per metre.
PERCENTILES = (5, 50, 95)


@functools.lru_cache(maxsize=16)
def _z(confidence: float) -> float:
    return float(norm.ppf(0.5 + confidence / 2))


def wilson(k: int, n: int, confidence: float = 0.95) -> tuple:
    """Wilson's score interval ``(low, high)`` of a proportion: ``k`` successes of ``n`` draws (module docstring).

    ``(0.0, 1.0)`` when ``n`` is 0 (nothing is known)."""
    if n <= 0:
        return (0.0, 1.0)
    z = _z(confidence)
    p = k / n
    den = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z / den * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    lo = 0.0 if k == 0 else max(0.0, centre - half)  # exactly 0 and 1 there (rounding would leave 1 - 1e-16)
    hi = 1.0 if k == n else min(1.0, centre + half)
    return (lo, hi)


def draws_for_half_width(p: float, half_width: float, confidence: float = 0.95) -> int:
    """Draws for an interval of about ``+- half_width`` around ``p`` (``n = z^2 p (1 - p) / h^2``, docs/odds.md)."""
    z = _z(confidence)
    return int(math.ceil(z * z * max(p * (1 - p), 1e-4) / half_width**2))


def percentiles(values, q=PERCENTILES) -> dict | None:
    """``{"p5": ..., "p50": ..., "p95": ...}`` of the finite ``values`` (None if there are none)."""
    v = np.asarray([x for x in values if x is not None], dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    return {f"p{p}": float(np.percentile(v, p)) for p in q}


def _indices(fA, fB, fAB):
    """First-order (Saltelli et al. 2010) and total (Jansen 1999) indices, as ``scipy.stats.sobol_indices``
    computes them: outputs centred on the mean of A and B, ``S_i = mean(f_B (f_ABi - f_A)) / V`` and
    ``S_Ti = mean((f_A - f_ABi)^2) / 2V`` with ``V`` the variance of A and B together."""
    m = np.mean(np.concatenate([fA, fB]))
    fA, fB, fAB = fA - m, fB - m, fAB - m
    var = np.var(np.concatenate([fA, fB]))
    with np.errstate(divide="ignore", invalid="ignore"):
        first = np.mean(fB * (fAB - fA), axis=-1) / var
        total = 0.5 * np.mean((fA - fAB) ** 2, axis=-1) / var
    return np.where(np.isfinite(first), first, 0.0), np.where(np.isfinite(total), total, 0.0)


def sobol(f, dsg, confidence: float = 0.95, n_resamples: int = 999, seed: int = 0) -> dict:
    """First-order and total Sobol indices of the output ``f`` (one value per draw of the Saltelli
    design ``dsg``) per input group, with bootstrap intervals.

    The point estimates are ``scipy.stats.sobol_indices``'s; the intervals are its bootstrap (BCa over
    the ``n`` rows of the design, the same estimators, :func:`_indices`) made with
    ``scipy.stats.bootstrap`` and a generator seeded by ``seed``: ``SobolResult.bootstrap`` draws its
    resamples from fresh OS entropy, so the same study would not give the same intervals twice.

    Returns
    -------
    dict
        ``{group: {"first", "total", "first_ci", "total_ci"}}``; indices of an output that does not vary
        are 0 (scipy's convention), with intervals ``[0, 0]``; a bound the bootstrap cannot give
        (every resample without variance) is None.
    """
    f = np.asarray(f, dtype=float)
    fA, fB = f[dsg.block("A")], f[dsg.block("B")]
    fAB = np.stack([f[dsg.block(f"AB:{g}")] for g in dsg.groups])
    k = len(dsg.groups)
    with warnings.catch_warnings():  # a bootstrap resample of a 0/1 output may have no variance: reported as None
        warnings.simplefilter("ignore")
        res = sobol_indices(func={"f_A": fA[None, :], "f_B": fB[None, :], "f_AB": fAB[:, None, :]}, n=dsg.n)
        first, total = np.atleast_1d(res.first_order), np.atleast_1d(res.total_order)
        if np.var(np.concatenate([fA, fB])) == 0:
            lo = hi = np.zeros(2 * k)
        else:
            boot = bootstrap(
                [np.arange(dsg.n)],
                lambda idx: np.concatenate(_indices(fA[idx], fB[idx], fAB[:, idx])),
                vectorized=False,
                method="BCa",
                n_resamples=n_resamples,
                confidence_level=confidence,
                rng=np.random.default_rng(seed),
            )
            lo, hi = boot.confidence_interval.low, boot.confidence_interval.high
    return {
        g: {
            "first": _finite(first[j]),
            "total": _finite(total[j]),
            "first_ci": [_finite(lo[j]), _finite(hi[j])],
            "total_ci": [_finite(lo[k + j]), _finite(hi[k + j])],
        }
        for j, g in enumerate(dsg.groups)
    }


def _finite(v):
    """``v`` as a float, or None where the estimator has no finite value (JSON has no NaN)."""
    v = float(v)
    return v if math.isfinite(v) else None
