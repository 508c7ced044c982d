"""Elevation along the track: the grade under each segment (docs/model.md section 7, beyond the paper).

The track is a curve in a vertical plane; ``s`` is the distance *along the track* (arc length),
the coordinate the chain already moves along (positions, X_t profiles and patches all use it).
The elevation is ``z(s)``; since ``s`` is arc length, ``dz/ds = sin(theta)`` with ``theta`` the grade
angle, positive uphill in the direction of travel.  (``theta = atan(dz/dD)`` holds for the
*horizontal* distance ``D``; along the track the exact relation is ``asin``.)

The grade under a segment is that of the chord between its two axles' contact points::

    sin(theta_k) = (z(x_k + b/2) - z(x_k - b/2)) / b          (b: wheelbase)

-- the pitch of a rigid chassis resting on its two axles, exact on any straight stretch and,
unlike the grade at a point, continuous across a kink of a piecewise-linear ``z(s)`` (so the
right-hand side stays smooth inside a solver step).  The work of the along-track gravity force
``-m g sin(theta_k)`` is then exactly ``-m g`` times the change of the wheelbase-mean elevation
:meth:`ElevationProfile.mean_elevation`, the potential energy of the energy balance.

:class:`ElevationProfile` is the single evaluation path of every grade input (a constant grade,
grade patches, an elevation table, a route file); the laws that use the grade (the normal load
and the gravity force) are in :mod:`snoworm.terrain`, composed by ``ChainModel.grade_terms``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ElevationProfile", "MAX_GRADE_DEG", "MIN_HALF_BASE_M", "grade_patch_profile"]

#: Largest |grade| any input may have [deg]: beyond the angle of repose of dry snow (30-40 deg) no
#: snow slope stands, and the small-curvature 1-D chain (docs/model.md section 7) loses meaning.
MAX_GRADE_DEG = 40.0

#: Smallest half chord [m] used for the grade under a segment (a segment with wheelbase 0 takes the
#: chord over +-1 mm, i.e. the grade at its reference point).
MIN_HALF_BASE_M = 1e-3


@dataclass(frozen=True)
class ElevationProfile:
    """Elevation ``z(s)`` along the track: a constant grade or a piecewise-linear table.

    Parameters
    ----------
    positions_m : tuple of float
        Strictly increasing distances along the track [m]; empty for a constant grade.
    elevations_m : tuple of float
        Elevation at each position [m] (held constant, i.e. level, beyond the table's ends).
    grade_deg : float
        The constant grade [deg] when ``positions_m`` is empty (``z = s sin(theta)``).
    """

    positions_m: tuple = ()
    elevations_m: tuple = ()
    grade_deg: float = 0.0

    @classmethod
    def constant(cls, grade_deg: float) -> ElevationProfile:
        return cls((), (), float(grade_deg))

    @property
    def is_constant(self) -> bool:
        """True for a constant grade (the grade does not depend on position)."""
        return len(self.positions_m) == 0

    @property
    def is_level(self) -> bool:
        """True when the grade is zero everywhere (the kernel then skips every grade term)."""
        if self.is_constant:
            return self.grade_deg == 0.0
        return len(set(self.elevations_m)) == 1

    def elevation(self, s_m):
        """``z(s)`` [m] at distances ``s_m`` (any shape)."""
        if self.is_constant:
            return np.asarray(s_m, float) * math.sin(math.radians(self.grade_deg))
        return np.interp(s_m, self.positions_m, self.elevations_m)

    def sin_grade(self, s_m, half_base_m):
        """``sin(theta)`` of the chord over ``[s - h, s + h]`` (the grade under a segment), any shape."""
        if self.is_constant:
            return np.full(np.shape(np.asarray(s_m) + half_base_m), math.sin(math.radians(self.grade_deg)))
        h = np.maximum(half_base_m, MIN_HALF_BASE_M)
        return (
            np.interp(s_m + h, self.positions_m, self.elevations_m)
            - np.interp(s_m - h, self.positions_m, self.elevations_m)
        ) / (2.0 * h)

    def mean_elevation(self, s_m, half_base_m):
        """Mean of ``z`` over ``[s - h, s + h]`` [m]: the potential-energy height of a segment.

        ``d/ds`` of it is exactly :meth:`sin_grade`, so the gravity force's work closes the energy
        balance (``energy_balance``).  ``h = 0`` (well, below :data:`MIN_HALF_BASE_M`) gives ``z(s)``.
        """
        if self.is_constant:
            return self.elevation(s_m)
        h = np.maximum(half_base_m, MIN_HALF_BASE_M)
        return (self._integral(s_m + h) - self._integral(s_m - h)) / (2.0 * h)

    def _integral(self, s_m):
        """``Z(s) = int_{s_0}^{s} z ds'`` of the piecewise-linear table (z level beyond its ends)."""
        P, Z = np.asarray(self.positions_m, float), np.asarray(self.elevations_m, float)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (Z[1:] + Z[:-1]) * np.diff(P))])
        s = np.asarray(s_m, float)
        j = np.clip(np.searchsorted(P, s, side="right") - 1, 0, len(P) - 1)
        ds = s - P[j]
        slope = np.zeros(len(P))
        if len(P) > 1:
            slope[:-1] = np.diff(Z) / np.diff(P)
        inside = s >= P[0]
        return np.where(inside, cum[j] + Z[j] * ds + 0.5 * slope[j] * ds * ds, Z[0] * (s - P[0]))

    def max_abs_grade_deg(self) -> float:
        """The steepest |grade| of the profile [deg] (of its table's pieces, or the constant)."""
        if self.is_constant:
            return abs(self.grade_deg)
        if len(self.positions_m) < 2:
            return 0.0
        r = np.abs(np.diff(self.elevations_m) / np.diff(self.positions_m))
        return float(np.degrees(np.arcsin(np.minimum(r.max(), 1.0))))


