/*
 * The test-campaign parts of the C HIL library (gearsim/hil.h) on the shipped
 * gear DBC: every fault class applied, counted, flagged and cleared at its
 * end, on the frames of the periods it covers, without touching the rig's
 * state; parameter changes one period after their request, equal to a rig
 * started with the new parameters from the same state; refusals counted and
 * acknowledged; the scenario reader's errors (file, line, key) and a
 * scenario's verdict in JUnit XML.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "gearsim/hil.h"
#include "gearsim/hil_dbc.h"

#define MAX_SENT 4096

typedef struct {
    unsigned count;
    uint32_t id[MAX_SENT];
    uint64_t period[MAX_SENT]; /* the period that sent it */
    uint8_t data[MAX_SENT][8];
} sink;

static gs_rig_consts consts;
static gs_rig_state state;
static gs_hil_bridge bridge;
static sink out;
static gs_simple_gear_params gear;
static gs_rig_params rig;

static int capture(void *context, const gs_hil_frame *frame)
{
    sink *s = context;
    if (s->count < MAX_SENT) {
        s->id[s->count] = frame->id;
        s->period[s->count] = (uint64_t)llround(frame->timestamp_s / 1e-3) - 1u;
        memcpy(s->data[s->count], frame->data, 8);
        s->count++;
    }
    return 0;
}

static unsigned frame_index(const char *name)
{
    for (unsigned i = 0; i < gs_hil_dbc_gear_rig.frame_count; ++i) {
        if (strcmp(gs_hil_dbc_gear_rig.frames[i].name, name) == 0) {
            return i;
        }
    }
    fail_msg("no frame %s", name);
    return 0;
}

static const gs_hil_signal *signal_of(const char *frame, int s)
{
    return &gs_hil_dbc_gear_rig.frames[frame_index(frame)].signals[s];
}

static void init_bridge(void)
{
    gear = gs_simple_gear_params_default();
    rig = gs_rig_params_default();
    rig.dt_s = GS_R(1e-3);
    gs_error err;
    assert_int_equal(gs_rig_init_gear(&consts, &state, &gear, &rig, &err), GS_OK);
    gs_hil_config config;
    memset(&config, 0, sizeof config);
    config.dbc = &gs_hil_dbc_gear_rig;
    config.base_drive = GS_BASE_SPEED_DRIVEN;
    config.dt_s = rig.dt_s;
    config.substeps = 1;
    config.timeout_s = 10.0; /* no timeouts in these tests */
    config.ambient_temperature_K = GS_R(293.15);
    config.send = capture;
    config.send_context = &out;
    config.gear_params = &gear;
    config.rig_params = &rig;
    memset(&out, 0, sizeof out);
    gs_hil_error herr;
    assert_int_equal(gs_hil_bridge_init(&bridge, &config, GS_RIG_SIMPLE_GEAR, &consts, &state, &herr), GS_HIL_OK);
}

/* A GearCmd: speed (rad/s) and load (N*m), mode Speed, stamped t. */
static gs_hil_frame command(double speed, double load, double t)
{
    gs_hil_frame f;
    memset(&f, 0, sizeof f);
    f.timestamp_s = t;
    f.id = 0x100;
    f.length = 8;
    const gs_hil_frame_spec *cmd = &gs_hil_dbc_gear_rig.frames[frame_index("GearCmd")];
    assert_int_equal(gs_hil_put_value(&cmd->signals[0], speed, f.data), 0);
    assert_int_equal(gs_hil_put_value(&cmd->signals[2], load, f.data), 0);
    assert_int_equal(gs_hil_put_value(&cmd->signals[3], 1.0, f.data), 0);
    return f;
}

/* Run periods, commanding speed(k) = 10 + 0.01 k rad/s before each: a
 * base speed that differs in every period. */
static void run_ramp(uint64_t periods)
{
    for (uint64_t j = 0; j < periods; ++j) {
        uint64_t k = bridge.counters.count[GS_HIL_COUNT_PERIODS];
        gs_hil_frame f = command(10.0 + 0.01 * (double)k, 0.0, (double)k * 1e-3);
        gs_hil_handle(&bridge, &f);
        gs_hil_advance(&bridge, 1);
    }
}

