/*
 * What a frame table may say (gearsim/hil.h, hil/src/dbc.c) and how its
 * signals are packed (hil/src/codec.c): the names of the lists, role and
 * mode names parsed, every rule of gs_hil_dbc_check refused with a message
 * naming frame and signal (tables written here by hand), the built-in
 * tables accepted, frame kinds and sending order, and big-endian and float
 * signals with bytes worked out by hand, plus a seeded random round trip of
 * raw values through every layout.
 */
#include "test_common.h"

#include "gearsim/hil.h"
#include "gearsim/hil_dbc.h"

static void test_names_come_from_the_lists(void **unused)
{
    (void)unused;
    assert_string_equal(gs_hil_role_name(GS_HIL_ROLE_CMD_LOAD), "cmd.load");
    assert_string_equal(gs_hil_role_name(GS_HIL_ROLE_STATUS_FLAG), "status.flag.");
    assert_string_equal(gs_hil_mode_name(GS_HIL_MODE_TORQUE), "torque");
    assert_string_equal(gs_hil_flag_name(GS_HIL_FLAG_TX_ERROR), "tx_error");
    assert_string_equal(gs_hil_count_name(GS_HIL_COUNT_PERIODS), "periods");
    assert_string_equal(gs_hil_reason_name(GS_HIL_IGNORED_REMOTE_FRAME), "ignored.remote_frame");
    assert_string_equal(gs_hil_reason_name(GS_HIL_REASONS), "?");
    assert_int_equal(GS_HIL_STATE_FLAGS + GS_HIL_LATCHED_FLAGS, GS_HIL_FLAGS);
}

static void test_role_parse(void **unused)
{
    (void)unused;
    gs_hil_role role;
    size_t aux;
    assert_int_equal(gs_hil_role_parse("cmd.base_speed", &role, &aux), 0);
    assert_int_equal(role, GS_HIL_ROLE_CMD_BASE_SPEED);
    assert_int_equal(gs_hil_role_parse("out.follower_angle", &role, &aux), 0); /* not an output field */
    assert_int_equal(role, GS_HIL_ROLE_OUT_FOLLOWER_ANGLE);
    assert_int_equal(gs_hil_role_parse("out.temperature", &role, &aux), 0);
    assert_int_equal(role, GS_HIL_ROLE_OUT);
    assert_int_equal(aux, GS_HIL_OUTPUT_INDEX(temperature));
    assert_int_equal(gs_hil_role_parse("status.flag.fb_saturated", &role, &aux), 0);
    assert_int_equal(role, GS_HIL_ROLE_STATUS_FLAG);
    assert_int_equal(aux, GS_HIL_FLAG_FB_SATURATED);
    assert_int_equal(gs_hil_role_parse("status.count.recoveries", &role, &aux), 0);
    assert_int_equal(aux, GS_HIL_COUNT_RECOVERIES);
    const char *unknown[] = {
        "",       "out.",          "out.warp_speed", "status.flag.rx_used", "status.count.", "cmd.base_speed ",
        "status", "in.temperature"};
    for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        assert_int_equal(gs_hil_role_parse(unknown[i], &role, &aux), -1);
        assert_int_equal(role, GS_HIL_ROLE_NONE);
    }
}

static void test_mode_parse(void **unused)
{
    (void)unused;
    assert_int_equal(gs_hil_mode_parse("Speed"), GS_HIL_MODE_SPEED);
    assert_int_equal(gs_hil_mode_parse("  TORQUE "), GS_HIL_MODE_TORQUE);
    assert_int_equal(gs_hil_mode_parse("Off"), GS_HIL_MODE_DISABLED);
    assert_int_equal(gs_hil_mode_parse("safe"), GS_HIL_MODE_DISABLED);
    assert_int_equal(gs_hil_mode_parse("Disable"), GS_HIL_MODE_DISABLED);
    assert_int_equal(gs_hil_mode_parse("Fast"), -1);
    assert_int_equal(gs_hil_mode_parse(""), -1);
    assert_int_equal(gs_hil_mode_parse("speedy"), -1);
}

