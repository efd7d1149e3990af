/*
 * gearsim/hil.h - a gearsim rig behind CAN frames (docs/hil-runner.md).
 *
 * The one implementation of the HIL bridge's semantics (docs/hil.md): the C
 * runner gearsim-hil and the Python bridge (gearsim.hil, through cffi) both
 * run it. A gs_hil_bridge classifies every received frame (used, rejected,
 * late, ignored), latches valid commands and applies them at the next frame
 * period (zero-order hold); a command timeout puts the rig in its safe state;
 * feedback frames are sent at their DBC cycle times, values clamped into
 * their DBC range and flagged, never wrapped; the status frames carry a
 * rolling counter, flags and frame counters.
 *
 * A test campaign lives here too (docs/hil.md): faults injected between the
 * model's values and the encoder (gs_hil_add_fault), rig parameters changed
 * at run time (parameter frames, gs_hil_request_param, gs_hil_prepare), and
 * scenario files (gs_hil_scenario_parse, gs_hil_attach_scenario) whose
 * expectations give a JUnit verdict (gs_hil_junit).
 *
 * No I/O, no heap, no clock: frames come in through gs_hil_handle and go out
 * through a callback; simulated time advances by step count (gs_hil_advance).
 *
 * Every name a DBC may use (roles, flags, counters, modes) and every name of
 * a received frame's fate (reasons) is listed once below; the rules a DBC
 * must follow are gs_hil_dbc_check's. A frame table (gs_hil_dbc) is made
 * from a DBC file by hil/dbc_tables.py at build time (the DBCs built into the
 * runner: gearsim/hil_dbc.h) or by gearsim.hil at run time.
 */
#ifndef GEARSIM_HIL_H
#define GEARSIM_HIL_H

#include <stddef.h>
#include <stdint.h>

#include "gearsim/rig.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GS_HIL_MAX_FRAMES         32
#define GS_HIL_MAX_COMMAND_FRAMES 4 /* one per command role at most */
#define GS_HIL_MAX_DATA           8 /* classic CAN */
#define GS_HIL_LATCHED_FLAGS      8 /* the latched flags: the last eight of GS_HIL_FLAG_LIST */
#define GS_HIL_STATE_FLAGS        4 /* the state flags: the first four */
/* A replayed frame up to this long after a period boundary counts as at it
 * (the rounding of log formats and of epoch time stamps), in seconds. */
#define GS_HIL_REPLAY_SLACK_S     1e-6

/* Index of a gs_rig_output member, for the frame tables. */
#define GS_HIL_OUTPUT_INDEX(field) (offsetof(gs_rig_output, field) / sizeof(gs_real))

/*
 * What a signal means: the string attribute GsRole of a DBC signal, listed
 * as X(ENUM_SUFFIX, "name"). A name ending in '.' is a family, followed by
 * the name of a gs_rig_output field (out.), a flag (status.flag.) or a
 * counter (status.count.); gs_hil_signal.aux says which.
 */
#define GS_HIL_ROLE_LIST(X)                                                                    \
    X(NONE, "")                                                                                \
    X(CMD_BASE_SPEED, "cmd.base_speed")                                                        \
    X(CMD_BASE_TORQUE, "cmd.base_torque")                                                      \
    X(CMD_LOAD, "cmd.load")                                                                    \
    X(CMD_MODE, "cmd.mode")                                                                    \
    X(OUT, "out.")                              /* aux: GS_HIL_OUTPUT_INDEX(field) */          \
    X(OUT_FOLLOWER_ANGLE, "out.follower_angle") /* follower_position modulo 2*pi, [0, 2*pi) */ \
    X(IN_BASE_SPEED, "in.base_speed")           /* the inputs the rig applied */               \
    X(IN_BASE_TORQUE, "in.base_torque")                                                        \
    X(IN_LOAD, "in.load")                                                                      \
    X(STATUS_COUNTER, "status.counter") /* rolling: +1 per frame sent */                       \
    X(STATUS_FLAG, "status.flag.")      /* aux: gs_hil_flag */                                 \
    X(STATUS_COUNT, "status.count.")    /* aux: gs_hil_count */                                \
    X(PARAM_ID, "param.id")             /* parameter frame: gs_hil_param_index */              \
    X(PARAM_ELEMENT, "param.element")   /* the element of an array or table, else 0 */         \
    X(PARAM_VALUE, "param.value")       /* the new value, SI */                                \
    X(ACK_ID, "ack.id")                 /* acknowledgement: the request's parameter */         \
    X(ACK_ELEMENT, "ack.element")                                                              \
    X(ACK_VALUE, "ack.value")                                                                  \
    X(ACK_RESULT, "ack.result") /* gs_hil_param_result */

