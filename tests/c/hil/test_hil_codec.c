/*
 * The C HIL library (gearsim/hil.h) on the shipped gear DBC: the codec's
 * range checks and saturation, with bytes worked out by hand from the DBC
 * (Intel order, two's complement), the bridge's fault classes, timeout and
 * safe state, feedback cycles and status, and the replay timing rule.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <string.h>

#include <cmocka.h>

#include "gearsim/hil.h"
#include "gearsim/hil_dbc.h"

#define GEAR_CMD 0u /* GearCmd is the first frame of gear_rig.dbc */

static const gs_hil_frame_spec *frame_named(const char *name)
{
    for (unsigned i = 0; i < gs_hil_dbc_gear_rig.frame_count; ++i) {
        if (strcmp(gs_hil_dbc_gear_rig.frames[i].name, name) == 0) {
            return &gs_hil_dbc_gear_rig.frames[i];
        }
    }
    fail_msg("no frame %s", name);
    return NULL;
}

static void test_decode_valid_command(void **unused)
{
    (void)unused;
    /* BaseSpeedCmd 10.000 rad/s = raw 10000 = 0x002710; LoadTorqueCmd -0.5 N*m =
     * raw -500 = 0xFE0C (16 bits at byte 5); DriveMode Speed = 1 at bit 56 */
    const uint8_t data[8] = {0x10, 0x27, 0x00, 0x00, 0x00, 0x0C, 0xFE, 0x01};
    gs_hil_command cmd;
    assert_int_equal(gs_hil_decode_command(frame_named("GearCmd"), data, 8, &cmd), GS_HIL_PENDING);
    assert_true(cmd.present[GS_HIL_CMD_BASE_SPEED] && cmd.present[GS_HIL_CMD_LOAD]);
    assert_float_equal(cmd.value[GS_HIL_CMD_BASE_SPEED], 10.0, 1e-12);
    assert_float_equal(cmd.value[GS_HIL_CMD_LOAD], -0.5, 1e-12);
    assert_float_equal(cmd.value[GS_HIL_CMD_MODE], (double)GS_HIL_MODE_SPEED, 0.0);
}

static void test_decode_rejections(void **unused)
{
    (void)unused;
    const gs_hil_frame_spec *cmd_frame = frame_named("GearCmd");
    gs_hil_command cmd;
    /* 0x7FFFFF * 0.001 = 8388.607 rad/s, outside [-1000, 1000]: rejected, not wrapped */
    const uint8_t too_fast[8] = {0xFF, 0xFF, 0x7F, 0, 0, 0, 0, 0x01};
    assert_int_equal(gs_hil_decode_command(cmd_frame, too_fast, 8, &cmd), GS_HIL_REJECTED_OUT_OF_RANGE);
    assert_int_equal(cmd.signal, 0); /* BaseSpeedCmd decided it */
    /* 1000.001 rad/s = raw 1000001 = 0x0F4241: just outside */
    const uint8_t just_outside[8] = {0x41, 0x42, 0x0F, 0, 0, 0, 0, 0x01};
    assert_int_equal(gs_hil_decode_command(cmd_frame, just_outside, 8, &cmd), GS_HIL_REJECTED_OUT_OF_RANGE);
    /* 1000.000 rad/s = 0x0F4240: the limit itself is valid */
    const uint8_t at_limit[8] = {0x40, 0x42, 0x0F, 0, 0, 0, 0, 0x01};
    assert_int_equal(gs_hil_decode_command(cmd_frame, at_limit, 8, &cmd), GS_HIL_PENDING);
    /* DriveMode 3 has no name in the value table */
    const uint8_t mode3[8] = {0, 0, 0, 0, 0, 0, 0, 0x03};
    assert_int_equal(gs_hil_decode_command(cmd_frame, mode3, 8, &cmd), GS_HIL_REJECTED_UNDECODABLE);
    assert_int_equal(cmd.signal, 3); /* DriveMode */
    assert_int_equal(gs_hil_decode_command(cmd_frame, mode3, 4, &cmd), GS_HIL_REJECTED_BAD_LENGTH);
    assert_int_equal(cmd.signal, -1);
}

