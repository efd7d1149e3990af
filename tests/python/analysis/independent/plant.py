"""The true mechanism: a speed-controlled drive, a compliant mesh with optional
backlash and the driven side, integrated by classical RK4 at a fine step.

Written from the physics of docs/physics.md (sign convention of section 0,
kinematics 1.1 / 6.1, torque balance 1.2 / 6.3, loss laws 2.2-2.4, driven side
of section 11), never from gearsim's C core or Python rig. Differences from
gearsim's rig are deliberate, they are what a real rig has:

- the mesh is compliant everywhere: a spring-damper along the pitch line,
  a dead zone in that spring when there is backlash (gearsim: rigid, or a hard
  stop with backlash);
- the base shaft is not given its speed: a motor with a PI speed loop and
  velocity feed-forward drives the base inertia after a commanded profile,
  so the base speed that a sensor sees is the real one;
- Coulomb friction on the driven side is a tanh of the driven speed with a
  threshold wide enough for the fine step; a Stribeck hump (breakaway level
  falling to the Coulomb level with speed) multiplies the same tanh, so the
  driven side "sticks" by creeping inside that band;
- optionally a compliant shaft between the motor and the base gear (a second
  inertia on the base side): the encoder sits on the motor, the torque sensor
  in the shaft;
- optionally a torque ripple on the base gear, a function of its own angle
  (per revolution and per tooth), acting between the torque sensor and the
  mesh.

States: base angle and speed (theta_b, omega_b), driven angle and speed
(theta_d, omega_d; for the rack x_R and v_R), integrator of the PI loop; with
a compliant shaft the base gear's angle and speed (theta_g, omega_g) too.
Units SI; the rack is the Simple Gear with follower radius 1 (physics.md 6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Losses:
    """What the true mechanism loses, each off by default.

    efficiency: constant mesh efficiency (None: no meshing loss);
    idle_torque_Nm, load_slope: load-dependent loss of eq. 2.3
    (tau_Coul = g*idle + k*|T_F|, gear only);
    efficiency_table: (temperatures K, efficiencies) read at the true
    temperature (eq. 2.4, linear, clamped);
    viscous: driven-side viscous coefficient (N*m/(rad/s) or N/(m/s));
    coulomb: driven-side Coulomb friction (N*m or N);
    load_offset: constant force or torque on the driven side (N*m or N);
    breakaway: driven-side friction level at rest (N*m or N; 0: no Stribeck
    hump), falling to `coulomb` as exp(-(v/stribeck_speed)^2) (physics.md
    11.1); stribeck_speed in rad/s (gear follower) or m/s (rack)."""

    efficiency: float | None = None
    idle_torque_Nm: float = 0.0
    load_slope: float = 0.0
    efficiency_table: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    viscous: float = 0.0
    coulomb: float = 0.0
    load_offset: float = 0.0
    breakaway: float = 0.0
    stribeck_speed: float = 0.01


@dataclass(frozen=True)
class Mechanism:
    """Geometry, inertias, mesh and drive of one rig.

    ratio_sign_s: +1 / -1 (same / opposite rotation; rack direction);
    base_radius_m: r_B (pinion radius); driven_radius_m: r_F = g*r_B for the
    gear, 1 for the rack (the rack moves along its own axis);
    teeth_ratio: g (gear), 1 for the rack (unused there);
    base_inertia: J_B (kg*m^2), on the drive's side of the torque sensor;
    driven_inertia: J_F (kg*m^2) or rack mass (kg);
    mesh_stiffness_N_m, mesh_damping_Ns_m: the pitch-line spring-damper;
    backlash_m: total free play along the pitch line (0: none);
    drive_bandwidth_rad_s: crossover of the PI speed loop;
    coulomb_speed: tanh threshold of the driven-side Coulomb friction;
    mesh_power_W: width of the blend between the two power-flow directions of
    an efficiency; idle_speed: tanh threshold of the load-dependent loss;
    shaft_stiffness_Nm_rad, shaft_damping_Nms_rad: the shaft between the
    motor (inertia base_inertia, the encoder's side) and the base gear
    (inertia gear_inertia, kg*m^2), 0: a rigid shaft (no gear_inertia then);
    ripple_revolution, ripple_mesh: (amplitude N*m, phase rad) per harmonic
    1, 2, ... of the base gear's angle and of its tooth angle teeth*angle,
    tau_r = sum A_i*cos(i*theta + phi_i) + sum M_j*cos(j*teeth*theta + psi_j)
    (physics.md 11.5)."""

    block: str
    ratio_sign_s: float
    base_radius_m: float
    driven_radius_m: float
    teeth_ratio: float
    base_inertia: float
    driven_inertia: float
    mesh_stiffness_N_m: float
    mesh_damping_Ns_m: float
    backlash_m: float = 0.0
    drive_bandwidth_rad_s: float = 2 * math.pi * 15.0
    coulomb_speed: float = 0.01
    mesh_power_W: float = 0.3
    idle_speed: float = 0.02
    shaft_stiffness_Nm_rad: float = 0.0
    shaft_damping_Nms_rad: float = 0.0
    gear_inertia: float = 0.0
    ripple_revolution: tuple[tuple[float, float], ...] = ()
    ripple_mesh: tuple[tuple[float, float], ...] = ()
    teeth: int = 0
    losses: Losses = field(default_factory=Losses)

    @property
    def compliant(self) -> bool:
        return self.shaft_stiffness_Nm_rad > 0.0

    @property
    def kinematic_ratio(self) -> float:
        """a = driven speed per base speed: s*r_B/r_F (s/g for the gear,
        s*r_P for the rack)."""
        return self.ratio_sign_s * self.base_radius_m / self.driven_radius_m

    @property
    def shaft_natural_frequency_rad_s(self) -> float:
        """The shaft's mode with the motor held and the mesh rigid
        (physics.md 11.4): sqrt(k/(J_g + a^2*J_F))."""
        j_eff = self.gear_inertia + self.kinematic_ratio**2 * self.driven_inertia
        return math.sqrt(self.shaft_stiffness_Nm_rad / j_eff)

    def ripple_torque(self, angle: float) -> float:
        """tau_r at the base gear's angle (rad), N*m."""
        total = 0.0
        for i, (amplitude, phase) in enumerate(self.ripple_revolution, start=1):
            total += amplitude * math.cos(i * angle + phase)
        for j, (amplitude, phase) in enumerate(self.ripple_mesh, start=1):
            total += amplitude * math.cos(j * self.teeth * angle + phase)
        return total

    @property
    def reflected_driven_inertia(self) -> float:
        """J_F seen at the base shaft (rigid kinematics): J_F*(r_B/r_F)^2."""
        return self.driven_inertia * (self.base_radius_m / self.driven_radius_m) ** 2

    @property
    def mesh_natural_frequency_rad_s(self) -> float:
        """Free-free two-mass mode of the mesh (drive loop open):
        sqrt(K*(1/m_B + 1/m_F)) with the masses reduced to the pitch line,
        m_B = J_B/r_B^2 and m_F = J_F/r_F^2."""
        m_b = self.base_inertia / self.base_radius_m**2
        m_f = self.driven_inertia / self.driven_radius_m**2
        return math.sqrt(self.mesh_stiffness_N_m * (1.0 / m_b + 1.0 / m_f))


@dataclass(frozen=True)
class TrueRun:
    """Noise-free signals at the sample instants (SI)."""

    time: np.ndarray
    base_angle: np.ndarray
    base_speed: np.ndarray
    base_torque: np.ndarray  # what the torque sensor reads (below)
    driven_position: np.ndarray
    driven_speed: np.ndarray
    load: np.ndarray
    temperature: np.ndarray
    # the torque sensor at every integration step's start (and the last
    # sample), spaced fine_dt: what a delayed sensor is read from
    fine_torque: np.ndarray | None = None
    fine_dt: float = 0.0
    # the base gear's side of a compliant shaft (None: rigid, = base_*)
    gear_angle: np.ndarray | None = None
    gear_speed: np.ndarray | None = None


# base_torque: rigid shaft, the torque the base shaft puts into the mesh plus
# the ripple, T_B = r_B*f + tau_r (the sensor sits between the motor's
# inertia and the base gear); compliant shaft, the shaft torque
# k*twist + c*(omega_b - omega_g).


def _mesh_force(mech: Mechanism, x: float, v: float) -> float:
    """Pitch-line force (N), positive when the base tooth pushes toward +x:
    a spring-damper, with a dead zone of width b that never pulls."""
    half = 0.5 * mech.backlash_m
    k, d = mech.mesh_stiffness_N_m, mech.mesh_damping_Ns_m
    if half == 0.0:
        return k * x + d * v
    if x > half:
        return max(0.0, k * (x - half) + d * v)
    if x < -half:
        return min(0.0, k * (x + half) + d * v)
    return 0.0


def _follower_port_torque(mech: Mechanism, t_f0: float, omega_d: float, eta: float | None) -> float:
    """T_F, the torque the driven side exerts on the mesh after the loss, from
    the loss-free T_F0 = -s*r_F*f (physics.md 4.6a)."""
    loss = mech.losses
    if eta is not None:
        # base drives when T_F0*omega < 0: T_F = eta*T_F0; driven side drives:
        # T_F = T_F0/eta (physics.md 4.6b limits), blended over the power
        follower_drives = 0.5 * (1.0 + math.tanh(t_f0 * omega_d / mech.mesh_power_W))
        return t_f0 * (follower_drives / eta + (1.0 - follower_drives) * eta)
    if loss.idle_torque_Nm > 0.0 or loss.load_slope > 0.0:
        # eq. 2.3 with |T_F| after the loss, solved on each sign (physics.md 4.6c)
        th = math.tanh(omega_d / mech.idle_speed)
        a = t_f0 + mech.teeth_ratio * loss.idle_torque_Nm * th
        sigma = 1.0 if a >= 0.0 else -1.0
        return a / (1.0 - sigma * loss.load_slope * th)
    return t_f0


def _driven_friction(mech: Mechanism, omega_d: float) -> float:
    """Coulomb (and Stribeck) friction on the driven side, against omega_d;
    the tanh makes it a steep damper near rest, where the driven side creeps
    instead of sticking."""
    loss = mech.losses
    if loss.breakaway > 0.0:
        hump = math.exp(-((omega_d / loss.stribeck_speed) ** 2))
        level = loss.coulomb + (loss.breakaway - loss.coulomb) * hump
        return level * math.tanh(omega_d / mech.coulomb_speed)
    return loss.coulomb * math.tanh(omega_d / mech.coulomb_speed)


def simulate_true(
    mech: Mechanism,
    time: np.ndarray,
    speed_command: np.ndarray,
    load: np.ndarray,
    temperature: np.ndarray,
    substeps: int = 4,
) -> TrueRun:
    """Integrate the mechanism over the sample instants `time` (uniform step),
    commanded base speed, true load (N*m on the follower, N on the rack) and
    true temperature (K) given per sample and held linearly between samples.

    The run starts at rest with the speed loop following the command; the
    command's first sample should be 0."""
    if mech.compliant and mech.gear_inertia <= 0.0:
        raise ValueError("a compliant shaft needs the base gear's inertia (gear_inertia > 0)")
    dt = float(time[1] - time[0])
    h = dt / substeps
    n = time.size
    g_sign, r_b, r_f = mech.ratio_sign_s, mech.base_radius_m, mech.driven_radius_m
    j_b, j_f = mech.base_inertia, mech.driven_inertia
    loss = mech.losses
    # PI speed loop on the inertia the drive sees: crossover w_c, integral
    # corner a quarter of it (a phase margin of about 75 degrees)
    j_g, k_shaft, c_shaft = (
        mech.gear_inertia,
        mech.shaft_stiffness_Nm_rad,
        mech.shaft_damping_Nms_rad,
    )
    j_drive = j_b + j_g + mech.reflected_driven_inertia
    ripple = bool(mech.ripple_revolution or mech.ripple_mesh)
    kp = mech.drive_bandwidth_rad_s * j_drive
    ki = kp * mech.drive_bandwidth_rad_s / 4.0
    cmd_accel = np.gradient(speed_command, dt)
    table = loss.efficiency_table

    def efficiency(temp: float) -> float | None:
        if table is not None:
            return float(np.interp(temp, table[0], table[1]))
        return loss.efficiency

    def rhs(state, w_cmd, a_cmd, tau_load, eta):
        th_b, w_b, x_d, w_d, integ = state
        x = r_b * th_b - g_sign * r_f * x_d
        v = r_b * w_b - g_sign * r_f * w_d
        f = _mesh_force(mech, x, v)
        t_b = r_b * f
        t_f = _follower_port_torque(mech, -g_sign * r_f * f, w_d, eta)
        if ripple:
            t_b = t_b + mech.ripple_torque(th_b)
        err = w_cmd - w_b
        # the drive's feed-forward knows only the base inertia and the rigid
        # driven inertia; the PI loop takes up the rest
        tau_motor = j_drive * a_cmd + kp * err + integ
        driven = (
            tau_load + loss.load_offset - t_f - loss.viscous * w_d - _driven_friction(mech, w_d)
        )
        return (w_b, (tau_motor - t_b) / j_b, w_d, driven / j_f, ki * err), t_b

    def rhs_compliant(state, w_cmd, a_cmd, tau_load, eta):
        # motor (encoder side) -> shaft spring-damper (torque sensor) -> base
        # gear -> mesh -> driven side
        th_b, w_b, th_g, w_g, x_d, w_d, integ = state
        x = r_b * th_g - g_sign * r_f * x_d
        v = r_b * w_g - g_sign * r_f * w_d
        f = _mesh_force(mech, x, v)
        t_mesh = r_b * f
        t_f = _follower_port_torque(mech, -g_sign * r_f * f, w_d, eta)
        t_shaft = k_shaft * (th_b - th_g) + c_shaft * (w_b - w_g)
        gear_side = t_shaft - t_mesh - (mech.ripple_torque(th_g) if ripple else 0.0)
        err = w_cmd - w_b
        tau_motor = j_drive * a_cmd + kp * err + integ
        driven = (
            tau_load + loss.load_offset - t_f - loss.viscous * w_d - _driven_friction(mech, w_d)
        )
        derivs = (w_b, (tau_motor - t_shaft) / j_b, w_g, gear_side / j_g, w_d, driven / j_f)
        return derivs + (ki * err,), t_shaft

    def lerp(arr, k, frac):
        if k + 1 >= n:
            return float(arr[-1])
        return float(arr[k] + (arr[k + 1] - arr[k]) * frac)

    w0 = float(speed_command[0])
    if mech.compliant:
        # (theta_b, omega_b, theta_g, omega_g, theta_d, omega_d, integrator):
        # the shaft starts untwisted, the driven side geared to the base gear
        derivatives = rhs_compliant
        state = (0.0, w0, 0.0, w0, 0.0, g_sign * r_b * w0 / r_f, 0.0)
        driven_at, gear_at = 4, 2
    else:
        derivatives = rhs
        state = (0.0, w0, 0.0, 0.0, 0.0)
        # the driven side starts geared to the base
        state = (0.0, state[1], 0.0, g_sign * r_b * state[1] / r_f, 0.0)
        driven_at, gear_at = 2, 0
    out = np.zeros((n, 7))
    fine_torque = np.zeros((n - 1) * substeps + 1)
    for k in range(n):
        _, t_b = derivatives(
            state,
            float(speed_command[k]),
            float(cmd_accel[k]),
            float(load[k]),
            efficiency(float(temperature[k])),
        )
        out[k] = (
            state[0],
            state[1],
            state[driven_at],
            state[driven_at + 1],
            t_b,
            state[gear_at],
            state[gear_at + 1],
        )
        if k + 1 == n:
            fine_torque[-1] = t_b
            break
        eta = efficiency(float(temperature[k]))
        for j in range(substeps):
            f0, f1 = j / substeps, (j + 0.5) / substeps
            f2 = (j + 1) / substeps
            u0 = (lerp(speed_command, k, f0), lerp(cmd_accel, k, f0), lerp(load, k, f0))
            u1 = (lerp(speed_command, k, f1), lerp(cmd_accel, k, f1), lerp(load, k, f1))
            u2 = (lerp(speed_command, k, f2), lerp(cmd_accel, k, f2), lerp(load, k, f2))
            k1, fine_torque[k * substeps + j] = derivatives(state, *u0, eta)
            s1 = tuple(a + 0.5 * h * b for a, b in zip(state, k1, strict=True))
            k2, _ = derivatives(s1, *u1, eta)
            s2 = tuple(a + 0.5 * h * b for a, b in zip(state, k2, strict=True))
            k3, _ = derivatives(s2, *u1, eta)
            s3 = tuple(a + h * b for a, b in zip(state, k3, strict=True))
            k4, _ = derivatives(s3, *u2, eta)
            state = tuple(
                a + h / 6.0 * (b + 2.0 * c + 2.0 * d + e)
                for a, b, c, d, e in zip(state, k1, k2, k3, k4, strict=True)
            )
    return TrueRun(
        time=np.asarray(time, dtype=float),
        base_angle=out[:, 0],
        base_speed=out[:, 1],
        base_torque=out[:, 4],
        driven_position=out[:, 2],
        driven_speed=out[:, 3],
        load=np.asarray(load, dtype=float),
        temperature=np.asarray(temperature, dtype=float),
        fine_torque=fine_torque,
        fine_dt=h,
        gear_angle=out[:, 5] if mech.compliant else None,
        gear_speed=out[:, 6] if mech.compliant else None,
    )