/* The modes of a cmd.mode signal; its raw values without a value table. */
#define GS_HIL_MODE_LIST(X) \
    X(DISABLED, "disabled") \
    X(SPEED, "speed")       \
    X(TORQUE, "torque")

/* Further names a cmd.mode value table may give a mode (case and surrounding
 * blanks do not matter). */
#define GS_HIL_MODE_ALIAS_LIST(X) \
    X(DISABLED, "disable")        \
    X(DISABLED, "off")            \
    X(DISABLED, "safe")

/* Status flags: the first GS_HIL_STATE_FLAGS are the state during the
 * period the status frame ends; the others are latched: set when their
 * counter grew since the previous frame of the same ID. */
#define GS_HIL_FLAG_LIST(X)                                                        \
    X(CMD_TIMEOUT, "cmd_timeout")                                                  \
    X(SAFE_STATE, "safe_state")                                                    \
    X(DRIVE_DISABLED, "drive_disabled")                                            \
    X(FAULT_ACTIVE, "fault_active")   /* an injected fault acted on this period */ \
    X(CMD_REJECTED, "cmd_rejected")   /* rx_rejected grew */                       \
    X(CMD_LATE, "cmd_late")           /* rx_late grew */                           \
    X(FB_SATURATED, "fb_saturated")   /* saturations grew */                       \
    X(OVERRUN, "overrun")             /* overruns grew */                          \
    X(TX_ERROR, "tx_error")           /* tx_errors grew */                         \
    X(PARAM_CHANGED, "param_changed") /* param_changes grew */                     \
    X(PARAM_REFUSED, "param_refused") /* param_refused grew */                     \
    X(LOG_OVERFLOW, "log_overflow")   /* log_dropped grew */

/* The counters, in the order of gs_hil_counters.count. */
#define GS_HIL_COUNT_LIST(X)                                                                  \
    X(RX_TOTAL, "rx_total")                                                                   \
    X(RX_USED, "rx_used")                                                                     \
    X(RX_REJECTED, "rx_rejected")                                                             \
    X(RX_LATE, "rx_late")                                                                     \
    X(RX_IGNORED, "rx_ignored")                                                               \
    X(TX_FRAMES, "tx_frames")                                                                 \
    X(TX_ERRORS, "tx_errors")                                                                 \
    X(TIMEOUTS, "timeouts")     /* entries into the command timeout after commands came */    \
    X(RECOVERIES, "recoveries") /* exits from it */                                           \
    X(OVERRUNS, "overruns")     /* paced run: periods that started more than a period late */ \
    X(RESYNCS, "resyncs")       /* paced run: schedule moved to now */                        \
    X(SATURATIONS, "saturations")                                                             \
    X(PERIODS, "periods")                                                                     \
    X(FAULTS, "faults")               /* values and frames an injected fault changed */       \
    X(PARAM_CHANGES, "param_changes") /* parameter changes that took effect */                \
    X(PARAM_REFUSED, "param_refused") /* parameter requests refused (rx_rejected too) */      \
    X(LOG_DROPPED, "log_dropped")     /* recording: frames the ring had no room for (runner) */

/* What became of a received frame: "class.reason". PENDING is a valid
 * command, applied by the next period; LATE_SUPERSEDED is counted for the
 * older command a newer one replaced. The classes are rejected, late and
 * ignored, in this order. */
#define GS_HIL_REASON_LIST(X)                                                                       \
    X(PENDING, "pending")                                                                           \
    X(REJECTED_UNKNOWN_ID, "rejected.unknown_id") /* not in the DBC, or extended/standard */        \
    X(REJECTED_BAD_LENGTH, "rejected.bad_length")                                                   \
    X(REJECTED_UNDECODABLE, "rejected.undecodable") /* not finite, or no such mode */               \
    X(REJECTED_OUT_OF_RANGE, "rejected.out_of_range")                                               \
    X(REJECTED_MODE_MISMATCH, "rejected.mode_mismatch")                                             \
    X(REJECTED_BAD_PARAM, "rejected.bad_param")   /* unknown parameter or element, invalid value */ \
    X(REJECTED_PARAM_BUSY, "rejected.param_busy") /* more requests in one period than the queue */  \
    X(LATE_SUPERSEDED, "late.superseded")                                                           \
    X(LATE_OUT_OF_ORDER, "late.out_of_order")                                                       \
    X(LATE_AFTER_STOP, "late.after_stop")                                                           \
    X(IGNORED_FEEDBACK_ID, "ignored.feedback_id")                                                   \
    X(IGNORED_OTHER_DBC_FRAME, "ignored.other_dbc_frame")                                           \
    X(IGNORED_ERROR_FRAME, "ignored.error_frame")                                                   \
    X(IGNORED_REMOTE_FRAME, "ignored.remote_frame")

