/* fuzz_rig.c - libFuzzer target: arbitrary finite input sequences to valid rigs.
 *
 * Input: 4 configuration bytes, ~40 bytes of parameters (each mapped into
 * its valid range, log-uniform where it spans decades), then 10 bytes per
 * step (5 inputs x 2 bytes). The configuration covers both blocks, both base
 * drives, the five (gear) / three (rack) friction models, both smoothings,
 * rigid mesh and backlash with the three hard-stop laws, no-pull, the static
 * lock, heat path and measured temperature; with bits 6 and 7 of the first
 * byte, the Stribeck friction and torque ripple, and the compliant base
 * shaft (speed-driven rigid rigs); with bits 6 and 7 of the third, the
 * regularised driven-side friction and the step-mean speed (no bytes of
 * their own).
 *
 * Input values: |base speed| <= 1e3 rad/s, |base torque| <= 1e3 N*m,
 * |load| <= 1e3 (N*m or N), temperatures in [1, 1e3] K; each is zero, a
 * uniform value, or +-10^u with u uniform over 9 decades.
 *
 * Properties, every step:
 *   - no crash, no sanitizer report; every output finite;
 *   - rigid mesh: port_power == loss_power to rounding, and
 *     loss_power >= 0 (passive smoothing; Simscape smoothing is documented
 *     as slightly active, so only the balance is checked there); with a
 *     compliant shaft only loss_power >= 0 (see the check);
 *   - torque-driven base, every mesh: the drive's work over a step is exact,
 *     W = (T_m - tau_r(theta_B))*(theta_B' - theta_B) + (L + L_0)*(x_F' - x_F)
 *     (motor torque and load held over the step, the ripple at the step's
 *     start angle, physics.md 11), and dKE + dE_contact <= W + rounding with
 *     KE = J_B*w_B^2/2 + J_F*w_F^2/2: no energy created by anything inside
 *     the rig (mesh loss, friction, contact, sub-steps);
 *   - backlash, every friction model and smoothing: port_power*dt >=
 *     loss_power*dt + (contact_energy now - contact_energy before) -
 *     rounding tolerance (no energy created), and loss_power*dt >=
 *     -tolerance (the balance alone cannot see a negative loss that the
 *     spring absorbs), with and without the no-pull clip;
 *   - determinism: a copy of the state (snapshot), stepped with a copy of
 *     the constants and the same input, gives the same bits, and gs_rig_run
 *     gives the bits of gs_rig_step. */
#include "fuzz_common.h"

#define MAX_STEPS 256

/* The rounding of the contact solve's force, in units of (1 + kappa)/c
 * times the pitch-line speed scale squared: the closed forms end on their
 * root to rounding, and the smooth law's iteration only on points whose
 * force is passive (docs/model.md), so its tolerance creates no energy.
 * About 4500 (float 84) rounding units. */
#ifdef GS_SINGLE_PRECISION
#define FZ_SOLVER_ROUNDING 1e-5
#else
#define FZ_SOLVER_ROUNDING 1e-12
#endif

#ifdef FZ_STRICT
#define FZ_STRICT_ENERGY 1
#else
#define FZ_STRICT_ENERGY 0
#endif

/* What the checks need to know of a rig: from its parameters (the constants
 * are opaque) and gs_rig_get_info. */
typedef struct {
    int gear;
    int backlash;
    gs_friction_model friction;
    int passive;
    double r_base;
    double r_follow;
    double dt;         /* dt_s */
    int substeps;      /* gs_rig_info.contact_substeps (1 without backlash) */
    int torque_driven; /* base_drive == GS_BASE_TORQUE_DRIVEN */
    double load_offset;
    double load_coulomb;
    double base_extra; /* largest ripple torque on the base, N*m */
    int compliant;     /* compliant base shaft */
    int ramp;          /* base_speed_ramp: torques at the step's mean speed */
    double stiffness;  /* backlash K, D, b/2, no-pull */
    double damping;
    double half_gap;
    int no_pull;
    double inv_eff_mass_contact; /* 1/m_eff at the pitch line for one sub-step (backlash) */
    double base_inertia;         /* J_B, J_F: the kinetic energy of a torque-driven rig */
    double driven_inertia;
    double ripple_cos[2], ripple_sin[2], mesh_cos[2], mesh_sin[2]; /* A*cos(phi), A*sin(phi) of eq. 11.5 */
    double ripple_sum;                                             /* sum of the ripple amplitudes, N*m */
    double ripple_stiffness;                                       /* K_r = sum i*A_i + j*Z*M_j, N*m/rad */
    int teeth;
} rig_info;

