/*
 * gearsim/hil.h - the embeddable part of the C HIL runner (docs/hil-runner.md).
 *
 * A gs_hil_bridge puts a gearsim rig (gearsim/rig.h) behind CAN frames, with
 * the semantics of the Python bridge (docs/hil.md): commands are classified
 * (used, rejected, late, ignored), latched and applied at the next frame
 * period (zero-order hold); a command timeout puts the rig in its safe state;
 * feedback frames are sent at their DBC cycle times, values clamped into
 * their DBC range and flagged, never wrapped; the status frames carry a
 * rolling counter, flags and frame counters.
 *
 * No I/O, no heap, no clock: frames come in through gs_hil_handle and go out
 * through a callback; simulated time advances by step count (gs_hil_advance).
 * The frame layouts come from the DBC at build time (hil/dbc_tables.py
 * writes one gs_hil_dbc per DBC file).
 */
#ifndef GEARSIM_HIL_H
#define GEARSIM_HIL_H

#include <stddef.h>
#include <stdint.h>

#include "gearsim/rig.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GS_HIL_MAX_FRAMES 32
#define GS_HIL_MAX_COMMAND_FRAMES 4 /* one per command role at most */
#define GS_HIL_MAX_DATA 8           /* classic CAN */

/* Index of a gs_rig_output member, for the generated tables. */
#define GS_HIL_OUTPUT_INDEX(field) (offsetof(gs_rig_output, field) / sizeof(gs_real))

typedef enum {
    GS_HIL_ROLE_NONE = 0,
    GS_HIL_ROLE_CMD_BASE_SPEED,
    GS_HIL_ROLE_CMD_BASE_TORQUE,
    GS_HIL_ROLE_CMD_LOAD,
    GS_HIL_ROLE_CMD_MODE,
    GS_HIL_ROLE_OUT,                /* aux: GS_HIL_OUTPUT_INDEX(field) */
    GS_HIL_ROLE_OUT_FOLLOWER_ANGLE, /* follower_position modulo 2*pi, in [0, 2*pi) */
    GS_HIL_ROLE_IN_BASE_SPEED,
    GS_HIL_ROLE_IN_BASE_TORQUE,
    GS_HIL_ROLE_IN_LOAD,
    GS_HIL_ROLE_STATUS_COUNTER,
    GS_HIL_ROLE_STATUS_FLAG,  /* aux: gs_hil_flag */
    GS_HIL_ROLE_STATUS_COUNT  /* aux: gs_hil_count */
} gs_hil_role;

/* The command roles' slots in gs_hil_command.value. */
enum { GS_HIL_CMD_BASE_SPEED = 0, GS_HIL_CMD_BASE_TORQUE, GS_HIL_CMD_LOAD, GS_HIL_CMD_MODE, GS_HIL_CMD_ROLES };

typedef enum { GS_HIL_MODE_DISABLED = 0, GS_HIL_MODE_SPEED = 1, GS_HIL_MODE_TORQUE = 2 } gs_hil_mode;

/*
 * Flags, counters and reasons are each listed once, as X(ENUM_SUFFIX, name):
 * the enums below and the name strings of bridge.c are expanded from these
 * lists. The Python side (codec and the table generator) takes its flag and
 * counter names from bindings/python/gearsim/hil/dbc_rules.py; each
 * generated table file checks at compile time that both name the same flags
 * and counters in the same order.
 */
#define GS_HIL_FLAG_LIST(X)                                                                         \
    X(CMD_TIMEOUT, cmd_timeout)                                                                     \
    X(SAFE_STATE, safe_state)                                                                       \
    X(DRIVE_DISABLED, drive_disabled)                                                               \
    X(CMD_REJECTED, cmd_rejected)   /* latched: since the previous frame of the same ID */          \
    X(CMD_LATE, cmd_late)                                                                           \
    X(FB_SATURATED, fb_saturated)                                                                   \
    X(OVERRUN, overrun)                                                                             \
    X(TX_ERROR, tx_error)

/* The counters, in the order of gs_hil_counters.count. */
#define GS_HIL_COUNT_LIST(X)                                                                        \
    X(RX_TOTAL, rx_total)                                                                           \
    X(RX_USED, rx_used)                                                                             \
    X(RX_REJECTED, rx_rejected)                                                                     \
    X(RX_LATE, rx_late)                                                                             \
    X(RX_IGNORED, rx_ignored)                                                                       \
    X(TX_FRAMES, tx_frames)                                                                         \
    X(TX_ERRORS, tx_errors)                                                                         \
    X(TIMEOUTS, timeouts)           /* entries into the command timeout after commands came */      \
    X(RECOVERIES, recoveries)       /* exits from it */                                             \
    X(OVERRUNS, overruns)           /* paced run: periods that started more than a period late */   \
    X(RESYNCS, resyncs)             /* paced run: schedule moved to now */                          \
    X(SATURATIONS, saturations)                                                                     \
    X(PERIODS, periods)

