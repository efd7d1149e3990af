/*
 * test_validation.c - parameter validation (docs/physics.md section 9, rig.h,
 * types.h): every validity rule returns its status and names the parameter
 * (program names of physics.md section 9; rig names of rig.h), NaN and
 * infinity give GS_E_NOT_FINITE, parameters of inactive options are not
 * validated, a failed init leaves the object unchanged, gs_status_str never
 * returns NULL, and the documented defaults.
 */
#include "test_common.h"

#define BAD_ENUM(type, v) ((type)(v))

/* ---------------------------------------------------------------- gear */
typedef void (*gear_mut)(gs_simple_gear_params *p);

typedef struct {
    const char *label;
    gear_mut mut;
    gs_status status;
    const char *param;     /* expected err.parameter ("" for GS_OK) */
    const char *alt_param; /* an equally valid name, or NULL */
    gs_status alt_status;  /* an equally valid status, or GS_OK */
} gear_case;

static void use_constant(gs_simple_gear_params *p)
{
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}
static void use_load(gs_simple_gear_params *p)
{
    p->friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
}
static void use_temp(gs_simple_gear_params *p)
{
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
}
static void use_2d(gs_simple_gear_params *p)
{
    int i, j;
    p->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    p->temperature_count = 3;
    p->temperature_vector_K[0] = R(280.0);
    p->temperature_vector_K[1] = R(300.0);
    p->temperature_vector_K[2] = R(320.0);
    p->load_count = 3;
    p->load_vector_Nm[0] = R(0.0);
    p->load_vector_Nm[1] = R(50.0);
    p->load_vector_Nm[2] = R(100.0);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            p->efficiency_matrix[i][j] = R(0.9 - 0.02 * i + 0.01 * j);
}
static void use_backlash(gs_simple_gear_params *p)
{
    p->backlash.enabled = 1;
    p->backlash.hard_stop_model = GS_HARD_STOP_SMOOTH;
    p->backlash.linear_backlash_m = R(1e-3);
    p->backlash.base_radius_m = R(0.1);
    p->backlash.transition_region_m = R(1e-4);
    p->backlash.stiffness_N_m = R(1e6);
    p->backlash.damping_N_s_m = R(1e3);
    p->backlash.initial_position_m = R(0.0);
}

#define GM(name, body)                         \
    static void name(gs_simple_gear_params *p) \
    {                                          \
        body;                                  \
    }

GM(g_nothing, (void)p)
GM(g_ratio_zero, p->teeth_ratio = R(0.0))
GM(g_ratio_neg, p->teeth_ratio = R(-2.0))
GM(g_ratio_nan, p->teeth_ratio = R(NAN))
GM(g_ratio_inf, p->teeth_ratio = R(INFINITY))
/* positive, but 1/x overflows gs_real (a subnormal of the precision) */
#ifdef GS_SINGLE_PRECISION
#define TINY_POSITIVE 1e-44f
#else
#define TINY_POSITIVE 1e-310
#endif
GM(g_ratio_tiny, p->teeth_ratio = TINY_POSITIVE)
GM(g_rot_bad, p->output_shaft_rotates = BAD_ENUM(gs_output_rotation, 7))
GM(g_fric_bad, p->friction_model = BAD_ENUM(gs_friction_model, 9))
GM(g_fric_neg, p->friction_model = BAD_ENUM(gs_friction_model, -1))
GM(g_smooth_bad, use_constant(p); p->loss_smoothing = BAD_ENUM(gs_loss_smoothing, 5))
GM(g_eta_zero, use_constant(p); p->efficiency_const = R(0.0))
GM(g_eta_neg, use_constant(p); p->efficiency_const = R(-0.5))
GM(g_eta_big, use_constant(p); p->efficiency_const = R(1.01))
GM(g_eta_nan, use_constant(p); p->efficiency_const = R(NAN))
GM(g_pth_zero, use_constant(p); p->power_threshold_W = R(0.0))
GM(g_pth_temp, use_temp(p); p->power_threshold_W = R(-1.0))
GM(g_pth_nan, use_constant(p); p->power_threshold_W = R(NAN))
GM(g_idle_neg, use_load(p); p->idle_torque_Nm = R(-0.1))
GM(g_nom_zero, use_load(p); p->nominal_output_torque_Nm = R(0.0))
GM(g_enom_one, use_load(p); p->efficiency_nominal = R(1.0))
GM(g_enom_zero, use_load(p); p->efficiency_nominal = R(0.0))
GM(g_k_neg, use_load(p); p->idle_torque_Nm = R(1.0))
GM(g_wth_zero, use_load(p); p->speed_threshold_rad_s = R(0.0))
GM(g_wth_2d, use_2d(p); p->speed_threshold_rad_s = R(-1.0))
GM(g_tcount_1, use_temp(p); p->temperature_count = 1)
GM(g_tcount_0, use_temp(p); p->temperature_count = 0)
GM(g_tcount_11, use_temp(p); p->temperature_count = GS_TABLE_MAX + 1)
GM(g_t_equal, use_temp(p); p->temperature_vector_K[1] = R(280.0))
GM(g_t_dec, use_temp(p); p->temperature_vector_K[0] = R(310.0))
GM(g_t_nan, use_temp(p); p->temperature_vector_K[1] = R(NAN))
GM(g_evec_zero, use_temp(p); p->efficiency_vector[1] = R(0.0))
GM(g_evec_big, use_temp(p); p->efficiency_vector[2] = R(1.2))
GM(g_evec_nan, use_temp(p); p->efficiency_vector[0] = R(NAN))
GM(g_cmass_zero, use_temp(p); p->thermal_mass_J_K = R(0.0))
GM(g_t0_zero, use_temp(p); p->initial_temperature_K = R(0.0))
GM(g_t0_neg, use_temp(p); p->initial_temperature_K = R(-5.0))
GM(g_2d_lcount, use_2d(p); p->load_count = 1)
GM(g_2d_lequal, use_2d(p); p->load_vector_Nm[2] = R(50.0))
GM(g_2d_lneg, use_2d(p); p->load_vector_Nm[0] = R(-10.0))
GM(g_2d_mat_zero, use_2d(p); p->efficiency_matrix[1][2] = R(0.0))
GM(g_2d_mat_big, use_2d(p); p->efficiency_matrix[2][0] = R(1.5))
GM(g_2d_mat_nan, use_2d(p); p->efficiency_matrix[0][1] = R(NAN))
GM(g_2d_mat_tiny, use_2d(p); p->efficiency_matrix[2][2] = TINY_POSITIVE) /* 1/eta overflows */
GM(g_eta_tiny, use_constant(p); p->efficiency_const = TINY_POSITIVE)
GM(g_2d_tcount, use_2d(p); p->temperature_count = 1)
GM(g_2d_t_dec, use_2d(p); p->temperature_vector_K[2] = R(290.0))
GM(g_2d_cmass, use_2d(p); p->thermal_mass_J_K = R(-1.0))
GM(g_visc_b, p->viscous_coefficients[0] = R(-1.0))
GM(g_visc_f, p->viscous_coefficients[1] = R(-0.1))
GM(g_visc_nan, p->viscous_coefficients[1] = R(NAN))
GM(g_bl_b_zero, use_backlash(p); p->backlash.linear_backlash_m = R(0.0))
GM(g_bl_b_nan, use_backlash(p); p->backlash.linear_backlash_m = R(NAN))
GM(g_bl_rb_zero, use_backlash(p); p->backlash.base_radius_m = R(0.0))
GM(g_bl_d_zero, use_backlash(p); p->backlash.transition_region_m = R(0.0))
GM(g_bl_d_neg, use_backlash(p); p->backlash.transition_region_m = R(-1e-4))
GM(g_bl_K_zero, use_backlash(p); p->backlash.stiffness_N_m = R(0.0))
GM(g_bl_K_inf, use_backlash(p); p->backlash.stiffness_N_m = R(INFINITY))
GM(g_bl_D_neg, use_backlash(p); p->backlash.damping_N_s_m = R(-1.0))
GM(g_bl_x0_high, use_backlash(p); p->backlash.initial_position_m = R(0.6e-3))
GM(g_bl_x0_low, use_backlash(p); p->backlash.initial_position_m = R(-0.6e-3))
GM(g_bl_model_bad, use_backlash(p); p->backlash.hard_stop_model = BAD_ENUM(gs_hard_stop_model, 7))
GM(g_bl_vth_zero, use_backlash(p); p->backlash.lock_enabled = 1; p->backlash.contact_speed_threshold_m_s = R(0.0))
GM(g_bl_fth_neg, use_backlash(p); p->backlash.lock_enabled = 1; p->backlash.contact_release_force_N = R(-1.0))
/* valid */
GM(v_eta_one, use_constant(p); p->efficiency_const = R(1.0))
GM(v_inactive_eta, p->friction_model = GS_FRICTION_NONE; p->efficiency_const = R(5.0); p->power_threshold_W = R(-1.0))
GM(v_inactive_tables, use_constant(p); p->temperature_count = 0; p->load_count = 0)
/* thermal_mass only: docs/model.md reports initial_temperature as the
 * (constant) temperature of the other models, so it stays validated */