/* The ripple torque of eq. 11.5 at base angle theta, from its definition. */
static double ripple_at(const rig_info *info, double theta)
{
    double t = 0.0;
    for (int i = 0; i < 2; ++i) {
        t += info->ripple_cos[i] * cos((i + 1) * theta) - info->ripple_sin[i] * sin((i + 1) * theta);
        t += info->mesh_cos[i] * cos((i + 1) * info->teeth * theta) -
             info->mesh_sin[i] * sin((i + 1) * info->teeth * theta);
    }
    return t;
}

/* 1/m_eff at the pitch line for the sub-step h = dt/substeps, viscous terms
 * implicit, as the rig's init derives it (docs/physics.md section 11):
 * r_F^2/(J_F + h*mu_F), plus r_B^2/(J_B + h*mu_B) for a torque-driven base;
 * in gs_real, as the library computes it. */
static double contact_inverse_mass(const gs_rig_params *rp, gs_real r_base, gs_real r_follow, gs_real mu_base,
                                   gs_real mu_follow, int substeps)
{
    const gs_real h = rp->dt_s / (gs_real)substeps;
    gs_real inv = r_follow * r_follow / (rp->driven_inertia + h * mu_follow);
    if (rp->base_drive == GS_BASE_TORQUE_DRIVEN) {
        inv += r_base * r_base / (rp->base_inertia_kg_m2 + h * mu_base);
    }
    return (double)inv;
}

/* Strictly increasing table of n breakpoints from lo with steps in [0.1, 50]. */
static void table_x(fz_reader *r, gs_real *x, int n, double lo)
{
    double v = lo;
    for (int i = 0; i < n; ++i) {
        x[i] = (gs_real)v;
        v += fz_log_range(r, 0.1, 50.0);
    }
}

static gs_real eff(fz_reader *r)
{
    return (gs_real)fz_range(r, 0.2, 1.0);
}

static void set_backlash(fz_reader *r, gs_backlash_params *b, uint8_t cfg, int gear)
{
    b->enabled = 1;
    b->hard_stop_model = (gs_hard_stop_model)(cfg % 3U);
    b->linear_backlash_m = (gs_real)fz_log_range(r, 1e-6, 1e-2);
    if (gear) {
        b->base_radius_m = (gs_real)fz_log_range(r, 1e-3, 1.0);
    }
    b->transition_region_m = (gs_real)((double)b->linear_backlash_m * fz_log_range(r, 1e-3, 0.5));
    b->stiffness_N_m = (gs_real)fz_log_range(r, 1e3, 1e9);
    b->damping_N_s_m = (fz_u8(r) & 7U) == 0 ? (gs_real)0.0 : (gs_real)fz_log_range(r, 1e-2, 1e5);
    b->initial_position_m = (gs_real)(0.5 * (double)b->linear_backlash_m * fz_range(r, -1.0, 1.0));
    b->no_pull = (cfg >> 2) & 1U;
    b->lock_enabled = (cfg >> 3) & 1U;
    b->contact_speed_threshold_m_s = (gs_real)fz_log_range(r, 1e-6, 1e-1);
    b->contact_release_force_N = (fz_u8(r) & 3U) == 0 ? (gs_real)0.0 : (gs_real)fz_log_range(r, 1e-3, 1e3);
}