/* What became of a received frame: its class and reason (the Python bridge's
 * reason keys). PENDING is a valid command, applied by the next period;
 * LATE_SUPERSEDED is counted for the older command a newer one replaced. */
#define GS_HIL_REASON_LIST(X)                                                                       \
    X(PENDING, "pending")                                                                           \
    X(REJECTED_UNKNOWN_ID, "rejected.unknown_id")                                                   \
    X(REJECTED_BAD_LENGTH, "rejected.bad_length")                                                   \
    X(REJECTED_UNDECODABLE, "rejected.undecodable")                                                 \
    X(REJECTED_OUT_OF_RANGE, "rejected.out_of_range")                                               \
    X(REJECTED_MODE_MISMATCH, "rejected.mode_mismatch")                                             \
    X(LATE_SUPERSEDED, "late.superseded")                                                           \
    X(LATE_OUT_OF_ORDER, "late.out_of_order")                                                       \
    X(LATE_AFTER_STOP, "late.after_stop")                                                           \
    X(IGNORED_FEEDBACK_ID, "ignored.feedback_id")                                                   \
    X(IGNORED_OTHER_DBC_FRAME, "ignored.other_dbc_frame")                                           \
    X(IGNORED_ERROR_FRAME, "ignored.error_frame")                                                   \
    X(IGNORED_REMOTE_FRAME, "ignored.remote_frame")

#define GS_HIL_FLAG_ENUM_(suffix, name) GS_HIL_FLAG_##suffix,
#define GS_HIL_COUNT_ENUM_(suffix, name) GS_HIL_COUNT_##suffix,
#define GS_HIL_REASON_ENUM_(suffix, name) GS_HIL_##suffix,

typedef enum { GS_HIL_FLAG_LIST(GS_HIL_FLAG_ENUM_) GS_HIL_FLAGS } gs_hil_flag;
typedef enum { GS_HIL_COUNT_LIST(GS_HIL_COUNT_ENUM_) GS_HIL_COUNTS } gs_hil_count;
typedef enum { GS_HIL_REASON_LIST(GS_HIL_REASON_ENUM_) GS_HIL_REASONS } gs_hil_reason;

/* "rejected.unknown_id", ... (the Python bridge's reason keys); "pending". */
const char *gs_hil_reason_name(gs_hil_reason reason);
/* "rx_total", ... ; "cmd_timeout", ... */
const char *gs_hil_count_name(gs_hil_count count);
const char *gs_hil_flag_name(gs_hil_flag flag);

typedef enum { GS_HIL_FRAME_COMMAND = 0, GS_HIL_FRAME_FEEDBACK, GS_HIL_FRAME_OTHER } gs_hil_frame_kind;

/* One signal of a DBC frame (little-endian integer signals only). */
typedef struct {
    const char *name;
    unsigned start, length; /* bits */
    int is_signed;
    double scale, offset;
    double minimum, maximum; /* physical; the DBC's, or the raw range when the DBC gives none */
    gs_hil_role role;
    size_t aux;
    const signed char *modes; /* cmd.mode: gs_hil_mode per raw value - raw minimum, -1 undefined */
    int mode_choices;         /* cmd.mode has a value table: an undefined value is checked first */
} gs_hil_signal;

typedef struct {
    const char *name;
    uint32_t id;
    int is_extended;
    unsigned length; /* bytes */
    gs_hil_frame_kind kind;
    unsigned cycle_ms; /* GenMsgCycleTime, 0 = none */
    const gs_hil_signal *signals;
    unsigned signal_count;
    int is_status; /* holds status.* roles (sent after the other feedback of a period) */
} gs_hil_frame_spec;

typedef struct {
    const char *name;
    gs_rig_block block;
    const gs_hil_frame_spec *frames;
    unsigned frame_count;
} gs_hil_dbc;

/* The DBCs built into the library (hil/dbc/gear_rig.dbc, hil/dbc/rack_rig.dbc). */
extern const gs_hil_dbc gs_hil_dbc_gear_rig;
extern const gs_hil_dbc gs_hil_dbc_rack_rig;

/* A classic CAN frame. timestamp_s: receive time (the out-of-order check
 * compares it) or, for frames the bridge sends, the stamp it chose. */
typedef struct {
    double timestamp_s;
    uint32_t id;
    int is_extended, is_remote, is_error;
    unsigned length;
    uint8_t data[GS_HIL_MAX_DATA];
} gs_hil_frame;

/* ---- codec ------------------------------------------------------------- */

/* Decoded command: value[GS_HIL_CMD_*] (mode as gs_hil_mode), present[]. */
typedef struct {
    double value[GS_HIL_CMD_ROLES];
    int present[GS_HIL_CMD_ROLES];
} gs_hil_command;

