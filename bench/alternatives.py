"""What a user would write instead of gearsim, for the benchmark comparison.

The same equations as the C rig (docs/physics.md), written plainly in Python:

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
- ``backlash_ode``: the Simple Gear with backlash (smooth hard stop, eq. 4.5,
  no-pull clip) between the speed-driven base and the follower inertia, as an
  ODE in (x, omega_F) for ``scipy.integrate.solve_ivp``. The held base speed
  is the same piecewise-linear ramp between samples that the C rig uses.

All take the parameters as a plain dict (``GEAR_PARAMS`` below), so that the
benchmark builds the gearsim model from the same numbers.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

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


def scenario(n: int, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """The benchmark's input, as in bench/gearsim_bench.c: base speed (rad/s)
    with reversals and a load (N*m) that changes sign."""
    t = np.arange(n) * dt
    two_pi = 2.0 * math.pi
    w = 20.0 * np.sin(two_pi * 0.5 * t) + 4.0 * np.sin(two_pi * 1.25 * t)
    load = 2.0 + 6.0 * np.sin(two_pi * 0.25 * t + 0.3) + 0.5 * np.sin(two_pi * 5.0 * t)
    return w, load


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
    ws = base_speed.tolist() if hasattr(base_speed, "tolist") else list(base_speed)
    loads = load.tolist() if hasattr(load, "tolist") else list(load)
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
    smooth hard stop (4.5), the no-pull clip, and the mesh loss of eq. 2.2 on
    T_F0 = -s*r_F*f. Sample k of the base speed is reached at t = (k+1)*dt
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
    loss_fd = 1.0 - eta
    loss_bd = 1.0 / eta - 1.0
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
        tau_mesh = t_f0 * tt * (loss_fd if tt >= 0.0 else loss_bd)
        return [v, (tau_load - tau_mesh - mu_f * w_f - t_f0) / j_f]

    t_eval = dt * np.arange(1, n + 1)
    y0 = [0.0, (s / g) * ws[0]]
    sol = solve_ivp(
        rhs, (0.0, n * dt), y0, method=method, t_eval=t_eval, rtol=rtol, atol=atol, max_step=dt
    )
    return {
        "driven_speed": sol.y[1],
        "backlash_position": sol.y[0],
        "nfev": int(sol.nfev),
        "status": int(sol.status),
        "message": str(sol.message),
    }