static gs_status build(fz_reader *r, gs_rig_consts *consts, gs_rig_state *state, rig_info *info)
{
    const uint8_t c0 = fz_u8(r), c1 = fz_u8(r), c2 = fz_u8(r), c3 = fz_u8(r);
    gs_rig_params rp = gs_rig_params_default();
    rp.dt_s = (gs_real)fz_log_range(r, 1e-5, 1e-2);
    rp.base_drive = (c0 & 2U) ? GS_BASE_TORQUE_DRIVEN : GS_BASE_SPEED_DRIVEN;
    rp.base_inertia_kg_m2 =
        (rp.base_drive == GS_BASE_TORQUE_DRIVEN || (c2 & 1U)) ? (gs_real)fz_log_range(r, 1e-6, 1e1) : (gs_real)0.0;
    rp.initial_base_speed_rad_s = (gs_real)fz_range(r, -100.0, 100.0);
    rp.driven_inertia = (gs_real)fz_log_range(r, 1e-6, 1e2);
    rp.load_coulomb_friction = (c2 & 2U) ? (gs_real)fz_log_range(r, 1e-3, 1e2) : (gs_real)0.0;
    rp.load_coulomb_speed_threshold = (gs_real)fz_log_range(r, 1e-4, 1.0);
    rp.load_offset = (gs_real)fz_range(r, -10.0, 10.0);
    rp.heat_path = (c2 >> 2) & 1U;
    rp.thermal_resistance_K_W = (gs_real)fz_log_range(r, 1e-2, 1e2);
    rp.temperature_source = (c2 & 8U) ? GS_TEMPERATURE_FROM_INPUT : GS_TEMPERATURE_FROM_MODEL;
    rp.accel_filter_time_constant_s = (c2 & 16U) ? (gs_real)fz_log_range(r, 1e-4, 1e-1) : (gs_real)0.0;
    rp.contact_substeps = (c2 & 32U) ? (int)(fz_u8(r) % (GS_MAX_SUBSTEPS + 1)) : 0;
    rp.load_friction_regularised = (c2 >> 6) & 1U;
    rp.base_speed_ramp = (c2 >> 7) & 1U;
    /* The rig terms of physics.md 11 read their bytes only when their bit
     * is set, so the corpus inputs without them keep their meaning. */
    double base_extra = 0.0; /* the largest ripple torque, N*m */
    if (c0 & 64U) {
        rp.load_breakaway_friction = (gs_real)((double)rp.load_coulomb_friction + fz_log_range(r, 1e-3, 1e2));
        rp.load_stribeck_speed = (gs_real)fz_log_range(r, 1e-4, 10.0);
        const uint8_t harmonics = fz_u8(r);
        for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
            rp.ripple_revolution_amplitude_Nm[i] =
                (harmonics >> i & 1U) ? (gs_real)fz_log_range(r, 1e-4, 1e2) : (gs_real)0.0;
            rp.ripple_revolution_phase_rad[i] = (gs_real)fz_range(r, -10.0, 10.0);
            rp.ripple_mesh_amplitude_Nm[i] =
                (harmonics >> (i + 2) & 1U) ? (gs_real)fz_log_range(r, 1e-4, 1e2) : (gs_real)0.0;
            rp.ripple_mesh_phase_rad[i] = (gs_real)fz_range(r, -10.0, 10.0);
            base_extra += (double)rp.ripple_revolution_amplitude_Nm[i] + (double)rp.ripple_mesh_amplitude_Nm[i];
        }
        rp.ripple_mesh_teeth = 1 + (int)(fz_u8(r) % 60U);
    }
    /* compliance: speed-driven base and rigid mesh only (GS_E_COMBINATION otherwise) */
    if ((c0 & 128U) && !(c0 & 2U) && !(c0 & 4U)) {
        rp.base_inertia_kg_m2 = (gs_real)fz_log_range(r, 1e-6, 1e1);
        rp.compliance_stiffness_Nm_rad = (gs_real)fz_log_range(r, 1e-2, 1e8);
        rp.compliance_damping_Nm_s_rad = (fz_u8(r) & 3U) == 0 ? (gs_real)0.0 : (gs_real)fz_log_range(r, 1e-4, 1e3);
    }
    const gs_loss_smoothing smoothing = (c0 & 8U) ? GS_SMOOTHING_SIMSCAPE : GS_SMOOTHING_PASSIVE;
    const double thermal_mass = fz_log_range(r, 1e-6, 1e3);
    info->gear = !(c0 & 1U);
    info->backlash = (c0 >> 2) & 1U;
    info->passive = smoothing == GS_SMOOTHING_PASSIVE;
    info->friction = GS_FRICTION_NONE;
    gs_error err;
    gs_status st;
    gs_backlash_params bl; /* the block's backlash parameters, kept past the block's scope */
    gs_real r_base, r_follow, mu_base, mu_follow;
    if (info->gear) {
        gs_simple_gear_params g = gs_simple_gear_params_default();
        g.teeth_ratio = (gs_real)fz_log_range(r, 1e-3, 1e3);
        g.output_shaft_rotates = (c0 & 16U) ? GS_ROTATES_SAME : GS_ROTATES_OPPOSITE;
        g.friction_model = (gs_friction_model)(c1 % 5U);
        g.loss_smoothing = smoothing;
        g.efficiency_const = eff(r);
        g.power_threshold_W = (gs_real)fz_log_range(r, 1e-6, 1e2);
        g.nominal_output_torque_Nm = (gs_real)fz_log_range(r, 1e-2, 1e3);
        g.efficiency_nominal = (gs_real)fz_range(r, 0.3, 0.99);
        /* idle torque within the k >= 0 limit of eq. 2.5 */
        const double k_max =
            (1.0 / (double)g.efficiency_nominal - 1.0) * (double)g.nominal_output_torque_Nm / (double)g.teeth_ratio;
        g.idle_torque_Nm = (gs_real)(0.999 * k_max * fz_range(r, 0.0, 1.0));
        g.speed_threshold_rad_s = (gs_real)fz_log_range(r, 1e-4, 1.0);
        g.temperature_count = 2 + (int)((c1 >> 3) % (GS_TABLE_MAX - 1));
        g.load_count = 2 + (int)((c3 >> 4) % (GS_TABLE_MAX - 1));
        table_x(r, g.temperature_vector_K, g.temperature_count, fz_range(r, 200.0, 300.0));
        table_x(r, g.load_vector_Nm, g.load_count, 0.0);
        for (int i = 0; i < g.temperature_count; ++i) {
            g.efficiency_vector[i] = eff(r);
            for (int j = 0; j < g.load_count; ++j) {
                g.efficiency_matrix[i][j] = eff(r);
            }
        }
        g.viscous_coefficients[0] = (c3 & 1U) ? (gs_real)fz_log_range(r, 1e-6, 1.0) : (gs_real)0.0;
        g.viscous_coefficients[1] = (c3 & 2U) ? (gs_real)fz_log_range(r, 1e-6, 1.0) : (gs_real)0.0;
        g.thermal_mass_J_K = (gs_real)thermal_mass;
        g.initial_temperature_K = (gs_real)fz_range(r, 250.0, 350.0);
        if (info->backlash) {
            set_backlash(r, &g.backlash, c3 >> 2, 1);
        }
        info->friction = g.friction_model;
        st = gs_rig_init_gear(consts, state, &g, &rp, &err);
        if (fz_verbose()) {
            fz_dump("gear", &g, fz_gear_fields, FZ_COUNT(fz_gear_fields));
        }
        info->r_base = (double)g.backlash.base_radius_m;
        info->r_follow = (double)g.teeth_ratio * (double)g.backlash.base_radius_m;
        bl = g.backlash;
        r_base = g.backlash.base_radius_m;
        r_follow = g.teeth_ratio * g.backlash.base_radius_m;
        mu_base = g.viscous_coefficients[0];
        mu_follow = g.viscous_coefficients[1];
    } else {
        static const gs_friction_model rack_models[3] = {GS_FRICTION_NONE, GS_FRICTION_CONSTANT_EFFICIENCY,
                                                         GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY};
        gs_rack_pinion_params k = gs_rack_pinion_params_default();
        k.parameterization = (c0 & 16U) ? GS_PARAMETERIZE_TOOTH_PARAMETERS : GS_PARAMETERIZE_PINION_RADIUS;
        k.pinion_radius_m = (gs_real)fz_log_range(r, 1e-3, 1.0);
        k.teeth_count = (gs_real)(5 + fz_u8(r) % 100U);
        k.spacing_m = (gs_real)fz_log_range(r, 1e-4, 1e-2);
        k.rack_directionality = (c0 & 32U) ? GS_RACK_NEGATIVE : GS_RACK_POSITIVE;
        k.friction_model = rack_models[c1 % 3U];
        k.loss_smoothing = smoothing;
        k.efficiency_const = eff(r);
        k.temperature_count = 2 + (int)((c1 >> 3) % (GS_TABLE_MAX - 1));
        table_x(r, k.temperature_vector_K, k.temperature_count, fz_range(r, 200.0, 300.0));
        for (int i = 0; i < k.temperature_count; ++i) {
            k.efficiency_vector[i] = eff(r);
        }
        k.power_threshold_W = (gs_real)fz_log_range(r, 1e-6, 1e2);
        k.pinion_viscous_coefficient = (c3 & 1U) ? (gs_real)fz_log_range(r, 1e-6, 1.0) : (gs_real)0.0;
        k.rack_viscous_coefficient = (c3 & 2U) ? (gs_real)fz_log_range(r, 1e-4, 1e2) : (gs_real)0.0;
        k.thermal_mass_J_K = (gs_real)thermal_mass;
        k.initial_temperature_K = (gs_real)fz_range(r, 250.0, 350.0);
        if (info->backlash) {
            set_backlash(r, &k.backlash, c3 >> 2, 0);
        }
        info->friction = k.friction_model;
        st = gs_rig_init_rack(consts, state, &k, &rp, &err);
        if (fz_verbose()) {
            fz_dump("rack", &k, fz_rack_fields, FZ_COUNT(fz_rack_fields));
        }
        info->r_base = (double)gs_rack_pinion_radius(&k);
        info->r_follow = 1.0;
        bl = k.backlash;
        r_base = gs_rack_pinion_radius(&k);
        r_follow = (gs_real)1.0;
        mu_base = k.pinion_viscous_coefficient;
        mu_follow = k.rack_viscous_coefficient;
    }
    if (fz_verbose()) {
        fz_dump("rp", &rp, fz_rig_fields, FZ_COUNT(fz_rig_fields));
    }
    FZ_CHECK(st == GS_OK, "generated parameters rejected: %s: %s", err.parameter, err.message);
    gs_rig_info ri;
    gs_rig_get_info(consts, &ri);
    info->dt = (double)rp.dt_s;
    info->substeps = ri.contact_substeps;
    info->torque_driven = rp.base_drive == GS_BASE_TORQUE_DRIVEN;
    info->load_offset = (double)rp.load_offset;
    /* the friction's largest level: breakaway with a Stribeck hump */
    info->load_coulomb = fmax((double)rp.load_coulomb_friction, (double)rp.load_breakaway_friction);
    info->base_extra = base_extra;
    info->compliant = rp.compliance_stiffness_Nm_rad > (gs_real)0.0;
    info->ramp = rp.base_speed_ramp != 0;
    info->base_inertia = (double)rp.base_inertia_kg_m2;
    info->driven_inertia = (double)rp.driven_inertia;
    info->teeth = rp.ripple_mesh_teeth;
    info->ripple_sum = 0.0;
    info->ripple_stiffness = 0.0;
    for (int i = 0; i < 2; ++i) {
        const double a = (double)rp.ripple_revolution_amplitude_Nm[i], pa = (double)rp.ripple_revolution_phase_rad[i];
        const double m = (double)rp.ripple_mesh_amplitude_Nm[i], pm = (double)rp.ripple_mesh_phase_rad[i];
        info->ripple_cos[i] = a * cos(pa);
        info->ripple_sin[i] = a * sin(pa);
        info->mesh_cos[i] = m * cos(pm);
        info->mesh_sin[i] = m * sin(pm);
        info->ripple_sum += a + m;
        info->ripple_stiffness += (i + 1) * a + (i + 1) * info->teeth * m;
    }
    info->stiffness = (double)bl.stiffness_N_m;
    info->damping = (double)bl.damping_N_s_m;
    info->half_gap = 0.5 * (double)bl.linear_backlash_m;
    info->no_pull = bl.no_pull != 0;
    info->inv_eff_mass_contact =
        info->backlash ? contact_inverse_mass(&rp, r_base, r_follow, mu_base, mu_follow, ri.contact_substeps) : 0.0;
    if (fz_verbose()) {
        fprintf(stderr,
                "rig: %s, %s-driven, friction %d (%s), backlash %d (hard stop %d, no_pull %d, lock %d), "
                "dt %.9g, substeps %d (capped %d), h*omega_n %.9g, follower per base %.9g, r_B %.9g, r_F %.9g, "
                "half gap %.9g, K %.9g, D %.9g, 1/m_eff %.9g\n",
                info->gear ? "gear" : "rack", info->torque_driven ? "torque" : "speed", (int)info->friction,
                info->passive ? "passive" : "simscape", info->backlash, (int)bl.hard_stop_model, bl.no_pull,
                bl.lock_enabled, info->dt, ri.contact_substeps, ri.substeps_capped, (double)ri.contact_h_omega_n,
                (double)ri.follower_per_base, info->r_base, info->r_follow, info->half_gap, info->stiffness,
                info->damping, info->inv_eff_mass_contact);
    }
    return st;
}

