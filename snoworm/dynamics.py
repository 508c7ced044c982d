r"""Longitudinal dynamics of a chain of wheeled segments (MODEL.md section 4).

::

        direction of travel  -->                                   x (forward, m)

      link N-2        link 1          link 0
    [seg N-1]==T==> ... [seg 1]==T==>[seg 0]      T_k > 0: link k in tension
      <-- F_tow                                   segment 0 is the leader (front)
      each segment: 2 axles at x_k +- wheelbase/2, each axle with 2 wheels

    m_k dv_k/dt = n_w * sum_axles (F_t - F_tr) + T_{k-1} - T_k - F_tow [k = N-1]
    J   dw/dt   = T_m - R_w (F_t - F_tr) - T_rr                 (per wheel, per axle)
    T_k = k_c (x_k - x_{k+1} - L_0 - s_k) + c_c (v_k - v_{k+1} - ds_k/dt)
          (spring-damper in series with the prismatic actuator of extension s_k; s_k = 0 fixed)

One kernel, :meth:`ChainModel.evaluate`, computes every force of the model from the state for
any leading batch shape: the right-hand side calls it on one state (or a stack of batch
members), the results module calls it on all output samples at once after the solve.

State layout (one block of ``n_s`` fields per segment, interleaved so the Jacobian is banded)::

    x_m, v_mps, omega_front, omega_rear, integral_front_Nm, integral_rear_Nm
    [, q_mps (outer force-loop integral, force-control mode)]
    [, s_m (extension of the prismatic joint in the link *behind* the segment)]
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import drivetrain, terrain
from .terrain import TerrainParams, TerrainProfile

__all__ = ["Controls", "ChainModel", "SegmentArrays", "StackedConstantProfile"]


@dataclass(frozen=True)
class SegmentArrays:
    """Per-segment physical parameters as arrays of length N (SI units)."""

    mass_kg: np.ndarray
    wheel_radius_m: np.ndarray
    wheel_inertia_kgm2: np.ndarray
    wheelbase_m: np.ndarray
    wheels_per_axle: np.ndarray
    gravity_mps2: np.ndarray
    motor_slope_Nms_per_rad: np.ndarray
    no_load_speed_radps: np.ndarray
    torque_limit_Nm: np.ndarray
    drivetrain_efficiency: np.ndarray
    speed_kp_Nms_per_rad: np.ndarray
    speed_ki_Nm_per_rad: np.ndarray

    @classmethod
    def from_list(cls, segments) -> "SegmentArrays":
        """Stack a list of per-segment parameter objects (with the same attribute names)."""
        names = cls.__dataclass_fields__
        return cls(**{n: np.array([float(getattr(s, n)) for s in segments]) for n in names})

    @property
    def normal_force_N(self) -> np.ndarray:
        """Static normal load per wheel, ``m g / (2 n_w)`` (no load transfer)."""
        return self.mass_kg * self.gravity_mps2 / (2.0 * self.wheels_per_axle)


@dataclass(frozen=True)
class LinkArrays:
    """Per-link parameters as arrays of length N-1."""

    stiffness_N_per_m: np.ndarray
    damping_Ns_per_m: np.ndarray
    rest_spacing_m: np.ndarray
    prismatic: np.ndarray          # 1.0 for an active prismatic joint, 0.0 for a fixed link
    stroke_min_m: np.ndarray
    stroke_max_m: np.ndarray
    force_max_N: np.ndarray
    rate_max_mps: np.ndarray
    force_gain_per_s: np.ndarray


#: Gain of the length servo of a length-commanded prismatic joint [1/s].
K_LENGTH = 20.0

#: Gain of the soft end stops of a prismatic joint [1/s]: the extension rate is limited to
#: ``K_STOP * (distance to the stop)``, so the stroke is never exceeded.
K_STOP = 50.0


@dataclass(frozen=True)
class Controls:
    """Piecewise-constant inputs of the chain during one integration interval.

    Modes (``snoworm.modes``) produce these; the physics stays the same for every mode.
    Arrays have length N (segments) or N-1 (links).

    Attributes
    ----------
    motor_on : (N,) 1 where the segment's motors run (after its start time), else 0.
    speed_sp_mps : (N,) wheel-speed set-point ``R_w w_ref`` [m/s]; 0 locks the wheels.
    fc_active : (N,) 1 where an outer force loop sets the wheel-speed set-point.
    fc_link : (N,) int, index of the controlled force: link ``j`` (0..N-2) or ``N-1`` = the tow.
    fc_sigma : (N,) +1 if the controlled link is behind the segment, -1 if ahead.
    fc_ref_N, fc_nominal_mps, fc_kp, fc_ki, fc_vmax_mps : (N,) outer PI loop settings:
        ``v_sp = clip(v_nom + kp e + q, 0, v_max)``, ``e = sigma (F_ref - F)``.
    joint_active : (N-1,) 1 where a prismatic joint is driven, 0 where it is locked at its length.
    joint_length_mode : (N-1,) 1: commanded in length (to ``joint_sref_m`` at rate
        ``joint_vtarget_mps``, force limited to ``joint_limit_N``); 0: commanded in force.
    joint_sref_m : (N-1,) length command (extension) of length-commanded joints [m].
    joint_dir : (N-1,) +1 to push (extend, compression), -1 to pull (contract, tension).
    joint_ff_N, joint_kv, joint_vtarget_mps, joint_limit_N : (N-1,) force command
        ``|F| = clip(ff + kv (v_target - v_mover), 0, limit)``.
    joint_mover : (N-1,) int, index of the segment whose speed the joint regulates.
    joint_anchor, joint_ka : (N-1,) int and [N s/m]: the held segment the joint bears on, and the
        gain by which the force command drops while that anchor slides backward,
        ``|F| -= ka max(0, -v_anchor)`` (limits backward sliding, paper section 5.1).
    """

    motor_on: np.ndarray
    speed_sp_mps: np.ndarray
    fc_active: np.ndarray
    fc_link: np.ndarray
    fc_sigma: np.ndarray
    fc_ref_N: np.ndarray
    fc_nominal_mps: np.ndarray
    fc_kp: np.ndarray
    fc_ki: np.ndarray
    fc_vmax_mps: np.ndarray
    joint_active: np.ndarray
    joint_length_mode: np.ndarray
    joint_sref_m: np.ndarray
    joint_dir: np.ndarray
    joint_ff_N: np.ndarray
    joint_kv: np.ndarray
    joint_vtarget_mps: np.ndarray
    joint_limit_N: np.ndarray
    joint_mover: np.ndarray
    joint_anchor: np.ndarray
    joint_ka: np.ndarray

    @classmethod
    def rolling(cls, n: int, motor_on, speed_sp_mps) -> "Controls":
        """Plain wheel-speed control: no force loop, every joint holding its length."""
        z = np.zeros(n)
        zl = np.zeros(max(n - 1, 0))
        return cls(
            motor_on=np.asarray(motor_on, float) * np.ones(n),
            speed_sp_mps=np.asarray(speed_sp_mps, float) * np.ones(n),
            fc_active=z.copy(), fc_link=np.full(n, n - 1, dtype=int), fc_sigma=np.ones(n),
            fc_ref_N=z.copy(), fc_nominal_mps=z.copy(), fc_kp=np.ones(n), fc_ki=z.copy(),
            fc_vmax_mps=z.copy(),
            joint_active=zl.copy(), joint_length_mode=zl.copy(), joint_sref_m=zl.copy(),
            joint_dir=np.ones_like(zl), joint_ff_N=zl.copy(),
            joint_kv=zl.copy(), joint_vtarget_mps=zl.copy(), joint_limit_N=zl.copy(),
            joint_mover=np.arange(max(n - 1, 0), dtype=int),
            joint_anchor=np.arange(1, max(n, 1), dtype=int), joint_ka=zl.copy(),
        )

    @classmethod
    def stack(cls, controls) -> "Controls":
        """The controls of B stacked chains (:meth:`ChainModel.stack`): arrays equal in every member
        stay as they are, the others get a leading batch axis; index arrays must be equal."""
        kw = {}
        for name in cls.__dataclass_fields__:
            arrs = [np.asarray(getattr(c, name)) for c in controls]
            if all(np.array_equal(a, arrs[0]) for a in arrs[1:]):
                kw[name] = arrs[0]
            elif arrs[0].dtype.kind in "iu":
                raise ValueError(f"stacked controls need the same {name}")
            else:
                kw[name] = np.stack(arrs)
        return cls(**kw)

    def with_(self, **kw) -> "Controls":
        """A copy with some arrays replaced (converted to float arrays)."""
        return replace(self, **{k: np.asarray(v) for k, v in kw.items()})


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
    """

    def __init__(self, seg: SegmentArrays, links: LinkArrays, terrain_params: TerrainParams,
                 profile: TerrainProfile, tow_force_N: float, force_loop: bool = False):
        self.seg = seg
        self.links = links
        self.tp = terrain_params
        self.profile = profile
        #: leading batch shape of the parameter arrays: () for one chain, (B,) for B stacked
        #: chains (see :meth:`stack`); every per-segment array then has shape (B, N)
        self.batch_shape = tuple(np.shape(seg.mass_kg)[:-1])
        self.tow_force_N = float(tow_force_N) if np.ndim(tow_force_N) == 0 else np.asarray(tow_force_N, float)
        self.n = int(np.shape(seg.mass_kg)[-1])
        self.force_loop = bool(force_loop)
        self.has_joints = bool(np.any(links.prismatic > 0))
        fields = ["x_m", "v_mps", "omega_front", "omega_rear", "integral_front_Nm", "integral_rear_Nm"]
        if self.force_loop:
            fields.append("q_mps")
        if self.has_joints:
            fields.append("s_m")
        self.fields = tuple(fields)
        self.idx = {f: j for j, f in enumerate(fields)}
        self.n_s = len(fields)
        self.n_batch = int(np.prod(self.batch_shape, dtype=int))
        self.n_states = self.n_batch * self.n * self.n_s
        self._shape = self.batch_shape + (self.n, self.n_s)
        # constants prepared once (shapes broadcast against (..., N, 2) axle arrays)
        col = lambda a: np.asarray(a, float)[..., None]
        self._R = col(seg.wheel_radius_m)
        self._J = col(seg.wheel_inertia_kgm2)
        self._Fn = col(seg.normal_force_N)
        self._axle_offset = np.stack([seg.wheelbase_m / 2.0, -seg.wheelbase_m / 2.0], axis=-1)
        self._kp = col(seg.speed_kp_Nms_per_rad)
        self._ki = col(seg.speed_ki_Nm_per_rad)
        self._slope = col(seg.motor_slope_Nms_per_rad)
        self._wnl = col(seg.no_load_speed_radps)
        self._Tmax = col(seg.torque_limit_Nm)
        self._nw = seg.wheels_per_axle.astype(float)
        self._m = seg.mass_kg.astype(float)
        self._prepare_kernel()

    def _prepare_kernel(self):
        """Derived constants of the kernel, computed once (micro-optimisations, same arithmetic).

        Scalars become 0-d arrays (NumPy multiplies by them ~2x faster than by Python floats);
        with X_t constant along the track, the position-independent factors of the terrain laws
        are evaluated once here (:func:`terrain.traction_coefficients` and friends).
        """
        tp, L = self.tp, self.links
        z = lambda v: np.array(v, float)
        self._tpk = replace(tp, **{k: z(getattr(tp, k)) for k in ("b_tF", "b_trF", "A", "peak_exponent_d", "tau0",
                                                                 "tau1", "slip_eps_mps", "sign_eps_mps")})
        self._zero = z(0.0)
        if getattr(self.profile, "is_constant", False):
            X = self.profile(self._axle_offset)
            self._Xc = X
            self._coef = (terrain.traction_coefficients(self._Fn, X, self._tpk),
                          terrain.resistance_coefficients(self._Fn, X, self._tpk),
                          terrain.torque_coefficient(self._Fn, X, self._R, self._tpk))
        else:
            self._Xc = self._coef = None
        # links: spring-damper constants and the joint servo's effective gain
        self._k_link = np.asarray(L.stiffness_N_per_m, float)
        self._c_link = np.asarray(L.damping_Ns_per_m, float)
        self._L0 = np.asarray(L.rest_spacing_m, float)
        gk0 = L.force_gain_per_s / L.stiffness_N_per_m if self.n > 1 else np.zeros(0)
        self._gk = gk0 / (1.0 + L.damping_Ns_per_m * gk0)
        self._rate_max = np.asarray(L.rate_max_mps, float)
        self._neg_rate_max = -self._rate_max
        self._k_stop, self._k_length = z(K_STOP), z(K_LENGTH)
        self._stroke_max = np.asarray(L.stroke_max_m, float)
        self._stroke_min = np.asarray(L.stroke_min_m, float)
        self._tow_col = np.asarray(self.tow_force_N, float)[..., None]
        self._ctl_cache = (None, None)

    def _controls(self, ctl: Controls):
        """Arrays derived from the controls of an interval, computed once per Controls object."""
        cached, d = self._ctl_cache
        if cached is ctl:
            return d
        d = {"on": np.asarray(ctl.motor_on, float)[..., None],
             "w_ref": (ctl.speed_sp_mps / self.seg.wheel_radius_m)[..., None]}
        if self.has_joints and self.n > 1:
            L = self.links
            d["neg_dir"] = -ctl.joint_dir
            d["neg_vt"] = -ctl.joint_vtarget_mps
            d["length_mode"] = ctl.joint_length_mode > 0
            d["active"] = ctl.joint_active * L.prismatic
            # which parts of the joint law this interval needs (constant within the interval,
            # so skipping the others changes no result; see _joint_rate)
            moving = d["active"] != 0
            d["any_active"] = bool(np.any(moving))
            d["any_length"] = bool(np.any(d["length_mode"] & moving))
            d["any_force"] = bool(np.any(~d["length_mode"] & moving))
            d["any_kv"] = bool(np.any(np.asarray(ctl.joint_kv) != 0))
            d["any_ka"] = bool(np.any(np.asarray(ctl.joint_ka) != 0))
        self._ctl_cache = (ctl, d)
        return d

    @classmethod
    def stack(cls, models) -> "ChainModel":
        """B chains of the same structure as ONE model with a leading batch axis (for batched sweeps).

        Every model must have the same N, state layout, terrain coefficients and either the same
        X_t profile or constant profiles (X_t may differ per chain).  Per-segment and per-link
        parameters and the tow force become arrays of shape (B, N), (B, N-1) and (B,); the state
        of the stacked model is the member-major concatenation of the B states, and its
        Jacobian is block-banded with each member's band.  The physics is :meth:`evaluate`,
        unchanged: the parameters simply carry one more leading axis.
        """
        m0 = models[0]
        for m in models[1:]:
            if (m.n, m.fields, m.force_loop, m.has_joints) != (m0.n, m0.fields, m0.force_loop, m0.has_joints):
                raise ValueError("stacked chains need the same number of segments and state layout")
            if m.tp != m0.tp:
                raise ValueError("stacked chains need the same terrain coefficients")
            if m.profile != m0.profile and not (m.profile.is_constant and m0.profile.is_constant):
                raise ValueError("stacked chains need the same X_t profile, or constant profiles")
        st = lambda objs, name: np.stack([np.asarray(getattr(o, name), float) for o in objs])
        seg = SegmentArrays(**{k: st([m.seg for m in models], k) for k in SegmentArrays.__dataclass_fields__})
        links = LinkArrays(**{k: st([m.links for m in models], k) for k in LinkArrays.__dataclass_fields__})
        if all(m.profile == m0.profile for m in models):
            profile = m0.profile
        else:
            profile = StackedConstantProfile(tuple(float(m.profile.values[0]) for m in models))
        return cls(seg, links, m0.tp, profile, np.array([m.tow_force_N for m in models]), force_loop=m0.force_loop)

    # ------------------------------------------------------------------ layout
    def unpack(self, y):
        """View a flat state (or stack of states, leading dims) as ``(..., N, n_s)``."""
        y = np.asarray(y)
        return y.reshape(y.shape[:-1] + self._shape)

    def field(self, Y, name):
        """One named field of an unpacked state, shape ``(..., N)``."""
        return Y[..., self.idx[name]]

    def initial_state(self, joint_extension_m=None) -> np.ndarray:
        """Chain at rest: leader at x = 0, links at their rest spacing (zero force)."""
        Y = np.zeros((self.n, self.n_s))
        spacing = self.links.rest_spacing_m.copy()
        if self.has_joints:
            s0 = np.zeros(self.n) if joint_extension_m is None else np.append(joint_extension_m, 0.0)
            Y[:, self.idx["s_m"]] = s0
            spacing = spacing + s0[:-1]
        Y[1:, 0] = -np.cumsum(spacing)
        return Y.reshape(-1)

    def jac_sparsity(self, member: bool = False):
        """Structural non-zero pattern of the Jacobian ``d(dy/dt)/dy`` (dense bool array).

        For stacked chains (:meth:`stack`) the pattern is block diagonal, one block per member,
        returned as a sparse matrix (``member=True``: one member's dense block).

        Within a segment every field may depend on every other (except ``x``, which is the
        integral of ``v``).  Across segments only the link forces couple: the force of link
        ``k-1`` (ahead) depends on ``x, v`` of segments ``k-1, k`` and on ``s_{k-1}``; link ``k``
        (behind) on ``x, v`` of ``k, k+1`` and on ``s_k``.  Rows that see a link force: ``v``;
        ``s`` (its own link, and the mover speed of the link's other segment); with a force
        loop also ``q`` and the wheel states that follow its set-point.
        """
        ns, n, I = self.n_s, self.n, self.idx
        own = np.ones((ns, ns), bool)
        own[I["x_m"], :] = False
        own[I["x_m"], I["v_mps"]] = True
        prev = np.zeros((ns, ns), bool)    # rows of segment k, columns of segment k-1
        nxt = np.zeros((ns, ns), bool)     # rows of segment k, columns of segment k+1
        ahead_rows = ["v_mps"]             # rows that see link k-1
        behind_rows = ["v_mps"]            # rows that see link k
        if self.has_joints:
            behind_rows.append("s_m")
        if self.force_loop:
            loop_rows = ["q_mps", "omega_front", "omega_rear", "integral_front_Nm", "integral_rear_Nm"]
            ahead_rows += loop_rows
            behind_rows += loop_rows
        for r in ahead_rows:
            for c in ("x_m", "v_mps"):
                prev[I[r], I[c]] = True
            if self.has_joints:
                prev[I[r], I["s_m"]] = True
        for r in behind_rows:
            for c in ("x_m", "v_mps"):
                nxt[I[r], I[c]] = True
        P = np.zeros((n * ns, n * ns), bool)
        for k in range(n):
            P[k * ns:(k + 1) * ns, k * ns:(k + 1) * ns] = own
            if k > 0:
                P[k * ns:(k + 1) * ns, (k - 1) * ns:k * ns] = prev
            if k < n - 1:
                P[k * ns:(k + 1) * ns, (k + 1) * ns:(k + 2) * ns] = nxt
        if member or not self.batch_shape:
            return P
        from scipy.sparse import block_diag
        return block_diag([P] * self.n_batch, format="csr").astype(bool)   # stacked chains

    def bandwidths(self):
        """``(lband, uband)`` of :meth:`jac_sparsity`, for LSODA's banded Jacobian."""
        if getattr(self, "_bands", None) is None:
            r, c = np.nonzero(self.jac_sparsity(member=True))
            self._bands = int(max(0, np.max(r - c))), int(max(0, np.max(c - r)))
        return self._bands

    def _fd_plan(self):
        """Column groups and gather indices of the banded finite-difference Jacobian (built once)."""
        if getattr(self, "_plan", None) is None:
            lb, ub = self.bandwidths()
            n = self.n_states
            w = min(lb + ub + 1, n)
            cols = np.arange(n)
            group = cols % w
            r = np.arange(lb + ub + 1)[:, None]
            rows = cols[None, :] + r - ub                 # row i of packed entry (r, j)
            valid = (rows >= 0) & (rows < n)
            self._plan = (w, group, rows, valid)
        return self._plan

    def jacobian_banded(self, t, y, ctl: "Controls", rel_step: float = 1.2e-4):
        """Finite-difference Jacobian in LAPACK packed band format, from ONE vectorised kernel call.

        All ``lband + uband + 1`` column groups of the band are perturbed at once and
        evaluated as a stack through :meth:`evaluate` (its leading batch axis), so a Jacobian
        costs about as much as one or two right-hand-side calls instead of one per group.
        Returns ``J_packed`` with ``J_packed[uband + i - j, j] = dF_i/dy_j``, the layout
        ``solve_ivp(method="LSODA", lband=..., uband=...)`` expects.
        """
        w, group, rows, valid = self._fd_plan()
        n = y.size
        h = rel_step * np.maximum(1e-3, np.abs(y))
        Yp = np.tile(y, (w + 1, 1))
        Yp[1 + group, np.arange(n)] += h
        h = Yp[1 + group, np.arange(n)] - y           # the step actually taken (rounding)
        dY, _ = self.evaluate(Yp.reshape((w + 1,) + self._shape), ctl)
        F = dY.reshape(w + 1, n)
        dF = F[1:] - F[0]
        g = np.broadcast_to(group, rows.shape)
        packed = np.where(valid, dF[g, np.where(valid, rows, 0)], 0.0) / h[None, :]
        return packed

    def jacobian_sparse(self, t, y, ctl: "Controls"):
        """The same finite-difference Jacobian as a sparse CSC matrix (for BDF and Radau)."""
        from scipy.sparse import dia_matrix
        lb, ub = self.bandwidths()
        packed = self.jacobian_banded(t, y, ctl)
        return dia_matrix((packed, np.arange(ub, -lb - 1, -1)), shape=(y.size, y.size)).tocsc()

    # ------------------------------------------------------------------ kernel
    def evaluate(self, Y, ctl: Controls, outputs: bool = False):
        """All forces and derivatives for unpacked states ``Y`` of shape ``(..., N, n_s)``.

        Returns
        -------
        dY : ndarray, shape ``(..., N, n_s)``
            Time derivatives of every field.
        out : dict or None
            With ``outputs=True``: named intermediate quantities (per axle arrays have a
            trailing axis of 2: front, rear), used for results after the solve.
        """
        tp = self._tpk
        I = self.idx
        x = Y[..., 0]
        v = Y[..., 1]
        w = Y[..., 2:4]
        integ = Y[..., 4:6]
        R = self._R
        cd = self._controls(ctl)
        # terrain, per axle (Eqs. 1-3, resistance torque), X_t evaluated at each axle
        wm = w * R
        V = v[..., None]
        i = terrain.slip(wm, V, tp.slip_eps_mps)
        if self._coef is not None:          # X_t constant: position-independent factors precomputed
            c_t, c_r, c_q = self._coef
            X = self._Xc
        else:
            X = self.profile(x[..., None] + self._axle_offset)
            c_t = terrain.traction_coefficients(self._Fn, X, tp)
            c_r = terrain.resistance_coefficients(self._Fn, X, tp)
            c_q = terrain.torque_coefficient(self._Fn, X, R, tp)
        Ft = terrain.traction_from_coefficients(i, c_t)
        Ftr = terrain.resistance_from_coefficients(V, c_r, tp)
        Trr = terrain.torque_from_coefficient(wm, c_q, tp)
        # links (tension positive): a spring-damper in series with the prismatic actuator
        dY = np.empty_like(Y)
        if self.n > 1:
            rel = v[..., :-1] - v[..., 1:]
            stretch = x[..., :-1] - x[..., 1:] - self._L0
            if self.has_joints:
                s = Y[..., :-1, I["s_m"]]
                T_spring = self._k_link * (stretch - s)
                ds = self._joint_rate(s, v, rel, T_spring, ctl, cd)
                dY[..., :-1, I["s_m"]] = ds
                dY[..., -1, I["s_m"]] = 0.0
                damper_v = rel - ds
            else:
                T_spring = self._k_link * stretch
                damper_v = rel
            T = T_spring + self._c_link * damper_v
        else:
            T = T_spring = damper_v = np.zeros(x.shape[:-1] + (0,))
            if self.has_joints:
                dY[..., I["s_m"]] = 0.0
        # wheel-speed set-points, from the outer force loop where it is active (section 5.2)
        sp = ctl.speed_sp_mps
        if self.force_loop:
            tow = np.broadcast_to(self._tow_col, T.shape[:-1] + (1,))
            Fsel = np.concatenate([T, tow], axis=-1)[..., ctl.fc_link]
            e = ctl.fc_sigma * (ctl.fc_ref_N - Fsel)
            q = Y[..., I["q_mps"]]
            raw = ctl.fc_nominal_mps + ctl.fc_kp * e + q
            vsp = np.minimum(np.maximum(raw, 0.0), ctl.fc_vmax_mps)
            dY[..., I["q_mps"]] = (ctl.fc_ki * e + (ctl.fc_ki / ctl.fc_kp) * (vsp - raw)) * ctl.fc_active * ctl.motor_on
            sp = np.where(ctl.fc_active > 0, vsp, sp)
            w_ref = (sp / self.seg.wheel_radius_m)[..., None]
        else:
            w_ref = cd["w_ref"]
        T_lo, T_hi = drivetrain.motor_envelope(w, self._slope, self._wnl, self._Tmax)
        Tm, dI = drivetrain.speed_pi(w_ref, w, integ, self._kp, self._ki, T_lo, T_hi, cd["on"])
        reaction = terrain.wheel_reaction_torque(Ft, Ftr, Trr, R, tp)
        dY[..., 2:4] = (Tm - reaction) / self._J
        dY[..., 4:6] = dI
        # chassis: the net link force on segment k is T_{k-1} - T_k (T_{-1} = 0, T_{N-1} = tow)
        net = Ft - Ftr
        wheel_net = self._nw * (net[..., 0] + net[..., 1])
        Tpad = np.empty(T.shape[:-1] + (self.n + 1,))
        Tpad[..., 0] = 0.0
        Tpad[..., 1:-1] = T
        Tpad[..., -1] = self.tow_force_N
        Fl = Tpad[..., :-1] - Tpad[..., 1:]
        dY[..., 0] = v
        dY[..., 1] = (wheel_net + Fl) / self._m
        if not outputs:
            return dY, None
        nw = self._nw[..., None]
        X = np.broadcast_to(X, Ft.shape)
        out = {
            "X": X, "slip": i, "traction_axle_N": Ft * nw, "resistance_axle_N": Ftr * nw,
            "resistance_torque_Nm": Trr, "motor_torque_Nm": Tm, "link_force_N": T,
            "wheel_net_N": wheel_net, "link_net_N": Fl, "speed_sp_mps": np.broadcast_to(sp, x.shape),
            "omega": w, "reaction_torque_Nm": reaction,
            "link_spring_N": T_spring, "link_damper_W": self._c_link * damper_v**2 if self.n > 1 else T,
            # power dissipated at the wheel-terrain contact: what the wheels take from the
            # motors minus what reaches the chassis, per segment [W]
            "terrain_dissipation_W": self._nw * np.sum(reaction * w - (Ft - Ftr) * V, axis=-1),
        }
        return dY, out

    def _joint_rate(self, s, v, rel, T_spring, ctl: Controls, cd=None):
        """Extension rate of the prismatic actuators: force-limited, rate-limited servos.

        Force command: velocity feed-forward (follow the segments' relative motion) plus a
        proportional loop on the spring force, ``d(T_spring)/dt = -g (T_spring - T_ref)``, so the
        force tracks without lag from the segments' accelerations.  Length command: a rate-limited servo to ``s_ref`` that backs off
        where the spring force would exceed the limit.  Both respect the actuator's rate limit
        and soft end stops; locked (inactive) joints and fixed links do not move.
        """
        cd = self._controls(ctl) if cd is None else cd
        if not cd["any_active"]:               # every joint locked in this interval
            return s * self._zero
        # with the damper in series, T = T_spring + c (rel - rate); solving the loop
        # rate = rel + (T - T_ref) g/k for T gives the effective gain below (``_gk``, prepared
        # once): T approaches T_ref monotonically (never beyond it), at the rate g / (1 + c g / k)
        gk = self._gk
        if cd["any_force"]:
            cmd = ctl.joint_ff_N
            if cd["any_kv"]:
                cmd = cmd + ctl.joint_kv * (ctl.joint_vtarget_mps - v[..., ctl.joint_mover])
            if cd["any_ka"]:
                cmd = cmd - ctl.joint_ka * np.maximum(-v[..., ctl.joint_anchor], self._zero)
            mag = np.minimum(np.maximum(cmd, self._zero), ctl.joint_limit_N)
            rate = rel + (T_spring - cd["neg_dir"] * mag) * gk
        if cd["any_length"]:
            vt = ctl.joint_vtarget_mps
            rate_l = np.minimum(np.maximum(self._k_length * (ctl.joint_sref_m - s), cd["neg_vt"]), vt)
            rate_l = np.minimum(rate_l, rel + (T_spring + ctl.joint_limit_N) * gk)
            rate_l = np.maximum(rate_l, rel + (T_spring - ctl.joint_limit_N) * gk)
            rate = np.where(cd["length_mode"], rate_l, rate) if cd["any_force"] else rate_l
        rate = np.minimum(np.maximum(rate, self._neg_rate_max), self._rate_max)
        rate = np.minimum(rate, self._k_stop * (self._stroke_max - s))
        rate = np.maximum(rate, self._k_stop * (self._stroke_min - s))
        return rate * cd["active"]

    def rhs(self, t, y, ctl: Controls):
        """``dy/dt`` for :func:`scipy.integrate.solve_ivp` (pure: records nothing)."""
        dY, _ = self.evaluate(y.reshape(self._shape), ctl)
        return dY.reshape(-1)