/* BaseSpeed (GearFbBase 24|24 s 0.001) of the frame GearFbBase sent by period p, or NaN. */
static double base_speed_sent(uint64_t p)
{
    for (unsigned i = 0; i < out.count; ++i) {
        if (out.id[i] == 0x200u && out.period[i] == p) {
            return gs_hil_signal_value(signal_of("GearFbBase", 1), out.data[i]);
        }
    }
    return nan("");
}

static unsigned frames_of(uint32_t id, uint64_t p)
{
    unsigned n = 0;
    for (unsigned i = 0; i < out.count; ++i) {
        n += out.id[i] == id && out.period[i] == p;
    }
    return n;
}

/* The model's base speed in period p: the command applied in it. */
static double model_speed(uint64_t p)
{
    return nearbyint((10.0 + 0.01 * (double)p) / 0.001) * 0.001;
}

static gs_hil_fault_spec spec_of(gs_hil_fault_kind kind, const char *frame, int signal, uint64_t start, uint64_t end)
{
    gs_hil_fault_spec f;
    memset(&f, 0, sizeof f);
    f.kind = kind;
    f.frame = frame_index(frame);
    f.signal = signal;
    f.start_period = start;
    f.end_period = end;
    f.seed = 7;
    return f;
}

static void add(const gs_hil_fault_spec *f)
{
    gs_hil_error err;
    if (gs_hil_add_fault(&bridge, f, &err) != GS_HIL_OK) {
        fail_msg("add_fault: %s", err.message);
    }
}

/* One value fault on BaseSpeed over periods [20, 40): the frames of periods
 * 29 and 39 carry it, those of 19 and 49 do not; counted twice; flagged in
 * exactly those periods; the rig's state as without it. */
static void value_fault(gs_hil_fault_kind kind, double value, double value2, double (*expected)(uint64_t, double))
{
    init_bridge();
    gs_hil_fault_spec f = spec_of(kind, "GearFbBase", 1, 20, 40);
    f.value = value;
    f.value2 = value2;
    f.periods = 5;
    add(&f);
    int flagged[60];
    for (uint64_t k = 0; k < 60; ++k) {
        run_ramp(1);
        flagged[k] = bridge.flag_state[GS_HIL_FLAG_FAULT_ACTIVE];
    }
    for (uint64_t k = 0; k < 60; ++k) {
        assert_int_equal(flagged[k], k >= 20 && k < 40);
    }
    for (uint64_t p = 9; p < 60; p += 10) {
        double sent = base_speed_sent(p);
        double want = p >= 20 && p < 40 ? expected(p, value) : model_speed(p);
        if (fabs(sent - want) > 0.0006) {
            fail_msg("%s: period %llu sent %.6f, expected %.6f", gs_hil_fault_name(kind), (unsigned long long)p, sent,
                     want);
        }
    }
    assert_int_equal(bridge.faults[0].count, 2);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_FAULTS], 2);
    /* the model never saw it: the same state as a bridge without the fault */
    gs_rig_state faulted = state;
    init_bridge();
    run_ramp(60);
    assert_memory_equal(&faulted, &state, sizeof state);
}

static double offset_of(uint64_t p, double v)
{
    return model_speed(p) + v;
}
static double gain_of(uint64_t p, double v)
{
    return model_speed(p) * v;
}
static double stuck_of(uint64_t p, double v)
{
    (void)p;
    return v;
}
static double freeze_of(uint64_t p, double v)
{
    (void)p;
    (void)v;
    return model_speed(19);
}
static double delay_of(uint64_t p, double v)
{
    (void)v;
    return model_speed(p - 5u);
}
static double quantise_of(uint64_t p, double v)
{
    return nearbyint(model_speed(p) / v) * v;
}
static double clamp_of(uint64_t p, double v)
{
    (void)p;
    (void)v;
    return 5.0;
}

static void test_value_faults(void **unused)
{
    (void)unused;
    value_fault(GS_HIL_FAULT_OFFSET, 0.5, 0.0, offset_of);
    value_fault(GS_HIL_FAULT_GAIN, 2.0, 0.0, gain_of);
    value_fault(GS_HIL_FAULT_STUCK, 3.25, 0.0, stuck_of);
    value_fault(GS_HIL_FAULT_FREEZE, 0.0, 0.0, freeze_of);
    value_fault(GS_HIL_FAULT_DELAY, 0.0, 0.0, delay_of);
    value_fault(GS_HIL_FAULT_QUANTISE, 0.25, 0.0, quantise_of);
    value_fault(GS_HIL_FAULT_CLAMP, -1.0, 5.0, clamp_of); /* max 5: below every speed sent */
}

