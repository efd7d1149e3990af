/* edge_params.c - parameters at the edges: extreme but valid values
 * initialise and step without overflow or NaN (scripts/hardening.sh builds it
 * with ASan+UBSan, in double and float).
 *
 * Cases: teeth ratio 1e-3 and 1e3 (rigid and with backlash), stiffness 1e9
 * (three hard-stop laws, gear and rack), thermal mass 1e-6 J/K (adiabatic and
 * with a heat path), tables of GS_TABLE_MAX entries (1-D and 10 x 10), and
 * combinations; the rig terms at their edges (shaft stiffness 1e9 and 1e-6,
 * Stribeck speed 1e-9 and 1e3, ripple 1e3 N*m at 1000 teeth with phases of
 * 1e6 rad); each on a speed-driven and a torque-driven rig (the compliant
 * shaft: speed-driven only), 2000 steps
 * of 1 ms with speed up to 100 rad/s, torque up to 5 N*m and load up to
 * 10 N*m (or N). Prints one line per case; exit 1 when an init fails or an
 * output is not finite. */
#include <math.h>
#include <stdio.h>

#include "gearsim/gearsim.h"

#define STEPS 2000

typedef struct {
    const char *name;
    int rack;
    void (*gear)(gs_simple_gear_params *p);
    void (*rack_p)(gs_rack_pinion_params *p);
    void (*rig)(gs_rig_params *p); /* the rig terms of physics.md 11, or NULL */
    int speed_only;                /* the compliant shaft needs a speed-driven base */
} edge_case;

static void backlash(gs_backlash_params *b, gs_hard_stop_model law, double stiffness)
{
    b->enabled = 1;
    b->hard_stop_model = law;
    b->stiffness_N_m = (gs_real)stiffness;
}

static void ratio_small(gs_simple_gear_params *p)
{
    p->teeth_ratio = (gs_real)1e-3;
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}
static void ratio_large(gs_simple_gear_params *p)
{
    p->teeth_ratio = (gs_real)1e3;
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}
static void ratio_small_backlash(gs_simple_gear_params *p)
{
    ratio_small(p);
    backlash(&p->backlash, GS_HARD_STOP_SMOOTH, 1e6);
}
static void ratio_large_backlash(gs_simple_gear_params *p)
{
    ratio_large(p);
    backlash(&p->backlash, GS_HARD_STOP_SMOOTH, 1e6);
}
static void ratio_small_load(gs_simple_gear_params *p)
{
    p->teeth_ratio = (gs_real)1e-3;
    p->friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
    p->idle_torque_Nm = (gs_real)1.0;
}
static void ratio_large_load(gs_simple_gear_params *p)
{
    p->teeth_ratio = (gs_real)1e3;
    p->friction_model = GS_FRICTION_LOAD_DEPENDENT_EFFICIENCY;
    p->idle_torque_Nm = (gs_real)1e-5;
}
static void stiff_smooth(gs_simple_gear_params *p)
{
    backlash(&p->backlash, GS_HARD_STOP_SMOOTH, 1e9);
}
static void stiff_undamped(gs_simple_gear_params *p)
{
    backlash(&p->backlash, GS_HARD_STOP_FULL_UNDAMPED, 1e9);
}
static void stiff_damped_lock(gs_simple_gear_params *p)
{
    backlash(&p->backlash, GS_HARD_STOP_FULL_DAMPED, 1e9);
    p->backlash.lock_enabled = 1;
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}
static void tiny_thermal(gs_simple_gear_params *p)
{
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    p->thermal_mass_J_K = (gs_real)1e-6;
}
static void max_tables(gs_simple_gear_params *p)
{
    p->friction_model = GS_FRICTION_TEMPERATURE_LOAD_DEPENDENT_EFFICIENCY;
    p->temperature_count = GS_TABLE_MAX;
    p->load_count = GS_TABLE_MAX;
    for (int i = 0; i < GS_TABLE_MAX; ++i) {
        p->temperature_vector_K[i] = (gs_real)(250.0 + 15.0 * i);
        p->efficiency_vector[i] = (gs_real)(0.95 - 0.03 * i);
        p->load_vector_Nm[i] = (gs_real)(i * i);
        for (int j = 0; j < GS_TABLE_MAX; ++j) {
            p->efficiency_matrix[i][j] = (gs_real)(0.6 + 0.035 * j - 0.02 * i);
        }
    }
}
static void max_tables_tiny_thermal_stiff(gs_simple_gear_params *p)
{
    max_tables(p);
    p->thermal_mass_J_K = (gs_real)1e-6;
    backlash(&p->backlash, GS_HARD_STOP_SMOOTH, 1e9);
}
static void everything_small(gs_simple_gear_params *p)
{
    ratio_small(p);
    p->thermal_mass_J_K = (gs_real)1e-6;
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    backlash(&p->backlash, GS_HARD_STOP_FULL_DAMPED, 1e9);
}
static void everything_large(gs_simple_gear_params *p)
{
    ratio_large(p);
    max_tables(p);
    p->thermal_mass_J_K = (gs_real)1e-6;
    backlash(&p->backlash, GS_HARD_STOP_FULL_UNDAMPED, 1e9);
}

