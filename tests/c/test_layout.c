/*
 * test_layout.c - the rig's data layout (rig.h, gearsim/fields.h):
 *  - a snapshot is a copy of the state struct alone: restore it and the rig
 *    repeats its outputs bit for bit;
 *  - one constants block shared by two states gives the outputs of two rigs
 *    initialised apart;
 *  - the state size: sizeof(gs_rig_state) <= 128 B in the float build;
 *  - the field tables gs_rig_input_info / gs_rig_output_info /
 *    gs_rig_state_info: counts, names, offsets, units, and the outputs' names
 *    in their (hash-relevant) order;
 *  - re-tuning: a running state stepped with the constants of other
 *    parameters continues from its speeds, under the new parameters;
 *  - the constants are const-qualifiable (compile-time) and copyable.
 */
#include "test_common.h"

#define N_WARM   500
#define N_RECORD 300
#define N_SHARED 2000

static gs_rig_input inputs_a[N_SHARED];
static gs_rig_input inputs_b[N_SHARED];
static gs_rig_output out_a[N_SHARED];
static gs_rig_output out_b[N_SHARED];
static gs_rig_output out_c[N_SHARED];
static gs_rig_output out_d[N_SHARED];

/* A backlash gear rig with every state variable in use: temperature-dependent
 * efficiency with the thermal state and a heat path, smooth backlash with the
 * contact lock, viscous losses, acceleration filter; speed-driven. */
static void backlash_gear(gs_simple_gear_params *gp, gs_rig_params *rp)
{
    *gp = gs_simple_gear_params_default();
    gp->teeth_ratio = R(2.5);
    gp->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    gp->power_threshold_W = R(0.05);
    gp->viscous_coefficients[0] = R(0.002);
    gp->viscous_coefficients[1] = R(0.004);
    gp->thermal_mass_J_K = R(3.0);
    gp->initial_temperature_K = R(295.0);
    gp->backlash.enabled = 1;
    gp->backlash.linear_backlash_m = R(8e-4);
    gp->backlash.base_radius_m = R(0.04);
    gp->backlash.transition_region_m = R(5e-5);
    gp->backlash.stiffness_N_m = R(5e6);
    gp->backlash.damping_N_s_m = R(400.0);
    gp->backlash.lock_enabled = 1;
    *rp = gs_rig_params_default();
    rp->dt_s = R(5e-4);
    rp->base_inertia_kg_m2 = R(0.003);
    rp->driven_inertia = R(0.02);
    rp->load_coulomb_friction = R(0.05);
    rp->load_coulomb_speed_threshold = R(0.01);
    rp->heat_path = 1;
    rp->thermal_resistance_K_W = R(4.0);
    rp->accel_filter_time_constant_s = R(0.002);
}

/* A backlash rack rig, torque-driven. */
static void backlash_rack(gs_rack_pinion_params *pp, gs_rig_params *rp)
{
    *pp = gs_rack_pinion_params_default();
    pp->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    pp->efficiency_const = R(0.85);
    pp->pinion_radius_m = R(0.03);
    pp->rack_viscous_coefficient = R(1.5);
    pp->backlash = gs_simple_gear_params_default().backlash;
    pp->backlash.enabled = 1;
    pp->backlash.hard_stop_model = GS_HARD_STOP_FULL_DAMPED;
    pp->backlash.linear_backlash_m = R(5e-4);
    pp->backlash.stiffness_N_m = R(2e6);
    pp->backlash.damping_N_s_m = R(800.0);
    *rp = gs_rig_params_default();
    rp->base_drive = GS_BASE_TORQUE_DRIVEN;
    rp->base_inertia_kg_m2 = R(2e-3);
    rp->driven_inertia = R(1.2);
    rp->load_coulomb_friction = R(2.0);
    rp->contact_substeps = 8;
}

static void init_backlash(test_rig *rig, int rack)
{
    gs_rig_params rp;
    if (rack) {
        gs_rack_pinion_params pp;
        backlash_rack(&pp, &rp);
        INIT_RACK_RIG(rig, &pp, &rp);
    } else {
        gs_simple_gear_params gp;
        backlash_gear(&gp, &rp);
        INIT_GEAR_RIG(rig, &gp, &rp);
    }
}

