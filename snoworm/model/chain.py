"""The chain kernel: :class:`ChainModel`, the laws composed into one right-hand side (docs/model.md section 4).

The equations, the sign conventions and the state layout are stated in :mod:`snoworm.dynamics`
(the kernel's public face).  This package, :mod:`snoworm.model`, holds the whole kernel behind
one interface:

* **the parameters it reads**: the attributes of a :class:`ChainModel`, listed by
  :meth:`ChainModel.kernel_inputs` (every one but the caches of :data:`CACHES`) and replaced
  by :meth:`ChainModel.with_inputs` (how :mod:`snoworm.model.floatkernel` traces the kernel with
  symbols in place of numbers);
* **the laws it evaluates**: :meth:`ChainModel.evaluate`, composing :mod:`snoworm.terrain`,
  :mod:`snoworm.drivetrain`, :mod:`snoworm.links` and :mod:`snoworm.feedback`, for any leading
  batch shape;
* **the code it generates**: :attr:`ChainModel.float_kernel`, the straight-line float code of a
  short single chain (:mod:`snoworm.model.floatkernel`; its inputs are the parameters above, its
  key everything else);
* **the outputs it derives**: :meth:`ChainModel.evaluate` with ``outputs=True``, the
  finite-difference Jacobian (:mod:`snoworm.model.jacobian`) and the quantities of results and
  observations (:mod:`snoworm.model.quantities`).

No code outside this module and :mod:`snoworm.model.arrays` addresses a state by a number, and
no module outside it reads a :class:`ChainModel`'s private attributes.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import numpy as np

from .. import drivetrain, feedback, links as link_law, terrain
from ..slope import ElevationProfile
from ..terrain import TerrainParams, TerrainProfile
from . import floatkernel, jacobian
from .arrays import LinkArrays, SegmentArrays, StateLayout
from .inputs import Controls, as_float as _as_float, control_arrays, control_flags

__all__ = ["CACHES", "ChainModel", "StackedConstantProfile"]

#: Attributes of a :class:`ChainModel` that are caches of derived objects, never read by the laws
#: (:meth:`ChainModel.kernel_inputs` leaves them out).
CACHES = frozenset({"float_kernel", "_fd", "_bands", "_ctl_cache"})


@dataclass(frozen=True)
class StackedConstantProfile:
    """Constant X_t per member of stacked chains (:meth:`ChainModel.stack`): ``values[b]``."""

    values: tuple
    is_constant = True

    def __call__(self, x_m):
        v = np.asarray(self.values, float)
        x = np.asarray(x_m)
        return np.zeros(x.shape) + v.reshape(-1, 1, 1)

    def minimum(self) -> float:
        return float(min(self.values))


class ChainModel:
    """An assembled chain: parameter arrays, state layout, Jacobian pattern and the force kernel.

    Parameters
    ----------
    seg : SegmentArrays
        Per-segment parameters (length N >= 1).
    links : LinkArrays
        Per-link parameters (length N-1).
    terrain_params : TerrainParams
        Terrain coefficients (Eqs. 1-3 and the resistance torque).
    profile : TerrainProfile
        X_t along the track.
    tow_force_N : float
        Constant towed load on the rear segment (pulls backward when positive).
    force_loop : bool
        Whether the state includes the outer force-loop integrators (force-control mode).
    elevation : ElevationProfile, optional
        Elevation along the track (docs/model.md section 7); None or level: level ground.
    sled_mass_kg, sled_friction : float, optional
        A sled towed behind the rear segment (mass 0: none): it adds
        :func:`terrain.sled_force_N` at the rear segment's grade to the tow (docs/model.md section 4,
        "Towed load").
    """

    def __init__(
        self,
        seg: SegmentArrays,
        links: LinkArrays,
        terrain_params: TerrainParams,
        profile: TerrainProfile,
        tow_force_N: float,
        force_loop: bool = False,
        elevation: ElevationProfile | None = None,
        sled_mass_kg: float = 0.0,
        sled_friction: float = 0.0,
    ):
        self.seg = seg
        self.links = links
        self.tp = terrain_params
        self.profile = profile
        self.elevation = elevation if elevation is not None and not elevation.is_level else None
        #: leading batch shape of the parameter arrays: () for one chain, (B,) for B stacked
        #: chains (see :meth:`stack`); every per-segment array then has shape (B, N)
        self.batch_shape = tuple(np.shape(seg.mass_kg)[:-1])
        self.tow_force_N = float(tow_force_N) if np.ndim(tow_force_N) == 0 else np.asarray(tow_force_N, float)
        self.sled_mass_kg = float(sled_mass_kg) if np.ndim(sled_mass_kg) == 0 else np.asarray(sled_mass_kg, float)
        self.sled_friction = float(sled_friction) if np.ndim(sled_friction) == 0 else np.asarray(sled_friction, float)
        #: whether a sled is towed (a structural flag: without one the tow is the constant force)
        self._sled = bool(np.any(np.asarray(sled_mass_kg) > 0))
        self.n = int(np.shape(seg.mass_kg)[-1])
        self.force_loop = bool(force_loop)
        self.has_joints = bool(np.any(links.prismatic > 0))
        #: whether the slip near rest follows the shear-displacement state (docs/model.md section 2)
        self.shear = terrain_params.standstill == "shear"
        #: whether each axle carries a slip-sinkage state (docs/model.md section 2, "Slip-sinkage")
        self.sinkage = terrain_params.sinkage == "slip"
        self.layout = StateLayout(
            self.n, self.force_loop, self.has_joints, self.batch_shape, shear=self.shear, sinkage=self.sinkage
        )
        self.n_batch = self.layout.n_batch
        self.n_states = self.layout.size

        def col(a):
            return np.asarray(a, float)[..., None]

        #: per-wheel static normal load, shape (..., N, 1) (broadcasts against axle arrays)
        self.normal_force_N = col(seg.normal_force_N)
        # grade terms (docs/model.md section 7): pitch transfer 2h/b and the chord's half-length
        b = np.asarray(seg.wheelbase_m, float)
        self._transfer = np.divide(2.0 * seg.com_height_m, b, out=np.zeros(b.shape), where=b > 0)
        self._half_base = b / 2.0
        #: axle positions relative to the segment's reference point, shape (..., N, 2): front, rear
        self.axle_offset_m = np.stack([seg.wheelbase_m / 2.0, -seg.wheelbase_m / 2.0], axis=-1)
        #: wheels on each axle, shape (..., N)
        self.wheels_per_axle = seg.wheels_per_axle.astype(float)
        self._R = col(seg.wheel_radius_m)
        self._J = col(seg.wheel_inertia_kgm2)
        self._kp, self._ki = col(seg.speed_kp_Nms_per_rad), col(seg.speed_ki_Nm_per_rad)
        self._ki_kp = self._ki / self._kp  # precomputed for feedback.speed_pi (same value)
        self._slope = col(seg.motor_slope_Nms_per_rad)
        self._wnl = col(seg.no_load_speed_radps)
        self._Tmax = col(seg.torque_limit_Nm)
        self._m = seg.mass_kg.astype(float)
        #: axles of segments with a failed drivetrain, bool (..., N, 1), None when every drivetrain works: no
        #: motor torque, the wheels roll free (docs/model.md section 4, "Failed drivetrain")
        self._free_axle = None if np.all(np.asarray(seg.driven) == 1.0) else (np.asarray(seg.driven) == 0.0)[..., None]
        self._bands = self._fd = None
        self._prepare_kernel()
        #: the float kernel of a single short chain (None: batches and long chains use :meth:`evaluate`)
        self.float_kernel = (
            floatkernel.FloatKernel(self) if not self.batch_shape and self.n <= floatkernel.MAX_SEGMENTS else None
        )

    def _prepare_kernel(self):
        """Derived constants of the kernel, computed once (micro-optimisations, same arithmetic).

        Scalars become 0-d arrays (NumPy multiplies by them ~2x faster than by Python floats);
        with X_t constant along the track, the position-independent factors of the terrain laws
        are evaluated once here (:func:`terrain.traction_coefficients` and friends).
        """
        tp, L = self.tp, self.links

        def z(v):
            return np.array(v, float)

        # the numbers of the terrain coefficients (not the law choices, nor an unused K of None)
        nums = {k: getattr(tp, k) for k in tp.__dataclass_fields__}
        self._tpk = replace(tp, **{k: z(v) for k, v in nums.items() if isinstance(v, (int, float))})
        self._zero = z(0.0)
        self._Fn_k, self._G_const = self.normal_force_N, None
        if self.elevation is not None and self.elevation.is_constant:  # constant grade: constant loads
            _, _, self._Fn_k, self._G_const = self.grade_terms(np.zeros(self.batch_shape + (self.n,)))
        Fn = self._Fn_k
        if getattr(self.profile, "is_constant", False) and (self.elevation is None or self._G_const is not None):
            X = self.profile(self.axle_offset_m)
            self._Xc = X
            self._coef = (
                terrain.traction_coefficients(Fn, X, self._tpk),
                terrain.resistance_coefficients(Fn, X, self._tpk),
                self._torque_coefficient(Fn, X, self._R, self._tpk),
            )
        else:
            self._Xc = self._coef = None
        self._k_link = np.asarray(L.stiffness_N_per_m, float)
        self._c_link = np.asarray(L.damping_Ns_per_m, float)
        self._L0 = np.asarray(L.rest_spacing_m, float)
        self._gk = (
            feedback.servo_gain(L.force_gain_per_s, L.stiffness_N_per_m, L.damping_Ns_per_m)
            if self.n > 1
            else np.zeros(0)
        )
        self._rate_max = np.asarray(L.rate_max_mps, float)
        self._neg_rate_max = -self._rate_max
        self._k_stop, self._k_length = z(link_law.K_STOP), z(feedback.K_LENGTH)
        self._stroke_max = np.asarray(L.stroke_max_m, float)
        self._stroke_min = np.asarray(L.stroke_min_m, float)
        self._tow_col = np.asarray(self.tow_force_N, float)[..., None]
        self._prepare_sled()
        self._ctl_cache = (None, None)

    def _prepare_sled(self):
        """The sled's weight and friction, and the grade at the rear segment where it is constant (level:
        0), as columns of shape (..., 1)."""
        self._sled_w = self._sled_mu = self._sled_sin = self._sled_cos = None
        if not self._sled:
            return
        g = np.asarray(self.seg.gravity_mps2, float)[..., -1:]
        self._sled_w = np.asarray(self.sled_mass_kg, float)[..., None] * g
        self._sled_mu = np.asarray(self.sled_friction, float)[..., None] + np.zeros(g.shape)
        if self.elevation is None or self.elevation.is_constant:
            zero = np.zeros(g.shape)
            s = zero if self.elevation is None else self.elevation.sin_grade(zero, self._half_base[..., -1:])
            self._sled_sin, self._sled_cos = np.asarray(s, float), np.asarray(np.sqrt(1.0 - s * s), float)

    def _tow_force_N(self, x, v):
        """The towed load on the rear segment with a sled, positive backward, shape (..., 1): the constant
        force plus the sled's gravity and friction at the rear segment's grade (:func:`terrain.sled_force_N`;
        docs/model.md section 4, "Towed load")."""
        s, c = self._sled_sin, self._sled_cos
        if s is None:  # a grade along the track: the chord grade under the rear segment
            s = self.elevation.sin_grade(x[..., -1:], self._half_base[..., -1:])
            c = np.sqrt(1.0 - s * s)
        d = terrain.smooth_sign(v[..., -1:], self._tpk.sign_eps_mps)
        return np.asarray(self.tow_force_N)[..., None] + terrain.sled_force_N(self._sled_w, self._sled_mu, s, c, d)

    def _controls(self, ctl: Controls):
        """Arrays derived from the controls of an interval, computed once per Controls object."""
        cached, d = self._ctl_cache
        if cached is ctl:
            return d
        d = control_arrays(self, ctl, control_flags(self, ctl))
        self._ctl_cache = (ctl, d)
        return d

    @classmethod
    def stack(cls, models) -> ChainModel:
        """B chains of the same structure as ONE model with a leading batch axis (for batched runs).

        Every model must have the same N, state layout, terrain coefficients and either the same
        X_t profile or constant profiles (X_t may differ per chain).  Per-segment and per-link
        parameters and the tow force become arrays of shape (B, N), (B, N-1) and (B,); the state
        of the stacked model is the member-major concatenation of the B states, and its
        Jacobian is block-banded with each member's band.  The physics is :meth:`evaluate`,
        unchanged: the parameters simply carry one more leading axis.
        """
        m0 = models[0]
        for m in models[1:]:
            if (m.n, m.layout.fields) != (m0.n, m0.layout.fields):
                raise ValueError("stacked chains need the same number of segments and state layout")
            if m.tp != m0.tp:
                raise ValueError("stacked chains need the same terrain coefficients")
            if m.profile != m0.profile and not (m.profile.is_constant and m0.profile.is_constant):
                raise ValueError("stacked chains need the same X_t profile, or constant profiles")
            if m.elevation != m0.elevation:
                raise ValueError("stacked chains need the same elevation profile")

        def st(objs, name):
            return np.stack([np.asarray(getattr(o, name), float) for o in objs])

        seg = SegmentArrays(**{k: st([m.seg for m in models], k) for k in SegmentArrays.__dataclass_fields__})
        links = LinkArrays(**{k: st([m.links for m in models], k) for k in LinkArrays.__dataclass_fields__})
        if all(m.profile == m0.profile for m in models):
            profile = m0.profile
        else:
            profile = StackedConstantProfile(tuple(float(m.profile.values[0]) for m in models))
        return cls(
            seg,
            links,
            m0.tp,
            profile,
            np.array([m.tow_force_N for m in models]),
            force_loop=m0.force_loop,
            elevation=m0.elevation,
            sled_mass_kg=np.array([m.sled_mass_kg for m in models]),
            sled_friction=np.array([m.sled_friction for m in models]),
        )

    # ------------------------------------------------------------------ the kernel's inputs
    def kernel_inputs(self) -> dict:
        """Everything the kernel reads: ``{attribute: value}`` for every attribute but the caches
        (:data:`CACHES`), in a fixed (sorted) order.  The float kernel walks it to tell the
        parameters of its generated code from the values that key the code
        (:func:`snoworm.model.floatkernel.model_parameters`)."""
        return {k: v for k, v in sorted(vars(self).items()) if k not in CACHES}

    def with_inputs(self, values: dict) -> ChainModel:
        """A shallow copy of the model whose kernel inputs ``values`` (a mapping like
        :meth:`kernel_inputs`, e.g. with symbols for numbers) replace its own; caches are shared."""
        unknown = set(values) - set(vars(self))
        if unknown or set(values) & CACHES:
            raise ValueError(f"not kernel inputs of a ChainModel: {sorted(unknown | (set(values) & CACHES))}")
        m = copy.copy(self)
        vars(m).update(values)
        return m

    # ------------------------------------------------------------------ layout and terrain
    def unpack(self, y):
        """View a flat state (or stack of states, leading dims) as ``(..., N, n_s)``."""
        return self.layout.unpack(y)

    def field(self, Y, name):
        """One named field of an unpacked state, shape ``(..., N)``."""
        return self.layout.get(Y, name)

    def xt_at_axles(self, x_m):
        """Terrain coefficient under each axle for segment positions ``x_m`` (..., N) -> (..., N, 2)."""
        return self.profile(np.asarray(x_m, float)[..., None] + self.axle_offset_m)

    def grade_terms(self, x_m):
        """``(sin theta, cos theta, F_n, F_g)`` under segments at positions ``x_m`` (..., N), docs/model.md
        section 7: the chord grade (:meth:`ElevationProfile.sin_grade`), the normal load per wheel, shape
        (..., N, 2) front and rear (:func:`terrain.normal_load_N`), and gravity along the track, shape
        (..., N) (:func:`terrain.gravity_force_N`).  Level ground: ``(0, 1, static load, 0)``."""
        x = _as_float(x_m)
        if self.elevation is None:
            z = np.zeros(np.shape(x + self._half_base))
            return z, z + 1.0, np.stack([z + self.normal_force_N[..., 0]] * 2, axis=-1), z
        s = self.elevation.sin_grade(x, self._half_base)
        c = np.sqrt(1.0 - s * s)
        Fn = terrain.normal_load_N(self.normal_force_N[..., 0], s, c, self._transfer)
        return s, c, Fn, terrain.gravity_force_N(self._m, self.seg.gravity_mps2, s)

    def initial_state(self, joint_extension_m=None) -> np.ndarray:
        """Chain at rest: leader at x = 0, links at their rest spacing (zero force)."""
        L = self.layout
        Y = np.zeros((self.n, L.n_s))
        spacing = self.links.rest_spacing_m.copy()
        if self.has_joints:
            s0 = np.zeros(self.n) if joint_extension_m is None else np.append(joint_extension_m, 0.0)
            Y[:, L.s] = s0
            spacing = spacing + s0[:-1]
        Y[1:, L.x] = -np.cumsum(spacing)
        return Y.reshape(-1)

    # ------------------------------------------------------------------ Jacobian
    def jac_sparsity(self, member: bool = False):
        """Structural non-zero pattern of ``d(dy/dt)/dy`` (:func:`snoworm.model.jacobian.sparsity`)."""
        return jacobian.sparsity(self, member)

    def bandwidths(self):
        """``(lband, uband)`` of :meth:`jac_sparsity`, for LSODA's banded Jacobian."""
        if self._bands is None:
            self._bands = jacobian.bandwidths(self.jac_sparsity(member=True))
        return self._bands

    def jacobian_banded(self, t, y, ctl: Controls):
        """Finite-difference Jacobian in LAPACK packed band format (:func:`snoworm.model.jacobian.banded`)."""
        if self._fd is None:
            self._fd = jacobian.BandedDifferences(self.n_states, *self.bandwidths())
        return self._fd(lambda Yp: self.evaluate(self.unpack(Yp), ctl)[0].reshape(Yp.shape), y)

    def jacobian_sparse(self, t, y, ctl: Controls):
        """The same finite-difference Jacobian as a sparse CSC matrix (for BDF and Radau)."""
        return jacobian.to_sparse(self.jacobian_banded(t, y, ctl), *self.bandwidths())

    # ------------------------------------------------------------------ kernel
    def evaluate(self, Y, ctl: Controls, outputs: bool = False, cd: dict | None = None):
        """All forces and derivatives for unpacked states ``Y`` of shape ``(..., N, n_s)``.

        Returns
        -------
        dY : ndarray, shape ``(..., N, n_s)``
            Time derivatives of every field.
        out : dict or None
            With ``outputs=True``: named intermediate quantities (per axle arrays have a
            trailing axis of 2: front, rear), used for results after the solve.

        ``cd``: the arrays of :func:`snoworm.model.inputs.control_arrays` for ``ctl`` (default: computed and cached).
        """
        tp, L = self._tpk, self.layout
        x, v = Y[..., L.x], Y[..., L.v]
        w, integ = Y[..., L.omega], Y[..., L.integral]
        R = self._R
        cd = self._controls(ctl) if cd is None else cd
        V = v[..., None]
        # normal load per wheel and gravity along the track: constant on level ground (G None) or a constant grade
        Fn, G = (
            (self._Fn_k, self._G_const)
            if self.elevation is None or self._G_const is not None
            else self.grade_terms(x)[2:]
        )
        wm = w * R
        dY = np.empty_like(Y)
        i = self._slip(Y, wm, V, dY)
        X, Ft, Ftr, Trr = self._terrain(x, V, wm, Fn, i)
        Ftr, z = self._sinkage(Y, wm, V, i, Ftr, dY)
        T, T_spring, damper_v = self._links(Y, x, v, ctl, cd, dY)
        F_tow = self._tow_force_N(x, v) if self._sled else None  # None: the constant tow_force_N
        # wheel-speed set-points, from the outer force loop where it is active (section 5.2)
        sp = ctl.speed_sp_mps
        if self.force_loop:
            tow = np.broadcast_to(self._tow_col if F_tow is None else F_tow, T.shape[:-1] + (1,))
            Fsel = np.concatenate([T, tow], axis=-1)[..., ctl.fc_link]
            vsp, dq = feedback.link_force_pi(
                Fsel, ctl.fc_ref_N, ctl.fc_sigma, Y[..., L.q], ctl.fc_nominal_mps, ctl.fc_kp, ctl.fc_ki, ctl.fc_vmax_mps
            )
            dY[..., L.q] = dq * ctl.fc_active * ctl.motor_on
            sp = np.where(ctl.fc_active > 0, vsp, sp)
            w_ref = (sp / self.seg.wheel_radius_m)[..., None]
        else:
            w_ref = cd["w_ref"]
        T_lo, T_hi = drivetrain.motor_envelope(w, self._slope, self._wnl, self._Tmax)
        Tm, dI = feedback.speed_pi(w_ref, w, integ, self._kp, self._ki, T_lo, T_hi, cd["on_mask"], self._ki_kp)
        if cd["torque"] is not None:  # direct torque commands (a controller's wheel_torque_Nm)
            Tm, dI = feedback.direct_torque(cd["torque_cmd"], T_lo, T_hi, cd["torque"], Tm, dI)
        if self._free_axle is not None:  # a failed drivetrain: no torque, the PI integral frozen
            Tm, dI = np.where(self._free_axle, self._zero, Tm), np.where(self._free_axle, self._zero, dI)
        reaction = terrain.wheel_reaction_torque(Ft, Ftr, Trr, R, tp)
        dY[..., L.omega] = (Tm - reaction) / self._J
        dY[..., L.integral] = dI
        # chassis: the net link force on segment k is T_{k-1} - T_k (T_{-1} = 0, T_{N-1} = tow)
        net = Ft - Ftr
        wheel_net = self.wheels_per_axle * (net[..., 0] + net[..., 1])
        Fl = self._connector_net_N(T, F_tow)
        dY[..., L.x] = v
        dY[..., L.v] = (wheel_net + Fl if G is None else wheel_net + Fl + G) / self._m
        if not outputs:
            return dY, None
        return dY, self._outputs(
            X=X,
            i=i,
            Ft=Ft,
            Ftr=Ftr,
            Trr=Trr,
            Tm=Tm,
            T=T,
            wheel_net=wheel_net,
            Fl=Fl,
            sp=sp,
            x=x,
            w=w,
            reaction=reaction,
            T_spring=T_spring,
            damper_v=damper_v,
            V=V,
            G=G,
            Fn=Fn,
            z=z,
        )

    def _outputs(
        self, *, X, i, Ft, Ftr, Trr, Tm, T, wheel_net, Fl, sp, x, w, reaction, T_spring, damper_v, V, G, Fn, z
    ):
        """The named quantities of :meth:`evaluate` for the results, from its intermediates."""
        nw = self.wheels_per_axle[..., None]
        return {
            "X": np.broadcast_to(X, Ft.shape),
            "slip": i,
            "traction_axle_N": Ft * nw,
            "resistance_axle_N": Ftr * nw,
            "resistance_torque_Nm": Trr,
            "motor_torque_Nm": Tm,
            "link_force_N": T,
            "wheel_net_N": wheel_net,
            "link_net_N": Fl,
            "speed_sp_mps": np.broadcast_to(sp, x.shape),
            "omega": w,
            "reaction_torque_Nm": reaction,
            "link_spring_N": T_spring,
            "link_damper_W": link_law.damper_power_W(damper_v, self._c_link) if self.n > 1 else T,
            # power dissipated at the wheel-terrain contact: what the wheels take from the
            # motors minus what reaches the chassis, per segment [W]
            "terrain_dissipation_W": self.wheels_per_axle * np.sum(reaction * w - (Ft - Ftr) * V, axis=-1),
            "gravity_N": np.zeros(x.shape) if G is None else np.broadcast_to(G, x.shape),
            "normal_load_N": np.broadcast_to(Fn, Ft.shape),
            "sinkage_m": np.zeros(Ft.shape) if z is None else z,
        }

    def _slip(self, Y, wm, V, dY):
        """Slip per axle, shape ``(..., N, 2)``: Eq. 1 regularised (:func:`terrain.slip`), or with
        ``standstill: shear`` the shear displacement's ``clip(j / K, -1, 1)``, whose rate it writes
        into ``dY`` (:func:`terrain.shear_displacement_rate`, docs/model.md section 2, "Standstill")."""
        tp = self._tpk
        if not self.shear:
            return terrain.slip(wm, V, tp.slip_eps_mps)
        j = Y[..., self.layout.j]
        dY[..., self.layout.j] = terrain.shear_displacement_rate(wm, V, j, tp.shear_modulus_K_m)
        return terrain.shear_slip(j, tp.shear_modulus_K_m)

    def _connector_net_N(self, T, F_tow):
        """Net force of the links and the tow on each segment, ``T_{k-1} - T_k`` with ``T_{-1} = 0`` and
        ``T_{N-1}`` the tow (``F_tow`` of :meth:`_tow_force_N`, None: the constant ``tow_force_N``)."""
        Tpad = np.empty_like(T, shape=T.shape[:-1] + (self.n + 1,))
        Tpad[..., 0] = 0.0
        Tpad[..., 1:-1] = T
        if F_tow is None:
            Tpad[..., -1] = self.tow_force_N
        else:
            Tpad[..., -1:] = F_tow
        return Tpad[..., :-1] - Tpad[..., 1:]

    def _torque_coefficient(self, Fn, X, R, tp):
        """Factor of the resistance torque per axle: the fitted ``T_rr`` of a driven wheel
        (:func:`terrain.torque_coefficient`), the free-rolling ``T_free`` where the drivetrain has failed
        (:func:`terrain.free_rolling_coefficient`; docs/model.md section 2, "Terrain resistance torque")."""
        c = terrain.torque_coefficient(Fn, X, R, tp)
        if self._free_axle is None:
            return c
        return np.where(self._free_axle, terrain.free_rolling_coefficient(Fn, X, R, tp), c)

    def _sinkage(self, Y, wm, V, i, Ftr, dY):
        """``(F_tr, z)``: with ``sinkage: slip`` the resistance raised by the sinkage ``z`` of each axle,
        whose rate it writes into ``dY`` (:func:`terrain.sinkage_rate`, docs/model.md section 2,
        "Slip-sinkage"); otherwise ``(F_tr, None)``."""
        if not self.sinkage:
            return Ftr, None
        tp, z_at = self._tpk, self.layout.z
        z = Y[..., z_at]
        dY[..., z_at] = terrain.sinkage_rate(wm, V, i, z, tp)
        return Ftr * terrain.sinkage_resistance_factor(z, tp), z

    def _terrain(self, x, V, wm, Fn, i):
        """Per-axle terrain quantities (Eqs. 2-3, resistance torque) at slip ``i``, X_t evaluated at each axle.

        Returns ``(X, F_t, F_tr, T_rr)`` per wheel, shape ``(..., N, 2)``.
        """
        tp, R = self._tpk, self._R
        if self._coef is not None:  # X_t constant: position-independent factors precomputed
            c_t, c_r, c_q = self._coef
            X = self._Xc
        else:
            X = self.profile(x[..., None] + self.axle_offset_m)
            c_t = terrain.traction_coefficients(Fn, X, tp)
            c_r = terrain.resistance_coefficients(Fn, X, tp)
            c_q = self._torque_coefficient(Fn, X, R, tp)
        Ft = terrain.traction_from_coefficients(i, c_t)
        Ftr = terrain.resistance_from_coefficients(V, c_r, tp)
        Trr = terrain.torque_from_coefficient(wm, c_q, tp)
        return X, Ft, Ftr, Trr

    def _links(self, Y, x, v, ctl, cd, dY):
        """Link forces (tension positive): spring-damper in series with the prismatic actuator.

        Writes the actuators' extension rates into ``dY``; returns ``(T, T_spring, damper speed)``.
        """
        L = self.layout
        if self.n == 1:
            if self.has_joints:
                dY[..., L.s] = 0.0
            T = np.zeros_like(x, shape=x.shape[:-1] + (0,))
            return T, T, T
        rel = v[..., :-1] - v[..., 1:]
        stretch = x[..., :-1] - x[..., 1:] - self._L0
        if self.has_joints:
            s = Y[..., :-1, L.s]
            T_spring = link_law.spring_force_N(stretch, s, self._k_link)
            ds = self._joint_rate(s, v, rel, T_spring, ctl, cd)
            dY[..., :-1, L.s] = ds
            dY[..., -1, L.s] = 0.0
            damper_v = rel - ds
        else:
            T_spring = link_law.spring_force_N(stretch, None, self._k_link)
            damper_v = rel
        return link_law.link_force_N(T_spring, damper_v, self._c_link), T_spring, damper_v

    def _joint_rate(self, s, v, rel, T_spring, ctl: Controls, cd):
        """Extension rate of the prismatic actuators: the commanded servo within the actuator's limits.

        Force command (:func:`snoworm.feedback.joint_force_rate_mps`) or length command
        (:func:`snoworm.feedback.joint_length_rate_mps`), then the actuator's rate limit and soft
        end stops (:func:`snoworm.links.actuator_rate_mps`); locked (inactive) joints and fixed
        links do not move.
        """
        if not cd["any_active"]:  # every joint locked in this interval
            return s * self._zero
        gk = self._gk
        if cd["any_force"]:
            mag = feedback.joint_force_command_N(
                ctl.joint_ff_N,
                ctl.joint_limit_N,
                self._zero,
                kv=ctl.joint_kv if cd["any_kv"] else None,
                v_target_mps=ctl.joint_vtarget_mps,
                v_mover_mps=v[..., ctl.joint_mover] if cd["any_kv"] else None,
                ka=ctl.joint_ka if cd["any_ka"] else None,
                v_anchor_mps=v[..., ctl.joint_anchor] if cd["any_ka"] else None,
            )
            rate = feedback.joint_force_rate_mps(rel, T_spring, cd["neg_dir"], mag, gk)
        if cd["any_length"]:
            rate_l = feedback.joint_length_rate_mps(
                s,
                ctl.joint_sref_m,
                ctl.joint_vtarget_mps,
                cd["neg_vt"],
                rel,
                T_spring,
                ctl.joint_limit_N,
                gk,
                self._k_length,
            )
            rate = np.where(cd["length_mode"], rate_l, rate) if cd["any_force"] else rate_l
        rate = link_law.actuator_rate_mps(
            rate, s, self._rate_max, self._neg_rate_max, self._stroke_min, self._stroke_max, self._k_stop
        )
        return rate * cd["active"]

    def rhs(self, t, y, ctl: Controls):
        """``dy/dt`` for :func:`scipy.integrate.solve_ivp` (pure: records nothing).

        A single chain of at most :data:`~snoworm.model.floatkernel.MAX_SEGMENTS` segments runs on
        the float kernel generated from :meth:`evaluate` (:attr:`float_kernel`); others on
        :meth:`evaluate` itself.
        """
        fk = self.float_kernel
        if fk is not None:
            return fk(y, ctl)
        dY, _ = self.evaluate(y.reshape(self.layout.shape), ctl)
        return dY.reshape(-1)
