/*
 * The runner's transports (docs/hil-runner.md, "Transports"): candump -L text
 * lines over pipes or FIFOs, SocketCAN CAN_RAW, and a socketcand server (TCP,
 * the ASCII protocol of socketcand's raw mode, which python-can's socketcand
 * interface speaks). Reads and writes never block; frames to send are queued
 * in a fixed buffer and written whole, so a slow reader costs frames (counted
 * as transmit errors), never the period.
 */
#ifndef GEARSIM_HIL_RUNNER_TRANSPORT_H
#define GEARSIM_HIL_RUNNER_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

#include "gearsim/hil.h"

typedef enum { TRANSPORT_CANDUMP = 0, TRANSPORT_SOCKETCAN = 1, TRANSPORT_SOCKETCAND = 2 } transport_kind;

/* socketcand: where a client is in the protocol. */
typedef enum { SC_NONE = 0, SC_GREETED, SC_OPEN, SC_RAW } socketcand_state;

/* socketcand: after its rawmode "< ok >" a client gets frames from this
 * long on (python-can's client reads the "< ok >" with one recv and must not
 * find a frame behind it). */
#define SOCKETCAND_GRACE_S 0.05

#define TRANSPORT_RX_BUFFER 65536
#define TRANSPORT_TX_BUFFER 262144

typedef struct {
    transport_kind kind;
    int rx_fd, tx_fd;
    int rx_eof;
    char rx_buf[TRANSPORT_RX_BUFFER];
    size_t rx_len;
    int rx_overlong; /* dropping the rest of a line longer than the buffer */
    char tx_buf[TRANSPORT_TX_BUFFER];
    size_t tx_start, tx_end;
    const char *channel; /* written in candump lines, e.g. "can0"; socketcand: the bus name */
    uint64_t malformed_lines;
    uint64_t write_errors;
    /* socketcand: the listening socket, the client (rx_fd = tx_fd), its state */
    int listen_fd;
    socketcand_state sc_state;
    double sc_send_from;
    uint64_t connects, disconnects;
    char listen_on[80]; /* "host:port" as bound */
} transport;

typedef void (*transport_handler)(void *context, const gs_hil_frame *frame);

/* candump text: rx_path / tx_path are files or FIFOs, "-" for stdin/stdout.
 * Returns 0, or -1 with one line in message. */
int transport_open_candump(transport *t, const char *rx_path, const char *tx_path, char *message, size_t size);

/* SocketCAN CAN_RAW on interface ifname. Returns 0, or -1 with one line. */
int transport_open_socketcan(transport *t, const char *ifname, char *message, size_t size);

/* socketcand: listen on "host:port" (port 0: any free one; listen_on says
 * which) for one client at a time; bus is the name a client must open.
 * Returns 0, or -1 with one line. */
int transport_open_socketcand(transport *t, const char *listen, const char *bus, char *message, size_t size);

/* Hand every frame waiting to handler, stamped now_s. Never blocks. Returns
 * the number of frames. */
unsigned transport_poll(transport *t, double now_s, transport_handler handler, void *context);

/* Queue one frame stamped stamp_s. 0: queued (or sent); -1: no room / error. */
int transport_send(transport *t, const gs_hil_frame *frame, double stamp_s);

/* Write what is queued, as far as the reader takes it. Never blocks. */
void transport_flush(transport *t);

/* Flush, waiting at most timeout_ms for a slow reader (at exit only). */
void transport_drain(transport *t, int timeout_ms);

void transport_close(transport *t);

#endif
