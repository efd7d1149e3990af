"""What a user would write instead of gearsim, for the benchmark comparison.

The equations of docs/physics.md that gearsim implements, written plainly in
Python:

- ``python_loop``: the speed-driven rigid Simple Gear rig with the passive
  constant-efficiency law (eq. 2.2), viscous losses (section 3), the load and
  the follower inertia driven by the backward-difference base acceleration
  (section 11), stepped one sample at a time in a Python ``for`` loop
  (``math`` on Python floats, the fastest plain-Python form).
- ``python_loop_numpy``: the same loop written the way it often is, indexing
  the numpy input arrays and calling numpy functions on each element.
- ``numpy_vectorised``: the same rig as whole-array numpy operations. This is
  possible because the rigid speed-driven rig with constant efficiency has no
  state besides the last input speed; with a thermal model or backlash it
  would need a loop again.
- ``python_loop_full``: the full Simple Gear rig of the C configuration
  ``sg_full`` (backlash with the smooth hard stop, the temperature x load
  efficiency table, the thermal mass with a heat path to ambient, viscous
  losses, the load's Coulomb friction), one Python step per sample, written
  from docs/physics.md and its documented choices, as a user would write
  it: contact sub-steps with the contact by backward Euler (a bracketed
  Newton iteration), the mesh loss by the corrected rule of physics.md 4.6
  (D1: T_F = T_F0 + tau_mesh(T_F), on the sign branch), the load's Coulomb
  friction as a set-valued law by velocity projection (D2), and the thermal
  mass by explicit Euler per step. The contact scheme is the one
  include/gearsim/rig.h documents (backward Euler on the contact in a fixed
  number of sub-steps), and with the mesh loss and the Coulomb friction off
  it reproduces gearsim to rounding; the loss and the friction are written
  here from D1/D2 (the loss evaluated explicitly on the previous sub-step's
  contact force), so with them on it agrees with gearsim to the two schemes'
  discretisation difference, not bit for bit (tests/python/
  test_bench_alternatives.py states the figures). This is what a user who
  needs backlash or heating writes instead of gearsim: nothing here can be
  vectorised, because every step depends on the last one.
- ``backlash_ode``: the Simple Gear with backlash (smooth hard stop, eq. 4.5,
  no-pull clip) between the speed-driven base and the follower inertia, as an
  ODE in (x, omega_F) for ``scipy.integrate.solve_ivp``, with the constant-
  efficiency mesh loss by the corrected rule (D1, loss factor on T_F0 from
  the power-flow sign of T_F0*omega_F). The held base speed is the same
  piecewise-linear ramp between samples that the C rig uses.

For an accurate (and slow) continuous-time reference of every block and
friction model, see tests/python/oracles/reference.py (a test oracle).

All take the parameters as a plain dict (``GEAR_PARAMS`` or ``FULL_PARAMS``
below), so that the benchmark builds the gearsim model from the same numbers
(``full_gearsim_params`` for the full rig).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: The automatic contact sub-step count's target, gearsim.AUTO_H_OMEGA_N_MAX
#: (GS_AUTO_H_OMEGA_N_MAX); this module does not import gearsim, and
#: tests/python/test_bench_alternatives.py checks that both pick the same count.
AUTO_H_OMEGA_N_MAX = 1.0

#: Shared parameters of the comparison (SI units). Simple Gear: teeth ratio
#: g = 2, opposite rotation (s = -1), constant efficiency with the passive law,
#: default power threshold, viscous [mu_B, mu_F]; rig: follower inertia, dt.
GEAR_PARAMS: dict[str, float] = {
    "teeth_ratio": 2.0,
    "direction": -1.0,
    "efficiency": 0.98,
    "power_threshold": 1e-3,
    "mu_base": 0.002,
    "mu_follower": 0.004,
    "follower_inertia": 0.05,
    "dt": 1e-3,
    # backlash (ODE case): smooth hard stop, defaults of docs/physics.md 9
    "linear_backlash": 1e-3,
    "base_radius": 0.1,
    "transition_region": 1e-4,
    "stiffness": 1e6,
    "damping": 1e3,
}

#: The full Simple Gear rig (= C configuration ``sg_full`` of
#: bench/bench_common.h): the defaults of docs/physics.md section 9 except
#: the friction model, initial temperature, viscous coefficients, backlash,
#: heat path and load Coulomb friction, which sg_full sets. SI units.
FULL_PARAMS: dict[str, Any] = {
    # gear: teeth ratio g = N_F/N_B, opposite rotation (s = -1)
    "teeth_ratio": 2.0,
    "direction": -1.0,
    # temperature x load efficiency table (eqs. 2.5, 2.7): rows at the
    # temperatures (K), columns at the base-referred load |T_F|/g (N*m)
    "temperature_vector": [280.0, 300.0, 320.0],
    "load_vector": [0.0, 50.0, 100.0],
    "efficiency_matrix": [[0.90, 0.95, 0.96], [0.85, 0.90, 0.92], [0.80, 0.85, 0.88]],
    "speed_threshold": 0.01,  # omega_th of the tanh speed smoothing, rad/s
    # viscous bearing losses [mu_B, mu_F], N*m/(rad/s)
    "mu_base": 0.002,
    "mu_follower": 0.004,
    # backlash: smooth hard stop (eq. 4.5) with the no-pull clip, teeth centred
    "linear_backlash": 1e-3,  # b, total free travel at the pitch line, m
    "base_radius": 0.1,  # r_B, m (r_F = g*r_B)
    "transition_region": 1e-4,  # d, m
    "stiffness": 1e6,  # K, N/m
    "damping": 1e3,  # D, N*s/m
    "contact_substeps": 0,  # 0: the rig's automatic count (h*omega_n <= AUTO_H_OMEGA_N_MAX)
    # thermal mass (eq. 5.1) with a heat path to ambient
    "thermal_mass": 50.0,  # C, J/K
    "initial_temperature": 295.0,  # K
    "thermal_resistance": 2.0,  # R_th, K/W
    "ambient_temperature": 293.15,  # K
    # rig: speed-driven base, follower inertia, Coulomb friction on the load
    "follower_inertia": 0.05,  # J_F, kg*m^2
    "load_coulomb_friction": 0.05,  # tau_C, N*m
    "load_coulomb_speed_threshold": 1e-3,  # rad/s
    "dt": 1e-3,  # s
}


def full_gearsim_params(p: dict[str, Any] = FULL_PARAMS) -> tuple[dict, dict]:
    """gearsim's block and rig parameters for the rig of python_loop_full
    (``gearsim.Model(block="simple_gear", block_params=..., rig_params=...)``)."""
    block = {
        "teeth_ratio": p["teeth_ratio"],
        "output_shaft_rotates": "opposite" if p["direction"] < 0 else "same",
        "friction_model": "temperature_load_dependent_efficiency",
        "temperature_vector": list(p["temperature_vector"]),
        "load_vector": list(p["load_vector"]),
        "efficiency_matrix": [list(row) for row in p["efficiency_matrix"]],
        "speed_threshold": p["speed_threshold"],
        "viscous_coefficients": [p["mu_base"], p["mu_follower"]],
        "backlash_enabled": True,
        "hard_stop_model": "smooth",
        "linear_backlash": p["linear_backlash"],
        "base_radius": p["base_radius"],
        "transition_region": p["transition_region"],
        "stiffness": p["stiffness"],
        "damping": p["damping"],
        "initial_backlash_position": 0.0,
        "contact_no_pull": True,
        "contact_lock_enabled": False,
        "thermal_mass": p["thermal_mass"],
        "initial_temperature": p["initial_temperature"],
    }
    rig = {
        "follower_inertia": p["follower_inertia"],
        "load_coulomb_friction": p["load_coulomb_friction"],
        "load_coulomb_speed_threshold": p["load_coulomb_speed_threshold"],
        "thermal_resistance": p["thermal_resistance"],
        "ambient_temperature": p["ambient_temperature"],
        "contact_substeps": p["contact_substeps"],
    }
    return block, rig


def scenario(n: int, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """The benchmark's input, as in bench/gearsim_bench.c: base speed (rad/s)
    with reversals and a load (N*m) that changes sign."""
    t = np.arange(n) * dt
    two_pi = 2.0 * math.pi
    w = 20.0 * np.sin(two_pi * 0.5 * t) + 4.0 * np.sin(two_pi * 1.25 * t)
    load = 2.0 + 6.0 * np.sin(two_pi * 0.25 * t + 0.3) + 0.5 * np.sin(two_pi * 5.0 * t)
    return w, load


def _floats(a: Any) -> list[float]:
    """An array or sequence as a list of Python floats, the fastest to index in a loop."""
    return a.tolist() if hasattr(a, "tolist") else list(a)


def python_loop(base_speed: Any, load: Any, p: dict[str, float] = GEAR_PARAMS) -> list[float]:
    """Base torque (N*m) of the rigid speed-driven rig, one Python step per sample."""
    inv_ratio = p["direction"] / p["teeth_ratio"]
    dt = p["dt"]
    j_f = p["follower_inertia"]
    mu_b = p["mu_base"]
    mu_f = p["mu_follower"]
    eta = p["efficiency"]
    loss_fd = 1.0 - eta
    loss_bd = 1.0 / eta - 1.0
    k_tanh = 4.0 / p["power_threshold"]
    tanh = math.tanh
    ws = _floats(base_speed)
    loads = _floats(load)
    out = [0.0] * len(ws)
    previous = ws[0] if ws else 0.0
    for i, w_b in enumerate(ws):
        alpha_b = (w_b - previous) / dt  # backward difference (no filter)
        previous = w_b
        w_f = inv_ratio * w_b
        tau_f = loads[i] - j_f * inv_ratio * alpha_b  # load minus follower inertia torque
        t_f = tau_f - mu_f * w_f  # net mesh torque at F
        t = tanh(k_tanh * t_f * w_f)  # power smoothing, eq. 2.2
        tau_mesh = t_f * t * (loss_fd if t >= 0.0 else loss_bd)
        out[i] = mu_b * w_b + inv_ratio * (tau_mesh - t_f)
    return out


def python_loop_numpy(
    base_speed: np.ndarray, load: np.ndarray, p: dict[str, float] = GEAR_PARAMS
) -> np.ndarray:
    """python_loop over numpy arrays element by element (np.tanh on scalars)."""
    inv_ratio = p["direction"] / p["teeth_ratio"]
    eta = p["efficiency"]
    n = len(base_speed)
    out = np.zeros(n)
    previous = base_speed[0]
    for i in range(n):
        w_b = base_speed[i]
        alpha_b = (w_b - previous) / p["dt"]
        previous = w_b
        w_f = inv_ratio * w_b
        t_f = load[i] - p["follower_inertia"] * inv_ratio * alpha_b - p["mu_follower"] * w_f
        t = np.tanh(4.0 / p["power_threshold"] * t_f * w_f)
        loss = 1.0 - eta if t >= 0.0 else 1.0 / eta - 1.0
        out[i] = p["mu_base"] * w_b + inv_ratio * (t_f * t * loss - t_f)
    return out


def numpy_vectorised(
    base_speed: np.ndarray, load: np.ndarray, p: dict[str, float] = GEAR_PARAMS
) -> np.ndarray:
    """Base torque (N*m) of the same rig, as whole-array numpy operations."""
    inv_ratio = p["direction"] / p["teeth_ratio"]
    eta = p["efficiency"]
    w_b = np.asarray(base_speed, dtype=np.float64)
    alpha_b = np.diff(w_b, prepend=w_b[:1]) / p["dt"]
    w_f = inv_ratio * w_b
    t_f = load - p["follower_inertia"] * inv_ratio * alpha_b - p["mu_follower"] * w_f
    t = np.tanh((4.0 / p["power_threshold"]) * t_f * w_f)
    tau_mesh = t_f * t * np.where(t >= 0.0, 1.0 - eta, 1.0 / eta - 1.0)
    return p["mu_base"] * w_b + inv_ratio * (tau_mesh - t_f)


def backlash_ode(
    base_speed: np.ndarray,
    load: np.ndarray,
    p: dict[str, float] = GEAR_PARAMS,
    method: str = "LSODA",
    rtol: float = 1e-6,
    atol: float = 1e-9,
) -> dict[str, Any]:
    """The backlash rig as an ODE for scipy.integrate.solve_ivp.

    State y = (x, omega_F): x' = r_B*omega_B(t) - s*r_F*omega_F and
    J_F*omega_F' = load - tau_mesh - mu_F*omega_F + s*r_F*f(x, x'), with the
    smooth hard stop (4.5), the no-pull clip, and the mesh loss by the
    corrected rule of physics.md 4.6 (D1): the passive constant-efficiency
    law (2.2) is written in T_F, the follower torque after the loss, so with
    the loss-free T_F0 = -s*r_F*f the saturated solution of
    T_F = T_F0 + tau_mesh(T_F) is T_F = eta*T_F0 when the base drives
    (T_F0*omega_F < 0) and T_F = T_F0/eta when the follower drives; smoothed
    by t0 = tanh(4*T_F0*omega_F/p_th), tau_mesh = T_F0*t0*(1/eta - 1) for
    t0 >= 0 and T_F0*t0*(1 - eta) for t0 < 0. Sample k of the base speed is reached at t = (k+1)*dt
    and held from t = 0 to dt (the C rig's convention: the first sample sets
    the speeds, then the speed ramps linearly between samples); the load is
    held over each step. Returns the follower speed at the sample instants
    (the C rig's step ends), the number of right-hand-side evaluations and
    the solver's status.
    """
    from scipy.integrate import solve_ivp

    dt = p["dt"]
    s = p["direction"]
    g = p["teeth_ratio"]
    r_b = p["base_radius"]
    sr_f = s * g * r_b
    half_gap = 0.5 * p["linear_backlash"]
    inv_d = 1.0 / p["transition_region"]
    k_c = p["stiffness"]
    d_c = p["damping"]
    j_f = p["follower_inertia"]
    mu_f = p["mu_follower"]
    eta = p["efficiency"]
    # D1: loss factors on T_F0 (follower drives: T_F = T_F0/eta; base drives: T_F = eta*T_F0)
    loss_fd0 = 1.0 / eta - 1.0
    loss_bd0 = 1.0 - eta
    k_tanh = 4.0 / p["power_threshold"]
    ws = np.asarray(base_speed, dtype=np.float64).tolist()
    loads = np.asarray(load, dtype=np.float64).tolist()
    n = len(ws)
    tanh = math.tanh

    def speed_and_load(t: float) -> tuple[float, float]:
        k = int(t / dt)  # step k covers [k*dt, (k+1)*dt)
        if k <= 0:
            return ws[0], loads[0]
        if k >= n:
            return ws[-1], loads[-1]
        a = t / dt - k
        return ws[k - 1] + a * (ws[k] - ws[k - 1]), loads[k]

    def rhs(t: float, y: np.ndarray) -> list[float]:
        x = y[0]
        w_f = y[1]
        w_b, tau_load = speed_and_load(t)
        v = r_b * w_b - sr_f * w_f
        f = 0.0
        if x > half_gap or x < -half_gap:
            delta = x - half_gap if x > half_gap else x + half_gap
            xi = min(abs(delta) * inv_d, 1.0)
            f = xi * xi * (3.0 - 2.0 * xi) * (k_c * delta + d_c * v)
            if (delta > 0.0 and f < 0.0) or (delta < 0.0 and f > 0.0):
                f = 0.0  # no pull
        t_f0 = -sr_f * f
        tt = tanh(k_tanh * t_f0 * w_f)
        tau_mesh = t_f0 * tt * (loss_fd0 if tt >= 0.0 else loss_bd0)
        return [v, (tau_load - tau_mesh - mu_f * w_f - t_f0) / j_f]

    t_eval = dt * np.arange(1, n + 1)
    y0 = [0.0, (s / g) * ws[0]]
    sol = solve_ivp(
        rhs, (0.0, n * dt), y0, method=method, t_eval=t_eval, rtol=rtol, atol=atol, max_step=dt
    )
    return {
        "follower_speed": sol.y[1],
        "backlash_position": sol.y[0],
        "nfev": int(sol.nfev),
        "status": int(sol.status),
        "message": str(sol.message),
    }


def _mesh_loss(t_f0: float, k_loss: float, th: float) -> float:
    """The meshing loss of python_loop_full for a follower torque t_f0 before
    the loss, loss factor k_loss = 1/eta - 1 and sliding direction th (+-1)."""
    if t_f0 == 0.0:
        return 0.0
    denominator = 1.0 - (k_loss * th if t_f0 > 0.0 else -k_loss * th)
    if denominator > 0.0:
        return t_f0 / denominator - t_f0
    return k_loss * abs(t_f0) * th  # self-locking: no solution on the branch


def python_loop_full(
    base_speed: Any,
    load: Any,
    p: dict[str, Any] = FULL_PARAMS,
    newton_iterations: int = 12,
    newton_tolerance: float = 1e-13,
) -> dict[str, Any]:
    """The full Simple Gear rig (sg_full), one Python step per sample.

    Speed-driven base, follower inertia J_F, and between them the gear with
    backlash. Each step of dt is cut into n sub-steps of h = dt/n (n: the
    smallest count with h*omega_n <= AUTO_H_OMEGA_N_MAX, at most 16, as
    gearsim documents its automatic choice). In each sub-step:

    1. explicit: the meshing loss of eq. 2.7 from the last contact force by
       the rule of physics.md 4.6, as the friction element of section 11
       (at full strength while the follower slides, no smoothing): with
       T_F0 = -s*r_F*f (eq. 4.6), th = sign(omega_F) and k = 1/eta - 1, the
       law tau_mesh = k*|T_F|*th written in T_F gives, on the sign branch
       sigma = sign(T_F0), T_F = T_F0/(1 - sigma*k*th) and
       tau_mesh = T_F - T_F0 (self-locking, 1 - sigma*k*th <= 0: the loss
       k*|T_F0|*th instead); eta from the temperature x load table at this
       step's temperature and the base load |T_F|/g of the previous
       evaluation (a fixed point that settles in steady contact). From rest
       it is projected with the Coulomb friction (step 4);
    2. the follower's free motion over h (viscous term implicit), then the
       contact by backward Euler: the relative tooth speed u at the end of
       the sub-step solves Phi(u) = u - u_free + c*f(x + h*u, u) = 0 with
       c = h*r_F^2/(J_F + h*mu_F), by Newton's method kept inside the
       bracket [u_free, u_free - c*f0] (bisection where a step would leave
       it), stopped once a step is below newton_tolerance of the bracket
       scale |u_free| + c*|f0|, at most newton_iterations steps;
    3. if the held loss would reverse the follower, the sub-step again
       without it (the loss can stop the follower, never reverse it);
    4. the load's Coulomb friction tau_C as a set-valued law (D2), by
       velocity projection on the follower speed after the contact: if
       |omega_F| <= h*tau_C/(J_F + h*mu_F) the follower stops (the friction
       holds it), else that amount is taken off its magnitude. It can stop
       the follower within a sub-step but never reverse it. A follower at
       rest adds the meshing loss the way it would move to that amount, so
       the loss holds it as well (section 11);
    5. the speeds, x (eq. 4.2 at the end speeds) and the sums of the outputs.

    After the sub-steps, the thermal mass: C*dT/dt = P_loss + (T_amb - T)/R_th
    (ambient term implicit). Returns lists of the base torque (N*m, the mean
    over the sub-steps), follower speed (rad/s), temperature (K) and backlash
    position (m) at each sample, and the sub-step count.
    """
    # -- constants (SI) --------------------------------------------------------
    g = p["teeth_ratio"]
    s = p["direction"]
    inv_g = 1.0 / g
    dt = p["dt"]
    r_b = p["base_radius"]  # m
    r_f = g * r_b  # m
    sr_f = s * r_f
    mu_b = p["mu_base"]  # N*m/(rad/s)
    mu_f = p["mu_follower"]
    j_f = p["follower_inertia"]  # kg*m^2
    half_gap = 0.5 * p["linear_backlash"]  # m
    inv_d = 1.0 / p["transition_region"]  # 1/m
    k_c = p["stiffness"]  # N/m
    d_c = p["damping"]  # N*s/m
    temps = [float(v) for v in p["temperature_vector"]]  # K
    loads = [float(v) for v in p["load_vector"]]  # N*m at the base
    columns = [[float(row[j]) for row in p["efficiency_matrix"]] for j in range(len(loads))]
    tau_c = p["load_coulomb_friction"]  # N*m
    a_th = dt / p["thermal_mass"]  # K/J
    g_th = 1.0 / p["thermal_resistance"]  # W/K
    t_amb = p["ambient_temperature"]  # K
    # sub-steps: the smallest n with h*omega_n <= AUTO_H_OMEGA_N_MAX, at most
    # 16, where omega_n^2 = K*r_F^2/(J_F + dt*mu_F) (the C rig's automatic count)
    n = int(p["contact_substeps"])
    if n <= 0:
        k_over_m = k_c * (r_f * r_f / (j_f + dt * mu_f))
        n = 1
        while n < 16 and not ((dt / n) * (dt / n) * k_over_m <= AUTO_H_OMEGA_N_MAX**2):
            n += 1
    h = dt / n  # s
    jh_f = j_f + h * mu_f  # follower inertia with the implicit viscous term
    c = h * (r_f * r_f / jh_f)  # h/m_eff at the pitch line, s/kg
    coulomb_step = h * tau_c / jh_f  # the speed the Coulomb friction takes in h, rad/s

    def interp(xs: list[float], ys: list[float], at: float) -> float:
        """Linear interpolation; the end values hold outside the table."""
        if not at > xs[0]:
            return ys[0]
        if not at < xs[-1]:
            return ys[-1]
        i = 1
        while not at < xs[i]:
            i += 1
        return ys[i - 1] + (at - xs[i - 1]) / (xs[i] - xs[i - 1]) * (ys[i] - ys[i - 1])

    def contact(x: float, u: float) -> tuple[float, float, float]:
        """Smooth hard stop (eq. 4.5) with the no-pull clip at x (m) and
        v = u (m/s): the force f (N), df/du along x = x0 + h*u, and the
        spring part of f."""
        if x > half_gap:
            delta = x - half_gap
            side = 1.0
        elif x < -half_gap:
            delta = x + half_gap
            side = -1.0
        else:
            return 0.0, 0.0, 0.0  # teeth apart
        xi = abs(delta) * inv_d
        if xi < 1.0:  # cubic step S = xi^2 (3 - 2 xi) through the transition region
            scale = xi * xi * (3.0 - 2.0 * xi)
            dscale = 6.0 * xi * (1.0 - xi) * inv_d * h * side
        else:
            scale = 1.0
            dscale = 0.0
        raw = k_c * delta + d_c * u
        f = scale * raw
        if side * f < 0.0:
            return 0.0, 0.0, scale * k_c * delta  # no pull
        return f, dscale * raw + scale * (k_c * h + d_c), scale * k_c * delta

    def solve_contact(x: float, u_free: float) -> tuple[float, float, float]:
        """Backward Euler over h: u = u_free - c*f(x + h*u, u). Returns u
        (m/s), the force of the impulse balance (N) and its spring part."""
        f, dfdu, f_spring = contact(x + h * u_free, u_free)
        if f == 0.0:
            return u_free, 0.0, f_spring
        # Phi(u) = u - u_free + c*f(u) increases; its root lies in [lo, hi]
        lo, hi = (u_free - c * f, u_free) if f > 0.0 else (u_free, u_free - c * f)
        tolerance = newton_tolerance * (abs(u_free) + c * abs(f))
        u = u_free
        for _ in range(newton_iterations):
            phi = u - u_free + c * f
            if phi > 0.0:
                hi = u
            elif phi < 0.0:
                lo = u
            else:
                break  # exact root
            slope = 1.0 + c * dfdu
            step_to = u - phi / slope if slope > 0.0 else lo
            converged = abs(step_to - u) <= tolerance and lo <= step_to <= hi
            if not converged and not lo < step_to < hi:
                step_to = 0.5 * (lo + hi)  # bisect where Newton leaves the bracket
            u = step_to
            f, dfdu, f_spring = contact(x + h * u, u)
            if converged:
                break
        force = (u_free - u) / c
        if (force - f_spring) * u < 0.0 and abs(x) <= half_gap:
            # first contact on a jump of the law: the root is the stop's edge
            edge = half_gap if x + h * u > 0.0 else -half_gap
            u_edge = (edge - x) / h
            if lo <= u_edge <= hi:
                u = u_edge
                force = (u_free - u) / c
                f_spring = 0.0
        return u, force, f_spring

    ws = _floats(base_speed)
    tau_loads = _floats(load)
    n_samples = len(ws)
    out_tau_b = [0.0] * n_samples
    out_w_f = [0.0] * n_samples
    out_temp = [0.0] * n_samples
    out_x = [0.0] * n_samples
    # -- state: the first sample sets the speeds, the teeth moving together ----
    w_b = ws[0] if ws else 0.0  # base speed, rad/s
    w_f = s * w_b / g  # follower speed, rad/s
    x = 0.0  # backlash position, m (centred)
    f_last = 0.0  # contact force of the last sub-step, N
    t_f_last = 0.0  # T_F of the last loss evaluation, N*m (its base load picks eta)
    temp = p["initial_temperature"]  # K
    for i in range(n_samples):
        w_in = ws[i]
        tau_load = tau_loads[i]
        # the table at this step's temperature: efficiency over the base load
        eta_of_load = [interp(temps, col, temp) for col in columns]
        w_b_start = w_b
        sum_tau_b = 0.0
        sum_loss = 0.0
        for k in range(n):
            # explicit: meshing loss (eq. 2.7) by the corrected rule (D1), at
            # full strength in the direction the follower slides
            t_f0 = -sr_f * f_last
            eta = interp(loads, eta_of_load, abs(t_f_last) * inv_g)
            k_loss = 1.0 / eta - 1.0
            at_rest = w_f == 0.0
            tau_mesh = _mesh_loss(t_f0, k_loss, 1.0 if w_f > 0.0 else -1.0) if not at_rest else 0.0
            t_f_last = t_f0 + tau_mesh
            # the held base speed ramps linearly from the last sample to this one
            w_b_new = w_b_start + (w_in - w_b_start) * (k + 1) / n
            # free motion of the follower over h, then the contact
            w_f_free = (j_f * w_f + h * (tau_load - tau_mesh)) / jh_f
            u, f, f_spring = solve_contact(x, r_b * w_b_new - sr_f * w_f_free)
            w_f_new = w_f_free + h * sr_f * f / jh_f
            if tau_mesh * w_f_new < 0.0:
                # the held loss would reverse the follower: this sub-step without it
                tau_mesh = 0.0
                w_f_free = (j_f * w_f + h * tau_load) / jh_f
                u, f, f_spring = solve_contact(x, r_b * w_b_new - sr_f * w_f_free)
                w_f_new = w_f_free + h * sr_f * f / jh_f
            # the load's Coulomb friction (D2): stops the follower or slows it by
            # h*tau_C/J; from rest, the meshing loss the way it would move too
            hold_step = coulomb_step
            if at_rest and w_f_new != 0.0:
                tau_mesh = _mesh_loss(t_f0, k_loss, 1.0 if w_f_new > 0.0 else -1.0)
                hold_step += h * abs(tau_mesh) / jh_f
            if w_f_new > hold_step:
                w_f_new -= hold_step
            elif w_f_new < -hold_step:
                w_f_new += hold_step
            else:
                w_f_new = 0.0
                tau_mesh = 0.0  # held: no work
            w_b = w_b_new
            w_f = w_f_new
            x += h * (r_b * w_b - sr_f * w_f)  # eq. 4.2 at the end speeds
            f_last = f
            sum_tau_b += r_b * f + mu_b * w_b  # tau_B = r_B*f + mu_B*omega_B
            # loss: mesh + viscous + contact damping (eq. 5.2)
            sum_loss += tau_mesh * w_f + mu_b * w_b * w_b + mu_f * w_f * w_f + (f - f_spring) * u
        # thermal mass (eq. 5.1), Q_H = (T_amb - T)/R_th taken implicitly
        temp = (temp + a_th * (sum_loss / n + g_th * t_amb)) / (1.0 + a_th * g_th)
        out_tau_b[i] = sum_tau_b / n
        out_w_f[i] = w_f
        out_temp[i] = temp
        out_x[i] = x
    return {
        "base_torque": out_tau_b,
        "follower_speed": out_w_f,
        "temperature": out_temp,
        "backlash_position": out_x,
        "substeps": n,
    }