static void test_noise_is_seeded(void **unused)
{
    (void)unused;
    double first[6], second[6];
    for (int run = 0; run < 2; ++run) {
        init_bridge();
        gs_hil_fault_spec f = spec_of(GS_HIL_FAULT_NOISE, "GearFbBase", 1, 0, UINT64_MAX);
        f.value = 0.1;
        add(&f);
        run_ramp(60);
        for (int k = 0; k < 6; ++k) {
            (run == 0 ? first : second)[k] = base_speed_sent((uint64_t)(10 * k + 9));
        }
    }
    double spread = 0.0;
    for (int k = 0; k < 6; ++k) {
        assert_float_equal(first[k], second[k], 0.0); /* the same seed, the same noise */
        spread += fabs(first[k] - model_speed((uint64_t)(10 * k + 9)));
    }
    assert_true(spread > 0.05); /* six draws of sigma 0.1 are not all within 0.001 */
}

static void test_frame_faults(void **unused)
{
    (void)unused;
    /* dropout of FollowerSpeed and drop of GearFbBase: no frame in [20, 40); duplicate: two */
    init_bridge();
    add((gs_hil_fault_spec[]){spec_of(GS_HIL_FAULT_DROPOUT, "GearFbFollower", 0, 20, 40)});
    add((gs_hil_fault_spec[]){spec_of(GS_HIL_FAULT_DROP, "GearFbBase", -1, 20, 40)});
    add((gs_hil_fault_spec[]){spec_of(GS_HIL_FAULT_DUPLICATE, "GearFbThermal", -1, 95, 105)});
    run_ramp(200);
    for (uint64_t p = 9; p < 60; p += 10) {
        unsigned want = p >= 20 && p < 40 ? 0u : 1u;
        assert_int_equal(frames_of(0x200, p), want);
        assert_int_equal(frames_of(0x201, p), want);
    }
    assert_int_equal(frames_of(0x202, 99), 2);
    assert_int_equal(frames_of(0x202, 199), 1);
    assert_int_equal(bridge.faults[0].count, 2);
    assert_int_equal(bridge.faults[1].count, 2);
    assert_int_equal(bridge.faults[2].count, 1);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_FAULTS], 5);
    /* sent: 20 GearFbBase + 20 GearFbFollower - 4 dropped, 2 + 1 thermal, 2 x 3 status */
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_TX_FRAMES], 36u + 3u + 6u);
}

static void test_corrupt_flips_bits(void **unused)
{
    (void)unused;
    init_bridge();
    gs_hil_fault_spec f = spec_of(GS_HIL_FAULT_CORRUPT, "GearFbBase", -1, 20, 40);
    f.periods = 3;
    add(&f);
    run_ramp(40);
    uint8_t corrupted[8];
    unsigned at = 0;
    for (unsigned i = 0; i < out.count; ++i) {
        if (out.id[i] == 0x200u && out.period[i] == 29u) {
            at = i;
        }
    }
    memcpy(corrupted, out.data[at], 8);
    init_bridge();
    run_ramp(40);
    unsigned flipped = 0;
    for (unsigned i = 0; i < out.count; ++i) {
        if (out.id[i] == 0x200u && out.period[i] == 29u) {
            for (int k = 0; k < 8; ++k) {
                flipped += (unsigned)__builtin_popcount((unsigned)(corrupted[k] ^ out.data[i][k]));
            }
        }
    }
    assert_int_equal(flipped, 3u); /* three distinct bits */
}