GM(v_inactive_thermal, use_load(p); p->thermal_mass_J_K = R(0.0))
GM(v_inactive_load_params, use_temp(p); p->idle_torque_Nm = R(-1.0); p->efficiency_nominal = R(2.0);
   p->speed_threshold_rad_s = R(0.0))
GM(v_inactive_backlash, p->backlash.enabled = 0; p->backlash.linear_backlash_m = R(-1.0);
   p->backlash.stiffness_N_m = R(0.0))
GM(v_full_d_zero, use_backlash(p); p->backlash.hard_stop_model = GS_HARD_STOP_FULL_DAMPED;
   p->backlash.transition_region_m = R(0.0))
GM(v_D_zero, use_backlash(p); p->backlash.damping_N_s_m = R(0.0))
GM(v_x0_high_edge, use_backlash(p); p->backlash.initial_position_m = R(0.5e-3))
GM(v_x0_low_edge, use_backlash(p); p->backlash.initial_position_m = R(-0.5e-3))
GM(v_lock_off, use_backlash(p); p->backlash.lock_enabled = 0; p->backlash.contact_speed_threshold_m_s = R(0.0);
   p->backlash.contact_release_force_N = R(-1.0))
GM(v_lock_on, use_backlash(p); p->backlash.lock_enabled = 1; p->backlash.contact_speed_threshold_m_s = R(1e-3);
   p->backlash.contact_release_force_N = R(0.0))
GM(v_load_default, use_load(p))
GM(v_temp_default, use_temp(p))
GM(v_2d, use_2d(p))
GM(
    v_table_max, int i; use_temp(p); p->temperature_count = GS_TABLE_MAX; for (i = 0; i < GS_TABLE_MAX; ++i) {
        p->temperature_vector_K[i] = R(250.0 + 10.0 * i);
        p->efficiency_vector[i] = R(1.0 - 0.01 * i);
    })
GM(v_unused_entries, use_temp(p); p->efficiency_vector[5] = R(0.0); p->temperature_vector_K[5] = R(NAN))
GM(v_k_zero_edge, use_load(p); p->teeth_ratio = R(2.0); p->nominal_output_torque_Nm = R(1.0);
   p->efficiency_nominal = R(0.8); p->idle_torque_Nm = R(0.1)) /* k = 0.25 - 0.2 > 0 */
GM(v_visc_zero, p->viscous_coefficients[0] = R(0.0); p->viscous_coefficients[1] = R(0.0))