static void rack_stiff(gs_rack_pinion_params *p)
{
    backlash(&p->backlash, GS_HARD_STOP_SMOOTH, 1e9);
}
static void rack_max_table_tiny_thermal(gs_rack_pinion_params *p)
{
    p->friction_model = GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY;
    p->temperature_count = GS_TABLE_MAX;
    for (int i = 0; i < GS_TABLE_MAX; ++i) {
        p->temperature_vector_K[i] = (gs_real)(250.0 + 15.0 * i);
        p->efficiency_vector[i] = (gs_real)(0.95 - 0.04 * i);
    }
    p->thermal_mass_J_K = (gs_real)1e-6;
}
static void rack_all(gs_rack_pinion_params *p)
{
    rack_max_table_tiny_thermal(p);
    backlash(&p->backlash, GS_HARD_STOP_FULL_DAMPED, 1e9);
    p->backlash.lock_enabled = 1;
}

static void gear_plain(gs_simple_gear_params *p)
{
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}
static void rack_plain(gs_rack_pinion_params *p)
{
    p->friction_model = GS_FRICTION_CONSTANT_EFFICIENCY;
}
/* far stiffer than 16 sub-steps resolve at 1 ms: h*omega_n about 5e3 */
static void shaft_stiff(gs_rig_params *p)
{
    p->compliance_stiffness_Nm_rad = (gs_real)1e9;
}
static void shaft_stiff_damped(gs_rig_params *p)
{
    shaft_stiff(p);
    p->compliance_damping_Nm_s_rad = (gs_real)1e6;
}
static void shaft_soft(gs_rig_params *p)
{
    p->compliance_stiffness_Nm_rad = (gs_real)1e-6;
}
static void stribeck_sharp(gs_rig_params *p)
{
    p->load_coulomb_friction = (gs_real)1.0;
    p->load_breakaway_friction = (gs_real)8.0;
    p->load_stribeck_speed = (gs_real)1e-9;
}
static void stribeck_wide(gs_rig_params *p)
{
    p->load_breakaway_friction = (gs_real)1e4;
    p->load_stribeck_speed = (gs_real)1e3;
}
static void ripple_large(gs_rig_params *p)
{
    for (int i = 0; i < GS_RIPPLE_HARMONICS; ++i) {
        p->ripple_revolution_amplitude_Nm[i] = (gs_real)1e3;
        p->ripple_mesh_amplitude_Nm[i] = (gs_real)1e3;
        p->ripple_revolution_phase_rad[i] = (gs_real)1e6;
        p->ripple_mesh_phase_rad[i] = (gs_real)-1e6;
    }
    p->ripple_mesh_teeth = 1000;
}
/* the regularised friction as a damper of 4e12 N*m*s/rad near rest */
static void creep_sharp(gs_rig_params *p)
{
    p->load_coulomb_friction = (gs_real)1e3;
    p->load_coulomb_speed_threshold = (gs_real)1e-9;
    p->load_friction_regularised = 1;
    p->base_speed_ramp = 1;
}
/* a compliant mesh: the spring with no base inertia, the friction creeping behind it */
static void mesh_spring_creep(gs_rig_params *p)
{
    shaft_stiff(p);
    creep_sharp(p);
    p->base_inertia_kg_m2 = (gs_real)0.0;
}
static void all_terms(gs_rig_params *p)
{
    shaft_stiff_damped(p);
    stribeck_sharp(p);
    ripple_large(p);
}