def grade_patch_profile(base_grade_deg: float, patches) -> ElevationProfile:
    """A base grade with patches of other grade, as one elevation table.

    Parameters
    ----------
    base_grade_deg : float
        Grade outside every patch [deg].
    patches : sequence of (start_m, end_m, grade_deg, ramp_m)
        Sorted, non-overlapping (validated by ``TerrainConfig``).  The grade is ``grade_deg`` on
        ``[start_m, end_m]`` and changes back to the base over ``ramp_m`` outside each edge; on a
        ramp ``z`` rises by the ramp's mean ``sin(theta)`` times its length (exact at the ramp's
        ends for ``sin(theta)`` linear along the ramp), and a step (``ramp_m = 0``) is a kink of
        ``z``, which the chord grade of a segment smooths over its wheelbase.

    Returns
    -------
    ElevationProfile
        Constant when there are no patches, else a table starting at ``z = 0`` at the first
        breakpoint with the base grade continued beyond both ends over 10 km.
    """
    if not patches:
        return ElevationProfile.constant(base_grade_deg)
    sb = math.sin(math.radians(base_grade_deg))
    knots = []  # (position, sin of the grade after it)
    for start, end, grade, ramp in patches:
        sp = math.sin(math.radians(grade))
        r = float(ramp)
        if r > 0:
            knots += [(start - r, 0.5 * (sb + sp)), (start, sp), (end, 0.5 * (sb + sp)), (end + r, sb)]
        else:
            knots += [(start, sp), (end, sb)]
    far = 1e4
    pos = [knots[0][0] - far]
    z = [0.0]
    prev_sin = sb
    for p, sn in knots:
        if p > pos[-1]:
            z.append(z[-1] + prev_sin * (p - pos[-1]))
            pos.append(p)
        prev_sin = sn
    z.append(z[-1] + sb * far)
    pos.append(pos[-1] + far)
    z0 = z[1]
    return ElevationProfile(tuple(float(p) for p in pos), tuple(float(v - z0) for v in z))