static const gear_case gear_cases[] = {
    {"default", g_nothing, GS_OK, "", NULL, GS_OK},
    {"teeth_ratio = 0", g_ratio_zero, GS_E_NOT_POSITIVE, "teeth_ratio", NULL, GS_OK},
    {"teeth_ratio < 0", g_ratio_neg, GS_E_NOT_POSITIVE, "teeth_ratio", NULL, GS_OK},
    {"teeth_ratio NaN", g_ratio_nan, GS_E_NOT_FINITE, "teeth_ratio", NULL, GS_OK},
    {"teeth_ratio inf", g_ratio_inf, GS_E_NOT_FINITE, "teeth_ratio", NULL, GS_OK},
    {"teeth_ratio subnormal", g_ratio_tiny, GS_E_MAGNITUDE, "teeth_ratio", NULL, GS_OK},
    {"output_shaft_rotates bad", g_rot_bad, GS_E_OPTION, "output_shaft_rotates", NULL, GS_OK},
    {"friction_model bad", g_fric_bad, GS_E_OPTION, "friction_model", NULL, GS_OK},
    {"friction_model -1", g_fric_neg, GS_E_OPTION, "friction_model", NULL, GS_OK},
    {"loss_smoothing bad", g_smooth_bad, GS_E_OPTION, "loss_smoothing", NULL, GS_OK},
    {"efficiency_const 0", g_eta_zero, GS_E_EFFICIENCY_RANGE, "efficiency_const", NULL, GS_OK},
    {"efficiency_const < 0", g_eta_neg, GS_E_EFFICIENCY_RANGE, "efficiency_const", NULL, GS_OK},
    {"efficiency_const > 1", g_eta_big, GS_E_EFFICIENCY_RANGE, "efficiency_const", NULL, GS_OK},
    {"efficiency_const NaN", g_eta_nan, GS_E_NOT_FINITE, "efficiency_const", NULL, GS_OK},
    {"power_threshold 0", g_pth_zero, GS_E_NOT_POSITIVE, "power_threshold", NULL, GS_OK},
    {"power_threshold < 0 (temperature)", g_pth_temp, GS_E_NOT_POSITIVE, "power_threshold", NULL, GS_OK},
    {"power_threshold NaN", g_pth_nan, GS_E_NOT_FINITE, "power_threshold", NULL, GS_OK},
    {"idle_torque < 0", g_idle_neg, GS_E_NEGATIVE, "idle_torque", NULL, GS_OK},
    {"nominal_output_torque 0", g_nom_zero, GS_E_NOT_POSITIVE, "nominal_output_torque", NULL, GS_OK},
    {"efficiency_nominal 1", g_enom_one, GS_E_NOMINAL_EFFICIENCY, "efficiency_nominal", NULL, GS_OK},
    {"efficiency_nominal 0", g_enom_zero, GS_E_NOMINAL_EFFICIENCY, "efficiency_nominal", NULL, GS_OK},
    /* k < 0 (eq. 2.5): physics.md lists the rule under efficiency_nominal,
     * types.h names it after the idle torque; either name is accepted */
    {"k < 0", g_k_neg, GS_E_IDLE_TORQUE_TOO_LARGE, "idle_torque", "efficiency_nominal", GS_OK},
    {"speed_threshold 0", g_wth_zero, GS_E_NOT_POSITIVE, "speed_threshold", NULL, GS_OK},
    {"speed_threshold < 0 (2-D)", g_wth_2d, GS_E_NOT_POSITIVE, "speed_threshold", NULL, GS_OK},
    {"temperature_count 1", g_tcount_1, GS_E_TABLE_LENGTH, "temperature_vector", NULL, GS_OK},
    {"temperature_count 0", g_tcount_0, GS_E_TABLE_LENGTH, "temperature_vector", NULL, GS_OK},
    {"temperature_count 11", g_tcount_11, GS_E_TABLE_LENGTH, "temperature_vector", NULL, GS_OK},
    {"temperature_vector equal", g_t_equal, GS_E_TABLE_NOT_INCREASING, "temperature_vector", NULL, GS_OK},
    {"temperature_vector decreasing", g_t_dec, GS_E_TABLE_NOT_INCREASING, "temperature_vector", NULL, GS_OK},
    {"temperature_vector NaN", g_t_nan, GS_E_NOT_FINITE, "temperature_vector", NULL, GS_OK},
    {"efficiency_vector 0", g_evec_zero, GS_E_EFFICIENCY_RANGE, "efficiency_vector", NULL, GS_OK},
    {"efficiency_vector > 1", g_evec_big, GS_E_EFFICIENCY_RANGE, "efficiency_vector", NULL, GS_OK},
    {"efficiency_vector NaN", g_evec_nan, GS_E_NOT_FINITE, "efficiency_vector", NULL, GS_OK},
    {"thermal_mass 0", g_cmass_zero, GS_E_NOT_POSITIVE, "thermal_mass", NULL, GS_OK},
    {"initial_temperature 0", g_t0_zero, GS_E_NOT_POSITIVE, "initial_temperature", NULL, GS_OK},
    {"initial_temperature < 0", g_t0_neg, GS_E_NOT_POSITIVE, "initial_temperature", NULL, GS_OK},
    {"load_count 1", g_2d_lcount, GS_E_TABLE_LENGTH, "load_vector", NULL, GS_OK},
    {"load_vector equal", g_2d_lequal, GS_E_TABLE_NOT_INCREASING, "load_vector", NULL, GS_OK},
    {"load_vector < 0", g_2d_lneg, GS_E_NEGATIVE, "load_vector", NULL, GS_OK},
    {"efficiency_matrix 0", g_2d_mat_zero, GS_E_EFFICIENCY_RANGE, "efficiency_matrix", NULL, GS_OK},
    {"efficiency_matrix > 1", g_2d_mat_big, GS_E_EFFICIENCY_RANGE, "efficiency_matrix", NULL, GS_OK},
    {"efficiency_matrix NaN", g_2d_mat_nan, GS_E_NOT_FINITE, "efficiency_matrix", NULL, GS_OK},
    {"efficiency_matrix subnormal", g_2d_mat_tiny, GS_E_MAGNITUDE, "efficiency_matrix", NULL, GS_OK},
    {"efficiency_const subnormal", g_eta_tiny, GS_E_MAGNITUDE, "efficiency_const", NULL, GS_OK},
    {"2-D temperature_count 1", g_2d_tcount, GS_E_TABLE_LENGTH, "temperature_vector", NULL, GS_OK},
    {"2-D temperature_vector decreasing", g_2d_t_dec, GS_E_TABLE_NOT_INCREASING, "temperature_vector", NULL, GS_OK},
    {"2-D thermal_mass < 0", g_2d_cmass, GS_E_NOT_POSITIVE, "thermal_mass", NULL, GS_OK},
    {"viscous mu_B < 0", g_visc_b, GS_E_NEGATIVE, "viscous_coefficients", NULL, GS_OK},
    {"viscous mu_F < 0", g_visc_f, GS_E_NEGATIVE, "viscous_coefficients", NULL, GS_OK},
    {"viscous NaN", g_visc_nan, GS_E_NOT_FINITE, "viscous_coefficients", NULL, GS_OK},
    {"linear_backlash 0", g_bl_b_zero, GS_E_NOT_POSITIVE, "linear_backlash", NULL, GS_OK},
    {"linear_backlash NaN", g_bl_b_nan, GS_E_NOT_FINITE, "linear_backlash", NULL, GS_OK},
    {"base_radius 0", g_bl_rb_zero, GS_E_NOT_POSITIVE, "base_radius", NULL, GS_OK},
    {"transition_region 0", g_bl_d_zero, GS_E_TRANSITION_REGION, "transition_region", NULL, GS_OK},
    {"transition_region < 0", g_bl_d_neg, GS_E_TRANSITION_REGION, "transition_region", NULL, GS_OK},
    {"stiffness 0", g_bl_K_zero, GS_E_NOT_POSITIVE, "stiffness", NULL, GS_OK},
    {"stiffness inf", g_bl_K_inf, GS_E_NOT_FINITE, "stiffness", NULL, GS_OK},
    {"damping < 0", g_bl_D_neg, GS_E_NEGATIVE, "damping", NULL, GS_OK},
    {"initial_backlash_position > b/2", g_bl_x0_high, GS_E_BACKLASH_POSITION, "initial_backlash_position", NULL, GS_OK},
    {"initial_backlash_position < -b/2", g_bl_x0_low, GS_E_BACKLASH_POSITION, "initial_backlash_position", NULL, GS_OK},
    {"hard_stop_model bad", g_bl_model_bad, GS_E_OPTION, "hard_stop_model", NULL, GS_OK},
    {"contact_speed_threshold 0 (lock)", g_bl_vth_zero, GS_E_NOT_POSITIVE, "contact_speed_threshold", NULL, GS_OK},
    {"contact_release_force < 0 (lock)", g_bl_fth_neg, GS_E_NEGATIVE, "contact_release_force", NULL, GS_OK},
    {"efficiency 1 allowed", v_eta_one, GS_OK, "", NULL, GS_OK},
    {"inactive efficiency not validated", v_inactive_eta, GS_OK, "", NULL, GS_OK},
    {"inactive tables not validated", v_inactive_tables, GS_OK, "", NULL, GS_OK},
    {"inactive thermal parameters not validated", v_inactive_thermal, GS_OK, "", NULL, GS_OK},
    {"inactive load-model parameters not validated", v_inactive_load_params, GS_OK, "", NULL, GS_OK},
    {"disabled backlash not validated", v_inactive_backlash, GS_OK, "", NULL, GS_OK},
    {"full models ignore transition_region", v_full_d_zero, GS_OK, "", NULL, GS_OK},
    {"damping 0 allowed", v_D_zero, GS_OK, "", NULL, GS_OK},
    {"x0 = +b/2 allowed", v_x0_high_edge, GS_OK, "", NULL, GS_OK},
    {"x0 = -b/2 allowed", v_x0_low_edge, GS_OK, "", NULL, GS_OK},
    {"lock thresholds ignored when lock off", v_lock_off, GS_OK, "", NULL, GS_OK},
    {"lock on with valid thresholds", v_lock_on, GS_OK, "", NULL, GS_OK},
    {"load-dependent defaults", v_load_default, GS_OK, "", NULL, GS_OK},
    {"temperature-dependent defaults", v_temp_default, GS_OK, "", NULL, GS_OK},
    {"2-D table", v_2d, GS_OK, "", NULL, GS_OK},
    {"table of GS_TABLE_MAX points", v_table_max, GS_OK, "", NULL, GS_OK},
    {"entries beyond the count ignored", v_unused_entries, GS_OK, "", NULL, GS_OK},
    {"k > 0 small", v_k_zero_edge, GS_OK, "", NULL, GS_OK},
    {"viscous 0", v_visc_zero, GS_OK, "", NULL, GS_OK},
};