static void test_encode_saturates_and_rounds(void **unused)
{
    (void)unused;
    const gs_hil_signal *torque = &frame_named("GearFbBase")->signals[0]; /* BaseTorque 0|24 s 1e-4 */
    uint8_t data[8] = {0};
    /* -1.23456 N*m / 1e-4 = -12345.6 -> -12346 = 0xFFCFC6 (24-bit two's complement) */
    assert_int_equal(gs_hil_put_value(torque, -1.23456, data), 0);
    assert_int_equal(data[0], 0xC6);
    assert_int_equal(data[1], 0xCF);
    assert_int_equal(data[2], 0xFF);
    assert_int_equal(data[3], 0x00);
    /* 1000 N*m is above 838.8607: clamped to raw 0x7FFFFF and reported */
    assert_int_equal(gs_hil_put_value(torque, 1000.0, data), 1);
    assert_int_equal(data[0], 0xFF);
    assert_int_equal(data[1], 0xFF);
    assert_int_equal(data[2], 0x7F);
    assert_float_equal(gs_hil_signal_value(torque, data), 838.8607, 1e-9);
    /* NaN: the value in range nearest 0 */
    assert_int_equal(gs_hil_put_value(torque, (double)NAN, data), 1);
    assert_int_equal(data[0] | data[1] | data[2], 0);
}

/* ---- the bridge ------------------------------------------------------------ */

typedef struct {
    unsigned sent;
    uint32_t last_id;
    uint8_t last_data[8];
    uint8_t counters_data[8]; /* the last GearCounters frame */
} sink;

static int capture(void *context, const gs_hil_frame *frame)
{
    sink *s = context;
    s->sent++;
    s->last_id = frame->id;
    memcpy(s->last_data, frame->data, 8);
    if (frame->id == 0x211u) {
        memcpy(s->counters_data, frame->data, 8);
    }
    return 0;
}

static gs_rig_consts consts;
static gs_rig_state state;
static gs_hil_bridge bridge;
static sink out;

static void init_gear_bridge(double timeout_s)
{
    gs_simple_gear_params gear = gs_simple_gear_params_default();
    gs_rig_params rp = gs_rig_params_default();
    gs_error err;
    assert_int_equal(gs_rig_init_gear(&consts, &state, &gear, &rp, &err), GS_OK);
    gs_hil_config config;
    memset(&config, 0, sizeof config);
    config.dbc = &gs_hil_dbc_gear_rig;
    config.base_drive = GS_BASE_SPEED_DRIVEN;
    config.dt_s = rp.dt_s;
    config.substeps = 1;
    config.timeout_s = timeout_s;
    config.ambient_temperature_K = GS_R(293.15);
    config.send = capture;
    config.send_context = &out;
    memset(&out, 0, sizeof out);
    gs_hil_error herr;
    assert_int_equal(gs_hil_bridge_init(&bridge, &config, GS_RIG_SIMPLE_GEAR, &consts, &state, &herr), GS_HIL_OK);
}

static gs_hil_frame frame_of(uint32_t id, const uint8_t *data, unsigned length, double t)
{
    gs_hil_frame f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.length = length;
    f.timestamp_s = t;
    if (data != NULL) {
        memcpy(f.data, data, length);
    }
    return f;
}

static const uint8_t speed10[8] = {0x10, 0x27, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01};

static void test_fault_classes(void **unused)
{
    (void)unused;
    init_gear_bridge(0.1);
    const uint8_t torque_mode[8] = {0, 0, 0, 0, 0, 0, 0, 0x02};
    gs_hil_frame f = frame_of(0x100, speed10, 8, 1.0);
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_PENDING);
    f.timestamp_s = 0.5;
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_LATE_OUT_OF_ORDER);
    f.timestamp_s = 1.1;
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_PENDING); /* the first one: superseded */
    f.is_extended = 1;
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_REJECTED_UNKNOWN_ID);
    f = frame_of(0x100, torque_mode, 8, 1.2);
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_REJECTED_MODE_MISMATCH);
    f = frame_of(0x201, NULL, 8, 1.2);
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_IGNORED_FEEDBACK_ID);
    f.is_remote = 1;
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_IGNORED_REMOTE_FRAME);
    f.is_error = 1;
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_IGNORED_ERROR_FRAME);
    gs_hil_advance(&bridge, 1); /* applies the pending command */
    f = frame_of(0x100, speed10, 8, 2.0);
    assert_int_equal(gs_hil_handle(&bridge, &f), GS_HIL_PENDING);
    gs_hil_close(&bridge); /* pending at the stop: late */
    const uint64_t *c = bridge.counters.count;
    assert_int_equal(c[GS_HIL_COUNT_RX_TOTAL], 9);
    assert_int_equal(c[GS_HIL_COUNT_RX_USED], 1);
    assert_int_equal(c[GS_HIL_COUNT_RX_REJECTED], 2);
    assert_int_equal(c[GS_HIL_COUNT_RX_LATE], 3);
    assert_int_equal(c[GS_HIL_COUNT_RX_IGNORED], 3);
    assert_int_equal(bridge.counters.reasons[GS_HIL_LATE_SUPERSEDED], 1);
    assert_int_equal(bridge.counters.reasons[GS_HIL_LATE_AFTER_STOP], 1);
}