/* The status frame GearStatus (4 bit counter at 0, FaultActive at bit 12). */
static void test_counter_stop_and_status_flag(void **unused)
{
    (void)unused;
    init_bridge();
    add((gs_hil_fault_spec[]){spec_of(GS_HIL_FAULT_COUNTER_STOP, "GearStatus", -1, 150, 450)});
    run_ramp(600);
    unsigned counters[6], active[6], n = 0;
    for (unsigned i = 0; i < out.count && n < 6; ++i) {
        if (out.id[i] == 0x210u) {
            counters[n] = out.data[i][0] & 0x0Fu;
            active[n++] = (out.data[i][1] >> 4) & 1u;
        }
    }
    assert_int_equal(n, 6);
    /* periods 99, 199, ..., 599: counter 0, then held at 0 over 199..399, then on */
    const unsigned want_counter[6] = {0, 0, 0, 0, 1, 2};
    const unsigned want_active[6] = {0, 1, 1, 1, 0, 0};
    for (unsigned k = 0; k < 6; ++k) {
        assert_int_equal(counters[k], want_counter[k]);
        assert_int_equal(active[k], want_active[k]);
    }
    assert_int_equal(bridge.faults[0].count, 3);
}

static void test_trigger_on_a_condition(void **unused)
{
    (void)unused;
    init_bridge();
    /* stuck at 0 once the base speed exceeds 10.25 rad/s (period 26), for 10 periods */
    gs_hil_fault_spec f = spec_of(GS_HIL_FAULT_STUCK, "GearFbBase", 1, 0, UINT64_MAX);
    f.value = 0.0;
    f.has_trigger = 1;
    f.duration_periods = 10;
    f.trigger.source = GS_HIL_SOURCE_FEEDBACK;
    f.trigger.frame = frame_index("GearFbBase");
    f.trigger.signal = 1;
    f.trigger.op = GS_HIL_OP_GT;
    f.trigger.value = 10.255;
    add(&f);
    run_ramp(60);
    assert_float_equal(base_speed_sent(19), model_speed(19), 1e-9);
    assert_float_equal(base_speed_sent(29), 0.0, 0.0);
    assert_float_equal(base_speed_sent(39), model_speed(39), 1e-9);
    assert_int_equal(bridge.faults[0].stop_period, 26u + 10u);
}

static void test_faults_refused(void **unused)
{
    (void)unused;
    init_bridge();
    gs_hil_error err;
    gs_hil_fault_spec f = spec_of(GS_HIL_FAULT_OFFSET, "GearStatus", 0, 0, 10); /* a counter, not a value */
    assert_int_equal(gs_hil_add_fault(&bridge, &f, &err), GS_HIL_E_CONFIG);
    f = spec_of(GS_HIL_FAULT_DROP, "GearCmd", -1, 0, 10); /* not feedback */
    assert_int_equal(gs_hil_add_fault(&bridge, &f, &err), GS_HIL_E_CONFIG);
    f = spec_of(GS_HIL_FAULT_COUNTER_STOP, "GearFbBase", -1, 0, 10); /* no counter */
    assert_int_equal(gs_hil_add_fault(&bridge, &f, &err), GS_HIL_E_CONFIG);
    f = spec_of(GS_HIL_FAULT_DELAY, "GearFbBase", 1, 0, 10);
    f.periods = GS_HIL_DELAY_MAX;
    assert_int_equal(gs_hil_add_fault(&bridge, &f, &err), GS_HIL_E_CONFIG);
    assert_string_equal(err.parameter, "periods");
    assert_int_equal(bridge.fault_count, 0);
}

/* ---- parameters at run time --------------------------------------------------------- */

static unsigned param_index(const char *key)
{
    unsigned index = 0, element = 0;
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, key, &index, &element), 0);
    return index;
}

static gs_hil_frame param_frame(unsigned id, unsigned element, double value)
{
    gs_hil_frame f;
    memset(&f, 0, sizeof f);
    f.id = 0x120;
    f.length = 8;
    const gs_hil_frame_spec *spec = &gs_hil_dbc_gear_rig.frames[frame_index("GearParam")];
    gs_hil_put_value(&spec->signals[0], (double)id, f.data);
    gs_hil_put_value(&spec->signals[1], (double)element, f.data);
    gs_hil_put_value(&spec->signals[2], value, f.data);
    return f;
}

