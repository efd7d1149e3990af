/* fuzz_init.c - libFuzzer target: arbitrary bytes as parameters to every init.
 *
 * Input: [head][n] then n records of 12 bytes (destination, field, element,
 * mode, 8 payload bytes) that patch fields of the default parameters (see
 * fuzz_common.h), then bytes for the step inputs.
 *   head bits 0-1: 0 gs_simple_gear_init, 1 gs_rack_pinion_init,
 *                  2 gs_rig_init_gear, 3 gs_rig_init_rack
 *   head bit 2:    pass err = NULL
 *   head bits 3-4: 3 = pass a NULL pointer argument (head bits 5-7 mod 3: the
 *                  model, the block params or the rig params; for the model,
 *                  the byte after the records picks its constants (even) or
 *                  its state (odd))
 * Properties:
 *   - no crash, no sanitizer report, whatever the bytes;
 *   - a failed init returns a negative status of the enum, fills err with that
 *     status, the parameter's name and gs_status_str(status), and leaves the
 *     model (its constants and its state) untouched;
 *   - a successful init clears err, and then 64 steps with finite bounded
 *     inputs (|speed| <= 1e3 rad/s, |torque|, |force|, |load| <= 1e3, heat
 *     flow <= 1e3 W, temperatures in [1, 1e3] K, dt in [1e-6, 0.1] s for the
 *     blocks) give finite outputs. This last check applies to parameters in
 *     the envelope of docs/hardening.md (*_in_envelope below) unless the target is
 *     built with -DFZ_STRICT, which applies it to every accepted parameter set
 *     and documents what lies outside the envelope. */
#include "fuzz_common.h"

#define STEPS 64

/* The envelope (docs/hardening.md, "Parameter envelope"): every real parameter
 * that scales the dynamics lies within magnitudes the fuzzer checks. */
static int in_mag(gs_real v, double lo, double hi)
{
    const double a = fabs((double)v);
    return a == 0.0 || (a >= lo && a <= hi);
}

static int backlash_in_envelope(const gs_backlash_params *b, int gear)
{
    if (!b->enabled) {
        return 1;
    }
    return in_mag(b->linear_backlash_m, 1e-9, 1.0) && (!gear || in_mag(b->base_radius_m, 1e-4, 10.0)) &&
           in_mag(b->transition_region_m, 1e-12, 1.0) && in_mag(b->stiffness_N_m, 1.0, 1e10) &&
           in_mag(b->damping_N_s_m, 1e-6, 1e7) && in_mag(b->initial_position_m, 1e-12, 1.0) &&
           in_mag(b->contact_speed_threshold_m_s, 1e-9, 1e3) && in_mag(b->contact_release_force_N, 1e-9, 1e6);
}

/* The first n of x (n a fuzzed count: at most cap). */
static int table_in_envelope(const gs_real *x, int n, int cap, double lo, double hi)
{
    for (int i = 0; i < n && i < cap; ++i) {
        if (!in_mag(x[i], lo, hi)) {
            return 0;
        }
    }
    return 1;
}

/* The efficiency matrix rows and columns in use (the 2-D table reads its
 * efficiency at any of them; checking only its first row missed a subnormal
 * entry whose reciprocal overflowed, fuzz finding). */
static int matrix_in_envelope(const gs_simple_gear_params *p)
{
    for (int i = 0; i < p->temperature_count && i < GS_TABLE_MAX; ++i) {
        if (!table_in_envelope(p->efficiency_matrix[i], p->load_count, GS_TABLE_MAX, 1e-3, 1.0)) {
            return 0;
        }
    }
    return 1;
}

static int gear_in_envelope(const gs_simple_gear_params *p)
{
    return in_mag(p->teeth_ratio, 1e-3, 1e3) && in_mag(p->power_threshold_W, 1e-9, 1e6) &&
           in_mag(p->idle_torque_Nm, 1e-9, 1e4) && in_mag(p->nominal_output_torque_Nm, 1e-6, 1e6) &&
           in_mag(p->efficiency_const, 1e-3, 1.0) && in_mag(p->efficiency_nominal, 1e-3, 1.0) &&
           in_mag(p->speed_threshold_rad_s, 1e-9, 1e6) &&
           table_in_envelope(p->efficiency_vector, p->temperature_count, GS_TABLE_MAX, 1e-3, 1.0) &&
           table_in_envelope(p->load_vector_Nm, p->load_count, GS_TABLE_MAX, 1e-9, 1e6) && matrix_in_envelope(p) &&
           in_mag(p->viscous_coefficients[0], 1e-9, 1e3) && in_mag(p->viscous_coefficients[1], 1e-9, 1e3) &&
           in_mag(p->thermal_mass_J_K, 1e-6, 1e9) && in_mag(p->initial_temperature_K, 1e-3, 1e4) &&
           backlash_in_envelope(&p->backlash, 1);
}