/* One input value: zero, uniform in [-hi, hi], or +-10^u (u over 9 decades below hi). */
static gs_real input_value(fz_reader *r, double lo, double hi)
{
    const uint8_t a = fz_u8(r);
    const uint8_t b = fz_u8(r);
    const double u = (double)(a >> 2 | (unsigned)b << 6) / 16383.0;
    switch (a & 3U) {
    case 0:
        return (gs_real)(lo >= 0.0 ? lo : 0.0);
    case 1:
        return (gs_real)(lo + (hi - lo) * u);
    default: {
        const double m = hi * pow(10.0, -9.0 * u);
        const double v = ((a & 3U) == 2 || lo >= 0.0) ? m : -m;
        return (gs_real)(v < lo ? lo : v);
    }
    }
}

static int same_bits(const gs_rig_output *a, const gs_rig_output *b)
{
    return memcmp(a, b, sizeof *a) == 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader r = {data, size};
    gs_rig_consts consts;
    gs_rig_state state;
    rig_info info;
    if (build(&r, &consts, &state, &info) != GS_OK) {
        return 0;
    }
    const double eps = FZ_EPS;
    const double dt = info.dt;
    /* Conditioning of the backward-Euler contact solve: kappa = c*(K*h + D)
     * with c = h/m_eff. When kappa*eps approaches 1 (float, stiff contact on a
     * light side), the impulse balance loses its significant digits: known
     * limit L2 (docs/hardening.md). Without -DFZ_STRICT such rigs are still
     * stepped (no crash, no UB) but their outputs are not checked. */
    const double h_sub = dt / (double)info.substeps;
    const double kappa =
        info.backlash ? h_sub * info.inv_eff_mass_contact * (info.stiffness * h_sub + info.damping) : 0.0;
    const int checked = FZ_STRICT_ENERGY || kappa * eps <= 1e-4;
    /* snapshots: copies of the state; the shadow steps with a copy of the
     * constants (plain data, no pointers) */
    const gs_rig_consts consts_copy = consts;
    gs_rig_state shadow = state;
    gs_rig_state batch = state;
    gs_rig_input inputs[MAX_STEPS];
    gs_rig_output outputs[MAX_STEPS];
    double energy_before = 0.0;
    /* the last step's kinematics, for the external work of a torque-driven rig */
    double w_b_before = (double)state.base_speed, w_f_before = (double)state.follower_speed;
    double theta_before = (double)state.base_angle, x_before = (double)state.follower_position;
    int k = 0;
    for (; k < MAX_STEPS && r.n >= 10; ++k) {
        gs_rig_input *in = &inputs[k];
        in->base_speed = input_value(&r, -1e3, 1e3);
        in->base_torque = input_value(&r, -1e3, 1e3);
        in->load = input_value(&r, -1e3, 1e3);
        in->ambient_temperature = input_value(&r, 1.0, 1e3);
        in->measured_temperature = input_value(&r, 1.0, 1e3);
        gs_rig_output *o = &outputs[k];
        gs_rig_step(&consts, &state, in, o);
        const gs_real *v = fz_rig_output_values(o);
        if (fz_verbose()) {
            fprintf(stderr, "step %d in: w_B %.17g tau_m %.17g load %.17g T_amb %.17g T_meas %.17g\n  out:", k,
                    (double)in->base_speed, (double)in->base_torque, (double)in->load, (double)in->ambient_temperature,
                    (double)in->measured_temperature);
            for (int i = 0; i < GS_RIG_OUTPUT_FIELDS; ++i) {
                fprintf(stderr, " %s %.9g", gs_rig_output_info[i].name, (double)v[i]);
            }
            fprintf(stderr, "\n");
        }
        gs_rig_output o2;
        gs_rig_step(&consts_copy, &shadow, in, &o2);
        FZ_CHECK(same_bits(o, &o2), "a snapshot copy stepped differently at step %d", k);
        if (!checked) {
            continue;
        }
        for (int i = 0; i < GS_RIG_OUTPUT_FIELDS; ++i) {
            FZ_CHECK(fz_finite(v[i]), "output field %d (%s) = %g at step %d (kappa %.3g)", i,
                     gs_rig_output_info[i].name, (double)v[i], k, kappa);
        }

        const double port = (double)o->port_power;
        const double loss = (double)o->loss_power;
        /* with the step-mean speed the torques are those of the mean of the
         * last and this speed: the larger of the two bounds it */
        const double w_b =
            info.ramp ? fmax(fabs((double)o->base_speed), fabs(w_b_before)) : fabs((double)o->base_speed);
        const double w_f =
            info.ramp ? fmax(fabs((double)o->follower_speed), fabs(w_f_before)) : fabs((double)o->follower_speed);
        /* magnitude of the terms whose rounding the balance carries */
        const double scale = fabs((double)o->base_port_torque) * w_b + fabs((double)o->follower_port_torque) * w_f +
                             fabs(loss) + fabs(port) +
                             fabs((double)o->contact_force) * (info.r_base * w_b + info.r_follow * w_f);
        /* With backlash the relative tooth speed is the difference of the free
         * speeds that the contact and external impulses produce in a sub-step;
         * on a light side those are much larger than the step's speeds, and
         * their rounding multiplies the contact force. */
        const double f_abs = fabs((double)o->contact_force);
        const double f_ext =
            (fabs((double)in->load) + fabs(info.load_offset) + info.load_coulomb) / info.r_follow +
            (info.torque_driven ? (fabs((double)in->base_torque) + info.base_extra) / info.r_base : 0.0);
        /* (f_abs + f_ext)^2, not f_abs*(f_abs + f_ext): the step means can
         * cancel (a locked light rack alternating between sliding and stuck
         * sub-steps has a mean force of 1e-16 N against 4.5 N per sub-step),
         * while the external push alone still makes large sub-step speeds */
        const double impulse_scale =
            info.backlash ? (f_abs + f_ext) * (f_abs + f_ext) * h_sub * info.inv_eff_mass_contact : 0.0;
        if (info.torque_driven) {
            /* The drive's work is exact: dKE + dE_contact <= W. */
            const double w_b1 = (double)o->base_speed, w_f1 = (double)o->follower_speed;
            const double theta1 = (double)o->base_angle, x1 = (double)o->follower_position;
            const double d_theta = theta1 - theta_before, d_x = x1 - x_before;
            const double push = (double)in->load + info.load_offset;
            const double motor = (double)in->base_torque;
            const double ripple = info.ripple_sum > 0.0 ? ripple_at(&info, theta_before) : 0.0;
            const double work = (motor - ripple) * d_theta + push * d_x;
            const double ke0 =
                0.5 * (info.base_inertia * w_b_before * w_b_before + info.driven_inertia * w_f_before * w_f_before);
            const double ke1 = 0.5 * (info.base_inertia * w_b1 * w_b1 + info.driven_inertia * w_f1 * w_f1);
            const double e0 = info.backlash ? energy_before : 0.0, e1 = (double)o->contact_energy;
            const double created = (ke1 - ke0) + (e1 - e0) - work;
            /* rounding: of the energies and works; of the stored angles (each
             * sub-step's addition rounds to ulp(theta)); of the ripple (float
             * cos, and the tooth phase Z*theta carries eps*|theta|*Z); of the
             * contact's absolute position like the backlash check below */
            const double n_sub = (double)info.substeps;
            const double quant = (n_sub + 1.0) * eps *
                                     (fabs(motor - ripple) * (fabs(theta_before) + fabs(theta1)) +
                                      fabs(push) * (fabs(x_before) + fabs(x1))) +
                                 4.0 * info.ripple_stiffness * eps * (fabs(theta_before) + 1.0) * fabs(d_theta);
            const double f_spring = info.backlash ? sqrt(2.0 * info.stiffness * fmax(e0, e1)) : 0.0;
            const double position =
                info.backlash ? 4.0 * f_spring * eps * (fabs((double)o->backlash_position) + info.half_gap) * n_sub
                              : 0.0;
            const double mag = ke0 + ke1 + e0 + e1 + fabs(motor * d_theta) + fabs(ripple * d_theta) + fabs(push * d_x) +
                               dt * (fabs(loss) + fabs(port) + fabs((double)o->base_port_torque) * fabs(w_b1) +
                                     fabs((double)o->follower_port_torque) * fabs(w_f1));
            /* and the sub-step impulses of the contact, whose free speeds
             * (a light side, a large motor torque on locked teeth) are far
             * larger than the step's: their rounding times the force */
            const double tol = 1024.0 * eps * (mag + impulse_scale * dt) + quant + position + 1e-300;
            FZ_CHECK(created <= tol,
                     "torque-driven: energy created %.9g J > tol %.3g J (dKE %.9g, dE %.9g, work %.9g: motor %.9g, "
                     "ripple %.9g, load %.9g) at step %d",
                     created, tol, ke1 - ke0, e1 - e0, work, motor * d_theta, -ripple * d_theta, push * d_x, k);
        }
        w_b_before = (double)o->base_speed;
        w_f_before = (double)o->follower_speed;
        theta_before = (double)o->base_angle;
        x_before = (double)o->follower_position;
        if (info.compliant) {
            /* The balance holds in every shaft sub-step, but the step's means
             * hide the sub-step magnitudes its rounding scales with (a stiff
             * shaft's sub-step torques cancel in the mean; fuzz finding): only
             * the sign of the loss, a sum of non-negative terms, is checked
             * here; tests/c checks the balance on resolved shafts. */
            if (info.passive) {
                FZ_CHECK(loss >= 0.0, "compliant shaft: loss_power %.9g < 0 at step %d", loss, k);
            }
        } else if (!info.backlash) {
            FZ_CHECK(fabs(port - loss) <= 64.0 * eps * scale + 1e-300,
                     "rigid mesh: port_power %.9g != loss_power %.9g (scale %.3g) at step %d", port, loss, scale, k);
            if (info.passive) {
                FZ_CHECK(loss >= -64.0 * eps * scale, "rigid mesh: loss_power %.9g < 0 (scale %.3g) at step %d", loss,
                         scale, k);
            }
        } else {
            /* With backlash the meshing loss acts only as a friction that never
             * reverses the follower, paired with the end speeds, for either
             * smoothing (the Simscape law's active sliver is not applied there):
             * the bound holds for every friction model. */
            const double energy = (double)o->contact_energy;
            const double created = (loss - port) * dt + (energy - energy_before);
            /* The backlash position is stored absolute: a sub-step's motion
             * below ulp(x) is lost while the ports still see it (float: x ~ b/2
             * resolves a stiff contact's penetration to a few hundred ulp). */
            const double f_spring = sqrt(2.0 * info.stiffness * fmax(energy, energy_before));
            const double quantum = 4.0 * (f_abs + f_spring) * eps *
                                       (fabs((double)o->backlash_position) + info.half_gap) * (double)info.substeps
                                   /* and the position moves by the rounding of the relative speed
                                    * r_B*w_B - r_F*w_F (locked teeth), against the spring */
                                   + 4.0 * f_spring * eps * (info.r_base * w_b + info.r_follow * w_f) * dt;
            const double tol =
                1024.0 * eps * ((scale + impulse_scale) * dt + energy + energy_before) + quantum + 1e-300;
            FZ_CHECK(created <= tol,
                     "backlash: energy created %.9g J > tol %.3g (port %.9g W, loss %.9g W, dt %g, E %.9g -> %.9g J)"
                     " at step %d",
                     created, tol, port, loss, dt, energy_before, energy, k);
            /* The balance above cannot see a negative loss that the spring
             * absorbs (port = loss + dE/dt still holds): check the loss itself,
             * with the no-pull clip and without (the pulling contact ends on its
             * root or on a passive bracket end, docs/model.md). */
            {
                /* plus the rounding of the contact solve's force
                 * (FZ_SOLVER_ROUNDING), against the closing speed */
                const double v_scale =
                    info.r_base * w_b + info.r_follow * w_f + h_sub * f_abs * info.inv_eff_mass_contact;
                const double c_sub = h_sub * info.inv_eff_mass_contact;
                const double solver = FZ_SOLVER_ROUNDING * (1.0 + kappa) / c_sub * v_scale * v_scale * dt;
                FZ_CHECK(loss * dt >= -(tol + solver),
                         "backlash: loss_power %.9g W < 0 (tol %.3g J + solver %.3g J) at step %d", loss, tol, solver,
                         k);
            }
            energy_before = energy;
        }
    }
    if (k > 0) {
        gs_rig_output run_out[MAX_STEPS];
        gs_rig_run(&consts, &batch, (size_t)k, inputs, run_out);
        FZ_CHECK(memcmp(run_out, outputs, (size_t)k * sizeof outputs[0]) == 0,
                 "gs_rig_run differs from %d gs_rig_step calls", k);
    }
    return 0;
}