static void test_timeout_safe_state_and_recovery(void **unused)
{
    (void)unused;
    init_gear_bridge(0.005); /* 5 periods of 1 ms */
    gs_hil_advance(&bridge, 3);
    assert_true(bridge.flag_state[GS_HIL_FLAG_CMD_TIMEOUT]); /* before the first command */
    gs_hil_frame f = frame_of(0x100, speed10, 8, 0.0);
    gs_hil_handle(&bridge, &f);
    gs_hil_advance(&bridge, 1); /* applied at period 3 */
    assert_false(bridge.flag_state[GS_HIL_FLAG_SAFE_STATE]);
    assert_float_equal(bridge.input.base_speed, 10.0, 1e-12);
    gs_hil_advance(&bridge, 5); /* periods 4..8: 5 periods since: still fresh */
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_TIMEOUTS], 0);
    gs_hil_advance(&bridge, 1); /* period 9: 6 > 5 periods: timeout, safe state, base stopped */
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_TIMEOUTS], 1);
    assert_true(bridge.flag_state[GS_HIL_FLAG_SAFE_STATE]);
    assert_float_equal(bridge.input.base_speed, 0.0, 0.0);
    assert_float_equal(bridge.output.base_speed, 0.0, 0.0);
    f.timestamp_s = 1.0;
    gs_hil_handle(&bridge, &f);
    gs_hil_advance(&bridge, 1);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_RECOVERIES], 1);
    assert_false(bridge.flag_state[GS_HIL_FLAG_CMD_TIMEOUT]);
}

static void test_feedback_cycles_and_status(void **unused)
{
    (void)unused;
    init_gear_bridge(0.1);
    gs_hil_advance(&bridge, 10); /* 10 ms: GearFbBase and GearFbFollower */
    assert_int_equal(out.sent, 2);
    gs_hil_advance(&bridge, 90); /* 100 ms: 10 x 2 + thermal, status, counters, faults */
    assert_int_equal(out.sent, 24);
    assert_int_equal(out.last_id, 0x212);
    /* GearCounters: TxFrames (16|16) counts the 22 frames sent before it */
    assert_int_equal(out.counters_data[2] | (out.counters_data[3] << 8), 22);
    /* GearFaults: no fault, no parameter change, nothing dropped */
    for (unsigned k = 0; k < 8; ++k) {
        assert_int_equal(out.last_data[k], 0);
    }
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_TX_FRAMES], 24);
}

/* Replay in log time: a frame t after the log's first is handled at the
 * first period boundary at or after t, within 1 us. Times are multiples of
 * the bridge's own period (1 ms as gs_real: 0.0010000000474974513 s in the
 * float build), which (m * p) / p gives back exactly for these m. */
static void test_replay_timing(void **unused)
{
    (void)unused;
    init_gear_bridge(0.1);
    const double p = bridge.period_s;
    assert_int_equal(gs_hil_period_at(&bridge, 0.0), 0);
    assert_int_equal(gs_hil_period_at(&bridge, 0.5 * p), 1);
    assert_int_equal(gs_hil_period_at(&bridge, p), 1);
    assert_int_equal(gs_hil_period_at(&bridge, p + 0.9e-6), 1); /* within the slack */
    assert_int_equal(gs_hil_period_at(&bridge, p + 1.1e-6), 2);
    assert_int_equal(gs_hil_period_at(&bridge, -5.0), 0);
    gs_hil_advance_to(&bridge, 2.5 * p);
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_PERIODS], 3);
    gs_hil_advance_to(&bridge, p); /* passed: nothing */
    assert_int_equal(bridge.counters.count[GS_HIL_COUNT_PERIODS], 3);
    assert_int_equal(gs_hil_periods_in(&bridge, 2.5 * p), 2); /* half to even */
    assert_int_equal(gs_hil_periods_in(&bridge, 3.5 * p), 4);
    assert_int_equal(gs_hil_periods_in(&bridge, -1.0), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decode_valid_command),
        cmocka_unit_test(test_decode_rejections),
        cmocka_unit_test(test_encode_saturates_and_rounds),
        cmocka_unit_test(test_fault_classes),
        cmocka_unit_test(test_timeout_safe_state_and_recovery),
        cmocka_unit_test(test_feedback_cycles_and_status),
        cmocka_unit_test(test_replay_timing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