/* What became of a parameter request: the ack.result signal's values. */
#define GS_HIL_PARAM_RESULT_LIST(X)                                                             \
    X(APPLIED, "applied")                                                                       \
    X(UNKNOWN_PARAM, "unknown_param") /* no tunable parameter of that index */                  \
    X(BAD_ELEMENT, "bad_element")     /* an element the parameter does not have (in use) */     \
    X(INVALID_VALUE, "invalid_value") /* the rig's init refused the new value */                \
    X(BUSY, "busy")                   /* more than GS_HIL_PARAM_QUEUE requests in one period */ \
    X(UNAVAILABLE, "unavailable")     /* the bridge was set up without the rig's parameters */

/* Injected faults (docs/hil.md, "Fault injection"). The first ones act on a
 * feedback signal's value between the model and the encoder; dropout drops
 * the frame of its signal; the last four act on a whole frame. */
#define GS_HIL_FAULT_LIST(X)                                                                 \
    X(OFFSET, "offset")             /* value + value */                                      \
    X(GAIN, "gain")                 /* value * value */                                      \
    X(NOISE, "noise")               /* value + value * N(0, 1), seeded */                    \
    X(FREEZE, "freeze")             /* the value its frame last carried before the fault */  \
    X(STUCK, "stuck")               /* value */                                              \
    X(DROPOUT, "dropout")           /* the signal's frame is not sent */                     \
    X(DELAY, "delay")               /* the model's value periods frame periods earlier */    \
    X(QUANTISE, "quantise")         /* value * round(x / value), half to even */             \
    X(CLAMP, "clamp")               /* x within [value, value2] */                           \
    X(DROP, "drop")                 /* the frame is not sent */                              \
    X(DUPLICATE, "duplicate")       /* the frame is sent twice */                            \
    X(CORRUPT, "corrupt")           /* periods distinct bits of the frame flipped, seeded */ \
    X(COUNTER_STOP, "counter_stop") /* the status frame's rolling counter stops */

/* Comparisons of a trigger condition. */
#define GS_HIL_OP_LIST(X) \
    X(LT, "<")            \
    X(LE, "<=")           \
    X(GT, ">")            \
    X(GE, ">=")           \
    X(EQ, "==")           \
    X(NE, "!=")

#define GS_HIL_ROLE_ENUM_(suffix, name)   GS_HIL_ROLE_##suffix,
#define GS_HIL_MODE_ENUM_(suffix, name)   GS_HIL_MODE_##suffix,
#define GS_HIL_FLAG_ENUM_(suffix, name)   GS_HIL_FLAG_##suffix,
#define GS_HIL_COUNT_ENUM_(suffix, name)  GS_HIL_COUNT_##suffix,
#define GS_HIL_REASON_ENUM_(suffix, name) GS_HIL_##suffix,

typedef enum { GS_HIL_ROLE_LIST(GS_HIL_ROLE_ENUM_) GS_HIL_ROLES } gs_hil_role;
typedef enum { GS_HIL_MODE_LIST(GS_HIL_MODE_ENUM_) GS_HIL_MODES } gs_hil_mode;
typedef enum { GS_HIL_FLAG_LIST(GS_HIL_FLAG_ENUM_) GS_HIL_FLAGS } gs_hil_flag;
typedef enum { GS_HIL_COUNT_LIST(GS_HIL_COUNT_ENUM_) GS_HIL_COUNTS } gs_hil_count;
typedef enum { GS_HIL_REASON_LIST(GS_HIL_REASON_ENUM_) GS_HIL_REASONS } gs_hil_reason;
#define GS_HIL_PARAM_RESULT_ENUM_(suffix, name) GS_HIL_PARAM_##suffix,
#define GS_HIL_FAULT_ENUM_(suffix, name)        GS_HIL_FAULT_##suffix,
#define GS_HIL_OP_ENUM_(suffix, name)           GS_HIL_OP_##suffix,
typedef enum { GS_HIL_PARAM_RESULT_LIST(GS_HIL_PARAM_RESULT_ENUM_) GS_HIL_PARAM_RESULTS } gs_hil_param_result;
typedef enum { GS_HIL_FAULT_LIST(GS_HIL_FAULT_ENUM_) GS_HIL_FAULTS } gs_hil_fault_kind;
typedef enum { GS_HIL_OP_LIST(GS_HIL_OP_ENUM_) GS_HIL_OPS } gs_hil_op;

/* The command roles' slots in gs_hil_command.value. */
enum { GS_HIL_CMD_BASE_SPEED = 0, GS_HIL_CMD_BASE_TORQUE, GS_HIL_CMD_LOAD, GS_HIL_CMD_MODE, GS_HIL_CMD_ROLES };