static void check_result(const char *what, const char *label, gs_status got, const gs_error *err, gs_status want,
                         gs_status alt_want, const char *param, const char *alt_param)
{
    int ok_status = got == want || (alt_want != GS_OK && got == alt_want);
    int ok_param;
    if (err->parameter == NULL || err->message == NULL) {
        print_error("%s [%s]: err.parameter or err.message is NULL\n", what, label);
        fail();
    }
    ok_param = strcmp(err->parameter, param) == 0 || (alt_param != NULL && strcmp(err->parameter, alt_param) == 0);
    if (!ok_status || !ok_param || err->status != got) {
        print_error("%s [%s]: got status %d (%s) parameter '%s' (err.status %d), expected %d (%s) "
                    "parameter '%s'%s%s\n",
                    what, label, (int)got, gs_status_str(got), err->parameter, (int)err->status, (int)want,
                    gs_status_str(want), param, alt_param ? " or " : "", alt_param ? alt_param : "");
        fail();
    }
    if (got != GS_OK) assert_true(strlen(err->message) > 0);
}

static void test_gear_rules(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < sizeof gear_cases / sizeof gear_cases[0]; ++i) {
        const gear_case *c = &gear_cases[i];
        gs_simple_gear_params p = gs_simple_gear_params_default();
        test_gear gear, before;
        gs_error err;
        gs_status st;
        c->mut(&p);
        memset(&gear, 0xA5, sizeof gear);
        before = gear;
        err.status = GS_E_NULL;
        err.parameter = "garbage";
        err.message = NULL;
        st = gs_simple_gear_init(&gear.c, &gear.s, &p, &err);
        check_result("gs_simple_gear_init", c->label, st, &err, c->status, c->alt_status, c->param, c->alt_param);
        if (st != GS_OK) assert_memory_equal(&gear, &before, sizeof gear); /* left unchanged */
        /* err may be NULL */
        assert_int_equal(gs_simple_gear_init(&gear.c, &gear.s, &p, NULL), st);
        /* the gear rig validates the block the same way */
        {
            gs_rig_params rp = gs_rig_params_default();
            test_rig rig;
            err.parameter = "garbage";
            st = gs_rig_init_gear(&rig.c, &rig.s, &p, &rp, &err);
            check_result("gs_rig_init_gear", c->label, st, &err, c->status, c->alt_status, c->param, c->alt_param);
        }
    }
}