/* Reversing drive with PRNG noise and a changing load: the teeth cross the
 * gap and hit both flanks. Different seeds give different scripts. */
static void script(gs_rig_input *in, int n, uint64_t seed, int torque_driven)
{
    test_rng rng = rng_seed(seed);
    int k;
    for (k = 0; k < n; ++k) {
        const double t = k * 5e-4;
        double base = 8.0 * sin(2.0 * TEST_PI * 3.0 * t) + rng_range(&rng, -0.05, 0.05);
        double load = 0.6 * sin(2.0 * TEST_PI * 0.7 * t) + (k > n / 2 ? 0.8 : 0.0);
        if (torque_driven) {
            base = 0.3 * sin(2.0 * TEST_PI * 2.1 * t) + rng_range(&rng, -0.02, 0.02);
            load *= 5.0;
        }
        in[k] = rig_input_blank();
        in[k].base_speed = R(base);
        in[k].base_torque = R(base);
        in[k].load = R(load);
        in[k].ambient_temperature = R(296.0 + 2.0 * sin(t));
    }
}

/* (a) Snapshot = state copy: 500 steps, copy the state, 300 steps recorded;
 * restore the copy, the same 300 steps again: bit-identical outputs. The
 * constants are not copied (they never change). */
static void test_snapshot_is_state_copy(void **state)
{
    test_rig rig;
    gs_rig_state snap;
    int k, contacts = 0;
    (void)state;
    script(inputs_a, N_WARM + N_RECORD, 11u, 0);
    init_backlash(&rig, 0);
    gs_rig_run(&rig.c, &rig.s, N_WARM, inputs_a, out_a);
    snap = rig.s;
    gs_rig_run(&rig.c, &rig.s, N_RECORD, inputs_a + N_WARM, out_a);
    /* perturb the running state, then restore the snapshot */
    gs_rig_run(&rig.c, &rig.s, 77, inputs_a, out_b);
    rig.s = snap;
    gs_rig_run(&rig.c, &rig.s, N_RECORD, inputs_a + N_WARM, out_b);
    assert_outputs_identical(out_a, out_b, N_RECORD, "snapshot/restore");
    /* the recorded stretch is not trivial: the teeth touch in it */
    for (k = 0; k < N_RECORD; ++k) {
        assert_true(rig_output_finite(&out_a[k]));
        if (!is_zero((double)out_a[k].contact_force)) ++contacts;
    }
    assert_true(contacts > 0);
}

/* (b) One constants block, two states (the second set by gs_rig_reset, as a
 * firmware with its constants in flash would), stepped interleaved with
 * different inputs == two rigs initialised apart. */
static void test_shared_consts(void **state)
{
    int rack, k;
    (void)state;
    for (rack = 0; rack < 2; ++rack) {
        test_rig shared, r1, r2;
        gs_rig_state s2;
        script(inputs_a, N_SHARED, 21u, rack);
        script(inputs_b, N_SHARED, 22u, rack);
        init_backlash(&shared, rack);
        gs_rig_reset(&shared.c, &s2);
        init_backlash(&r1, rack);
        init_backlash(&r2, rack);
        for (k = 0; k < N_SHARED; ++k) {
            gs_rig_step(&shared.c, &shared.s, &inputs_a[k], &out_a[k]);
            gs_rig_step(&shared.c, &s2, &inputs_b[k], &out_b[k]);
        }
        for (k = 0; k < N_SHARED; ++k) {
            gs_rig_step(&r1.c, &r1.s, &inputs_a[k], &out_c[k]);
            gs_rig_step(&r2.c, &r2.s, &inputs_b[k], &out_d[k]);
        }
        assert_outputs_identical(out_a, out_c, N_SHARED,
                                 rack ? "rack, shared consts, state 1" : "gear, shared consts, state 1");
        assert_outputs_identical(out_b, out_d, N_SHARED,
                                 rack ? "rack, shared consts, state 2" : "gear, shared consts, state 2");
        /* the two states did run apart */
        assert_true(memcmp(&out_a[N_SHARED - 1], &out_b[N_SHARED - 1], sizeof out_a[0]) != 0);
    }
}