static int rack_in_envelope(const gs_rack_pinion_params *p)
{
    const int radius_ok = p->parameterization == GS_PARAMETERIZE_TOOTH_PARAMETERS
                              ? in_mag(p->teeth_count, 1.0, 1e3) && in_mag(p->spacing_m, 1e-4, 1.0)
                              : in_mag(p->pinion_radius_m, 1e-4, 10.0);
    return radius_ok && in_mag(p->power_threshold_W, 1e-9, 1e6) && in_mag(p->efficiency_const, 1e-3, 1.0) &&
           table_in_envelope(p->efficiency_vector, p->temperature_count, GS_TABLE_MAX, 1e-3, 1.0) &&
           in_mag(p->pinion_viscous_coefficient, 1e-9, 1e3) && in_mag(p->rack_viscous_coefficient, 1e-9, 1e4) &&
           in_mag(p->thermal_mass_J_K, 1e-6, 1e9) && in_mag(p->initial_temperature_K, 1e-3, 1e4) &&
           backlash_in_envelope(&p->backlash, 0);
}

static int ripple_in_envelope(const gs_rig_params *p)
{
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        if (!in_mag(p->ripple_revolution_amplitude_Nm[i], 1e-9, 1e4) ||
            !in_mag(p->ripple_mesh_amplitude_Nm[i], 1e-9, 1e4) ||
            !in_mag(p->ripple_revolution_phase_rad[i], 0.0, 1e6) || !in_mag(p->ripple_mesh_phase_rad[i], 0.0, 1e6)) {
            return 0;
        }
    }
    return p->ripple_mesh_teeth <= 1000;
}

static int rig_in_envelope(const gs_rig_params *p)
{
    return in_mag(p->dt_s, 1e-6, 0.1) && in_mag(p->base_inertia_kg_m2, 1e-7, 1e3) &&
           in_mag(p->initial_base_speed_rad_s, 1e-9, 1e3) && in_mag(p->driven_inertia, 1e-7, 1e4) &&
           in_mag(p->load_coulomb_friction, 1e-9, 1e4) && in_mag(p->load_coulomb_speed_threshold, 1e-9, 1e3) &&
           in_mag(p->load_offset, 1e-9, 1e4) && in_mag(p->thermal_resistance_K_W, 1e-6, 1e6) &&
           in_mag(p->accel_filter_time_constant_s, 1e-9, 1e3) && in_mag(p->load_breakaway_friction, 1e-9, 1e4) &&
           in_mag(p->load_stribeck_speed, 1e-9, 1e3) && in_mag(p->compliance_stiffness_Nm_rad, 1e-6, 1e9) &&
           in_mag(p->compliance_damping_Nm_s_rad, 1e-9, 1e6) && ripple_in_envelope(p);
}

static void check_error(gs_status st, const gs_error *err, int pattern_ok)
{
    if (st == GS_OK) {
        if (err != NULL) {
            FZ_CHECK(err->status == GS_OK && err->parameter != NULL && err->parameter[0] == '\0',
                     "success must clear err (status %d)", (int)err->status);
        }
        return;
    }
    FZ_CHECK(st <= GS_E_NULL && st >= GS_STATUS_MIN, "status %d is not one of gs_status", (int)st);
    FZ_CHECK(pattern_ok, "failed init (status %d) modified the model", (int)st);
    if (err != NULL) {
        FZ_CHECK(err->status == st, "err->status %d != returned %d", (int)err->status, (int)st);
        FZ_CHECK(err->parameter != NULL && err->parameter[0] != '\0', "no parameter name for status %d", (int)st);
        FZ_CHECK(err->message == gs_status_str(st), "err->message is not gs_status_str(%d)", (int)st);
    }
}

static int untouched(const void *obj, size_t n)
{
    const unsigned char *p = (const unsigned char *)obj;
    for (size_t i = 0; i < n; ++i) {
        if (p[i] != 0xA5U) {
            return 0;
        }
    }
    return 1;
}

