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

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <math.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdlib.h>
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
    t->listen_fd = -1;
    t->sc_state = SC_NONE;
    t->sc_send_from = 0.0;
    t->connects = t->disconnects = 0;
    t->listen_on[0] = '\0';
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
        snprintf(message, size, "--channel %s: cannot open a SocketCAN socket: %s%s", ifname, strerror(e),
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

/* ---- socketcand ------------------------------------------------------------------ */

int transport_open_socketcand(transport *t, const char *listen_spec, const char *bus, char *message, size_t size)
{
    init_common(t, TRANSPORT_SOCKETCAND);
    t->channel = bus;
    char host[64];
    const char *colon = strrchr(listen_spec, ':');
    char *end = NULL;
    long port = colon != NULL ? strtol(colon + 1, &end, 10) : -1;
    if (colon == NULL || (size_t)(colon - listen_spec) >= sizeof host || end == colon + 1 || *end != '\0' || port < 0 ||
        port > 65535) {
        snprintf(message, size, "--listen %s: expected HOST:PORT (e.g. 127.0.0.1:29536)", listen_spec);
        return -1;
    }
    snprintf(host, sizeof host, "%.*s", (int)(colon - listen_spec), listen_spec);
    struct sockaddr_in addr;
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons((uint16_t)port);
    if (inet_pton(AF_INET, host, &addr.sin_addr) != 1) {
        snprintf(message, size, "--listen %s: %s is not an IPv4 address", listen_spec, host);
        return -1;
    }
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    int one = 1;
    if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        bind(fd, (struct sockaddr *)(void *)&addr, sizeof addr) != 0 || listen(fd, 4) != 0) {
        int e = errno;
        if (fd >= 0) {
            close(fd);
        }
        snprintf(message, size, "--listen %s: cannot listen there: %s", listen_spec, strerror(e));
        return -1;
    }
    socklen_t len = sizeof addr;
    getsockname(fd, (struct sockaddr *)(void *)&addr, &len);
    snprintf(t->listen_on, sizeof t->listen_on, "%s:%u", host, (unsigned)ntohs(addr.sin_port));
    t->listen_fd = fd;
    return 0;
}

static void sc_write_now(transport *t, const char *text)
{
    /* a handshake answer: a few bytes to a socket that has room for them */
    (void)send(t->rx_fd, text, strlen(text), MSG_NOSIGNAL | MSG_DONTWAIT);
}

static void sc_disconnect(transport *t)
{
    if (t->rx_fd >= 0) {
        close(t->rx_fd);
        t->disconnects++;
    }
    t->rx_fd = t->tx_fd = -1;
    t->sc_state = SC_NONE;
    t->rx_len = 0;
    t->rx_overlong = 0;
    t->tx_start = t->tx_end = 0; /* what was queued for that client goes nowhere */
}