/* (c) The published state size; the target is <= 128 B in float. */
static void test_state_size(void **state)
{
#ifdef GS_SINGLE_PRECISION
    const char *precision = "float";
#else
    const char *precision = "double";
#endif
    (void)state;
    print_message("sizeof(gs_rig_state) = %lu B, sizeof(gs_block_state) = %lu B, "
                  "sizeof(gs_rig_consts) = %lu B (%s)\n",
                  (unsigned long)sizeof(gs_rig_state), (unsigned long)sizeof(gs_block_state),
                  (unsigned long)sizeof(gs_rig_consts), precision);
#ifdef GS_SINGLE_PRECISION
    assert_true(sizeof(gs_rig_state) <= 128);
#endif
}

/* (d) The field tables. Expected entries are expanded here from the same
 * lists of gearsim/fields.h, with the members' offsets from offsetof. */
typedef struct {
    const char *name;
    size_t offset;
    int is_integer;
} expected_field;

/* 1 for a member declared int, 0 for gs_real (as the lists spell the type) */
#define EXP_IS_INT_(type)                 ((int)(sizeof(#type) == sizeof("int")))
#define EXP_IN_(type, name, gu, ru, doc)  {#name, offsetof(gs_rig_input, name), EXP_IS_INT_(type)},
#define EXP_OUT_(type, name, gu, ru, doc) {#name, offsetof(gs_rig_output, name), EXP_IS_INT_(type)},
#define EXP_BLOCK_(type, name, gu, ru, doc) \
    {#name, offsetof(gs_rig_state, block) + offsetof(gs_block_state, name), EXP_IS_INT_(type)},
#define EXP_STATE_(type, name, gu, ru, doc) {#name, offsetof(gs_rig_state, name), EXP_IS_INT_(type)},

static int nonempty(const char *s)
{
    return s != NULL && s[0] != '\0';
}

static void check_table(const char *what, const gs_field_info *info, int count, const expected_field *want,
                        int want_count, size_t struct_size)
{
    int i, j;
    assert_int_equal(count, want_count);
    for (i = 0; i < count; ++i) {
        const gs_field_info *f = &info[i];
        const size_t member_size = f->is_integer ? sizeof(int) : sizeof(gs_real);
        if (!nonempty(f->name) || !nonempty(f->gear_unit) || !nonempty(f->rack_unit) || !nonempty(f->doc))
            fail_msg("%s[%d]: empty name, unit or doc ('%s', '%s', '%s')", what, i, f->name ? f->name : "(null)",
                     f->gear_unit ? f->gear_unit : "(null)", f->rack_unit ? f->rack_unit : "(null)");
        for (j = 0; j < i; ++j)
            if (strcmp(info[j].name, f->name) == 0) fail_msg("%s: name '%s' at %d and %d", what, f->name, j, i);
        if (i > 0 && !(f->offset > info[i - 1].offset))
            fail_msg("%s[%d] '%s': offset %lu not above the previous %lu", what, i, f->name, (unsigned long)f->offset,
                     (unsigned long)info[i - 1].offset);
        if (!(f->offset + member_size <= struct_size))
            fail_msg("%s[%d] '%s': offset %lu + %lu outside the struct (%lu B)", what, i, f->name,
                     (unsigned long)f->offset, (unsigned long)member_size, (unsigned long)struct_size);
        /* the entry describes the member of that name */
        if (strcmp(f->name, want[i].name) != 0 || f->offset != want[i].offset || f->is_integer != want[i].is_integer)
            fail_msg("%s[%d]: '%s' offset %lu int %d, the header gives '%s' offset %lu int %d", what, i, f->name,
                     (unsigned long)f->offset, f->is_integer, want[i].name, (unsigned long)want[i].offset,
                     want[i].is_integer);
    }
}

static void test_field_tables(void **state)
{
    static const expected_field want_in[] = {GS_RIG_INPUT_LIST(EXP_IN_)};
    static const expected_field want_out[] = {GS_RIG_OUTPUT_LIST(EXP_OUT_)};
    static const expected_field want_state[] = {GS_BLOCK_STATE_LIST(EXP_BLOCK_) GS_RIG_STATE_LIST(EXP_STATE_)};
    /* the outputs in the order of the golden hashes (test_determinism.c) */
    static const char *const output_names[] = {
        "base_torque",      "base_speed",           "base_angle",        "follower_speed", "follower_position",
        "base_port_torque", "follower_port_torque", "mesh_loss_power",   "loss_power",     "port_power",
        "contact_energy",   "temperature",          "backlash_position", "contact_force",  "follower_acceleration"};
    const int n_names = (int)(sizeof output_names / sizeof output_names[0]);
    int i;
    (void)state;
    check_table("gs_rig_input_info", gs_rig_input_info, GS_RIG_INPUT_FIELDS, want_in,
                (int)(sizeof want_in / sizeof want_in[0]), sizeof(gs_rig_input));
    check_table("gs_rig_output_info", gs_rig_output_info, GS_RIG_OUTPUT_FIELDS, want_out,
                (int)(sizeof want_out / sizeof want_out[0]), sizeof(gs_rig_output));
    check_table("gs_rig_state_info", gs_rig_state_info, GS_RIG_STATE_FIELDS, want_state,
                (int)(sizeof want_state / sizeof want_state[0]), sizeof(gs_rig_state));
    /* inputs and outputs are arrays of reals (rig.h) */
    assert_int_equal(sizeof(gs_rig_input), GS_RIG_INPUT_FIELDS * sizeof(gs_real));
    assert_int_equal(sizeof(gs_rig_output), GS_RIG_OUTPUT_FIELDS * sizeof(gs_real));
    assert_int_equal(GS_RIG_OUTPUT_FIELDS, n_names);
    for (i = 0; i < n_names; ++i) {
        if (strcmp(gs_rig_output_info[i].name, output_names[i]) != 0)
            fail_msg("gs_rig_output_info[%d] is '%s', expected '%s'", i, gs_rig_output_info[i].name, output_names[i]);
        assert_int_equal(gs_rig_output_info[i].offset, (size_t)i * sizeof(gs_real));
    }
}

/* (e) Re-tuning: a torque-driven rigid gear rig accelerates under consts A
 * (constant efficiency 0.95); a second consts B is initialised from other
 * parameters (efficiency 0.8, all else equal) into a scratch state, and the
 * running state is then stepped with B. The speeds continue from where A left
 * them (a fresh rig from B would start at rest), and the acceleration is B's:
 * T/(J_B + J_F/(eta_B*g^2)) (physics as in test_kinematics.c). */
static void retune_params(double eta, gs_simple_gear_params *gp, gs_rig_params *rp)
{
    *gp = gs_simple_gear_params_default();
    gp->teeth_ratio = R(2.0);
    gp->output_shaft_rotates = GS_ROTATES_OPPOSITE;
    gp->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
    gp->efficiency_const = R(eta);
    gp->power_threshold_W = R(1e-6);
    *rp = gs_rig_params_default();
    rp->base_drive = GS_BASE_TORQUE_DRIVEN;
    rp->base_inertia_kg_m2 = R(0.01);
    rp->driven_inertia = R(0.05);
    rp->dt_s = R(1e-3);
}

static void test_retune_continues(void **state)
{
    const double T = 0.5, JB = 0.01, JF = 0.05, g = 2.0, eta_a = 0.95, eta_b = 0.8;
    const double alpha_a = T / (JB + JF / (eta_a * g * g));
    const double alpha_b = T / (JB + JF / (eta_b * g * g));
#ifdef GS_SINGLE_PRECISION
    const double rtol = 5e-3;
#else
    const double rtol = 1e-6;
#endif
    gs_simple_gear_params gp;
    gs_rig_params rp;
    test_rig rig;
    gs_rig_consts consts_b;
    gs_rig_state scratch;
    gs_rig_output out, last;
    const gs_rig_input in = rig_torque_input(T, 0.0);
    double dt, w_prev;
    int k;
    (void)state;
    retune_params(eta_a, &gp, &rp);
    INIT_GEAR_RIG(&rig, &gp, &rp);
    dt = (double)rp.dt_s;
    memset(&last, 0, sizeof last);
    for (k = 0; k < 400; ++k) {
        gs_rig_step(&rig.c, &rig.s, &in, &last);
    }
    /* the state carries the speeds the outputs reported */
    ASSERT_NEAR(rig.s.base_speed, last.base_speed, 0.0, 0.0);
    ASSERT_NEAR(rig.s.follower_speed, last.follower_speed, 0.0, 0.0);
    assert_true((double)last.base_speed > 100.0 * dt * alpha_a); /* well away from rest */
    /* re-tune: constants of other parameters, the running state */
    retune_params(eta_b, &gp, &rp);
    INIT_OK(gs_rig_init_gear, &consts_b, &scratch, &gp, &rp);
    gs_rig_step(&consts_b, &rig.s, &in, &out);
    assert_true(rig_output_finite(&out));
    /* continues from A's speeds: one step of acceleration at most */
    ASSERT_LE(fabs((double)out.base_speed - (double)last.base_speed), 2.0 * dt * alpha_a, 0.0);
    assert_true((double)out.base_speed > (double)last.base_speed);
    ASSERT_NEAR(out.follower_speed, -(double)out.base_speed / g, TOL_REL, 1e-12);
    /* the angle advances by about one step of the continued speed */
    ASSERT_NEAR((double)out.base_angle - (double)last.base_angle, dt * (double)out.base_speed, 0.0,
                dt * fabs((double)out.base_speed - (double)last.base_speed) +
                    4.0 * GS_EPS * fabs((double)out.base_angle));
    /* and runs under B's parameters */
    w_prev = (double)out.base_speed;
    for (k = 1; k <= 10; ++k) {
        gs_rig_step(&consts_b, &rig.s, &in, &out);
        if (k >= 3) ASSERT_NEAR(((double)out.base_speed - w_prev) / dt, alpha_b, rtol, 0.0);
        w_prev = (double)out.base_speed;
    }
    assert_true(fabs(alpha_a - alpha_b) > 0.05 * alpha_b); /* the check bites */
}

/* (f) The constants are const-qualifiable: every call that reads them takes
 * a const pointer, so stepping through one compiles; a const copy of an
 * initialised block steps like the original (an image kept in flash). */
static void test_consts_const(void **state)
{
    int k;
    test_rig rig;
    gs_rig_state s2;
    gs_rig_info info;
    (void)state;
    script(inputs_a, N_WARM + N_RECORD, 31u, 0);
    init_backlash(&rig, 0);
    {
        const gs_rig_consts *cc = &rig.c;
        const gs_rig_consts image = rig.c;
        gs_rig_reset(&image, &s2);
        gs_rig_get_info(cc, &info);
        assert_true(info.contact_substeps >= 1);
        gs_rig_run(cc, &rig.s, 100, inputs_a, out_a);
        for (k = 0; k < 100; ++k)
            gs_rig_step(cc, &rig.s, &inputs_a[100 + k], &out_a[100 + k]);
        gs_rig_run(&image, &s2, 200, inputs_a, out_b);
        assert_outputs_identical(out_a, out_b, 200, "const consts, const copy");
    }
    {
        /* the blocks' constants likewise */
        test_gear gear;
        test_rack rack;
        gs_simple_gear_params gp = gs_simple_gear_params_default();
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        gs_gear_ports_in gin;
        gs_gear_ports_out gout;
        gs_rack_ports_in rin;
        gs_rack_ports_out rout;
        const gs_simple_gear_consts *gc = &gear.c;
        const gs_rack_pinion_consts *rc = &rack.c;
        INIT_GEAR(&gear, &gp);
        INIT_RACK(&rack, &pp);
        memset(&gin, 0, sizeof gin);
        memset(&rin, 0, sizeof rin);
        gin.base_speed_rad_s = R(3.0);
        rin.pinion_speed_rad_s = R(3.0);
        gs_simple_gear_reset(gc, &gear.s);
        gs_simple_gear_step(gc, &gear.s, R(1e-3), &gin, &gout);
        gs_rack_pinion_reset(rc, &rack.s);
        gs_rack_pinion_step(rc, &rack.s, R(1e-3), &rin, &rout);
        assert_true(isfinite((double)gout.follower_speed_rad_s));
        assert_true(isfinite((double)rout.rack_velocity_m_s));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_snapshot_is_state_copy),
        cmocka_unit_test(test_shared_consts),
        cmocka_unit_test(test_state_size),
        cmocka_unit_test(test_field_tables),
        cmocka_unit_test(test_retune_continues),
        cmocka_unit_test(test_consts_const),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