/* The names of the lists above ("" or "?" out of range). */
const char *gs_hil_role_name(gs_hil_role role);                   /* "cmd.load", "out." (a family) */
const char *gs_hil_mode_name(gs_hil_mode mode);                   /* "disabled", "speed", "torque" */
const char *gs_hil_flag_name(gs_hil_flag flag);                   /* "cmd_timeout", ... */
const char *gs_hil_count_name(gs_hil_count count);                /* "rx_total", ... */
const char *gs_hil_reason_name(gs_hil_reason reason);             /* "rejected.unknown_id", ... "pending" */
const char *gs_hil_param_result_name(gs_hil_param_result result); /* "applied", ... */
const char *gs_hil_fault_name(gs_hil_fault_kind kind);            /* "offset", ... */
const char *gs_hil_op_name(gs_hil_op op);                         /* "<", ... */

/* A GsRole text -> *role and *aux (0 where no aux). 0, or -1 when the text
 * names no role ("" included). */
int gs_hil_role_parse(const char *text, gs_hil_role *role, size_t *aux);

/* A mode name of a cmd.mode value table -> gs_hil_mode, or -1. */
int gs_hil_mode_parse(const char *name);

/* The slot of a command role in gs_hil_command.value (GS_HIL_CMD_*), -1 for
 * any other role. */
int gs_hil_role_command_index(gs_hil_role role);

/* ---- frame tables -------------------------------------------------------- */

/* One entry of a signal's value table. */
typedef struct {
    int64_t value; /* looked up by the physical value truncated to an integer */
    const char *name;
} gs_hil_choice;

/* One signal of a DBC frame: integer (signed or not) or IEEE float (32 or 64
 * bits), little-endian (Intel) or big-endian (Motorola). */
typedef struct {
    const char *name;
    unsigned start, length; /* bits, as the DBC numbers them (big-endian: the most significant bit) */
    int is_signed, is_big_endian, is_float;
    double scale, offset;
    double minimum, maximum; /* physical, as the DBC gives them: -HUGE_VAL / HUGE_VAL for none */
    gs_hil_role role;
    size_t aux;
    const gs_hil_choice *choices; /* the value table, or NULL */
    unsigned choice_count;
} gs_hil_signal;

typedef struct {
    const char *name;
    uint32_t id;
    int is_extended;
    unsigned length;   /* bytes */
    unsigned cycle_ms; /* GenMsgCycleTime, 0 = none */
    int is_multiplexed;
    const gs_hil_signal *signals;
    unsigned signal_count;
} gs_hil_frame_spec;

typedef struct {
    const char *name;
    gs_rig_block block;
    const gs_hil_frame_spec *frames;
    unsigned frame_count;
} gs_hil_dbc;

/* What a frame is, from its signals' roles: a command frame holds a cmd.*
 * role, a parameter frame param.* roles, an acknowledgement frame ack.*
 * roles, a feedback frame any other role, an "other" frame none. */
typedef enum {
    GS_HIL_FRAME_COMMAND = 0,
    GS_HIL_FRAME_FEEDBACK,
    GS_HIL_FRAME_OTHER,
    GS_HIL_FRAME_PARAM, /* from the host: change a rig parameter (gs_hil_param_request) */
    GS_HIL_FRAME_ACK    /* to the host, once per request: its result (sent when decided) */
} gs_hil_frame_kind;

gs_hil_frame_kind gs_hil_frame_kind_of(const gs_hil_frame_spec *spec);

/* A feedback frame holding status.* roles: sent after the other feedback of
 * its period, so that it counts their saturations. */
int gs_hil_frame_is_status(const gs_hil_frame_spec *spec);

/* The feedback frames' indices in sending order (the others by ID, then the
 * status frames by ID); returns their number. */
unsigned gs_hil_feedback_order(const gs_hil_dbc *dbc, unsigned order[GS_HIL_MAX_FRAMES]);

typedef enum {
    GS_HIL_OK = 0,
    GS_HIL_E_CONFIG = -1, /* see gs_hil_error: parameter and message */
} gs_hil_status;

typedef struct {
    const char *parameter;
    char message[512];
} gs_hil_error;

/* The rules a frame table must follow, each refused with one message naming
 * the frame and signal (parameter "dbc"): roles known and in range of their
 * lists; a command role on one signal only; a frame not mixing command and
 * feedback roles; a feedback frame with a cycle time; no multiplexed command
 * or feedback frame; command and feedback frames of at most 8 bytes with
 * every signal inside them; a feedback signal's range within what its bits
 * hold (so that no value wraps); counters unsigned integers of scale 1,
 * offset 0; flags able to hold 0 and 1; mode signals integers whose value
 * names are modes; at most GS_HIL_MAX_FRAMES frames and
 * GS_HIL_MAX_COMMAND_FRAMES command frames. gs_hil_bridge_init checks it. */
gs_hil_status gs_hil_dbc_check(const gs_hil_dbc *dbc, gs_hil_error *err);

