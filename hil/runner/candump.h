/*
 * The candump -L text format: "(1700000000.123456) can0 100#1027000000000001 T".
 * docs/hil-runner.md, "Transports".
 */
#ifndef GEARSIM_HIL_RUNNER_CANDUMP_H
#define GEARSIM_HIL_RUNNER_CANDUMP_H

#include <stddef.h>

#include "gearsim/hil.h"

/* Longest data a line may carry (CAN FD); longer than classic CAN is kept as
 * a length only, so that the bridge counts the frame as bad_length. */
#define CANDUMP_MAX_DATA 64u

/* 1 when line[0..length) holds only blanks (skipped, not malformed). */
int candump_is_blank(const char *line, size_t length);

/* One candump -L line ("(1.5) can0 100#0102", "... 100#R", "... 1234ABCD#",
 * error frames with CAN_ERR_FLAG|CAN_ERR_BUSERROR in the ID) -> frame,
 * stamped with the line's time. 0, or -1 when the line is not such a frame. */
int candump_parse_line(const char *line, size_t length, gs_hil_frame *frame);

/* frame -> candump -L line stamped stamp_s, python-can's format (6 decimals,
 * upper-case hex, 3 or 8 ID digits, " T" as sent, newline). Returns its
 * length (< size), or 0 when it does not fit or the stamp is not in [0, 1e12). */
size_t candump_format_line(const gs_hil_frame *frame, double stamp_s, const char *channel, char *out, size_t size);

/* The same with the direction field given: 'T' sent, 'R' received. Error
 * frames are written with CAN_ERR_FLAG|CAN_ERR_BUSERROR as their ID and
 * remote frames as ID#R, as candump_parse_line reads them. */
size_t candump_format_line_dir(const gs_hil_frame *frame, double stamp_s, const char *channel, char direction,
                               char *out, size_t size);

#endif