/* ---------------------------------------------------------------- rack */
typedef void (*rack_mut)(gs_rack_pinion_params *p);

typedef struct {
    const char *label;
    rack_mut mut;
    gs_status status;
    const char *param;
} rack_case;

#define RM(name, body)                         \
    static void name(gs_rack_pinion_params *p) \
    {                                          \
        body;                                  \
    }

static void rack_backlash(gs_rack_pinion_params *p)
{
    p->backlash = gs_simple_gear_params_default().backlash;
    p->backlash.enabled = 1;
    p->backlash.linear_backlash_m = R(1e-3);
    p->backlash.initial_position_m = R(0.0);
}

RM(r_nothing, (void)p)
RM(r_param_bad, p->parameterization = BAD_ENUM(gs_rack_parameterization, 3))
RM(r_radius_zero, p->pinion_radius_m = R(0.0))
RM(r_radius_nan, p->pinion_radius_m = R(NAN))
RM(r_teeth_zero, p->parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS; p->teeth_count = R(0.0))
RM(r_spacing_zero, p->parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS; p->spacing_m = R(-0.005))
RM(r_dir_bad, p->rack_directionality = BAD_ENUM(gs_rack_direction, 2))
RM(r_fric_load, p->friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY)
RM(r_fric_2d, p->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY)
RM(r_fric_bad, p->friction_model = BAD_ENUM(gs_friction_model, 11))
RM(r_eta_zero, p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY; p->efficiency_const = R(0.0))
RM(r_eta_big, p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY; p->efficiency_const = R(1.5))
RM(r_pth_zero, p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY; p->power_threshold_W = R(0.0))
RM(r_tcount, p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY; p->temperature_count = 1)
RM(r_t_dec, p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY; p->temperature_vector_K[2] = R(300.0))
RM(r_evec, p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY; p->efficiency_vector[2] = R(1.5))
RM(r_visc_p, p->pinion_viscous_coefficient = R(-1.0))
RM(r_visc_r, p->rack_viscous_coefficient = R(-1.0))
RM(r_visc_nan, p->rack_viscous_coefficient = R(NAN))
RM(r_cmass, p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY; p->thermal_mass_J_K = R(0.0))
RM(r_t0, p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY; p->initial_temperature_K = R(0.0))
RM(r_bl_b, rack_backlash(p); p->backlash.linear_backlash_m = R(0.0))
RM(r_bl_K, rack_backlash(p); p->backlash.stiffness_N_m = R(-1.0))
RM(r_bl_x0, rack_backlash(p); p->backlash.initial_position_m = R(1e-3))
RM(r_bl_d, rack_backlash(p); p->backlash.transition_region_m = R(0.0))
RM(v_r_tooth_ignores_radius, p->parameterization = GS_PARAMETERIZE_TOOTH_PARAMETERS; p->pinion_radius_m = R(0.0))
RM(v_r_radius_ignores_teeth, p->teeth_count = R(0.0); p->spacing_m = R(0.0))
RM(v_r_backlash_no_base_radius, rack_backlash(p); p->backlash.base_radius_m = R(0.0))
RM(v_r_inactive_eta, p->efficiency_const = R(7.0))
RM(v_r_temp, p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY)

static const rack_case rack_cases[] = {
    {"default", r_nothing, GS_OK, ""},
    {"parameterization bad", r_param_bad, GS_E_OPTION, "parameterization"},
    {"pinion_radius 0", r_radius_zero, GS_E_NOT_POSITIVE, "pinion_radius"},
    {"pinion_radius NaN", r_radius_nan, GS_E_NOT_FINITE, "pinion_radius"},
    {"teeth_count 0", r_teeth_zero, GS_E_NOT_POSITIVE, "teeth_count"},
    {"spacing < 0", r_spacing_zero, GS_E_NOT_POSITIVE, "spacing"},
    {"rack_directionality bad", r_dir_bad, GS_E_OPTION, "rack_directionality"},
    {"friction_model load-dependent", r_fric_load, GS_E_OPTION, "friction_model"},
    {"friction_model temperature+load", r_fric_2d, GS_E_OPTION, "friction_model"},
    {"friction_model bad", r_fric_bad, GS_E_OPTION, "friction_model"},
    {"efficiency_const 0", r_eta_zero, GS_E_EFFICIENCY_RANGE, "efficiency_const"},
    {"efficiency_const > 1", r_eta_big, GS_E_EFFICIENCY_RANGE, "efficiency_const"},
    {"power_threshold 0", r_pth_zero, GS_E_NOT_POSITIVE, "power_threshold"},
    {"temperature_count 1", r_tcount, GS_E_TABLE_LENGTH, "temperature_vector"},
    {"temperature_vector decreasing", r_t_dec, GS_E_TABLE_NOT_INCREASING, "temperature_vector"},
    {"efficiency_vector > 1", r_evec, GS_E_EFFICIENCY_RANGE, "efficiency_vector"},
    {"pinion viscous < 0", r_visc_p, GS_E_NEGATIVE, "pinion_viscous_coefficient"},
    {"rack viscous < 0", r_visc_r, GS_E_NEGATIVE, "rack_viscous_coefficient"},
    {"rack viscous NaN", r_visc_nan, GS_E_NOT_FINITE, "rack_viscous_coefficient"},
    {"thermal_mass 0", r_cmass, GS_E_NOT_POSITIVE, "thermal_mass"},
    {"initial_temperature 0", r_t0, GS_E_NOT_POSITIVE, "initial_temperature"},
    {"linear_backlash 0", r_bl_b, GS_E_NOT_POSITIVE, "linear_backlash"},
    {"stiffness < 0", r_bl_K, GS_E_NOT_POSITIVE, "stiffness"},
    {"initial_backlash_position > b/2", r_bl_x0, GS_E_BACKLASH_POSITION, "initial_backlash_position"},
    {"transition_region 0", r_bl_d, GS_E_TRANSITION_REGION, "transition_region"},
    {"tooth parameterization ignores pinion_radius", v_r_tooth_ignores_radius, GS_OK, ""},
    {"radius parameterization ignores teeth", v_r_radius_ignores_teeth, GS_OK, ""},
    {"rack backlash ignores base_radius", v_r_backlash_no_base_radius, GS_OK, ""},
    {"inactive efficiency not validated", v_r_inactive_eta, GS_OK, ""},
    {"temperature-dependent defaults", v_r_temp, GS_OK, ""},
};