/* The slot of a command role in gs_hil_command.value (GS_HIL_CMD_*), -1 for
 * any other role. */
int gs_hil_role_command_index(gs_hil_role role);

/* Decode and range-check a command frame: GS_HIL_PENDING with *cmd filled,
 * or GS_HIL_REJECTED_BAD_LENGTH / _UNDECODABLE / _OUT_OF_RANGE. The first
 * failing signal in DBC order gives the reason; nothing is applied in part. */
gs_hil_reason gs_hil_decode_command(const gs_hil_frame_spec *spec, const uint8_t *data, unsigned length,
                                    gs_hil_command *cmd);

/* Physical value of a signal in data (raw * scale + offset). */
double gs_hil_signal_value(const gs_hil_signal *sig, const uint8_t *data);

/* Put a physical value into data: clamped into [minimum, maximum] (NaN: the
 * value in range nearest 0; +-inf: the bound), then raw = round half to even
 * ((x - offset) / scale). Returns 1 when the value was clamped, else 0. */
int gs_hil_put_value(const gs_hil_signal *sig, double value, uint8_t *data);

/* Put a raw value (counters: taken modulo 2^length). */
void gs_hil_put_raw(const gs_hil_signal *sig, uint64_t raw, uint8_t *data);

/* ---- the bridge ------------------------------------------------------------ */

typedef struct {
    uint64_t count[GS_HIL_COUNTS];
    uint64_t reasons[GS_HIL_REASONS];
    uint64_t steps;
} gs_hil_counters;

/* Where feedback goes: 0 = sent (tx_frames + 1), else a transmit error
 * (tx_errors + 1, flag TxError, the frame is dropped). */
typedef int (*gs_hil_send_fn)(void *context, const gs_hil_frame *frame);

typedef struct {
    const gs_hil_dbc *dbc;
    gs_base_drive base_drive;   /* must be the rig's */
    gs_real dt_s;               /* the rig's step */
    unsigned substeps;          /* rig steps per frame period (>= 1) */
    double timeout_s;           /* command timeout, rounded to whole periods (>= 1) */
    gs_real ambient_temperature_K; /* the ambient and measured temperature inputs */
    double stamp_origin_s;      /* sent frames carry stamp_origin_s + periods * period_s */
    gs_hil_send_fn send;
    void *send_context;
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
    unsigned cycle_periods[GS_HIL_MAX_FRAMES]; /* feedback frames, 0 otherwise */
    unsigned feedback_order[GS_HIL_MAX_FRAMES]; /* frame indices: others by ID, then status by ID */
    unsigned feedback_count;
    unsigned command_index[GS_HIL_MAX_FRAMES]; /* frame index -> command slot */
    unsigned command_count;
    gs_hil_command_slot commands[GS_HIL_MAX_COMMAND_FRAMES];
    int has_role[GS_HIL_CMD_ROLES];
    int timed_out, ever_commanded, dirty, closed;
    uint64_t stale_at;
    int flag_state[3]; /* cmd_timeout, safe_state, drive_disabled */
    gs_rig_input input;
    gs_rig_output output;
    unsigned status_seq[GS_HIL_MAX_FRAMES];
    uint64_t latched_at[GS_HIL_MAX_FRAMES][5];
    gs_hil_counters counters;
} gs_hil_bridge;

typedef enum {
    GS_HIL_OK = 0,
    GS_HIL_E_CONFIG = -1, /* see gs_hil_error: parameter and message */
} gs_hil_status;

typedef struct {
    const char *parameter;
    char message[200];
} gs_hil_error;

/* Set up a bridge around an initialised rig (gs_rig_init_*: consts read, state
 * stepped). Checks: DBC for the rig's block, the driving command role present,
 * substeps >= 1, timeout > 0, every feedback cycle time a whole number of
 * frame periods. */
gs_hil_status gs_hil_bridge_init(gs_hil_bridge *bridge, const gs_hil_config *config, gs_rig_block block,
                                 const gs_rig_consts *consts, gs_rig_state *state, gs_hil_error *err);

/* Classify one received frame (counted in exactly one class). */
gs_hil_reason gs_hil_handle(gs_hil_bridge *bridge, const gs_hil_frame *frame);

/* Run n frame periods: apply pending commands, check the timeout, step the
 * rig substeps times, send the feedback that is due. Never blocks. */
void gs_hil_advance(gs_hil_bridge *bridge, uint64_t periods);

/* Stop: pending commands count as late (after_stop). Idempotent. */
void gs_hil_close(gs_hil_bridge *bridge);

/* Commands received and not yet applied. */
unsigned gs_hil_pending(const gs_hil_bridge *bridge);

#ifdef __cplusplus
}
#endif
#endif /* GEARSIM_HIL_H */