static void test_builtin_tables_pass_and_have_kinds(void **unused)
{
    (void)unused;
    gs_hil_error err;
    assert_int_equal(gs_hil_dbc_check(&gs_hil_dbc_gear_rig, &err), GS_HIL_OK);
    assert_int_equal(gs_hil_dbc_check(&gs_hil_dbc_rack_rig, &err), GS_HIL_OK);
    const gs_hil_dbc *d = &gs_hil_dbc_gear_rig;
    assert_int_equal(gs_hil_frame_kind_of(&d->frames[0]), GS_HIL_FRAME_COMMAND); /* GearCmd */
    unsigned order[GS_HIL_MAX_FRAMES];
    assert_int_equal(gs_hil_feedback_order(d, order), 6);
    /* data frames by ID, then status frames by ID; not the parameter acknowledgement */
    const uint32_t ids[6] = {0x200, 0x201, 0x202, 0x210, 0x211, 0x212};
    for (unsigned k = 0; k < 6; ++k) {
        assert_int_equal(d->frames[order[k]].id, ids[k]);
        assert_int_equal(gs_hil_frame_is_status(&d->frames[order[k]]), k >= 3);
    }
}

/* ---- one-frame tables that break a rule ---------------------------------- */

static gs_hil_signal sig(const char *name, unsigned start, unsigned length, int is_signed, double scale, double minimum,
                         double maximum, gs_hil_role role, size_t aux)
{
    gs_hil_signal s;
    memset(&s, 0, sizeof s);
    s.name = name;
    s.start = start;
    s.length = length;
    s.is_signed = is_signed;
    s.scale = scale;
    s.minimum = minimum;
    s.maximum = maximum;
    s.role = role;
    s.aux = aux;
    return s;
}

static gs_hil_frame_spec frame(const char *name, uint32_t id, unsigned length, unsigned cycle_ms,
                               const gs_hil_signal *signals, unsigned count)
{
    gs_hil_frame_spec f;
    memset(&f, 0, sizeof f);
    f.name = name;
    f.id = id;
    f.length = length;
    f.cycle_ms = cycle_ms;
    f.signals = signals;
    f.signal_count = count;
    return f;
}

static void refused(const gs_hil_frame_spec *frames, unsigned count, const char *expected)
{
    gs_hil_dbc d = {"test", GS_RIG_SIMPLE_GEAR, frames, count};
    gs_hil_error err;
    memset(&err, 0, sizeof err);
    assert_int_equal(gs_hil_dbc_check(&d, &err), GS_HIL_E_CONFIG);
    assert_string_equal(err.parameter, "dbc");
    if (strstr(err.message, expected) == NULL) {
        fail_msg("message \"%s\" lacks \"%s\"", err.message, expected);
    }
}

