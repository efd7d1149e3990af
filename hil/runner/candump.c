/*
 * The candump -L text format (docs/hil-runner.md, "Transports"): one classic
 * CAN frame a line, as python-can's .log files and can-utils write it. Pure
 * text to frame and back: no I/O, no heap, no stdio, so that the paced loop
 * can format its answers.
 */
#include "candump.h"

#include <math.h>
#include <string.h>

/* python-can marks error frames with these bits of the ID (can/io/canutils.py). */
#define CANDUMP_ERR_FLAG     0x20000000u
#define CANDUMP_ERR_BUSERROR 0x00000080u

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

int candump_is_blank(const char *line, size_t length)
{
    for (size_t k = 0; k < length; ++k) {
        if (!is_space(line[k])) {
            return 0;
        }
    }
    return 1;
}

/* "(seconds)" as a double: digits, one optional '.', digits (no exponent). */
static int parse_stamp(const char *s, const char *end, double *value)
{
    double whole = 0.0, scale = 1.0, frac = 0.0;
    int digits = 0, dot = 0;
    for (; s < end; ++s) {
        if (*s == '.' && !dot) {
            dot = 1;
        } else if (*s >= '0' && *s <= '9') {
            if (dot) {
                scale /= 10.0;
                frac += (double)(*s - '0') * scale;
            } else {
                whole = whole * 10.0 + (double)(*s - '0');
            }
            ++digits;
        } else {
            return -1;
        }
    }
    *value = whole + frac;
    return digits > 0 ? 0 : -1;
}

int candump_parse_line(const char *line, size_t length, gs_hil_frame *frame)
{
    const char *p = line, *end = line + length;
    const char *tok[4];
    const char *tok_end[4];
    int n = 0;
    while (p < end) {
        while (p < end && is_space(*p)) {
            ++p;
        }
        if (p == end) {
            break;
        }
        if (n == 4) {
            return -1;
        }
        tok[n] = p;
        while (p < end && !is_space(*p)) {
            ++p;
        }
        tok_end[n++] = p;
    }
    if (n < 3 || tok[0][0] != '(' || tok_end[0][-1] != ')') {
        return -1;
    }
    memset(frame, 0, sizeof *frame);
    if (parse_stamp(tok[0] + 1, tok_end[0] - 1, &frame->timestamp_s) != 0) {
        return -1;
    }
    const char *f = tok[2], *fend = tok_end[2];
    const char *hash = memchr(f, '#', (size_t)(fend - f));
    if (hash == NULL || hash == f || hash - f > 8) {
        return -1;
    }
    uint32_t id = 0;
    for (const char *c = f; c < hash; ++c) {
        int d = hex_digit(*c);
        if (d < 0) {
            return -1;
        }
        id = (id << 4) | (uint32_t)d;
    }
    frame->is_extended = (hash - f) > 3; /* python-can's rule: more than 3 hex digits */
    const char *data = hash + 1;
    if (data < fend && *data == '#') { /* CAN FD: "##<flags><data>" */
        if (data + 1 >= fend || hex_digit(data[1]) < 0) {
            return -1;
        }
        data += 2;
    }
    if ((id & CANDUMP_ERR_FLAG) != 0u && (id & CANDUMP_ERR_BUSERROR) != 0u) {
        frame->is_error = 1;
        return 0;
    }
    frame->id = id & 0x1FFFFFFFu;
    if (data < fend && (*data == 'R' || *data == 'r')) {
        frame->is_remote = 1;
        return 0;
    }
    size_t hex = (size_t)(fend - data);
    if (hex % 2u != 0u || hex / 2u > CANDUMP_MAX_DATA) {
        return -1;
    }
    for (size_t i = 0; i < hex / 2u; ++i) {
        int hi = hex_digit(data[2u * i]), lo = hex_digit(data[2u * i + 1u]);
        if (hi < 0 || lo < 0) {
            return -1;
        }
        if (i < GS_HIL_MAX_DATA) {
            frame->data[i] = (uint8_t)(hi * 16 + lo);
        }
    }
    /* longer than classic CAN: kept as a length, so the bridge counts it bad_length */
    frame->length = (unsigned)(hex / 2u);
    return 0;
}

static size_t put_unsigned(char *out, uint64_t value, unsigned min_digits)
{
    char tmp[24];
    unsigned n = 0;
    do {
        tmp[n++] = (char)('0' + (int)(value % 10u));
        value /= 10u;
    } while (value != 0u || n < min_digits);
    for (unsigned i = 0; i < n; ++i) {
        out[i] = tmp[n - 1u - i];
    }
    return n;
}

static size_t put_hex(char *out, uint32_t value, unsigned digits)
{
    static const char hexchars[] = "0123456789ABCDEF";
    for (unsigned i = 0; i < digits; ++i) {
        out[i] = hexchars[(value >> (4u * (digits - 1u - i))) & 0xFu];
    }
    return digits;
}

size_t candump_format_line_dir(const gs_hil_frame *frame, double stamp_s, const char *channel, char direction,
                               char *out, size_t size)
{
    size_t channel_len = strlen(channel);
    if (size < 64u + channel_len || !(stamp_s >= 0.0 && stamp_s < 1e12)) {
        return 0;
    }
    uint64_t micros = (uint64_t)llround(stamp_s * 1e6);
    size_t n = 0;
    out[n++] = '(';
    n += put_unsigned(out + n, micros / 1000000u, 1);
    out[n++] = '.';
    n += put_unsigned(out + n, micros % 1000000u, 6);
    out[n++] = ')';
    out[n++] = ' ';
    memcpy(out + n, channel, channel_len);
    n += channel_len;
    out[n++] = ' ';
    if (frame->is_error) {
        n += put_hex(out + n, CANDUMP_ERR_FLAG | CANDUMP_ERR_BUSERROR, 8u);
        out[n++] = '#';
    } else {
        n += put_hex(out + n, frame->id, frame->is_extended ? 8u : 3u);
        out[n++] = '#';
        if (frame->is_remote) {
            out[n++] = 'R';
        } else {
            unsigned length = frame->length < GS_HIL_MAX_DATA ? frame->length : GS_HIL_MAX_DATA;
            for (unsigned i = 0; i < length; ++i) {
                n += put_hex(out + n, frame->data[i], 2u);
            }
        }
    }
    out[n++] = ' ';
    out[n++] = direction;
    out[n++] = '\n';
    return n;
}

size_t candump_format_line(const gs_hil_frame *frame, double stamp_s, const char *channel, char *out, size_t size)
{
    return candump_format_line_dir(frame, stamp_s, channel, 'T', out, size);
}