/* ---- codec --------------------------------------------------------------- */

/* A classic CAN frame. timestamp_s: receive time (the out-of-order check
 * compares it) or, for frames the bridge sends, stamp_origin_s + simulated
 * time. saturated: of a frame the bridge sends, bit s set when signal s of
 * its frame spec was clamped. */
typedef struct {
    double timestamp_s;
    uint32_t id;
    int is_extended, is_remote, is_error;
    unsigned length;
    uint8_t data[GS_HIL_MAX_DATA];
    uint64_t saturated;
} gs_hil_frame;

/* Decoded command: value[GS_HIL_CMD_*] (mode as gs_hil_mode), present[];
 * signal: the index of the signal that decided a rejection, else -1. */
typedef struct {
    double value[GS_HIL_CMD_ROLES];
    int present[GS_HIL_CMD_ROLES];
    int signal;
} gs_hil_command;

/* Decode and range-check a command frame: GS_HIL_PENDING with *cmd filled,
 * or GS_HIL_REJECTED_BAD_LENGTH / _UNDECODABLE / _OUT_OF_RANGE. The first
 * failing signal in DBC order gives the reason; nothing is applied in part. */
gs_hil_reason gs_hil_decode_command(const gs_hil_frame_spec *spec, const uint8_t *data, unsigned length,
                                    gs_hil_command *cmd);

/* The range a signal's values are kept in: its DBC range within what its
 * bits hold. */
void gs_hil_signal_limits(const gs_hil_signal *sig, double *minimum, double *maximum);

/* Physical value of a signal in data (raw * scale + offset). */
double gs_hil_signal_value(const gs_hil_signal *sig, const uint8_t *data);

/* Put a physical value into data: clamped into gs_hil_signal_limits (NaN:
 * the value in range nearest 0; +-inf: the bound), then raw = round half to
 * even ((x - offset) / scale), or that quotient as a float for a float
 * signal. Returns 1 when the value was clamped, else 0. */
int gs_hil_put_value(const gs_hil_signal *sig, double value, uint8_t *data);

/* Put a raw value (counters: taken modulo 2^length). */
void gs_hil_put_raw(const gs_hil_signal *sig, uint64_t raw, uint8_t *data);

/* ---- the bridge ---------------------------------------------------------- */

typedef struct {
    uint64_t count[GS_HIL_COUNTS];
    uint64_t reasons[GS_HIL_REASONS];
    uint64_t steps;
} gs_hil_counters;

/* Where feedback goes: 0 = sent (tx_frames + 1), else a transmit error
 * (tx_errors + 1, flag TxError, the frame is dropped). */
typedef int (*gs_hil_send_fn)(void *context, const gs_hil_frame *frame);

/* ---- rig parameters at run time ------------------------------------------ */

/* The rig's parameters, block and rig, as gs_rig_init_* takes them. */
typedef union {
    gs_simple_gear_params gear;
    gs_rack_pinion_params rack;
} gs_hil_block_params;

typedef struct {
    gs_hil_block_params block;
    gs_rig_params rig;
} gs_hil_rig_params;

/* The parameters a running rig may change: the TUNABLE entries of kind
 * REAL, ARRAY, TABLE and MATRIX of the block's table (gs_simple_gear_param_info
 * or gs_rack_pinion_param_info), then of gs_rig_param_info, in table order.
 * A parameter frame names one by its index in this list and an element
 * (0 for a scalar; i for an array or table; row * GS_TABLE_MAX + column for
 * a matrix). The names are the tables' keys in the rig (rack_key in the
 * Rack & Pinion rig). */
unsigned gs_hil_param_count(gs_rig_block block);
/* The table entry of index, or NULL; *is_rig: 1 for a gs_rig_params member. */
const gs_param_info *gs_hil_param_info(gs_rig_block block, unsigned index, int *is_rig);
/* The key of index in the rig ("" out of range). */
const char *gs_hil_param_key(gs_rig_block block, unsigned index);
/* "key", "key[i]" or "key[i][j]" -> index and element; 0, or -1 (no such
 * tunable parameter, or an element it cannot have). */
int gs_hil_param_parse(gs_rig_block block, const char *text, unsigned *index, unsigned *element);
/* Set element of index to value in *params: APPLIED, UNKNOWN_PARAM,
 * BAD_ELEMENT (not one it has, or a table entry beyond the count in use) or
 * INVALID_VALUE (not finite). Whether the rig takes the value is its
 * init's to say. */
gs_hil_param_result gs_hil_param_set(gs_rig_block block, gs_hil_rig_params *params, unsigned index, unsigned element,
                                     double value);

#define GS_HIL_PARAM_QUEUE 8 /* parameter requests per period */