static void test_rack_rules(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < sizeof rack_cases / sizeof rack_cases[0]; ++i) {
        const rack_case *c = &rack_cases[i];
        gs_rack_pinion_params p = gs_rack_pinion_params_default();
        test_rack rp, before;
        gs_rig_params rigp = gs_rig_params_default();
        test_rig rig;
        gs_error err;
        gs_status st;
        c->mut(&p);
        memset(&rp, 0x5A, sizeof rp);
        before = rp;
        err.parameter = "garbage";
        st = gs_rack_pinion_init(&rp.c, &rp.s, &p, &err);
        check_result("gs_rack_pinion_init", c->label, st, &err, c->status, GS_OK, c->param, NULL);
        if (st != GS_OK) assert_memory_equal(&rp, &before, sizeof rp);
        assert_int_equal(gs_rack_pinion_init(&rp.c, &rp.s, &p, NULL), st);
        err.parameter = "garbage";
        st = gs_rig_init_rack(&rig.c, &rig.s, &p, &rigp, &err);
        check_result("gs_rig_init_rack", c->label, st, &err, c->status, GS_OK, c->param, NULL);
    }
}

/* ---------------------------------------------------------------- rig */
typedef void (*rig_mut)(gs_rig_params *p);

typedef struct {
    const char *label;
    rig_mut mut;
    gs_status status;
    gs_status alt_status;
    const char *gear_param; /* name with the gear rig */
    const char *rack_param; /* name with the rack rig */
} rig_case;

#define RGM(name, body)                \
    static void name(gs_rig_params *p) \
    {                                  \
        body;                          \
    }

RGM(rg_nothing, (void)p)
RGM(rg_dt_zero, p->dt_s = R(0.0))
RGM(rg_dt_neg, p->dt_s = R(-1e-3))
RGM(rg_dt_nan, p->dt_s = R(NAN))
RGM(rg_dt_inf, p->dt_s = R(INFINITY))
RGM(rg_dt_tiny, p->dt_s = TINY_POSITIVE)
RGM(rg_J_zero, p->driven_inertia = R(0.0))
RGM(rg_J_neg, p->driven_inertia = R(-0.05))
RGM(rg_J_nan, p->driven_inertia = R(NAN))
RGM(rg_JB_torque_zero, p->base_drive = GS_BASE_TORQUE_DRIVEN; p->base_inertia_kg_m2 = R(0.0))
RGM(rg_JB_speed_neg, p->base_inertia_kg_m2 = R(-1.0))
RGM(rg_coul_neg, p->load_coulomb_friction = R(-1.0))
RGM(rg_coulth_zero, p->load_coulomb_speed_threshold = R(0.0))
RGM(rg_rth_zero, p->heat_path = 1; p->thermal_resistance_K_W = R(0.0))
RGM(rg_filter_neg, p->accel_filter_time_constant_s = R(-1.0))
RGM(rg_sub_neg, p->contact_substeps = -1)
RGM(rg_sub_big, p->contact_substeps = GS_MAX_SUBSTEPS + 1)
RGM(rg_drive_bad, p->base_drive = BAD_ENUM(gs_base_drive, 5))
RGM(rg_tsrc_bad, p->temperature_source = BAD_ENUM(gs_temperature_source, 5))
RGM(rg_offset_nan, p->load_offset = R(NAN))
RGM(rg_w0_nan, p->base_drive = GS_BASE_TORQUE_DRIVEN; p->base_inertia_kg_m2 = R(0.01);
    p->initial_base_speed_rad_s = R(NAN))
RGM(vg_JB_speed_zero, p->base_inertia_kg_m2 = R(0.0))
RGM(vg_no_heat_path, p->heat_path = 0; p->thermal_resistance_K_W = R(0.0))
RGM(vg_sub_max, p->contact_substeps = GS_MAX_SUBSTEPS)
RGM(vg_sub_auto, p->contact_substeps = 0)
RGM(vg_torque, p->base_drive = GS_BASE_TORQUE_DRIVEN; p->base_inertia_kg_m2 = R(0.01))

static const rig_case rig_cases[] = {
    {"default", rg_nothing, GS_OK, GS_OK, "", ""},
    {"dt 0", rg_dt_zero, GS_E_STEP_SIZE, GS_OK, "dt", "dt"},
    {"dt < 0", rg_dt_neg, GS_E_STEP_SIZE, GS_OK, "dt", "dt"},
    /* types.h: "dt must be > 0 and finite" (STEP_SIZE) vs "NaN -> NOT_FINITE" */
    {"dt NaN", rg_dt_nan, GS_E_STEP_SIZE, GS_E_NOT_FINITE, "dt", "dt"},
    {"dt inf", rg_dt_inf, GS_E_STEP_SIZE, GS_E_NOT_FINITE, "dt", "dt"},
    {"dt subnormal", rg_dt_tiny, GS_E_MAGNITUDE, GS_OK, "dt", "dt"},
    {"driven inertia 0", rg_J_zero, GS_E_NOT_POSITIVE, GS_OK, "follower_inertia", "rack_mass"},
    {"driven inertia < 0", rg_J_neg, GS_E_NOT_POSITIVE, GS_OK, "follower_inertia", "rack_mass"},
    {"driven inertia NaN", rg_J_nan, GS_E_NOT_FINITE, GS_OK, "follower_inertia", "rack_mass"},
    {"base_inertia 0, torque-driven", rg_JB_torque_zero, GS_E_NOT_POSITIVE, GS_OK, "base_inertia", "base_inertia"},
    {"base_inertia < 0, speed-driven", rg_JB_speed_neg, GS_E_NEGATIVE, GS_OK, "base_inertia", "base_inertia"},
    {"load_coulomb_friction < 0", rg_coul_neg, GS_E_NEGATIVE, GS_OK, "load_coulomb_friction", "load_coulomb_friction"},
    {"load_coulomb_speed_threshold 0", rg_coulth_zero, GS_E_NOT_POSITIVE, GS_OK, "load_coulomb_speed_threshold",
     "load_coulomb_speed_threshold"},
    {"thermal_resistance 0 with heat path", rg_rth_zero, GS_E_NOT_POSITIVE, GS_OK, "thermal_resistance",
     "thermal_resistance"},
    {"accel_filter_time_constant < 0", rg_filter_neg, GS_E_NEGATIVE, GS_OK, "accel_filter_time_constant",
     "accel_filter_time_constant"},
    {"contact_substeps < 0", rg_sub_neg, GS_E_SUBSTEPS, GS_OK, "contact_substeps", "contact_substeps"},
    {"contact_substeps > max", rg_sub_big, GS_E_SUBSTEPS, GS_OK, "contact_substeps", "contact_substeps"},
    {"base_drive bad", rg_drive_bad, GS_E_OPTION, GS_OK, "base_drive", "base_drive"},
    {"temperature_source bad", rg_tsrc_bad, GS_E_OPTION, GS_OK, "temperature_source", "temperature_source"},
    {"load_offset NaN", rg_offset_nan, GS_E_NOT_FINITE, GS_OK, "load_offset", "load_offset"},
    {"initial_base_speed NaN", rg_w0_nan, GS_E_NOT_FINITE, GS_OK, "initial_base_speed", "initial_base_speed"},
    {"base_inertia 0, speed-driven", vg_JB_speed_zero, GS_OK, GS_OK, "", ""},
    {"adiabatic ignores thermal_resistance", vg_no_heat_path, GS_OK, GS_OK, "", ""},
    {"contact_substeps = max", vg_sub_max, GS_OK, GS_OK, "", ""},
    {"contact_substeps = 0 (auto)", vg_sub_auto, GS_OK, GS_OK, "", ""},
    {"torque-driven", vg_torque, GS_OK, GS_OK, "", ""},
};