static void test_every_rule_is_refused(void **unused)
{
    (void)unused;
    const double inf = HUGE_VAL;
    gs_hil_signal s[2];
    gs_hil_frame_spec f[2];
    /* a feedback range wider than 16 signed bits at 0.01: [-327.68, 327.67] */
    s[0] = sig("T", 0, 16, 1, 0.01, -500.0, 500.0, GS_HIL_ROLE_OUT, GS_HIL_OUTPUT_INDEX(base_torque));
    f[0] = frame("Fb", 0x200, 2, 10, s, 1);
    refused(f, 1, "Fb.T: range [-500, 500] does not fit 16 signed bits at scale 0.01 ([-327.68, 327.67])");
    /* ... which a command signal may have (it is range-checked, never encoded) */
    s[0].role = GS_HIL_ROLE_CMD_LOAD;
    s[0].aux = 0;
    gs_hil_error err;
    gs_hil_dbc ok = {"test", GS_RIG_SIMPLE_GEAR, f, 1};
    assert_int_equal(gs_hil_dbc_check(&ok, &err), GS_HIL_OK);
    s[0] = sig("T", 0, 16, 1, 0.01, -300.0, 300.0, GS_HIL_ROLE_OUT, GS_HIL_OUTPUT_INDEX(base_torque));
    f[0] = frame("Fb", 0x200, 2, 0, s, 1);
    refused(f, 1, "feedback frame Fb has no GenMsgCycleTime");
    f[0] = frame("Fb", 0x200, 2, 10, s, 1);
    f[0].is_multiplexed = 1;
    refused(f, 1, "Fb: multiplexed frames are not supported for commands, parameters or feedback");
    f[0] = frame("Fb", 0x200, 16, 10, s, 1);
    refused(f, 1, "Fb: 16 data bytes; command and feedback frames are classic CAN frames");
    f[0] = frame("Fb", 0x200, 1, 10, s, 1);
    refused(f, 1, "Fb.T: its 16 bits from bit 0 do not fit the frame's 1 bytes");
    s[0].is_float = 1;
    f[0] = frame("Fb", 0x200, 2, 10, s, 1);
    refused(f, 1, "Fb.T: a float signal has 32 or 64 bits, not 16");
    s[0] = sig("C", 0, 16, 1, 1.0, -inf, inf, GS_HIL_ROLE_STATUS_COUNT, GS_HIL_COUNT_RX_USED);
    f[0] = frame("St", 0x210, 2, 100, s, 1);
    refused(f, 1, "St.C: a counter must be an unsigned integer signal (scale 1, offset 0)");
    s[0] = sig("F", 0, 1, 0, 1.0, -inf, inf, GS_HIL_ROLE_STATUS_FLAG, GS_HIL_FLAG_OVERRUN);
    s[0].offset = 2.0;
    refused(f, 1, "St.F: a flag must hold 0 and 1");
    s[0] = sig("F", 0, 1, 0, 1.0, 0.0, 1.0, GS_HIL_ROLE_STATUS_FLAG, GS_HIL_FLAGS); /* no such flag */
    refused(f, 1, "St.F: role 11 (aux 12) is not a role of gearsim/hil.h");
    s[0] = sig("L", 0, 16, 1, 0.001, -30.0, 30.0, GS_HIL_ROLE_CMD_LOAD, 0);
    s[1] = sig("T", 16, 16, 1, 0.001, -30.0, 30.0, GS_HIL_ROLE_OUT, GS_HIL_OUTPUT_INDEX(base_torque));
    f[0] = frame("Mix", 0x100, 4, 10, s, 2);
    refused(f, 1, "Mix mixes command and feedback roles");
    s[1].role = GS_HIL_ROLE_CMD_LOAD;
    s[1].aux = 0;
    f[0] = frame("A", 0x100, 2, 0, &s[0], 1);
    f[1] = frame("B", 0x101, 4, 0, &s[1], 1);
    refused(f, 2, "command role 'cmd.load' is on A.L and on B.T");
    static const gs_hil_choice names[3] = {{0, "Off"}, {1, "Fast"}, {2, "Torque"}};
    s[0] = sig("M", 0, 2, 0, 1.0, 0.0, 2.0, GS_HIL_ROLE_CMD_MODE, 0);
    s[0].choices = names;
    s[0].choice_count = 3;
    f[0] = frame("Cmd", 0x100, 1, 0, s, 1);
    refused(f, 1, "Cmd.M: mode value 1 is named 'Fast'; expected one of Disabled, Speed, Torque");
    s[0] = sig("X", 0, 8, 0, 1.0, 5.0, 1.0, GS_HIL_ROLE_NONE, 0);
    f[0] = frame("Other", 0x300, 1, 0, s, 1);
    refused(f, 1, "Other.X: minimum 5 > maximum 1");
}

/* ---- layouts: big-endian and float signals by hand --------------------------- */

static void test_big_endian_by_hand(void **unused)
{
    (void)unused;
    uint8_t data[8] = {0};
    /* 7|24@0- (0.0001,0): the most significant bit is bit 7 of byte 0; 1.2345 = raw 12345 = 0x003039 */
    gs_hil_signal t = sig("T", 7, 24, 1, 1e-4, -800.0, 800.0, GS_HIL_ROLE_OUT, 0);
    t.is_big_endian = 1;
    assert_int_equal(gs_hil_put_value(&t, 1.2345, data), 0);
    assert_int_equal(data[0], 0x00);
    assert_int_equal(data[1], 0x30);
    assert_int_equal(data[2], 0x39);
    assert_int_equal(data[3], 0x00);
    assert_float_equal(gs_hil_signal_value(&t, data), 1.2345, 1e-12);
    /* -1 = raw 0xFFFFD8F0 -> 24 bits 0xFFD8F0 */
    assert_int_equal(gs_hil_put_value(&t, -1.0, data), 0);
    assert_int_equal(data[0], 0xFF);
    assert_int_equal(data[1], 0xD8);
    assert_int_equal(data[2], 0xF0);
    /* 3|12@0+: the low nibble of byte 0, then byte 1; 0xABC */
    memset(data, 0, sizeof data);
    gs_hil_signal n = sig("N", 3, 12, 0, 1.0, -HUGE_VAL, HUGE_VAL, GS_HIL_ROLE_NONE, 0);
    n.is_big_endian = 1;
    gs_hil_put_raw(&n, 0xABCu, data);
    assert_int_equal(data[0], 0x0A);
    assert_int_equal(data[1], 0xBC);
    assert_int_equal(data[2], 0x00);
    /* 63|8@0+ (0.5,0): the whole of byte 7 */
    memset(data, 0, sizeof data);
    gs_hil_signal s = sig("S", 63, 8, 0, 0.5, 0.0, 100.0, GS_HIL_ROLE_OUT, 0);
    s.is_big_endian = 1;
    gs_hil_put_value(&s, 50.0, data);
    assert_int_equal(data[7], 0x64);
    assert_int_equal(data[6], 0x00);
}