static void test_parameter_list(void **unused)
{
    (void)unused;
    unsigned n = gs_hil_param_count(GS_RIG_SIMPLE_GEAR);
    assert_true(n > 5u);
    unsigned index = 99, element = 99;
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, "load_coulomb_friction", &index, &element), 0);
    assert_string_equal(gs_hil_param_key(GS_RIG_SIMPLE_GEAR, index), "load_coulomb_friction");
    assert_int_equal(element, 0);
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, "viscous_coefficients[1]", &index, &element), 0);
    assert_int_equal(element, 1);
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, "efficiency_matrix[2][3]", &index, &element), 0);
    assert_int_equal(element, 2u * GS_TABLE_MAX + 3u);
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, "viscous_coefficients[2]", &index, &element), -1);
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, "teeth_ratio", &index, &element), -1); /* fixed */
    assert_int_equal(gs_hil_param_parse(GS_RIG_SIMPLE_GEAR, "load_coulomb_friction[0]", &index, &element), -1);
    /* the rack rig names the driven side its own way */
    assert_int_equal(gs_hil_param_parse(GS_RIG_RACK_PINION, "load_coulomb_friction", &index, &element), 0);
    assert_int_equal(gs_hil_param_parse(GS_RIG_RACK_PINION, "idle_torque", &index, &element), -1);
    for (unsigned i = 0; i < n; ++i) {
        int is_rig = 0;
        const gs_param_info *e = gs_hil_param_info(GS_RIG_SIMPLE_GEAR, i, &is_rig);
        assert_non_null(e);
        assert_int_equal(e->flags, GS_PARAM_TUNABLE);
    }
    assert_null(gs_hil_param_info(GS_RIG_SIMPLE_GEAR, n, NULL));
}

/* A change requested before period k acts from period k + 1, and from there
 * the outputs are those of a rig started with the new parameters from the
 * state at that boundary. */
static void test_parameter_change_takes_effect_one_period_later(void **unused)
{
    (void)unused;
    init_bridge();
    const unsigned friction = param_index("load_coulomb_friction");
    for (uint64_t k = 0; k < 30; ++k) {
        gs_hil_frame f = command(10.0, 0.0, (double)k * 1e-3);
        gs_hil_handle(&bridge, &f);
        if (k == 20) {
            gs_hil_frame p = param_frame(friction, 0, 0.5);
            assert_int_equal(gs_hil_handle(&bridge, &p), GS_HIL_PENDING);
            assert_int_equal(gs_hil_pending(&bridge), 2);
        }
        gs_hil_advance(&bridge, 1);
        if (k == 20) {
            assert_true(bridge.consts == &consts); /* period 20: the old constants */
        }
        if (k == 21) {
            assert_true(bridge.consts != &consts);
            assert_float_equal(gs_hil_params(&bridge)->rig.load_coulomb_friction, 0.5, 0.0);
        }
    }
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_PARAM_CHANGES], 1);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_RX_USED], 31); /* 30 commands, 1 change */

    /* the same run by hand: the old rig to period 21, then a rig of the new parameters */
    gs_rig_consts a, b2;
    gs_rig_state s, scratch;
    memset(&s, 0, sizeof s); /* padding as in the bridge's (static) state: compared as bytes below */
    gs_error err;
    gs_rig_params changed = gs_rig_params_default();
    changed.dt_s = GS_R(1e-3);
    gs_simple_gear_params g = gs_simple_gear_params_default();
    assert_int_equal(gs_rig_init_gear(&a, &s, &g, &changed, &err), GS_OK);
    changed.load_coulomb_friction = GS_R(0.5);
    assert_int_equal(gs_rig_init_gear(&b2, &scratch, &g, &changed, &err), GS_OK);
    gs_rig_input in;
    memset(&in, 0, sizeof in);
    in.base_speed = GS_R(10.0);
    in.ambient_temperature = in.measured_temperature = GS_R(293.15);
    gs_rig_output o;
    for (int k = 0; k < 30; ++k) {
        gs_rig_step(k <= 20 ? &a : &b2, &s, &in, &o);
    }
    assert_memory_equal(&s, &state, sizeof s);
    assert_memory_equal(&o, &bridge.output, sizeof o);
}