static void test_rig_rules(void **state)
{
    size_t i;
    (void)state;
    for (i = 0; i < sizeof rig_cases / sizeof rig_cases[0]; ++i) {
        const rig_case *c = &rig_cases[i];
        gs_simple_gear_params gp = gs_simple_gear_params_default();
        gs_rack_pinion_params pp = gs_rack_pinion_params_default();
        gs_rig_params rp = gs_rig_params_default();
        test_rig rig, before;
        gs_error err;
        gs_status st;
        use_backlash(&gp); /* contact sub-steps are active */
        rack_backlash(&pp);
        c->mut(&rp);
        memset(&rig, 0x3C, sizeof rig);
        before = rig;
        err.parameter = "garbage";
        st = gs_rig_init_gear(&rig.c, &rig.s, &gp, &rp, &err);
        check_result("gs_rig_init_gear", c->label, st, &err, c->status, c->alt_status, c->gear_param, NULL);
        if (st != GS_OK) assert_memory_equal(&rig, &before, sizeof rig);
        assert_int_equal(gs_rig_init_gear(&rig.c, &rig.s, &gp, &rp, NULL), st);
        err.parameter = "garbage";
        st = gs_rig_init_rack(&rig.c, &rig.s, &pp, &rp, &err);
        check_result("gs_rig_init_rack", c->label, st, &err, c->status, c->alt_status, c->rack_param, NULL);
    }
}