static const edge_case cases[] = {
    {"teeth_ratio 1e-3", 0, ratio_small, NULL, NULL, 0},
    {"teeth_ratio 1e3", 0, ratio_large, NULL, NULL, 0},
    {"teeth_ratio 1e-3 + backlash", 0, ratio_small_backlash, NULL, NULL, 0},
    {"teeth_ratio 1e3 + backlash", 0, ratio_large_backlash, NULL, NULL, 0},
    {"teeth_ratio 1e-3, load-dependent", 0, ratio_small_load, NULL, NULL, 0},
    {"teeth_ratio 1e3, load-dependent", 0, ratio_large_load, NULL, NULL, 0},
    {"stiffness 1e9 smooth", 0, stiff_smooth, NULL, NULL, 0},
    {"stiffness 1e9 full undamped", 0, stiff_undamped, NULL, NULL, 0},
    {"stiffness 1e9 full damped + lock", 0, stiff_damped_lock, NULL, NULL, 0},
    {"thermal mass 1e-6", 0, tiny_thermal, NULL, NULL, 0},
    {"tables GS_TABLE_MAX (10, 10x10)", 0, max_tables, NULL, NULL, 0},
    {"10x10 table + C 1e-6 + K 1e9", 0, max_tables_tiny_thermal_stiff, NULL, NULL, 0},
    {"ratio 1e-3 + C 1e-6 + K 1e9", 0, everything_small, NULL, NULL, 0},
    {"ratio 1e3 + 10x10 + C 1e-6 + K 1e9", 0, everything_large, NULL, NULL, 0},
    {"rack stiffness 1e9", 1, NULL, rack_stiff, NULL, 0},
    {"rack table 10 + C 1e-6", 1, NULL, rack_max_table_tiny_thermal, NULL, 0},
    {"rack table 10 + C 1e-6 + K 1e9 + lock", 1, NULL, rack_all, NULL, 0},
    {"shaft k 1e9", 0, gear_plain, NULL, shaft_stiff, 1},
    {"shaft k 1e9, c 1e6", 0, gear_plain, NULL, shaft_stiff_damped, 1},
    {"shaft k 1e-6, ratio 1e3", 0, ratio_large, NULL, shaft_soft, 1},
    {"rack shaft k 1e9", 1, NULL, rack_plain, shaft_stiff, 1},
    {"Stribeck v_S 1e-9", 0, gear_plain, NULL, stribeck_sharp, 0},
    {"Stribeck F_brk 1e4, v_S 1e3 + backlash", 0, stiff_smooth, NULL, stribeck_wide, 0},
    {"rack Stribeck v_S 1e-9 + K 1e9", 1, NULL, rack_stiff, stribeck_sharp, 0},
    {"ripple 1e3 N*m, Z 1000, phases 1e6", 0, gear_plain, NULL, ripple_large, 0},
    {"rack ripple + K 1e9", 1, NULL, rack_stiff, ripple_large, 0},
    {"shaft k 1e9 + Stribeck + ripple", 0, ratio_small, NULL, all_terms, 1},
    {"regularised friction 1e3, v_th 1e-9 + backlash", 0, stiff_smooth, NULL, creep_sharp, 0},
    {"rack regularised friction 1e3, v_th 1e-9", 1, NULL, rack_plain, creep_sharp, 0},
    {"shaft k 1e9 at the mesh + regularised friction", 0, gear_plain, NULL, mesh_spring_creep, 1},
};