static gs_real in_range(fz_reader *r, double lo, double hi)
{
    return (gs_real)fz_range(r, lo, hi);
}

#define CHECK_FINITE(v, what) FZ_CHECK(fz_finite(v), "%s = %g at step %d", what, (double)(v), k)

static void step_gear(const gs_simple_gear_consts *consts, gs_block_state *state, fz_reader *r)
{
    const gs_real dt = (gs_real)fz_log_range(r, 1e-6, 0.1);
    for (int k = 0; k < STEPS; ++k) {
        gs_gear_ports_in in;
        in.base_speed_rad_s = in_range(r, -1e3, 1e3);
        in.follower_speed_rad_s = in_range(r, -1e3, 1e3);
        in.follower_torque_Nm = in_range(r, -1e3, 1e3);
        in.heat_flow_W = in_range(r, -1e3, 1e3);
        in.temperature_K = in_range(r, 1.0, 1e3);
        in.use_temperature_input = fz_u8(r) & 1;
        gs_gear_ports_out o;
        gs_simple_gear_step(consts, state, dt, &in, &o);
        CHECK_FINITE(o.base_torque_Nm, "base_torque_Nm");
        CHECK_FINITE(o.follower_torque_Nm, "follower_torque_Nm");
        CHECK_FINITE(o.follower_speed_rad_s, "follower_speed_rad_s");
        CHECK_FINITE(o.mesh_loss_torque_Nm, "mesh_loss_torque_Nm");
        CHECK_FINITE(o.mesh_loss_power_W, "mesh_loss_power_W");
        CHECK_FINITE(o.loss_power_W, "loss_power_W");
        CHECK_FINITE(o.temperature_K, "temperature_K");
        CHECK_FINITE(o.backlash_position_m, "backlash_position_m");
        CHECK_FINITE(o.contact_force_N, "contact_force_N");
    }
}

static void step_rack(const gs_rack_pinion_consts *consts, gs_block_state *state, fz_reader *r)
{
    const gs_real dt = (gs_real)fz_log_range(r, 1e-6, 0.1);
    for (int k = 0; k < STEPS; ++k) {
        gs_rack_ports_in in;
        in.pinion_speed_rad_s = in_range(r, -1e3, 1e3);
        in.rack_velocity_m_s = in_range(r, -1e3, 1e3);
        in.rack_force_N = in_range(r, -1e3, 1e3);
        in.heat_flow_W = in_range(r, -1e3, 1e3);
        in.temperature_K = in_range(r, 1.0, 1e3);
        in.use_temperature_input = fz_u8(r) & 1;
        gs_rack_ports_out o;
        gs_rack_pinion_step(consts, state, dt, &in, &o);
        CHECK_FINITE(o.pinion_torque_Nm, "pinion_torque_Nm");
        CHECK_FINITE(o.rack_force_N, "rack_force_N");
        CHECK_FINITE(o.rack_velocity_m_s, "rack_velocity_m_s");
        CHECK_FINITE(o.mesh_loss_force_N, "mesh_loss_force_N");
        CHECK_FINITE(o.mesh_loss_power_W, "mesh_loss_power_W");
        CHECK_FINITE(o.loss_power_W, "loss_power_W");
        CHECK_FINITE(o.temperature_K, "temperature_K");
        CHECK_FINITE(o.backlash_position_m, "backlash_position_m");
        CHECK_FINITE(o.contact_force_N, "contact_force_N");
    }
}