typedef struct {
    unsigned index, element;
    double value;
    gs_hil_param_result result;
    int prepared; /* result decided and, if applied, the constants ready */
} gs_hil_param_request;

/* ---- faults ---------------------------------------------------------------- */

#define GS_HIL_MAX_FAULTS 16
#define GS_HIL_DELAY_MAX  128 /* periods a delay fault may hold back */

/* Where a condition's value comes from. */
typedef enum {
    GS_HIL_SOURCE_FEEDBACK = 0, /* a feedback signal: the model's value this period, before faults */
    GS_HIL_SOURCE_COMMAND,      /* a command signal: the value applied this period (NaN before any) */
    GS_HIL_SOURCE_FLAG          /* a state flag: 0 or 1 */
} gs_hil_source;

typedef struct {
    gs_hil_source source;
    unsigned frame, signal; /* FEEDBACK, COMMAND: the DBC frame and signal indices */
    unsigned flag;          /* FLAG: a state flag (< GS_HIL_STATE_FLAGS) */
    gs_hil_op op;
    double value;
} gs_hil_condition;

/* One fault: what, on which frame or signal, and when. It acts on the
 * periods [start_period, end_period); with a trigger, from the first of those
 * periods at whose end the condition holds, for duration_periods periods (0:
 * to end_period). */
typedef struct {
    gs_hil_fault_kind kind;
    unsigned frame;       /* DBC frame index */
    int signal;           /* signal index in the frame; -1 for a frame fault */
    double value, value2; /* see GS_HIL_FAULT_LIST; clamp: [value, value2] (+-inf: no bound) */
    unsigned periods;     /* delay: periods (1..GS_HIL_DELAY_MAX); corrupt: bits per frame (1..64) */
    uint64_t seed;        /* noise, corrupt */
    uint64_t start_period, end_period;
    uint64_t duration_periods;
    int has_trigger;
    gs_hil_condition trigger;
} gs_hil_fault_spec;

typedef struct {
    gs_hil_fault_spec spec;
    int active, triggered;
    uint64_t stop_period; /* triggered: first period it no longer acts on */
    uint64_t rng;         /* noise, corrupt: the generator's state */
    double last_value;    /* freeze: the value its frame last carried */
    int has_last;
    uint64_t counter; /* counter_stop: the counter value held */
    int has_counter;
    uint64_t count;                /* values and frames it changed */
    uint64_t ring_start;           /* delay: the first period recorded */
    double ring[GS_HIL_DELAY_MAX]; /* delay: the model's value of the last periods */
} gs_hil_fault;

/* ---- scenarios --------------------------------------------------------------- */

#define GS_HIL_SCENARIO_MAX_STEPS 256
#define GS_HIL_MAX_EXPECTS        64
#define GS_HIL_TEXT_MAX           128

typedef enum { GS_HIL_STEP_LOAD = 0, GS_HIL_STEP_PARAM, GS_HIL_STEP_FAULT, GS_HIL_STEP_EXPECT } gs_hil_step_kind;
typedef enum { GS_HIL_EXPECT_AT = 0, GS_HIL_EXPECT_WITHIN, GS_HIL_EXPECT_UNTIL } gs_hil_expect_mode;
typedef enum { GS_HIL_VERDICT_PENDING = 0, GS_HIL_VERDICT_PASS, GS_HIL_VERDICT_FAIL } gs_hil_verdict;

/* One [[step]] of a scenario file (docs/hil.md, "Scenarios"); times in s. */
typedef struct {
    gs_hil_step_kind kind;
    unsigned line; /* in the scenario file */
    double at_s;
    char name[GS_HIL_TEXT_MAX];
    double value, over_s;    /* LOAD: the scenario's load from at_s (a ramp over over_s); PARAM: the value */
    unsigned param, element; /* PARAM */
    unsigned index;          /* FAULT: in faults[]; EXPECT: in expects[] */
} gs_hil_step;

typedef struct {
    gs_hil_fault_spec spec;           /* periods resolved when attached */
    double at_s, until_s, duration_s; /* until_s: +inf, duration_s: 0 when not given */
    unsigned line;
} gs_hil_fault_def;

typedef struct {
    gs_hil_condition target; /* a command signal or a state flag (op and value unused) */
    double minimum, maximum; /* the range the value must be in */
    gs_hil_expect_mode mode;
    double at_s, window_s;      /* WITHIN: the window's length; UNTIL: its end time */
    char what[GS_HIL_TEXT_MAX]; /* "BaseSpeedCmd in [4, 6]", for the verdict */
    char name[GS_HIL_TEXT_MAX]; /* the test case's name */
    unsigned line;
} gs_hil_expect_def;