/* Triangle wave in [-1, 1]. */
static double tri(double t, double period)
{
    const double p = t / period - floor(t / period);
    return p < 0.5 ? 4.0 * p - 1.0 : 3.0 - 4.0 * p;
}

static int run(const edge_case *c, gs_base_drive drive, int heat_path)
{
    gs_rig_params rp = gs_rig_params_default();
    rp.base_drive = drive;
    rp.base_inertia_kg_m2 = (gs_real)1e-3;
    rp.heat_path = heat_path;
    rp.driven_inertia = c->rack ? (gs_real)5.0 : (gs_real)0.05;
    if (c->rig != NULL) {
        c->rig(&rp);
    }
    gs_rig_consts consts;
    gs_rig_state state;
    gs_error err;
    gs_status st;
    if (c->rack) {
        gs_rack_pinion_params p = gs_rack_pinion_params_default();
        c->rack_p(&p);
        st = gs_rig_init_rack(&consts, &state, &p, &rp, &err);
    } else {
        gs_simple_gear_params p = gs_simple_gear_params_default();
        c->gear(&p);
        st = gs_rig_init_gear(&consts, &state, &p, &rp, &err);
    }
    const char *drive_name = drive == GS_BASE_SPEED_DRIVEN ? "speed" : "torque";
    if (st != GS_OK) {
        printf("FAIL %-38s %-6s heat %d: init rejected: %s: %s\n", c->name, drive_name, heat_path, err.parameter,
               err.message);
        return 1;
    }
    double peak_torque = 0.0, peak_speed = 0.0, peak_temp = 0.0, peak_force = 0.0;
    for (int k = 0; k < STEPS; ++k) {
        const double t = 1e-3 * (k + 1);
        gs_rig_input in;
        in.base_speed = (gs_real)(100.0 * tri(t, 0.7));
        in.base_torque = (gs_real)(5.0 * tri(t, 0.3));
        in.load = (gs_real)(-10.0 * tri(t, 0.45));
        in.ambient_temperature = (gs_real)300.0;
        in.measured_temperature = (gs_real)300.0;
        gs_rig_output o;
        gs_rig_step(&consts, &state, &in, &o);
        /* every output (an array of reals, gearsim/rig.h), named by gs_rig_output_info */
        const gs_real *v = (const gs_real *)(const void *)&o;
        for (int i = 0; i < GS_RIG_OUTPUT_FIELDS; ++i) {
            if (!isfinite(v[i])) {
                printf("FAIL %-38s %-6s heat %d: output %s = %g at step %d\n", c->name, drive_name, heat_path,
                       gs_rig_output_info[i].name, (double)v[i], k);
                return 1;
            }
        }
        peak_torque = fmax(peak_torque, fabs((double)o.base_torque));
        peak_speed = fmax(peak_speed, fabs((double)o.follower_speed));
        peak_temp = fmax(peak_temp, (double)o.temperature);
        peak_force = fmax(peak_force, fabs((double)o.contact_force));
    }
    gs_rig_info info;
    gs_rig_get_info(&consts, &info);
    printf("ok   %-38s %-6s heat %d: substeps %2d, max |tau_B| %9.3g, |driven speed| %9.3g, T %9.3g K, "
           "|contact force| %9.3g\n",
           c->name, drive_name, heat_path, info.contact_substeps, peak_torque, peak_speed, peak_temp, peak_force);
    return 0;
}

int main(void)
{
    int failures = 0, runs = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        for (int drive = 0; drive < (cases[i].speed_only ? 1 : 2); ++drive) {
            for (int heat = 0; heat < 2; ++heat) {
                failures += run(&cases[i], drive ? GS_BASE_TORQUE_DRIVEN : GS_BASE_SPEED_DRIVEN, heat);
                ++runs;
            }
        }
    }
#ifdef GS_SINGLE_PRECISION
    const char *precision = "float";
#else
    const char *precision = "double";
#endif
    printf("edge parameters (%s): %d passed, %d failed\n", precision, runs - failures, failures);
    return failures != 0;
}