static void test_parameter_refusals_are_counted_and_acknowledged(void **unused)
{
    (void)unused;
    init_bridge();
    gs_hil_frame unknown = param_frame(500, 0, 1.0);
    assert_int_equal(gs_hil_handle(&bridge, &unknown), GS_HIL_REJECTED_BAD_PARAM);
    gs_hil_frame negative = param_frame(param_index("load_coulomb_friction"), 0, -1.0); /* init refuses < 0 */
    assert_int_equal(gs_hil_handle(&bridge, &negative), GS_HIL_PENDING);
    gs_hil_advance(&bridge, 2);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_PARAM_REFUSED], 2);
    assert_int_equal(bridge.counters.reasons[GS_HIL_REJECTED_BAD_PARAM], 2);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_RX_REJECTED], 2);
    assert_true(bridge.consts == &consts); /* nothing changed */
    /* the acknowledgements: unknown_param at the end of period 0, invalid_value at the end of period 1 */
    const gs_hil_frame_spec *ack = &gs_hil_dbc_gear_rig.frames[frame_index("GearParamAck")];
    unsigned seen = 0;
    for (unsigned i = 0; i < out.count; ++i) {
        if (out.id[i] != 0x220u) {
            continue;
        }
        double result = gs_hil_signal_value(&ack->signals[2], out.data[i]);
        assert_int_equal(out.period[i], seen);
        assert_int_equal((int)result, seen == 0 ? GS_HIL_PARAM_UNKNOWN_PARAM : GS_HIL_PARAM_INVALID_VALUE);
        ++seen;
    }
    assert_int_equal(seen, 2);
    /* the queue holds GS_HIL_PARAM_QUEUE requests per period */
    for (unsigned k = 0; k <= GS_HIL_PARAM_QUEUE; ++k) {
        gs_hil_frame p = param_frame(param_index("load_offset"), 0, 0.001 * k);
        assert_int_equal(gs_hil_handle(&bridge, &p),
                         k < GS_HIL_PARAM_QUEUE ? GS_HIL_PENDING : GS_HIL_REJECTED_PARAM_BUSY);
    }
    gs_hil_advance(&bridge, 2);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_PARAM_CHANGES], GS_HIL_PARAM_QUEUE);
    assert_float_equal(gs_hil_params(&bridge)->rig.load_offset, (gs_real)(0.001 * (GS_HIL_PARAM_QUEUE - 1)), 0.0);
}

/* ---- scenarios -------------------------------------------------------------------------- */

static gs_hil_scenario scenario;

static void parse_fails(const char *text, const char *expected)
{
    gs_hil_error err;
    memset(&err, 0, sizeof err);
    assert_int_equal(
        gs_hil_scenario_parse(&scenario, text, strlen(text), "s.toml", &gs_hil_dbc_gear_rig, GS_RIG_SIMPLE_GEAR, &err),
        GS_HIL_E_CONFIG);
    if (strstr(err.message, expected) == NULL) {
        fail_msg("message \"%s\" lacks \"%s\"", err.message, expected);
    }
}