static void sc_accept(transport *t)
{
    for (;;) {
        int fd = accept4(t->listen_fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            return; /* EAGAIN: nobody waiting */
        }
        if (t->rx_fd >= 0) {
            sc_disconnect(t); /* one client at a time: the newest (a client that came back) */
        }
        int one = 1;
        (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        t->rx_fd = t->tx_fd = fd;
        t->connects++;
        t->sc_state = SC_GREETED;
        sc_write_now(t, "< hi >");
    }
}

static int hex_value(const char *s, unsigned long *out)
{
    char *end = NULL;
    if (*s == '\0') {
        return -1;
    }
    *out = strtoul(s, &end, 16);
    return *end == '\0' ? 0 : -1;
}

/* "send ID DLC B0 B1 ..." (words) -> a frame; 0, or -1 when it is not one. */
static int sc_frame(char **word, int words, gs_hil_frame *frame)
{
    unsigned long id, dlc, byte;
    if (words < 3 || hex_value(word[1], &id) != 0 || hex_value(word[2], &dlc) != 0 || dlc > GS_HIL_MAX_DATA ||
        (unsigned long)(words - 3) != dlc || id > 0x1FFFFFFFul) {
        return -1;
    }
    memset(frame, 0, sizeof *frame);
    frame->id = (uint32_t)id;
    frame->is_extended = strlen(word[1]) > 3u || id > 0x7FFul;
    frame->length = (unsigned)dlc;
    for (int i = 0; i < (int)dlc; ++i) {
        if (hex_value(word[3 + i], &byte) != 0 || byte > 0xFFul) {
            return -1;
        }
        frame->data[i] = (uint8_t)byte;
    }
    return 0;
}

/* One "< ... >" message of the client (text without the brackets). */
static unsigned sc_message(transport *t, char *text, double now_s, transport_handler handler, void *context)
{
    char *word[4 + GS_HIL_MAX_DATA];
    int words = 0;
    for (char *save = NULL, *w = strtok_r(text, " \t\r\n", &save);
         w != NULL && words < (int)(sizeof word / sizeof word[0]); w = strtok_r(NULL, " \t\r\n", &save)) {
        word[words++] = w;
    }
    if (words == 0) {
        t->malformed_lines++;
        return 0;
    }
    if (strcmp(word[0], "echo") == 0) {
        sc_write_now(t, "< echo >");
    } else if (t->sc_state == SC_GREETED && strcmp(word[0], "open") == 0 && words == 2) {
        if (strcmp(word[1], t->channel) == 0) {
            t->sc_state = SC_OPEN;
            sc_write_now(t, "< ok >");
        } else {
            sc_write_now(t, "< error could not open bus >");
        }
    } else if (t->sc_state == SC_OPEN && strcmp(word[0], "rawmode") == 0) {
        t->sc_state = SC_RAW;
        t->sc_send_from = now_s + SOCKETCAND_GRACE_S;
        sc_write_now(t, "< ok >");
    } else if (t->sc_state == SC_RAW && strcmp(word[0], "send") == 0) {
        gs_hil_frame frame;
        if (sc_frame(word, words, &frame) == 0) {
            frame.timestamp_s = now_s;
            handler(context, &frame);
            return 1;
        }
        t->malformed_lines++;
    } else {
        t->malformed_lines++; /* in raw mode nothing else is answered: a client reads answers as frames */
    }
    return 0;
}

/* The complete messages in the buffer; a partial one waits for its end. */
static unsigned sc_take(transport *t, double now_s, transport_handler handler, void *context)
{
    unsigned n = 0;
    size_t start = 0;
    for (;;) {
        char *open = memchr(t->rx_buf + start, '<', t->rx_len - start);
        if (open == NULL) {
            start = t->rx_len; /* text outside brackets: dropped */
            break;
        }
        char *close_ = memchr(open, '>', (size_t)(t->rx_buf + t->rx_len - open));
        if (close_ == NULL) {
            start = (size_t)(open - t->rx_buf);
            break;
        }
        *close_ = '\0';
        n += sc_message(t, open + 1, now_s, handler, context);
        start = (size_t)(close_ - t->rx_buf) + 1u;
    }
    memmove(t->rx_buf, t->rx_buf + start, t->rx_len - start);
    t->rx_len -= start;
    if (t->rx_len == sizeof t->rx_buf) {
        t->malformed_lines++;
        t->rx_len = 0;
    }
    return n;
}

static unsigned poll_socketcand(transport *t, double now_s, transport_handler handler, void *context)
{
    sc_accept(t);
    unsigned n = 0;
    while (t->rx_fd >= 0) {
        ssize_t got = recv(t->rx_fd, t->rx_buf + t->rx_len, sizeof t->rx_buf - t->rx_len, MSG_DONTWAIT);
        if (got > 0) {
            t->rx_len += (size_t)got;
            n += sc_take(t, now_s, handler, context);
            continue;
        }
        if (got < 0 && errno == EINTR) {
            continue;
        }
        if (got == 0 || (errno != EAGAIN && errno != EWOULDBLOCK)) {
            if (t->rx_len > 0u) {
                t->malformed_lines++; /* a message cut by the disconnect */
            }
            sc_disconnect(t); /* everything it sent before is handled above */
        }
        break;
    }
    return n;
}

unsigned transport_poll(transport *t, double now_s, transport_handler handler, void *context)
{
    switch (t->kind) {
    case TRANSPORT_SOCKETCAN:
        return poll_socketcan(t, now_s, handler, context);
    case TRANSPORT_SOCKETCAND:
        return poll_socketcand(t, now_s, handler, context);
    case TRANSPORT_CANDUMP:
    default:
        return poll_candump(t, now_s, handler, context);
    }
}

/* "< frame ID SECONDS.MICROS DATA >" of socketcand's raw mode. */
static size_t sc_format(const gs_hil_frame *frame, double stamp_s, char *out, size_t size)
{
    char data[2 * GS_HIL_MAX_DATA + 1];
    unsigned length = frame->length < GS_HIL_MAX_DATA ? frame->length : GS_HIL_MAX_DATA;
    for (unsigned i = 0; i < length; ++i) {
        snprintf(data + 2 * i, 3, "%02X", frame->data[i]);
    }
    data[2 * length] = '\0';
    long long micros = llround(stamp_s * 1e6);
    int n = snprintf(out, size, frame->is_extended ? "< frame %08X %lld.%06lld %s >" : "< frame %03X %lld.%06lld %s >",
                     (unsigned)frame->id, micros / 1000000, micros % 1000000, data);
    return n > 0 && (size_t)n < size ? (size_t)n : 0u;
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
    if (t->kind == TRANSPORT_SOCKETCAND && (t->sc_state != SC_RAW || stamp_s < t->sc_send_from)) {
        return 0; /* nobody listening yet: sent into an empty bus, as on CAN */
    }
    if (t->tx_start == t->tx_end) {
        t->tx_start = t->tx_end = 0;
    }
    if (sizeof t->tx_buf - t->tx_end < 128u) { /* compact: move the unsent bytes to the front */
        memmove(t->tx_buf, t->tx_buf + t->tx_start, t->tx_end - t->tx_start);
        t->tx_end -= t->tx_start;
        t->tx_start = 0;
    }
    size_t room = sizeof t->tx_buf - t->tx_end;
    size_t n = t->kind == TRANSPORT_SOCKETCAND
                   ? sc_format(frame, stamp_s, t->tx_buf + t->tx_end, room)
                   : candump_format_line(frame, stamp_s, t->channel, t->tx_buf + t->tx_end, room);
    if (n == 0) {
        return -1; /* no room: the reader is too slow */
    }
    t->tx_end += n;
    return 0;
}

void transport_flush(transport *t)
{
    if (t->kind == TRANSPORT_SOCKETCAND) {
        while (t->tx_fd >= 0 && t->tx_start < t->tx_end) {
            ssize_t put = send(t->tx_fd, t->tx_buf + t->tx_start, t->tx_end - t->tx_start, MSG_NOSIGNAL | MSG_DONTWAIT);
            if (put > 0) {
                t->tx_start += (size_t)put;
            } else if (put < 0 && errno == EINTR) {
                continue;
            } else {
                if (put < 0 && errno != EAGAIN && errno != EWOULDBLOCK) {
                    sc_disconnect(t); /* reset by the peer: the next poll sees no client */
                }
                break;
            }
        }
        return;
    }
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
    for (int waited = 0;
         t->kind != TRANSPORT_SOCKETCAN && t->tx_fd >= 0 && t->tx_start < t->tx_end && waited < timeout_ms;
         waited += 10) {
        transport_flush(t);
        if (t->tx_start < t->tx_end) {
            struct pollfd pfd = {t->tx_fd, POLLOUT, 0};
            (void)poll(&pfd, 1, 10);
        }
    }
}

void transport_close(transport *t)
{
    if (t->listen_fd >= 0) {
        close(t->listen_fd);
        t->listen_fd = -1;
    }
    if (t->rx_fd > STDERR_FILENO) {
        close(t->rx_fd);
    }
    if (t->tx_fd > STDERR_FILENO && t->tx_fd != t->rx_fd) {
        close(t->tx_fd);
    }
    t->rx_fd = t->tx_fd = -1;
}