static void step_rig(const gs_rig_consts *consts, gs_rig_state *state, fz_reader *r)
{
    for (int k = 0; k < STEPS; ++k) {
        gs_rig_input in;
        in.base_speed = in_range(r, -1e3, 1e3);
        in.base_torque = in_range(r, -1e3, 1e3);
        in.load = in_range(r, -1e3, 1e3);
        in.ambient_temperature = in_range(r, 1.0, 1e3);
        in.measured_temperature = in_range(r, 1.0, 1e3);
        gs_rig_output o;
        gs_rig_step(consts, state, &in, &o);
        const gs_real *v = fz_rig_output_values(&o);
        for (int i = 0; i < GS_RIG_OUTPUT_FIELDS; ++i) {
            FZ_CHECK(fz_finite(v[i]), "rig output field %d (%s) = %g at step %d", i, gs_rig_output_info[i].name,
                     (double)v[i], k);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader r = {data, size};
    const uint8_t head = fz_u8(&r);
    const unsigned target = head & 3U;
    const int use_err = !(head & 4U);
    const int null_arg = ((head >> 3) & 3U) == 3U ? 1 + (int)((head >> 5) % 3U) : 0;
    const unsigned records = fz_u8(&r) % 48U;

    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gs_rack_pinion_params kp = gs_rack_pinion_params_default();
    gs_rig_params rp = gs_rig_params_default();
    for (unsigned i = 0; i < records; ++i) {
        const uint8_t dest = fz_u8(&r);
        if (dest & 1U) {
            fz_patch(&r, &rp, fz_rig_fields, FZ_COUNT(fz_rig_fields));
        } else if (target == 0 || target == 2) {
            fz_patch(&r, &gp, fz_gear_fields, FZ_COUNT(fz_gear_fields));
        } else {
            fz_patch(&r, &kp, fz_rack_fields, FZ_COUNT(fz_rack_fields));
        }
    }

    /* which model pointer is NULL when null_arg == 1: the constants or the state */
    const int null_state = null_arg == 1 && (fz_u8(&r) & 1U) != 0;
    const int null_consts = null_arg == 1 && !null_state;

    gs_error err_store;
    memset(&err_store, 0x5A, sizeof err_store);
    gs_error *err = use_err ? &err_store : NULL;
    gs_status st;
    int envelope;
#ifdef FZ_STRICT
    const int strict = 1;
#else
    const int strict = 0;
#endif
    switch (target) {
    case 0: {
        gs_simple_gear_consts consts;
        gs_block_state state;
        memset(&consts, 0xA5, sizeof consts);
        memset(&state, 0xA5, sizeof state);
        st = gs_simple_gear_init(null_consts ? NULL : &consts, null_state ? NULL : &state, null_arg >= 2 ? NULL : &gp,
                                 err);
        check_error(st, err, untouched(&consts, sizeof consts) && untouched(&state, sizeof state));
        FZ_CHECK(!null_arg || st == GS_E_NULL, "NULL argument gave status %d", (int)st);
        envelope = gear_in_envelope(&gp);
        if (st == GS_OK && (strict || envelope)) {
            step_gear(&consts, &state, &r);
        }
        break;
    }
    case 1: {
        gs_rack_pinion_consts consts;
        gs_block_state state;
        memset(&consts, 0xA5, sizeof consts);
        memset(&state, 0xA5, sizeof state);
        st = gs_rack_pinion_init(null_consts ? NULL : &consts, null_state ? NULL : &state, null_arg >= 2 ? NULL : &kp,
                                 err);
        check_error(st, err, untouched(&consts, sizeof consts) && untouched(&state, sizeof state));
        FZ_CHECK(!null_arg || st == GS_E_NULL, "NULL argument gave status %d", (int)st);
        envelope = rack_in_envelope(&kp);
        if (st == GS_OK && (strict || envelope)) {
            step_rack(&consts, &state, &r);
        }
        break;
    }
    default: {
        gs_rig_consts consts;
        gs_rig_state state;
        memset(&consts, 0xA5, sizeof consts);
        memset(&state, 0xA5, sizeof state);
        gs_rig_consts *consts_arg = null_consts ? NULL : &consts;
        gs_rig_state *state_arg = null_state ? NULL : &state;
        const gs_rig_params *rp_arg = null_arg == 3 ? NULL : &rp;
        if (target == 2) {
            st = gs_rig_init_gear(consts_arg, state_arg, null_arg == 2 ? NULL : &gp, rp_arg, err);
            envelope = gear_in_envelope(&gp) && rig_in_envelope(&rp);
        } else {
            st = gs_rig_init_rack(consts_arg, state_arg, null_arg == 2 ? NULL : &kp, rp_arg, err);
            envelope = rack_in_envelope(&kp) && rig_in_envelope(&rp);
        }
        check_error(st, err, untouched(&consts, sizeof consts) && untouched(&state, sizeof state));
        FZ_CHECK(!null_arg || st == GS_E_NULL, "NULL argument gave status %d", (int)st);
        if (st == GS_OK && (strict || envelope)) {
            step_rig(&consts, &state, &r);
        }
        break;
    }
    }
    return 0;
}
