/*
 * Transports of the runner: file descriptors (pipes, FIFOs, files, a CAN_RAW
 * socket), read and written without blocking (every descriptor is
 * O_NONBLOCK). The text of the candump transport is candump.c's. Inside the
 * paced loop only read(), write() and that formatting run here: no stdio, no
 * heap, nothing that blocks.
 */
#define _GNU_SOURCE
#include "transport.h"

#include "candump.h"

#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

static int set_nonblocking(int fd)
{
    int flags = fcntl(fd, F_GETFL);
    return flags < 0 ? -1 : fcntl(fd, F_SETFL, flags | O_NONBLOCK);
}

static int is_fifo(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISFIFO(st.st_mode);
}

static void init_common(transport *t, transport_kind kind)
{
    t->kind = kind;
    t->rx_fd = -1;
    t->tx_fd = -1;
    t->rx_eof = 0;
    t->rx_len = 0;
    t->rx_overlong = 0;
    t->tx_start = t->tx_end = 0;
    t->malformed_lines = 0;
    t->write_errors = 0;
    t->channel = "can0";
}

int transport_open_candump(transport *t, const char *rx_path, const char *tx_path, char *message, size_t size)
{
    init_common(t, TRANSPORT_CANDUMP);
    /* A FIFO is opened read-write: opening does not wait for the other end,
     * and it never reads end-of-file while the peer reopens it. */
    if (strcmp(rx_path, "-") == 0) {
        t->rx_fd = STDIN_FILENO;
    } else {
        t->rx_fd = open(rx_path, (is_fifo(rx_path) ? O_RDWR : O_RDONLY) | O_NONBLOCK | O_CLOEXEC);
    }
    if (t->rx_fd < 0 || set_nonblocking(t->rx_fd) != 0) {
        snprintf(message, size, "--rx %s: cannot open: %s", rx_path, strerror(errno));
        return -1;
    }
    if (strcmp(tx_path, "-") == 0) {
        t->tx_fd = STDOUT_FILENO;
    } else if (is_fifo(tx_path)) {
        t->tx_fd = open(tx_path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    } else {
        t->tx_fd = open(tx_path, O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK | O_CLOEXEC, 0666);
    }
    if (t->tx_fd < 0 || set_nonblocking(t->tx_fd) != 0) {
        snprintf(message, size, "--tx %s: cannot open: %s", tx_path, strerror(errno));
        return -1;
    }
    return 0;
}

int transport_open_socketcan(transport *t, const char *ifname, char *message, size_t size)
{
    init_common(t, TRANSPORT_SOCKETCAN);
    t->channel = ifname;
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        int e = errno;
        snprintf(message, size,
                 "--channel %s: cannot open a SocketCAN socket: %s%s", ifname, strerror(e),
                 e == EAFNOSUPPORT ? " (this kernel has no AF_CAN; load it with modprobe can_raw, or use "
                                     "--transport candump)"
                                   : "");
        return -1;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    if (strlen(ifname) >= sizeof ifr.ifr_name) {
        close(fd);
        snprintf(message, size, "--channel %s: interface name too long", ifname);
        return -1;
    }
    memcpy(ifr.ifr_name, ifname, strlen(ifname));
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        int e = errno;
        close(fd);
        snprintf(message, size, "--channel %s: no such CAN interface: %s (ip link show)", ifname, strerror(e));
        return -1;
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(fd, (struct sockaddr *)(void *)&addr, sizeof addr) < 0) {
        int e = errno;
        close(fd);
        snprintf(message, size, "--channel %s: cannot bind: %s (is the interface up?)", ifname, strerror(e));
        return -1;
    }
    t->rx_fd = t->tx_fd = fd;
    return 0;
}

static unsigned poll_socketcan(transport *t, double now_s, transport_handler handler, void *context)
{
    unsigned n = 0;
    struct can_frame cf;
    for (;;) {
        ssize_t got = read(t->rx_fd, &cf, sizeof cf);
        if (got != (ssize_t)sizeof cf) {
            return n; /* EAGAIN: nothing more; a short read cannot happen on CAN_RAW */
        }
        gs_hil_frame frame;
        memset(&frame, 0, sizeof frame);
        frame.timestamp_s = now_s;
        frame.is_extended = (cf.can_id & CAN_EFF_FLAG) != 0u;
        frame.is_remote = (cf.can_id & CAN_RTR_FLAG) != 0u;
        frame.is_error = (cf.can_id & CAN_ERR_FLAG) != 0u;
        frame.id = cf.can_id & (frame.is_extended ? CAN_EFF_MASK : CAN_SFF_MASK);
        frame.length = cf.can_dlc <= GS_HIL_MAX_DATA ? cf.can_dlc : GS_HIL_MAX_DATA;
        memcpy(frame.data, cf.data, frame.length);
        handler(context, &frame);
        ++n;
    }
}