static void test_bad_scenarios_name_file_line_and_key(void **unused)
{
    (void)unused;
    const char head[] = "[scenario]\nduration = 1.0\n";
    char text[512];
    parse_fails("[[step]]\nat = 0.1\nload = 1\n", "s.toml:3: [scenario]: missing");
    parse_fails("[scenario]\nname = \"x\"\n", "s.toml:1: duration: missing (a number)");
    parse_fails("x = 1\n", "s.toml:1: x: outside a table");
    parse_fails("[scenario]\nduration = 1.0\nduration = 2\n", "s.toml:3: duration: given twice (first on line 2)");
    parse_fails("[scenarios]\n", "s.toml:1: [table]: unknown table 'scenarios'");
    parse_fails("[scenario]\nduration = [1, 2]\n", "s.toml:2: duration: arrays and inline tables");
    parse_fails("[scenario]\nduration = inf\n", "s.toml:2: duration: not a value");
    parse_fails("[scenario]\nduration = \"1\"\n", "s.toml:2: duration: expected a number");
    parse_fails("[scenario]\nduration = 1 2\n", "s.toml:2: duration: unexpected text after the value");
    const struct {
        const char *step, *expected;
    } bad[] = {
        {"[[step]]\nat = 0.1\n", "s.toml:3: [[step]]: needs one of load, param, fault, expect"},
        {"[[step]]\nat = 0.1\nload = 1\nparam = \"load_offset\"\n", "s.toml:6: param: one action per step"},
        {"[[step]]\nat = 2\nload = 1\n", "s.toml:4: at: 2 s is after the scenario's duration"},
        {"[[step]]\nload = 1\n", "s.toml:3: at: missing"},
        {"[[step]]\nat = 0\nfault = \"offset\"\nsignal = \"Nope\"\nvalue = 1\n",
         "s.toml:6: signal: 'Nope' is no feedback signal of gear_rig"},
        {"[[step]]\nat = 0\nfault = \"wobble\"\nsignal = \"BaseSpeed\"\n", "s.toml:5: fault: 'wobble' is no fault"},
        {"[[step]]\nat = 0\nfault = \"offset\"\nsignal = \"BaseSpeed\"\n", "s.toml:3: value: missing (a number)"},
        {"[[step]]\nat = 0\nfault = \"freeze\"\nsignal = \"BaseSpeed\"\nvalue = 2\n",
         "s.toml:7: value: not a key of a fault step"},
        {"[[step]]\nat = 0\nfault = \"drop\"\nframe = \"GearCmd\"\n",
         "s.toml:6: frame: 'GearCmd' is no feedback frame"},
        {"[[step]]\nat = 0.5\nfault = \"stuck\"\nsignal = \"BaseSpeed\"\nvalue = 1\nuntil = 0.2\n",
         "s.toml:8: until: a time after the step's 'at'"},
        {"[[step]]\nat = 0\nfault = \"stuck\"\nsignal = \"BaseSpeed\"\nvalue = 1\nwhen = \"BaseSpeed >> 3\"\n",
         "s.toml:8: when: expected 'Signal op number'"},
        {"[[step]]\nat = 0\nfault = \"delay\"\nsignal = \"BaseSpeed\"\nperiods = 0\n",
         "s.toml:7: periods: a whole number from 1 to 127"},
        {"[[step]]\nat = 0\nparam = \"teeth_ratio\"\nvalue = 2\n", "s.toml:5: param: 'teeth_ratio' is no tunable"},
        {"[[step]]\nat = 0\nexpect = \"BaseSpeed\"\nmin = 1\n", "s.toml:5: expect: 'BaseSpeed' is no command signal"},
        {"[[step]]\nat = 0\nexpect = \"DriveMode\"\nequals = \"fast\"\n", "s.toml:6: equals: 'fast'"},
        {"[[step]]\nat = 0\nexpect = \"BaseSpeedCmd\"\n", "s.toml:3: equals: an expect step needs equals, min or max"},
        {"[[step]]\nat = 0\nexpect = \"BaseSpeedCmd\"\nmin = 1\nwithin = 0.1\nuntil = 0.5\n",
         "s.toml:8: until: give within (eventually) or until (always), not both"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(text, sizeof text, "%s%s", head, bad[i].step);
        parse_fails(text, bad[i].expected);
    }
}

static void run_scenario(const char *text, double speed, uint64_t periods)
{
    init_bridge();
    gs_hil_error err;
    if (gs_hil_scenario_parse(&scenario, text, strlen(text), "campaign.toml", &gs_hil_dbc_gear_rig, GS_RIG_SIMPLE_GEAR,
                              &err) != GS_HIL_OK ||
        gs_hil_attach_scenario(&bridge, &scenario, &err) != GS_HIL_OK) {
        fail_msg("%s", err.message);
    }
    for (uint64_t k = 0; k < periods; ++k) {
        if (k % 10 == 0) {
            gs_hil_frame f = command(k >= 200 ? speed : 10.0, 0.0, (double)k * 1e-3);
            gs_hil_handle(&bridge, &f);
        }
        gs_hil_advance(&bridge, 1);
    }
    gs_hil_finish_scenario(&bridge);
}

static const char campaign[] =
    "# a campaign\n"
    "[scenario]\n"
    "name = \"gear & <campaign>\"\n"
    "duration = 0.5\n"
    "[[step]]\nat = 0.1\nload = 0.2\n"
    "[[step]]\nat = 0.15\nparam = \"load_offset\"\nvalue = 0.01\n"
    "[[step]]\nat = 0.1\nfault = \"offset\"\nsignal = \"BaseSpeed\"\nvalue = 1.5\nuntil = 0.2\n"
    "[[step]]\nat = 0.25\nexpect = \"BaseSpeedCmd\"\nmin = 4\nmax = 6\nwithin = 0.1\nname = \"speed drops\"\n"
    "[[step]]\nat = 0.05\nexpect = \"DriveMode\"\nequals = \"speed\"\nuntil = 0.4\n"
    "[[step]]\nat = 0.3\nexpect = \"fault_active\"\nequals = false\n";

static void test_scenario_verdict_and_junit(void **unused)
{
    (void)unused;
    char xml[8192];
    /* a controller that drops to 5 rad/s at 0.2 s: every expectation passes */
    run_scenario(campaign, 5.0, 500);
    unsigned passed, failed, pending;
    gs_hil_verdict_counts(&bridge, &passed, &failed, &pending);
    assert_int_equal(passed, 3);
    assert_int_equal(failed, 0);
    assert_float_equal(bridge.input.load, 0.2, 1e-12);                            /* the load profile */
    assert_float_equal(gs_hil_params(&bridge)->rig.load_offset, GS_R(0.01), 0.0); /* the parameter step */
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_FAULTS], 10);             /* frames of periods 109..199 */
    size_t n = gs_hil_junit(&bridge, xml, sizeof xml);
    assert_true(n < sizeof xml && n == strlen(xml));
    assert_non_null(strstr(xml, "<testsuite name=\"gear &amp; &lt;campaign&gt;\" tests=\"3\" failures=\"0\""));
    assert_non_null(strstr(xml, "<testcase name=\"speed drops\""));
    /* one that does not: the within expectation fails, with what it saw */
    run_scenario(campaign, 8.0, 500);
    gs_hil_verdict_counts(&bridge, &passed, &failed, &pending);
    assert_int_equal(passed, 2);
    assert_int_equal(failed, 1);
    n = gs_hil_junit(&bridge, xml, sizeof xml);
    assert_non_null(strstr(xml, "failures=\"1\""));
    assert_non_null(strstr(xml, "message=\"never BaseSpeedCmd in [4, 6] from 0.25 s to 0.35 s (last: 8)\""));
    /* a run that ends inside a window: incomplete */
    run_scenario(campaign, 5.0, 300);
    gs_hil_verdict_counts(&bridge, &passed, &failed, &pending);
    assert_int_equal(failed, 2); /* DriveMode until 0.4 s; fault_active at 0.3 s not reached */
    gs_hil_junit(&bridge, xml, sizeof xml);
    assert_non_null(strstr(xml, "type=\"incomplete\""));
    /* the text is cut, never overrun, in a small buffer */
    char small[64];
    assert_int_equal(gs_hil_junit(&bridge, small, sizeof small), strlen(xml));
    assert_int_equal(strlen(small), sizeof small - 1u);
}