/* NULL pointers give GS_E_NULL. */
static void test_null_pointers(void **state)
{
    gs_simple_gear_params gp = gs_simple_gear_params_default();
    gs_rack_pinion_params pp = gs_rack_pinion_params_default();
    gs_rig_params rp = gs_rig_params_default();
    test_gear gear;
    test_rack rack;
    test_rig rig;
    gs_error err;
    (void)state;
    /* the object is now consts + state: either one NULL is GS_E_NULL */
    assert_int_equal(gs_simple_gear_init(NULL, &gear.s, &gp, &err), GS_E_NULL);
    assert_int_equal(err.status, GS_E_NULL);
    assert_int_equal(gs_simple_gear_init(&gear.c, NULL, &gp, &err), GS_E_NULL);
    assert_int_equal(gs_simple_gear_init(&gear.c, &gear.s, NULL, &err), GS_E_NULL);
    assert_int_equal(gs_rack_pinion_init(NULL, &rack.s, &pp, &err), GS_E_NULL);
    assert_int_equal(gs_rack_pinion_init(&rack.c, NULL, &pp, &err), GS_E_NULL);
    assert_int_equal(gs_rack_pinion_init(&rack.c, &rack.s, NULL, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_gear(NULL, &rig.s, &gp, &rp, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_gear(&rig.c, NULL, &gp, &rp, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_gear(&rig.c, &rig.s, NULL, &rp, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_gear(&rig.c, &rig.s, &gp, NULL, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_rack(NULL, &rig.s, &pp, &rp, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_rack(&rig.c, NULL, &pp, &rp, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_rack(&rig.c, &rig.s, NULL, &rp, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_rack(&rig.c, &rig.s, &pp, NULL, &err), GS_E_NULL);
    assert_int_equal(gs_rig_init_rack(&rig.c, &rig.s, &pp, &rp, NULL), GS_OK);
}

/* gs_status_str: never NULL, never empty, one message per defined status. */
static void test_status_strings(void **state)
{
    int c, d;
    (void)state;
    for (c = -100; c <= 100; ++c) {
        const char *s = gs_status_str((gs_status)c);
        assert_non_null(s);
        assert_true(strlen(s) > 0);
    }
    for (c = GS_STATUS_MIN; c <= GS_OK; ++c)
        for (d = c + 1; d <= GS_OK; ++d)
            if (strcmp(gs_status_str((gs_status)c), gs_status_str((gs_status)d)) == 0) {
                print_error("statuses %d and %d share the message '%s'\n", c, d, gs_status_str((gs_status)c));
                fail();
            }
}

/* Documented defaults (physics.md section 9, headers). */
static void test_defaults(void **state)
{
    const gs_simple_gear_params g = gs_simple_gear_params_default();
    const gs_rack_pinion_params r = gs_rack_pinion_params_default();
    const gs_rig_params p = gs_rig_params_default();
    const double tol = 1e-6;
    (void)state;
    ASSERT_NEAR(g.teeth_ratio, 2.0, tol, 0.0);
    assert_int_equal(g.output_shaft_rotates, GS_ROTATES_OPPOSITE);
    assert_int_equal(g.friction_model, GS_FRICTION_NONE);
    assert_int_equal(g.loss_smoothing, GS_SMOOTHING_PASSIVE);
    ASSERT_NEAR(g.efficiency_const, 0.98, tol, 0.0);
    ASSERT_NEAR(g.power_threshold_W, 1e-3, tol, 0.0);
    ASSERT_NEAR(g.idle_torque_Nm, 0.01, tol, 0.0);
    ASSERT_NEAR(g.nominal_output_torque_Nm, 1.0, tol, 0.0);
    ASSERT_NEAR(g.efficiency_nominal, 0.95, tol, 0.0);
    ASSERT_NEAR(g.speed_threshold_rad_s, 0.01, tol, 0.0);
    assert_int_equal(g.temperature_count, 3);
    ASSERT_NEAR(g.temperature_vector_K[0], 280.0, tol, 0.0);
    ASSERT_NEAR(g.temperature_vector_K[1], 300.0, tol, 0.0);
    ASSERT_NEAR(g.temperature_vector_K[2], 320.0, tol, 0.0);
    ASSERT_NEAR(g.efficiency_vector[0], 0.95, tol, 0.0);
    ASSERT_NEAR(g.efficiency_vector[1], 0.90, tol, 0.0);
    ASSERT_NEAR(g.efficiency_vector[2], 0.85, tol, 0.0);
    assert_int_equal(g.load_count, 3);
    ASSERT_NEAR(g.load_vector_Nm[0], 0.0, 0.0, 0.0);
    ASSERT_NEAR(g.load_vector_Nm[1], 50.0, tol, 0.0);
    ASSERT_NEAR(g.load_vector_Nm[2], 100.0, tol, 0.0);
    assert_int_equal(g.backlash.enabled, 0);
    assert_int_equal(g.backlash.hard_stop_model, GS_HARD_STOP_SMOOTH);
    ASSERT_NEAR(g.backlash.linear_backlash_m, 1e-3, tol, 0.0);
    ASSERT_NEAR(g.backlash.base_radius_m, 0.1, tol, 0.0);
    ASSERT_NEAR(g.backlash.transition_region_m, 1e-4, tol, 0.0);
    ASSERT_NEAR(g.backlash.stiffness_N_m, 1e6, tol, 0.0);
    ASSERT_NEAR(g.backlash.damping_N_s_m, 1e3, tol, 0.0);
    ASSERT_NEAR(g.backlash.initial_position_m, 0.0, 0.0, 0.0);
    assert_int_equal(g.backlash.no_pull, 1);
    assert_int_equal(g.backlash.lock_enabled, 0);
    ASSERT_NEAR(g.backlash.contact_speed_threshold_m_s, 1e-3, tol, 0.0);
    ASSERT_NEAR(g.backlash.contact_release_force_N, 0.0, 0.0, 0.0);
    ASSERT_NEAR(g.viscous_coefficients[0], 0.0, 0.0, 0.0);
    ASSERT_NEAR(g.viscous_coefficients[1], 0.0, 0.0, 0.0);
    ASSERT_NEAR(g.thermal_mass_J_K, 50.0, tol, 0.0);
    ASSERT_NEAR(g.initial_temperature_K, 300.0, tol, 0.0);

    assert_int_equal(r.parameterization, GS_PARAMETERIZE_PINION_RADIUS);
    ASSERT_NEAR(r.pinion_radius_m, 0.1, tol, 0.0);
    ASSERT_NEAR(r.teeth_count, 20.0, tol, 0.0);
    ASSERT_NEAR(r.spacing_m, 0.005, tol, 0.0);
    assert_int_equal(r.rack_directionality, GS_RACK_POSITIVE);
    assert_int_equal(r.friction_model, GS_FRICTION_NONE);
    assert_int_equal(r.loss_smoothing, GS_SMOOTHING_PASSIVE);
    ASSERT_NEAR(r.efficiency_const, 0.8, tol, 0.0);
    assert_int_equal(r.temperature_count, 3);
    ASSERT_NEAR(r.temperature_vector_K[0], 280.0, tol, 0.0);
    ASSERT_NEAR(r.temperature_vector_K[2], 320.0, tol, 0.0);
    ASSERT_NEAR(r.efficiency_vector[0], 0.95, tol, 0.0);
    ASSERT_NEAR(r.efficiency_vector[2], 0.85, tol, 0.0);
    ASSERT_NEAR(r.power_threshold_W, 1e-3, tol, 0.0);
    ASSERT_NEAR(r.pinion_viscous_coefficient, 0.0, 0.0, 0.0);
    ASSERT_NEAR(r.rack_viscous_coefficient, 0.0, 0.0, 0.0);
    ASSERT_NEAR(r.thermal_mass_J_K, 50.0, tol, 0.0);
    ASSERT_NEAR(r.initial_temperature_K, 300.0, tol, 0.0);
    assert_int_equal(r.backlash.enabled, 0);

    ASSERT_NEAR(p.dt_s, 1e-3, tol, 0.0);
    assert_int_equal(p.base_drive, GS_BASE_SPEED_DRIVEN);
    ASSERT_NEAR(p.base_inertia_kg_m2, 0.0, 0.0, 0.0);
    ASSERT_NEAR(p.initial_base_speed_rad_s, 0.0, 0.0, 0.0);
    ASSERT_NEAR(p.driven_inertia, 0.05, tol, 0.0);
    ASSERT_NEAR(p.load_coulomb_friction, 0.0, 0.0, 0.0);
    ASSERT_NEAR(p.load_coulomb_speed_threshold, 1e-3, tol, 0.0);
    ASSERT_NEAR(p.load_offset, 0.0, 0.0, 0.0);
    assert_int_equal(p.heat_path, 0);
    ASSERT_NEAR(p.thermal_resistance_K_W, 2.0, tol, 0.0);
    assert_int_equal(p.temperature_source, GS_TEMPERATURE_FROM_MODEL);
    ASSERT_NEAR(p.accel_filter_time_constant_s, 0.0, 0.0, 0.0);
    assert_int_equal(p.contact_substeps, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gear_rules),    cmocka_unit_test(test_rack_rules),     cmocka_unit_test(test_rig_rules),
        cmocka_unit_test(test_null_pointers), cmocka_unit_test(test_status_strings), cmocka_unit_test(test_defaults),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
