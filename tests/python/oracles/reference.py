"""An independent continuous-time reference of gearsim's rigs with backlash.

Written from the documented equations only (docs/physics.md sections 0-6, 8
and 11, with the correction of section 4.6, and the decisions D1/D2 of issue
12), never from the C sources, so that the tests can hold the C rig against
something that does not share its closed forms or its time stepping.

What it models (both blocks, every friction model, backlash always on):

- The mesh is compliant. State ``x`` (m), the backlash position at the pitch
  line: ``dx/dt = v = r_B*omega_B - c_F*omega_F`` (eq. 4.1/4.2), where
  ``c_F = s*r_F`` for the Simple Gear (``r_F = g*r_B``) and ``c_F = s_R`` for
  the Rack & Pinion (the rack is the follower with radius 1, eq. 6.1).
- Contact force ``f(x, v)`` by the hard-stop laws of section 4.3-4.5
  (``full_damped``, ``full_undamped``, ``smooth`` with the cubic step over the
  transition region ``d``), with the optional no-pull clip.
- Loss-free tooth torques (eq. 4.6): ``T_B = r_B*f``, ``T_F0 = -c_F*f``.
- The mesh loss by the corrected rule of section 4.6: the loss laws of
  sections 2.2, 2.6, 2.7 and 6.4 are written in ``T_F``, the follower torque
  after the loss, so ``T_F = T_F0 + tau_mesh(T_F)`` is *solved numerically*
  (``scipy.optimize.brentq`` on a bracket that holds the root) at every
  evaluation of the right-hand side. No closed form of the C core is used.
  As in the rigs (section 11, "Lossy meshes hold") the loss is a friction
  element on the follower: while it slides, the law at full strength (every
  tanh factor +-1, the sign of the speed or the power flow); at rest (a mode
  entered by an event when the follower's speed reaches zero), no motion
  while the torque that would move it, ``load + offset - T_F0``, stays
  between the two bounds, the loss sliding forward and backward, and a
  breakaway event when it leaves them. ``set_valued=False`` keeps the
  smoothed laws everywhere.
- Port torques ``tau_B = T_B + mu_B*omega_B`` and ``tau_F = T_F + mu_F*omega_F``
  (rack: ``F_R = F_net + mu_R*v_R``); the block applies ``-tau_X`` to its shaft.
- Driven side: ``J_F*domega_F/dt = load + load_offset - coulomb(omega_F) - tau_F``
  with ``coulomb = F_C*tanh(4*omega_F/omega_C)`` (section 11). The rig's
  Coulomb friction is only the *regularised* law here, not D2's set-valued
  stick-slip: compare with ``load_coulomb_friction = 0``, or with a steep
  regularisation and runs that do not dwell at standstill.
- Base side: speed-driven (the held base speed ramps linearly between samples;
  sample k is reached at the end of step k; the first sample sets the initial
  speeds with the follower geared to it and the teeth at
  ``initial_backlash_position``) or torque-driven (``J_B*domega_B/dt =
  motor - tau_B``, the motor torque held over each step).
- Temperature: the measured input (held over each step) when
  ``temperature_input=True``, else, for the temperature-dependent models, the
  thermal state of eq. 5.1 ``C*dT/dt = P_loss + Q_H`` with
  ``P_loss = tau_mesh*omega_F + mu_B*omega_B^2 + mu_F*omega_F^2 + P_contact``,
  ``P_contact = (f - f_spring(x))*v`` (all that the contact dissipates,
  damping and what the no-pull clip throws away), and
  ``Q_H = (T_amb - T)/R_th`` with a heat path.

Integration: ``scipy.integrate.solve_ivp`` over each step separately (the
inputs are discontinuous at the sample instants), at rtol 1e-9 by default,
with terminal events at the contact boundaries ``|x| = b/2`` (and ``b/2 + d``
for the smooth law), so that no step of the integrator straddles a jump of
the force law, and ``max_step`` a small fraction of the contact period. The
step means of torques, contact force and loss power are integrals over the
step carried as extra states (not sub-step samples), divided by dt.

Outputs (``Reference.run``) use gearsim's RigResult names: ``base_torque``,
``base_port_torque``, ``follower_port_torque``, ``contact_force``,
``mesh_loss_power``, ``loss_power`` (step means), ``base_speed``,
``base_angle``, ``follower_speed``, ``follower_position``, ``backlash_position``,
``temperature`` (values at the end of each step); plus ``contact_changes``
(per step, how often the teeth met or parted, |x| = b/2) and ``nfev``.
``Reference.rigid_speed_driven`` and ``Reference.rigid_torque_driven`` give
the steady-contact values of the rigid law from the same loss law, for
settled comparisons.

Cost: ~0.3-0.8 ms of CPU per step at dt = 1 ms (50-100 right-hand-side
evaluations per step, each with a brentq solve for the lossy models).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

__all__ = [
    "SIMPLE_GEAR_DEFAULTS",
    "RACK_PINION_DEFAULTS",
    "RIG_DEFAULTS",
    "MeshLoss",
    "Reference",
    "reference_run",
]

#: Simple Gear defaults of docs/physics.md section 9 (the bracketed proposals
#: where the vendor gives none), with backlash on.
SIMPLE_GEAR_DEFAULTS: dict[str, Any] = {
    "teeth_ratio": 2.0,
    "output_shaft_rotates": "opposite",
    "friction_model": "none",
    "loss_smoothing": "passive",
    "efficiency_const": 0.98,
    "power_threshold": 1e-3,
    "idle_torque": 0.01,
    "nominal_output_torque": 1.0,
    "efficiency_nominal": 0.95,
    "speed_threshold": 0.01,
    "temperature_vector": [280.0, 300.0, 320.0],
    "efficiency_vector": [0.95, 0.90, 0.85],
    "load_vector": [0.0, 50.0, 100.0],
    "efficiency_matrix": [[0.90, 0.95, 0.96], [0.85, 0.90, 0.92], [0.80, 0.85, 0.88]],
    "backlash_enabled": True,
    "hard_stop_model": "smooth",
    "linear_backlash": 1e-3,
    "base_radius": 0.1,
    "transition_region": 1e-4,
    "stiffness": 1e6,
    "damping": 1e3,
    "initial_backlash_position": 0.0,
    "contact_no_pull": True,
    "viscous_coefficients": [0.0, 0.0],
    "thermal_mass": 50.0,
    "initial_temperature": 300.0,
}

#: Rack & Pinion defaults of docs/physics.md section 9, with backlash on.
RACK_PINION_DEFAULTS: dict[str, Any] = {
    "parameterization": "pinion_radius",
    "pinion_radius": 0.1,
    "teeth_count": 20.0,
    "spacing": 0.005,
    "rack_directionality": "positive",
    "friction_model": "none",
    "loss_smoothing": "passive",
    "efficiency_const": 0.8,
    "temperature_vector": [280.0, 300.0, 320.0],
    "efficiency_vector": [0.95, 0.90, 0.85],
    "power_threshold": 1e-3,
    "pinion_viscous_coefficient": 0.0,
    "rack_viscous_coefficient": 0.0,
    "thermal_mass": 50.0,
    "initial_temperature": 300.0,
    "backlash_enabled": True,
    "hard_stop_model": "smooth",
    "linear_backlash": 1e-3,
    "transition_region": 1e-4,
    "stiffness": 1e6,
    "damping": 1e3,
    "initial_backlash_position": 0.0,
    "contact_no_pull": True,
}

#: Rig parameters of docs/physics.md section 11 (driven inertia: follower_inertia
#: for the gear, rack_mass for the rack).
RIG_DEFAULTS: dict[str, Any] = {
    "follower_inertia": 0.05,
    "rack_mass": 0.05,
    "load_coulomb_friction": 0.0,
    "load_coulomb_speed_threshold": 1e-3,
    "load_offset": 0.0,
    "thermal_resistance": None,
    "ambient_temperature": 293.15,
    "base_inertia": 0.0,
    "initial_base_speed": 0.0,
    "base_drive": "speed",
}

_TEMPERATURE_MODELS = (
    "temperature_dependent_efficiency",
    "temperature_load_dependent_efficiency",
)
_GEAR_MODELS = (
    "none",
    "constant_efficiency",
    "load_dependent_efficiency",
    "temperature_dependent_efficiency",
    "temperature_load_dependent_efficiency",
)
_RACK_MODELS = ("none", "constant_efficiency", "temperature_dependent_efficiency")


def interp1(xs: list[float], ys: list[float], at: float) -> float:
    """Linear interpolation, end values held outside the table (section 2.4)."""
    if at <= xs[0]:
        return ys[0]
    if at >= xs[-1]:
        return ys[-1]
    i = 1
    while at > xs[i]:
        i += 1
    w = (at - xs[i - 1]) / (xs[i] - xs[i - 1])
    return ys[i - 1] + w * (ys[i] - ys[i - 1])


class MeshLoss:
    """The mesh loss law of one block, written in T_F (the follower torque
    after the loss; rack: the net rack force), and the solve of
    T_F = T_F0 + tau_mesh(T_F) of the corrected section 4.6.

    Args:
        model: the friction_model option string.
        p: the block parameters (section 9 names).
        g: follower-to-base ratio that refers follower torques to the base
            (teeth ratio; 1/r_P for the rack). Used for the idle torque
            g*tau_idle (2.3) and the base load |T_F|/g of the table (2.5).
    """

    def __init__(self, model: str, p: Mapping[str, Any], g: float) -> None:
        self.model = model
        self.g = g
        self.smoothing = p.get("loss_smoothing", "passive")
        if self.smoothing not in ("passive", "simscape"):
            raise ValueError(f"loss_smoothing: unknown {self.smoothing!r}")
        self.temps = [float(v) for v in p["temperature_vector"]]
        self._cached_temperature = math.nan
        self._cached_eta = math.nan
        self._cached_row: list[float] = []
        if model in ("constant_efficiency", "temperature_dependent_efficiency"):
            self.power_gain = 4.0 / float(p["power_threshold"])  # tanh(4 p / p_th)
        if model == "constant_efficiency":
            self.eta_const = float(p["efficiency_const"])
        elif model == "temperature_dependent_efficiency":
            self.etas = [float(v) for v in p["efficiency_vector"]]
        elif model == "load_dependent_efficiency":
            eta_nom = float(p["efficiency_nominal"])
            tau_nom = float(p["nominal_output_torque"])
            self.c0 = g * float(p["idle_torque"])  # g*tau_idle, follower-referred (2.3)
            self.k = 1.0 / eta_nom - 1.0 - self.c0 / tau_nom  # (2.5)
            if self.k < 0.0:
                raise ValueError("load_dependent_efficiency: k < 0 (eq. 2.5)")
            self.speed_gain = 4.0 / float(p["speed_threshold"])
        elif model == "temperature_load_dependent_efficiency":
            self.loads = [float(v) for v in p["load_vector"]]
            self.matrix = [[float(v) for v in row] for row in p["efficiency_matrix"]]
            self.speed_gain = 4.0 / float(p["speed_threshold"])
            self.l_max = 1.0 / min(min(r) for r in self.matrix) - 1.0
            self.l_min = 1.0 / max(max(r) for r in self.matrix) - 1.0
        elif model != "none":
            raise ValueError(f"friction_model: unknown {model!r}")

    def efficiency(self, temperature: float) -> float:
        """eta of the power-smoothed laws (2.2 / 2.4 / 6.4) at a temperature."""
        if self.model == "constant_efficiency":
            return self.eta_const
        if temperature != self._cached_temperature:
            self._cached_temperature = temperature
            self._cached_eta = interp1(self.temps, self.etas, temperature)
        return self._cached_eta

    def table_row(self, temperature: float) -> list[float]:
        """The efficiency table of (2.5) interpolated at a temperature: one
        value per load_vector entry (cached for the last temperature)."""
        if temperature != self._cached_temperature:
            self._cached_temperature = temperature
            self._cached_row = [
                interp1(self.temps, [row[j] for row in self.matrix], temperature)
                for j in range(len(self.loads))
            ]
        return self._cached_row

    def tau_mesh(
        self, t_f: float, w_f: float, temperature: float, sigma: float | None = None
    ) -> float:
        """tau_mesh (or F_Coul) as the documented function of T_F, omega_F, T.

        With ``sigma`` (+1 or -1) the law at full strength for a follower
        sliding that way (section 11, the friction element): every tanh
        factor is +-1, the sign of the power or of the speed it blends on."""
        m = self.model
        if m == "none":
            return 0.0
        if m in ("constant_efficiency", "temperature_dependent_efficiency"):
            eta = self.efficiency(temperature)
            l_fd = 1.0 - eta  # follower drives, p > 0
            l_bd = 1.0 / eta - 1.0  # base drives, p < 0
            if sigma is None:
                t = math.tanh(self.power_gain * t_f * w_f)
            else:
                t = math.copysign(1.0, t_f * sigma) if t_f != 0.0 else 0.0
            if self.smoothing == "passive":  # (2.2)
                return t_f * t * (l_fd if t >= 0.0 else l_bd)
            return 0.5 * t_f * ((l_fd + l_bd) * t + l_fd - l_bd)  # (2.1)
        th = math.tanh(self.speed_gain * w_f) if sigma is None else sigma
        if m == "load_dependent_efficiency":  # (2.6)
            return (self.c0 + self.k * abs(t_f)) * th
        # (2.7): eta from the table at the temperature and the base load |T_F|/g
        eta = interp1(self.loads, self.table_row(temperature), abs(t_f) / self.g)
        return abs(t_f) * (1.0 / eta - 1.0) * th

    def solve(
        self, t_f0: float, w_f: float, temperature: float, sigma: float | None = None
    ) -> float:
        """T_F with T_F = T_F0 + tau_mesh(T_F, omega_F, T), by brentq on a
        bracket that provably holds the root; with ``sigma``, for the law at
        full strength sliding that way (a self-locking direction, where no
        root exists, raises SelfLocking)."""
        m = self.model
        if m == "none":
            return t_f0

        def tau(t_f: float, w_f: float, temperature: float) -> float:
            return self.tau_mesh(t_f, w_f, temperature, sigma)

        def phi(t_f: float) -> float:
            return t_f - t_f0 - tau(t_f, w_f, temperature)

        if m in ("constant_efficiency", "temperature_dependent_efficiency"):
            # T_F - tau_mesh(T_F) = T_F*(1 - c) with 1 - c in [eta, 1/eta]: the
            # root has the sign of T_F0 and lies between eta*T_F0 and T_F0/eta.
            if t_f0 == 0.0:
                return 0.0
            eta = self.efficiency(temperature)
            if eta == 1.0:
                return t_f0
            # widened by 1e-12 so that rounding at a saturated end keeps the sign change
            a, b = eta * t_f0 * (1.0 - 1e-12), t_f0 / eta * (1.0 + 1e-12)
            lo, hi = (a, b) if a < b else (b, a)
        elif m == "load_dependent_efficiency":
            th = math.tanh(self.speed_gain * w_f) if sigma is None else sigma
            if self.k * abs(th) >= 1.0:
                raise SelfLocking(
                    f"{m}: self-locking (k*|tanh| >= 1), T_F = T_F0 + tau_mesh(T_F) has no root"
                )
            # phi is piecewise linear with slopes 1 -+ k*th > 0: one root, with
            # |T_F| <= (|T_F0| + c0*|th|)/(1 - k*|th|)
            bound = (abs(t_f0) + self.c0 * abs(th)) / (1.0 - self.k * abs(th))
            if bound == 0.0:
                return 0.0
            lo, hi = -bound * (1.0 + 1e-12), bound * (1.0 + 1e-12)
        else:  # temperature_load_dependent_efficiency, (2.7)
            # phi(0) = -T_F0, so a root has the sign s of T_F0, and there
            # T_F*(1 - s*th*L) = T_F0 with L = 1/eta - 1 between the table's
            # extremes: T_F lies between T_F0/(1 - s*th*L_min) and T_F0/(1 - s*th*L_max).
            if t_f0 == 0.0:
                return 0.0
            th = math.tanh(self.speed_gain * w_f) if sigma is None else sigma
            sth = th if t_f0 > 0.0 else -th
            q1, q2 = 1.0 - sth * self.l_min, 1.0 - sth * self.l_max
            if min(q1, q2) <= 0.0:
                raise SelfLocking(f"{m}: self-locking (L*|tanh| >= 1), no root")
            a, b = t_f0 / q1, t_f0 / q2
            lo, hi = (a, b) if a < b else (b, a)
            lo, hi = lo - 1e-12 * abs(lo), hi + 1e-12 * abs(hi)
        f_lo, f_hi = phi(lo), phi(hi)
        if f_lo == 0.0:
            return lo
        if f_hi == 0.0:
            return hi
        if f_lo > 0.0 or f_hi < 0.0:  # pragma: no cover - the bracket is proven
            raise RuntimeError(f"{m}: no sign change on [{lo}, {hi}]")
        scale = max(abs(lo), abs(hi))
        return brentq(phi, lo, hi, xtol=1e-15 * scale + 1e-300, rtol=1e-14, maxiter=200)


class SelfLocking(ValueError):
    """The loss law has no solution T_F = T_F0 + tau_mesh(T_F) that way."""


def _contact_law(
    model: str, half_gap: float, k_c: float, d_c: float, d_tr: float, no_pull: bool
) -> Callable[[float, float], tuple[float, float]]:
    """f(x, v) of section 4.3-4.5 and the spring part of the law (for the
    dissipation): returns (f, f_spring)."""
    if model not in ("smooth", "full_damped", "full_undamped"):
        raise ValueError(f"hard_stop_model: unknown {model!r}")
    inv_d = 1.0 / d_tr if d_tr > 0.0 else math.inf

    def law(x: float, v: float) -> tuple[float, float]:
        if x >= half_gap:
            delta = x - half_gap
            upper = True
        elif x <= -half_gap:
            delta = x + half_gap
            upper = False
        else:
            return 0.0, 0.0
        if model == "smooth":
            xi = min(abs(delta) * inv_d, 1.0)
            scale = xi * xi * (3.0 - 2.0 * xi)
            spring = scale * k_c * delta
            f = spring + scale * d_c * v
        elif model == "full_damped":
            spring = k_c * delta
            f = spring + d_c * v
        else:  # full_undamped: damping only while the teeth close (4.4)
            spring = k_c * delta
            closing = v >= 0.0 if upper else v <= 0.0
            f = spring + d_c * v if closing else spring
        if no_pull:
            f = max(f, 0.0) if upper else min(f, 0.0)
        return f, spring

    return law


class Reference:
    """The rig with backlash as an ODE (see the module docstring).

    Args:
        block: "simple_gear" or "rack_pinion".
        block_params: block parameters (section 9 names; missing ones take the
            defaults above). Backlash is always on.
        rig_params: rig parameters (section 11 / docs/python-api.md names).
        dt: sample period (s).
        temperature_input: the losses use the measured_temperature input.
        rtol: relative tolerance of solve_ivp.
        method: solve_ivp method; a one-step method, since every step starts
            the integrator anew (DOP853 default; Radau for stiff settings).
        max_step: largest integrator step; default 1/40 of the undamped
            contact period 2*pi/omega_n and at most dt/2.
    """

    def __init__(
        self,
        block: str,
        block_params: Mapping[str, Any] | None = None,
        rig_params: Mapping[str, Any] | None = None,
        dt: float = 1e-3,
        *,
        temperature_input: bool = False,
        rtol: float = 1e-9,
        method: str = "DOP853",
        max_step: float | None = None,
        set_valued: bool = True,
    ) -> None:
        self.block = block
        if block == "simple_gear":
            p = {**SIMPLE_GEAR_DEFAULTS, **(block_params or {})}
            models = _GEAR_MODELS
        elif block == "rack_pinion":
            p = {**RACK_PINION_DEFAULTS, **(block_params or {})}
            models = _RACK_MODELS
        else:
            raise ValueError(f"block: unknown {block!r}")
        if not p.get("backlash_enabled", True):
            raise ValueError("the reference models the rig with backlash only")
        if p["friction_model"] not in models:
            raise ValueError(f"friction_model {p['friction_model']!r} is not a {block} model")
        r = {**RIG_DEFAULTS, **(rig_params or {})}
        self.p, self.r = p, r
        self.dt = float(dt)
        self.temperature_input = bool(temperature_input)
        self.rtol = float(rtol)
        self.method = method
        self.set_valued = bool(set_valued)

        # -- geometry: v = r_B*omega_B - c_F*omega_F, T_B = r_B*f, T_F0 = -c_F*f
        if block == "simple_gear":
            g = float(p["teeth_ratio"])
            s = 1.0 if p["output_shaft_rotates"] == "same" else -1.0
            r_b = float(p["base_radius"])
            c_f = s * g * r_b  # s*r_F
            mu_b, mu_f = (float(v) for v in p["viscous_coefficients"])
            j_f = float(r["follower_inertia"])
            ratio = s * g  # omega_B = s*g*omega_F (1.1)
        else:
            if p["parameterization"] == "pinion_radius":
                r_b = float(p["pinion_radius"])
            else:
                r_b = float(p["teeth_count"]) * float(p["spacing"]) / (2.0 * math.pi)  # (6.2)
            s = 1.0 if p["rack_directionality"] == "positive" else -1.0
            g = 1.0 / r_b  # |R_RP|
            c_f = s  # the rack is the follower with radius 1
            mu_b = float(p["pinion_viscous_coefficient"])
            mu_f = float(p["rack_viscous_coefficient"])
            j_f = float(r["rack_mass"])
            ratio = s / r_b  # omega_P = R_RP*v_R (6.1)
        self.r_b, self.c_f, self.mu_b, self.mu_f, self.j_f = r_b, c_f, mu_b, mu_f, j_f
        self.ratio = ratio  # omega_B = ratio*omega_F in rigid motion
        self.loss = MeshLoss(p["friction_model"], p, g)
        self.contact = _contact_law(
            p["hard_stop_model"],
            0.5 * float(p["linear_backlash"]),
            float(p["stiffness"]),
            float(p["damping"]),
            float(p["transition_region"]),
            bool(p.get("contact_no_pull", True)),
        )
        self.half_gap = 0.5 * float(p["linear_backlash"])
        self.transition = float(p["transition_region"])
        self.x0 = float(p["initial_backlash_position"])
        self.torque_driven = r["base_drive"] == "torque"
        self.j_b = float(r["base_inertia"])
        if self.torque_driven and not self.j_b > 0.0:
            raise ValueError("base_inertia must be > 0 for a torque-driven base")
        self.coulomb = float(r["load_coulomb_friction"])
        self.coulomb_gain = 4.0 / float(r["load_coulomb_speed_threshold"])
        self.offset = float(r["load_offset"])
        self.thermal_state = (
            p["friction_model"] in _TEMPERATURE_MODELS and not self.temperature_input
        )
        self.thermal_mass = float(p["thermal_mass"])
        r_th = r.get("thermal_resistance")
        self.g_th = 0.0 if r_th is None else 1.0 / float(r_th)
        self.ambient = float(r["ambient_temperature"])
        self.initial_temperature = float(p["initial_temperature"])
        # contact period: 1/m_eff = r_B^2/J_B + c_F^2/J_F at the pitch line
        inv_m = c_f * c_f / j_f + (r_b * r_b / self.j_b if self.torque_driven else 0.0)
        omega_n = math.sqrt(float(p["stiffness"]) * inv_m)
        self.omega_n = omega_n
        default_step = min(2.0 * math.pi / omega_n / 40.0, 0.5 * self.dt)
        self.max_step = default_step if max_step is None else float(max_step)

    # -- the rigid law (section 8, form A), for settled steady-contact values --
    def rigid_speed_driven(
        self, base_speed: float, load: float, temperature: float | None = None
    ) -> dict[str, float]:
        """Steady contact at a constant base speed: the follower balance gives
        T_F = load + offset - coulomb - mu_F*omega_F, the loss law (written in
        T_F) gives T_F0 = T_F - tau_mesh(T_F), and T_B = -T_F0*r_B/c_F."""
        temp = self.initial_temperature if temperature is None else temperature
        w_b = base_speed
        w_f = w_b / self.ratio
        ext = load + self.offset - self.coulomb * math.tanh(self.coulomb_gain * w_f)
        tau_f = ext  # no acceleration: the follower port takes the whole external torque
        t_f = tau_f - self.mu_f * w_f
        t_f0 = t_f - self.loss.tau_mesh(t_f, w_f, temp)
        f = -t_f0 / self.c_f
        tau_b = self.r_b * f + self.mu_b * w_b
        return {
            "base_port_torque": tau_b,
            "follower_port_torque": tau_f,
            "follower_speed": w_f,
            "contact_force": f,
        }

    def rigid_torque_driven(
        self,
        motor_torque: float,
        load: float,
        follower_speed: float,
        temperature: float | None = None,
    ) -> dict[str, float]:
        """Steady contact of the torque-driven rig: the teeth at rest relative
        to each other, both shafts with the common (geared) acceleration. With
        a_F = (load + offset - coulomb - tau_F)/J_F and
        J_B*ratio*a_F = motor - tau_B, T_F solves (by brentq)
        ratio*(motor - mu_B*omega_B - T_B(T_F)) - J_B*ratio^2*a_F(T_F) = 0,
        where T_B = -r_B*T_F0/c_F and T_F0 = T_F - tau_mesh(T_F)."""
        temp = self.initial_temperature if temperature is None else temperature
        w_f = follower_speed
        w_b = self.ratio * w_f
        ext = load + self.offset - self.coulomb * math.tanh(self.coulomb_gain * w_f)
        tau = self.loss.tau_mesh

        def parts(t_f: float) -> tuple[float, float, float]:
            t_f0 = t_f - tau(t_f, w_f, temp)
            f = -t_f0 / self.c_f
            a_f = (ext - t_f - self.mu_f * w_f) / self.j_f
            return f, a_f, t_f0

        def psi(t_f: float) -> float:
            f, a_f, _ = parts(t_f)
            tau_b = self.r_b * f + self.mu_b * w_b
            return self.ratio * (motor_torque - tau_b) - self.j_b * self.ratio**2 * a_f

        span = 1.0 + abs(ext) + abs(motor_torque) * abs(self.ratio)
        while psi(-span) * psi(span) > 0.0:
            span *= 2.0
        t_f = brentq(psi, -span, span, xtol=1e-15, rtol=1e-15, maxiter=500)
        f, a_f, _ = parts(t_f)
        return {
            "base_port_torque": self.r_b * f + self.mu_b * w_b,
            "follower_port_torque": t_f + self.mu_f * w_f,
            "follower_acceleration": a_f,
            "contact_force": f,
        }

    # -- the ODE ----------------------------------------------------------------
    def run(
        self,
        *,
        base_speed: Any = None,
        base_torque: Any = None,
        load: Any = 0.0,
        measured_temperature: Any = None,
        ambient_temperature: Any = None,
    ) -> dict[str, np.ndarray]:
        """Integrate the rig over the samples; see the module docstring."""
        driving = base_torque if self.torque_driven else base_speed
        if driving is None:
            raise ValueError("base_torque" if self.torque_driven else "base_speed")
        drive = np.atleast_1d(np.asarray(driving, dtype=np.float64))
        n = drive.size
        loads = np.broadcast_to(np.asarray(load, dtype=np.float64), (n,)).tolist()
        if self.temperature_input:
            if measured_temperature is None:
                raise ValueError("measured_temperature")
            temps_in = np.broadcast_to(np.asarray(measured_temperature, float), (n,)).tolist()
        else:
            temps_in = [self.initial_temperature] * n
        amb = self.ambient if ambient_temperature is None else ambient_temperature
        ambs = np.broadcast_to(np.asarray(amb, dtype=np.float64), (n,)).tolist()
        drive_l = drive.tolist()

        dt = self.dt
        r_b, c_f, mu_b, mu_f = self.r_b, self.c_f, self.mu_b, self.mu_f
        inv_j_f = 1.0 / self.j_f
        inv_j_b = 1.0 / self.j_b if self.torque_driven else 0.0
        contact = self.contact
        solve_loss = self.loss.solve
        coulomb, coulomb_gain, offset = self.coulomb, self.coulomb_gain, self.offset
        thermal_state = self.thermal_state
        inv_c = 1.0 / self.thermal_mass
        g_th = self.g_th
        tanh = math.tanh
        torque_driven = self.torque_driven
        set_valued = self.set_valued

        # state: x, w_f, th_f, w_b, th_b, T, and the step integrals of tau_B,
        # tau_F, f, P_mesh, P_loss (reset to 0 at each step start)
        I_TB, I_TF, I_F, I_PM, I_PL = 6, 7, 8, 9, 10
        # per-step inputs, read by rhs
        cur = {"w0": 0.0, "dw": 0.0, "load": 0.0, "motor": 0.0, "temp": 0.0, "amb": 0.0}

        # The meshing loss is a friction element on the follower (section 11):
        # at full strength while it slides (mode +1 / -1, the sign of omega_F),
        # holding it at rest (mode 0) while the torque that would move it stays
        # within the two bounds, the loss it would take sliding either way.
        mode = {"sigma": 0.0}

        def drive_parts(t: float, y: np.ndarray) -> tuple[float, ...]:
            x, w_f, w_b, temp = y[0], y[1], y[3], y[5]
            if not torque_driven:
                w_b = cur["w0"] + cur["dw"] * t
            if not thermal_state:
                temp = cur["temp"]
            v = r_b * w_b - c_f * w_f
            f, f_spring = contact(x, v)
            ext = cur["load"] + offset
            if coulomb:
                ext -= coulomb * tanh(coulomb_gain * w_f)
            return w_f, w_b, temp, v, f, f_spring, ext

        def bounds(t_f0: float, temp: float) -> tuple[float, float]:
            """The loss sliding forward (+) and backward (-), as magnitudes;
            inf where the mesh self-locks that way."""
            out = []
            for sigma in (1.0, -1.0):
                try:
                    out.append(sigma * (solve_loss(t_f0, 0.0, temp, sigma) - t_f0))
                except SelfLocking:
                    out.append(math.inf)
            return out[0], out[1]

        def hold(t: float, y: np.ndarray) -> tuple[float, float, float]:
            """What holding the follower needs from the mesh, and the bounds."""
            _, _, temp, _, f, _, ext = drive_parts(t, y)
            t_f0 = -c_f * f
            fwd, bwd = bounds(t_f0, temp)
            return ext - t_f0, fwd, bwd

        def rhs(t: float, y: np.ndarray) -> list[float]:
            w_f, w_b, temp, v, f, f_spring, ext = drive_parts(t, y)
            t_f0 = -c_f * f
            if set_valued and mode["sigma"] == 0.0:
                w_f = 0.0
                t_f = ext  # held: the mesh takes ext - T_F0
            elif set_valued:
                t_f = solve_loss(t_f0, w_f, temp, mode["sigma"])
            else:
                t_f = solve_loss(t_f0, w_f, temp)
            tau_f = t_f + mu_f * w_f
            tau_b = r_b * f + mu_b * w_b
            dw_f = (ext - tau_f) * inv_j_f if not (set_valued and mode["sigma"] == 0.0) else 0.0
            dw_b = (cur["motor"] - tau_b) * inv_j_b if torque_driven else 0.0
            p_mesh = (t_f - t_f0) * w_f
            p_loss = p_mesh + mu_b * w_b * w_b + mu_f * w_f * w_f + (f - f_spring) * v
            if thermal_state:
                d_temp = (p_loss + g_th * (cur["amb"] - temp)) * inv_c
            else:
                d_temp = 0.0
            return [v, dw_f, w_f, dw_b, w_b, d_temp, tau_b, tau_f, f, p_mesh, p_loss]

        # events at the force law's breakpoints; each one's direction is set,
        # after it fires, to the opposite of the crossing it saw, so that a
        # restart at the event does not see the same crossing again
        breakpoints = [self.half_gap, -self.half_gap]
        if self.p["hard_stop_model"] == "smooth":
            breakpoints += [self.half_gap + self.transition, -self.half_gap - self.transition]
        contact_events = []
        for b in breakpoints:

            def ev(t: float, y: np.ndarray, b: float = b) -> float:
                return y[0] - b

            ev.terminal = True
            ev.direction = 0.0
            contact_events.append(ev)

        # the friction element's events: a sliding follower reaching rest; a
        # held one whose holding torque leaves its bounds
        def stops(t: float, y: np.ndarray) -> float:
            return y[1]

        stops.terminal = True

        def breaks_forward(t: float, y: np.ndarray) -> float:
            need, fwd, _ = hold(t, y)
            return need - fwd if math.isfinite(fwd) else -1.0

        breaks_forward.terminal = True
        breaks_forward.direction = 1.0

        def breaks_backward(t: float, y: np.ndarray) -> float:
            need, _, bwd = hold(t, y)
            return need + bwd if math.isfinite(bwd) else 1.0

        breaks_backward.terminal = True
        breaks_backward.direction = -1.0

        def settle_mode(t: float, y: np.ndarray) -> None:
            """At rest: hold, or break away the way the torque pushes."""
            need, fwd, bwd = hold(t, y)
            mode["sigma"] = 1.0 if need > fwd else (-1.0 if need < -bwd else 0.0)

        def events_now() -> list:
            if not set_valued:
                return contact_events
            if mode["sigma"] == 0.0:
                return contact_events + [breaks_forward, breaks_backward]
            stops.direction = -mode["sigma"]
            return contact_events + [stops]

        # initial state
        w_b0 = drive_l[0] if not torque_driven else float(self.r["initial_base_speed"])
        temp0 = self.initial_temperature
        y = np.array([self.x0, w_b0 / self.ratio, 0.0, w_b0, 0.0, temp0] + [0.0] * 5)
        mode["sigma"] = math.copysign(1.0, y[1]) if y[1] != 0.0 else 0.0
        atol = np.array(
            [1e-14, 1e-11, 1e-11, 1e-11, 1e-11, 1e-9, 1e-14, 1e-14, 1e-12, 1e-14, 1e-14]
        )
        out = {
            name: np.zeros(n)
            for name in (
                "base_torque",
                "base_port_torque",
                "follower_port_torque",
                "contact_force",
                "mesh_loss_power",
                "loss_power",
                "base_speed",
                "base_angle",
                "follower_speed",
                "follower_position",
                "backlash_position",
                "temperature",
            )
        }
        out["contact_changes"] = np.zeros(n, dtype=np.int64)
        nfev = 0
        last_h = self.max_step
        previous = drive_l[0]
        for k in range(n):
            if torque_driven:
                cur["motor"] = drive_l[k]
            else:
                w_end = drive_l[k]
                cur["w0"] = previous
                cur["dw"] = (w_end - previous) / dt
                previous = w_end
            cur["load"] = loads[k]
            cur["temp"] = temps_in[k]
            cur["amb"] = ambs[k]
            y[6:] = 0.0
            t = 0.0
            changes = 0
            while True:
                if set_valued and mode["sigma"] == 0.0:
                    settle_mode(t, y)  # the new inputs may break it away
                events = events_now()
                sol = solve_ivp(
                    rhs,
                    (t, dt),
                    y,
                    method=self.method,
                    rtol=self.rtol,
                    atol=atol,
                    max_step=self.max_step,
                    first_step=min(last_h, dt - t),
                    events=events,
                )
                nfev += sol.nfev
                if sol.status < 0:
                    raise RuntimeError(f"solve_ivp failed in step {k}: {sol.message}")
                if len(sol.t) > 2:  # the last full step: a good first try for the next call
                    last_h = max(float(sol.t[-2] - sol.t[-3]), 1e-9)
                y = sol.y[:, -1].copy()
                t = float(sol.t[-1])
                if sol.status == 0:
                    break
                for i, te in enumerate(sol.t_events):
                    if not len(te):
                        continue
                    if events[i] is stops:  # the follower reached rest
                        y[1] = 0.0
                        settle_mode(t, y)
                    elif events[i] is breaks_forward or events[i] is breaks_backward:
                        mode["sigma"] = 1.0 if events[i] is breaks_forward else -1.0
                    else:
                        v = rhs(t, y)[0]
                        events[i].direction = -1.0 if v > 0.0 else 1.0
                        changes += i < 2  # the teeth met or parted at |x| = b/2
                if t >= dt:
                    break
            out["contact_changes"][k] = changes
            w_b = y[3] if torque_driven else previous
            out["base_port_torque"][k] = y[I_TB] / dt
            out["follower_port_torque"][k] = y[I_TF] / dt
            out["contact_force"][k] = y[I_F] / dt
            out["mesh_loss_power"][k] = y[I_PM] / dt
            out["loss_power"][k] = y[I_PL] / dt
            out["base_speed"][k] = w_b
            out["base_angle"][k] = y[4]
            out["follower_speed"][k] = y[1]
            out["follower_position"][k] = y[2]
            out["backlash_position"][k] = y[0]
            out["temperature"][k] = y[5] if thermal_state else temps_in[k]
            if torque_driven:
                out["base_torque"][k] = drive_l[k]
            else:
                out["base_torque"][k] = out["base_port_torque"][k] + self.j_b * cur["dw"]
        out["nfev"] = np.array(nfev)
        return out


def reference_run(
    block: str,
    block_params: Mapping[str, Any] | None,
    rig_params: Mapping[str, Any] | None,
    dt: float,
    *,
    temperature_input: bool = False,
    rtol: float = 1e-9,
    method: str = "DOP853",
    max_step: float | None = None,
    **inputs: Any,
) -> dict[str, np.ndarray]:
    """One call: Reference(...).run(**inputs)."""
    ref = Reference(
        block,
        block_params,
        rig_params,
        dt,
        temperature_input=temperature_input,
        rtol=rtol,
        method=method,
        max_step=max_step,
    )
    return ref.run(**inputs)