static void test_float_by_hand(void **unused)
{
    (void)unused;
    uint8_t data[8] = {0};
    /* 24|32@1- float, offset 0.5: 4.0 is 3.5f = 0x40600000 in bytes 3..6 */
    gs_hil_signal f = sig("F", 24, 32, 1, 1.0, -1000.0, 1000.0, GS_HIL_ROLE_OUT, 0);
    f.is_float = 1;
    f.offset = 0.5;
    assert_int_equal(gs_hil_put_value(&f, 4.0, data), 0);
    const uint8_t want[8] = {0, 0, 0, 0x00, 0x00, 0x60, 0x40, 0};
    assert_memory_equal(data, want, 8);
    assert_float_equal(gs_hil_signal_value(&f, data), 4.0, 0.0);
    /* clamped, and never wrapped, like an integer signal */
    assert_int_equal(gs_hil_put_value(&f, 5000.0, data), 1);
    assert_float_equal(gs_hil_signal_value(&f, data), 1000.0, 0.0);
    /* 0|64@1- double: 1.0 = 0x3FF0000000000000 */
    gs_hil_signal d = sig("D", 0, 64, 1, 1.0, -HUGE_VAL, HUGE_VAL, GS_HIL_ROLE_OUT, 0);
    d.is_float = 1;
    memset(data, 0, sizeof data);
    assert_int_equal(gs_hil_put_value(&d, 1.0, data), 0);
    assert_int_equal(data[7], 0x3F);
    assert_int_equal(data[6], 0xF0);
    /* an infinity has no range to stay in: it counts as clamped */
    assert_int_equal(gs_hil_put_value(&d, HUGE_VAL, data), 1);
}

/* Random integer signals of every layout that fits 8 bytes: a raw value put
 * reads back, and the bits outside the signal stay as they were. */
static void test_raw_round_trip_every_layout(void **unused)
{
    (void)unused;
    test_rng seed = rng_seed(42u);
    for (int k = 0; k < 200000; ++k) {
        gs_hil_signal s = sig("R", 0, 1, 0, 1.0, -HUGE_VAL, HUGE_VAL, GS_HIL_ROLE_NONE, 0);
        s.length = 1u + (unsigned)(rng_next(&seed) % 64u);
        s.is_signed = (int)(rng_next(&seed) % 2u);
        s.is_big_endian = (int)(rng_next(&seed) % 2u);
        unsigned first = (unsigned)(rng_next(&seed) % (65u - s.length)); /* first bit from the frame's start */
        s.start = s.is_big_endian ? (first / 8u) * 8u + 7u - first % 8u : first;
        uint8_t data[8], before[8];
        for (unsigned i = 0; i < 8; ++i) {
            data[i] = before[i] = (uint8_t)rng_next(&seed);
        }
        uint64_t mask = s.length == 64u ? ~(uint64_t)0 : (((uint64_t)1 << s.length) - 1u);
        uint64_t raw = rng_next(&seed) & mask;
        gs_hil_put_raw(&s, raw, data);
        double v = gs_hil_signal_value(&s, data);
        int64_t expected = (int64_t)raw;
        if (s.is_signed && s.length < 64u && (raw >> (s.length - 1u)) != 0u) {
            expected = (int64_t)(raw | ~mask);
        }
        assert_false(v < (double)expected || v > (double)expected); /* the same double */
        gs_hil_put_raw(&s, 0, data);
        gs_hil_put_raw(&s, 0, before);
        assert_memory_equal(data, before, 8);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names_come_from_the_lists),
        cmocka_unit_test(test_role_parse),
        cmocka_unit_test(test_mode_parse),
        cmocka_unit_test(test_builtin_tables_pass_and_have_kinds),
        cmocka_unit_test(test_every_rule_is_refused),
        cmocka_unit_test(test_big_endian_by_hand),
        cmocka_unit_test(test_float_by_hand),
        cmocka_unit_test(test_raw_round_trip_every_layout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