/* Complete lines in the buffer -> frames; a partial line waits for its end. */
static unsigned take_lines(transport *t, double now_s, transport_handler handler, void *context)
{
    unsigned n = 0;
    size_t start = 0;
    for (size_t i = 0; i < t->rx_len; ++i) {
        if (t->rx_buf[i] != '\n') {
            continue;
        }
        const char *line = t->rx_buf + start;
        size_t len = i - start;
        start = i + 1u;
        if (t->rx_overlong) {
            t->rx_overlong = 0;
            continue;
        }
        if (candump_is_blank(line, len)) {
            continue;
        }
        gs_hil_frame frame;
        if (candump_parse_line(line, len, &frame) != 0) {
            t->malformed_lines++;
            continue;
        }
        frame.timestamp_s = now_s; /* live: the receive time, as a bus stamps it */
        handler(context, &frame);
        ++n;
    }
    memmove(t->rx_buf, t->rx_buf + start, t->rx_len - start);
    t->rx_len -= start;
    if (t->rx_len == sizeof t->rx_buf) { /* one line fills the buffer: drop it */
        t->malformed_lines++;
        t->rx_overlong = 1;
        t->rx_len = 0;
    }
    return n;
}

static unsigned poll_candump(transport *t, double now_s, transport_handler handler, void *context)
{
    unsigned n = 0;
    while (!t->rx_eof) {
        ssize_t got = read(t->rx_fd, t->rx_buf + t->rx_len, sizeof t->rx_buf - t->rx_len);
        if (got > 0) {
            t->rx_len += (size_t)got;
            n += take_lines(t, now_s, handler, context);
            continue;
        }
        if (got == 0) {
            t->rx_eof = 1; /* the peer closed its end: keep answering (commands time out) */
        } else if (errno == EINTR) {
            continue;
        }
        break;
    }
    return n;
}

unsigned transport_poll(transport *t, double now_s, transport_handler handler, void *context)
{
    return t->kind == TRANSPORT_SOCKETCAN ? poll_socketcan(t, now_s, handler, context)
                                          : poll_candump(t, now_s, handler, context);
}

static int send_socketcan(transport *t, const gs_hil_frame *frame)
{
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = frame->id | (frame->is_extended ? CAN_EFF_FLAG : 0u);
    cf.can_dlc = (uint8_t)(frame->length < GS_HIL_MAX_DATA ? frame->length : GS_HIL_MAX_DATA);
    memcpy(cf.data, frame->data, cf.can_dlc);
    /* ENOBUFS (queue full, no acknowledging node) and EAGAIN: the frame is dropped */
    return write(t->tx_fd, &cf, sizeof cf) == (ssize_t)sizeof cf ? 0 : -1;
}

int transport_send(transport *t, const gs_hil_frame *frame, double stamp_s)
{
    if (t->kind == TRANSPORT_SOCKETCAN) {
        return send_socketcan(t, frame);
    }
    if (t->tx_start == t->tx_end) {
        t->tx_start = t->tx_end = 0;
    }
    if (sizeof t->tx_buf - t->tx_end < 128u) { /* compact: move the unsent bytes to the front */
        memmove(t->tx_buf, t->tx_buf + t->tx_start, t->tx_end - t->tx_start);
        t->tx_end -= t->tx_start;
        t->tx_start = 0;
    }
    size_t n = candump_format_line(frame, stamp_s, t->channel, t->tx_buf + t->tx_end, sizeof t->tx_buf - t->tx_end);
    if (n == 0) {
        return -1; /* no room: the reader is too slow */
    }
    t->tx_end += n;
    return 0;
}

void transport_flush(transport *t)
{
    while (t->kind == TRANSPORT_CANDUMP && t->tx_start < t->tx_end) {
        ssize_t put = write(t->tx_fd, t->tx_buf + t->tx_start, t->tx_end - t->tx_start);
        if (put > 0) {
            t->tx_start += (size_t)put;
            continue;
        }
        if (put < 0 && errno == EINTR) {
            continue;
        }
        if (put < 0 && errno != EAGAIN) {
            t->write_errors++; /* EPIPE: nobody reads; drop what is queued */
            t->tx_start = t->tx_end;
        }
        break;
    }
}

void transport_drain(transport *t, int timeout_ms)
{
    for (int waited = 0; t->kind == TRANSPORT_CANDUMP && t->tx_start < t->tx_end && waited < timeout_ms; waited += 10) {
        transport_flush(t);
        if (t->tx_start < t->tx_end) {
            struct pollfd pfd = {t->tx_fd, POLLOUT, 0};
            (void)poll(&pfd, 1, 10);
        }
    }
}

void transport_close(transport *t)
{
    if (t->rx_fd > STDERR_FILENO) {
        close(t->rx_fd);
    }
    if (t->tx_fd > STDERR_FILENO && t->tx_fd != t->rx_fd) {
        close(t->tx_fd);
    }
    t->rx_fd = t->tx_fd = -1;
}