typedef struct {
    char name[GS_HIL_TEXT_MAX];
    char file[GS_HIL_TEXT_MAX]; /* as given to gs_hil_scenario_parse (messages, verdict) */
    double duration_s;
    uint64_t seed;
    gs_rig_block block;
    const gs_hil_dbc *dbc;
    unsigned step_count, fault_count, expect_count;
    gs_hil_step steps[GS_HIL_SCENARIO_MAX_STEPS]; /* by at_s, then file order */
    gs_hil_fault_def faults[GS_HIL_MAX_FAULTS];
    gs_hil_expect_def expects[GS_HIL_MAX_EXPECTS];
} gs_hil_scenario;

/* How an expectation ended (the bridge keeps one per expectation). */
typedef struct {
    gs_hil_verdict verdict;
    int incomplete;                    /* failed because the run ended inside the window */
    uint64_t start_period, end_period; /* its window [start, end) */
    uint64_t decided_period;
    double observed; /* the value that decided (NaN: no command yet) */
} gs_hil_expect_state;

typedef struct {
    const gs_hil_dbc *dbc;
    gs_base_drive base_drive;      /* must be the rig's */
    gs_real dt_s;                  /* the rig's step */
    unsigned substeps;             /* rig steps per frame period (>= 1) */
    double timeout_s;              /* command timeout, rounded to whole periods (>= 1) */
    gs_real ambient_temperature_K; /* the ambient and measured temperature inputs */
    double stamp_origin_s;         /* sent frames carry stamp_origin_s + periods * period_s */
    gs_hil_send_fn send;
    void *send_context;
    /* The parameters the rig was initialised with: parameter changes at run
     * time need them (NULL: every request is refused as unavailable). */
    const gs_simple_gear_params *gear_params; /* or rack_params, by the block */
    const gs_rack_pinion_params *rack_params;
    const gs_rig_params *rig_params;
    /* 0: gs_hil_advance prepares the parameter requests itself; 1: the caller
     * calls gs_hil_prepare between periods (the C runner, after its flush). */
    int deferred_prepare;
} gs_hil_config;

typedef struct {
    gs_hil_command held, pending;
    double held_ts, pending_ts;
    int has_held, has_pending;
    uint64_t last_rx_period;
    int has_last_rx;
} gs_hil_command_slot;

typedef struct {
    gs_hil_config config;
    const gs_rig_consts *consts;
    gs_rig_state *state;
    double period_s; /* dt_s * substeps */
    uint64_t timeout_periods;
    gs_hil_frame_kind kind[GS_HIL_MAX_FRAMES];
    unsigned cycle_periods[GS_HIL_MAX_FRAMES];  /* feedback frames, 0 otherwise */
    unsigned feedback_order[GS_HIL_MAX_FRAMES]; /* gs_hil_feedback_order */
    unsigned feedback_count;
    unsigned command_index[GS_HIL_MAX_FRAMES]; /* frame index -> command slot */
    unsigned command_count;
    gs_hil_command_slot commands[GS_HIL_MAX_COMMAND_FRAMES];
    int has_role[GS_HIL_CMD_ROLES];
    int timed_out, ever_commanded, dirty, closed;
    uint64_t stale_at;
    int flag_state[GS_HIL_STATE_FLAGS]; /* cmd_timeout, safe_state, drive_disabled */
    gs_rig_input input;
    gs_rig_output output;
    unsigned status_seq[GS_HIL_MAX_FRAMES];
    uint64_t latched_at[GS_HIL_MAX_FRAMES][GS_HIL_LATCHED_FLAGS];
    gs_hil_counters counters;
    /* the inputs from the commands (or the safe state), before the scenario's load */
    gs_rig_input commanded;
    /* parameter changes: the parameters in use and after the prepared
     * requests, constants prepared off the period (two buffers, swapped at a
     * period boundary), requests of the current period, acknowledgements due */
    int tunable;
    gs_rig_block block;
    gs_hil_rig_params params, params_next, params_try;
    gs_rig_consts consts_buf[2];
    unsigned consts_next;
    int next_ready;
    gs_rig_state scratch;
    gs_hil_param_request requests[GS_HIL_PARAM_QUEUE];
    unsigned request_count;
    uint64_t requests_due; /* the period at whose start they take effect */
    gs_hil_param_request acks[2 * GS_HIL_PARAM_QUEUE];
    unsigned ack_count;
    /* faults */
    gs_hil_fault faults[GS_HIL_MAX_FAULTS];
    unsigned fault_count;
    /* the scenario attached (NULL: none) and its progress */
    const gs_hil_scenario *scenario;
    uint64_t step_period[GS_HIL_SCENARIO_MAX_STEPS];
    unsigned next_step, next_param_step;
    int has_load;
    double load_from, load_to;
    uint64_t load_start, load_end;
    gs_hil_expect_state expects[GS_HIL_MAX_EXPECTS];
} gs_hil_bridge;