static void test_scenario_refuses_a_value_the_rig_refuses(void **unused)
{
    (void)unused;
    const char text[] = "[scenario]\nduration = 1\n[[step]]\nat = 0.2\nparam = \"load_coulomb_friction\"\n"
                        "value = -3\n";
    init_bridge();
    gs_hil_error err;
    assert_int_equal(
        gs_hil_scenario_parse(&scenario, text, strlen(text), "p.toml", &gs_hil_dbc_gear_rig, GS_RIG_SIMPLE_GEAR, &err),
        GS_HIL_OK);
    assert_int_equal(gs_hil_attach_scenario(&bridge, &scenario, &err), GS_HIL_E_CONFIG);
    if (strstr(err.message, "p.toml:6: value: load_coulomb_friction = -3 refused by the rig") == NULL) {
        fail_msg("%s", err.message);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_value_faults),
        cmocka_unit_test(test_noise_is_seeded),
        cmocka_unit_test(test_frame_faults),
        cmocka_unit_test(test_corrupt_flips_bits),
        cmocka_unit_test(test_counter_stop_and_status_flag),
        cmocka_unit_test(test_trigger_on_a_condition),
        cmocka_unit_test(test_faults_refused),
        cmocka_unit_test(test_parameter_list),
        cmocka_unit_test(test_parameter_change_takes_effect_one_period_later),
        cmocka_unit_test(test_parameter_refusals_are_counted_and_acknowledged),
        cmocka_unit_test(test_bad_scenarios_name_file_line_and_key),
        cmocka_unit_test(test_scenario_verdict_and_junit),
        cmocka_unit_test(test_scenario_refuses_a_value_the_rig_refuses),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
