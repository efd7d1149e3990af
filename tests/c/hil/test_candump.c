/*
 * The runner's candump -L codec (hil/runner/candump.c): lines written by hand
 * as python-can and can-utils write them, the frames they are, the lines
 * that are not frames, and a seeded random round trip frame -> line -> frame.
 */
#include "test_common.h"

#include "candump.h"

static gs_hil_frame parsed(const char *line)
{
    gs_hil_frame f;
    assert_int_equal(candump_parse_line(line, strlen(line), &f), 0);
    return f;
}

static void test_standard_and_extended_frames(void **unused)
{
    (void)unused;
    gs_hil_frame f = parsed("(1700000000.123456) can0 100#1027000000000001\n");
    assert_int_equal(f.id, 0x100);
    assert_false(f.is_extended || f.is_remote || f.is_error);
    assert_int_equal(f.length, 8);
    assert_int_equal(f.data[0], 0x10);
    assert_int_equal(f.data[1], 0x27);
    assert_int_equal(f.data[7], 0x01);
    assert_float_equal(f.timestamp_s, 1700000000.123456, 1e-6);
    /* more than three ID digits: extended (python-can's rule), trailing " R"/" T" ignored */
    f = parsed("(0.5) vcan0 000001AB#0102 T");
    assert_true(f.is_extended);
    assert_int_equal(f.id, 0x1AB);
    assert_int_equal(f.length, 2);
    /* no data */
    f = parsed("(2) can0 7FF#");
    assert_int_equal(f.id, 0x7FF);
    assert_int_equal(f.length, 0);
}

static void test_remote_error_and_fd_frames(void **unused)
{
    (void)unused;
    gs_hil_frame f = parsed("(0.0) can0 100#R");
    assert_true(f.is_remote);
    assert_int_equal(f.id, 0x100);
    /* CAN_ERR_FLAG | CAN_ERR_BUSERROR, as python-can writes an error frame */
    f = parsed("(0.0) can0 200000FF#");
    assert_true(f.is_error);
    /* CAN FD "##<flags>": 12 data bytes kept as a length (the bridge: bad_length), 8 stored */
    f = parsed("(1.0) can0 100##1000102030405060708090A0B");
    assert_int_equal(f.length, 12);
    assert_int_equal(f.data[7], 0x07);
}

static void test_lines_that_are_not_frames(void **unused)
{
    (void)unused;
    const char *bad[] = {
        "this is not a frame",
        "1.0 can0 100#01",           /* stamp without parentheses */
        "(1.0e3) can0 100#01",       /* no exponent */
        "(1.0) can0 100#012",        /* odd number of hex digits */
        "(1.0) can0 #01",            /* no ID */
        "(1.0) can0 123456789#01",   /* nine ID digits */
        "(1.0) can0 10G#01",         /* not hex */
        "(1.0) can0 100#01 T extra", /* five fields */
        "(1.0) can0",                /* two fields */
    };
    gs_hil_frame f;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        assert_int_equal(candump_parse_line(bad[i], strlen(bad[i]), &f), -1);
    }
    assert_true(candump_is_blank(" \t\r\n", 4));
    assert_false(candump_is_blank("  x ", 4));
}

static void test_format_as_python_can(void **unused)
{
    (void)unused;
    gs_hil_frame f;
    memset(&f, 0, sizeof f);
    f.id = 0x201;
    f.length = 3;
    f.data[0] = 0xAB;
    f.data[1] = 0x01;
    f.data[2] = 0xFF;
    char line[128];
    size_t n = candump_format_line(&f, 1700000000.25, "can0", line, sizeof line);
    line[n] = '\0'; /* the codec writes the line's bytes only */
    /* 6 decimals, upper-case hex, " T": sent */
    assert_string_equal(line, "(1700000000.250000) can0 201#AB01FF T\n");
    n = candump_format_line(&f, 3.0000004999, "can0", line, sizeof line);
    line[n] = '\0';
    assert_string_equal(line, "(3.000000) can0 201#AB01FF T\n"); /* rounded to the microsecond */
    f.is_extended = 1;
    f.id = 0x1ABCDE;
    f.length = 0;
    n = candump_format_line(&f, 2.5, "vcan0", line, sizeof line);
    line[n] = '\0';
    assert_string_equal(line, "(2.500000) vcan0 001ABCDE# T\n");
    /* no room, or a stamp outside [0, 1e12): nothing */
    assert_int_equal(candump_format_line(&f, 2.5, "vcan0", line, 16), 0);
    assert_int_equal(candump_format_line(&f, -1.0, "vcan0", line, sizeof line), 0);
}

/* Random classic frames written and read back: the same ID, kind, data, and
 * the stamp to the microsecond. */
static void test_round_trip(void **unused)
{
    (void)unused;
    test_rng seed = rng_seed(20261126u);
    for (int k = 0; k < 20000; ++k) {
        gs_hil_frame f;
        memset(&f, 0, sizeof f);
        f.is_extended = (int)(rng_next(&seed) % 2u);
        f.id = (uint32_t)(rng_next(&seed) & (f.is_extended ? 0x1FFFFFFFu : 0x7FFu));
        f.length = (unsigned)(rng_next(&seed) % 9u);
        for (unsigned i = 0; i < f.length; ++i) {
            f.data[i] = (uint8_t)rng_next(&seed);
        }
        double stamp = (double)(rng_next(&seed) % 2000000000000000u) * 1e-6; /* whole microseconds below 2e9 s */
        char line[128];
        size_t n = candump_format_line(&f, stamp, "can0", line, sizeof line);
        assert_true(n > 0);
        gs_hil_frame g;
        assert_int_equal(candump_parse_line(line, n, &g), 0);
        assert_int_equal(g.is_extended, f.is_extended); /* 8 ID digits or 3 */
        assert_int_equal(g.id, f.id);
        assert_int_equal(g.length, f.length);
        assert_memory_equal(g.data, f.data, f.length);
        assert_float_equal(g.timestamp_s, stamp, 1e-6);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_standard_and_extended_frames),
        cmocka_unit_test(test_remote_error_and_fd_frames),
        cmocka_unit_test(test_lines_that_are_not_frames),
        cmocka_unit_test(test_format_as_python_can),
        cmocka_unit_test(test_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