/* Set up a bridge around an initialised rig (gs_rig_init_*: consts read, state
 * stepped). Checks: the frame table (gs_hil_dbc_check), a DBC for the rig's
 * block, the driving command role present, substeps >= 1, timeout > 0, every
 * feedback cycle time a whole number of frame periods. */
gs_hil_status gs_hil_bridge_init(gs_hil_bridge *bridge, const gs_hil_config *config, gs_rig_block block,
                                 const gs_rig_consts *consts, gs_rig_state *state, gs_hil_error *err);

/* Classify one received frame (counted in exactly one class). */
gs_hil_reason gs_hil_handle(gs_hil_bridge *bridge, const gs_hil_frame *frame);

/* Run n frame periods: apply pending commands, check the timeout, step the
 * rig substeps times, send the feedback that is due. Never blocks. */
void gs_hil_advance(gs_hil_bridge *bridge, uint64_t periods);

/* Replay in log time: a frame t_s seconds after the log's first frame is
 * handled at the first period boundary at or after t_s (within
 * GS_HIL_REPLAY_SLACK_S), so that it acts on the period starting there.
 * gs_hil_period_at is that boundary's period count; gs_hil_advance_to runs
 * the periods up to it (nothing when it has passed). */
uint64_t gs_hil_period_at(const gs_hil_bridge *bridge, double t_s);
void gs_hil_advance_to(gs_hil_bridge *bridge, double t_s);

/* Whole frame periods in s seconds, rounded half to even (0 for s <= 0). */
uint64_t gs_hil_periods_in(const gs_hil_bridge *bridge, double s);

/* Stop: pending commands count as late (after_stop). Idempotent. */
void gs_hil_close(gs_hil_bridge *bridge);

/* Commands and parameter requests received and not yet applied or refused. */
unsigned gs_hil_pending(const gs_hil_bridge *bridge);

/* ---- parameter changes, faults, scenarios (docs/hil.md) -------------------- */

/* Parameter requests (a parameter frame, or gs_hil_request_param) handled
 * before period k starts take effect at the start of period k + 1: their
 * constants are derived between periods k and k + 1, by gs_hil_prepare (the
 * caller's, with config.deferred_prepare) or by gs_hil_advance itself, and
 * the two constants buffers are swapped at the boundary. At most
 * GS_HIL_PARAM_QUEUE requests per period; each costs one gs_rig_init_*. */
gs_hil_param_result gs_hil_request_param(gs_hil_bridge *bridge, unsigned index, unsigned element, double value);
void gs_hil_prepare(gs_hil_bridge *bridge);

/* The constants and parameters in use. */
const gs_hil_rig_params *gs_hil_params(const gs_hil_bridge *bridge);

/* Add a fault (before or while running); GS_HIL_E_CONFIG with err when the
 * spec does not fit the DBC (a signal fault on a signal without a value
 * role, a frame fault on a frame that is not feedback, ...). */
gs_hil_status gs_hil_add_fault(gs_hil_bridge *bridge, const gs_hil_fault_spec *spec, gs_hil_error *err);

/* Read a scenario file's text (a TOML subset: docs/hil.md) into *scenario,
 * resolving its signal, frame and parameter names against dbc and block.
 * file names the file in messages. GS_HIL_E_CONFIG with err->message
 * "FILE:LINE: key: what" on the first error. */
gs_hil_status gs_hil_scenario_parse(gs_hil_scenario *scenario, const char *text, size_t length, const char *file,
                                    const gs_hil_dbc *dbc, gs_rig_block block, gs_hil_error *err);

/* Attach a parsed scenario to a bridge that has not run yet: times become
 * periods, its faults are added, its parameter changes are checked against
 * the rig's parameters (each must be a value the rig's init takes; the
 * message names the step's line and key), steps at time 0 take effect now.
 * The scenario must outlive the bridge's use of it. */
gs_hil_status gs_hil_attach_scenario(gs_hil_bridge *bridge, const gs_hil_scenario *scenario, gs_hil_error *err);

/* The period count at which the scenario has run its course (its duration). */
uint64_t gs_hil_scenario_end(const gs_hil_bridge *bridge);

/* Close the expectations whose window is still open (at the end of a run):
 * an UNTIL window that reached its end passes, anything else fails as
 * incomplete. Idempotent. */
void gs_hil_finish_scenario(gs_hil_bridge *bridge);

/* Expectations passed and failed so far. */
void gs_hil_verdict_counts(const gs_hil_bridge *bridge, unsigned *passed, unsigned *failed, unsigned *pending);

/* The verdict as JUnit XML into out (snprintf's contract: returns the length
 * the whole text needs; out holds as much as fits, terminated). The same
 * bytes for the same run, whoever runs the bridge. */
size_t gs_hil_junit(const gs_hil_bridge *bridge, char *out, size_t size);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_HIL_H */
