/*
 * The recording's ring and writer thread (recorder.h). The ring's indices
 * are published with release stores and read with acquire loads (GCC's
 * __atomic builtins, as C99 has no <stdatomic.h>): the loop writes an entry,
 * then moves head; the writer reads entries up to head, then moves tail.
 */
#define _GNU_SOURCE
#include "recorder.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "candump.h"

static void *writer_main(void *arg)
{
    recorder *r = arg;
    char line[160];
    for (;;) {
        int stopping = __atomic_load_n(&r->stop, __ATOMIC_ACQUIRE);
        uint64_t head = __atomic_load_n(&r->head, __ATOMIC_ACQUIRE);
        uint64_t tail = r->tail;
        while (tail != head) {
            const recorder_entry *e = &r->ring[tail % RECORDER_RING];
            size_t n = candump_format_line_dir(&e->frame, e->stamp_s, r->channel, e->direction, line, sizeof line);
            if (n == 0 || fwrite(line, 1, n, r->file) != n) {
                r->write_failed = 1;
            }
            ++tail;
            r->written++;
            __atomic_store_n(&r->tail, tail, __ATOMIC_RELEASE);
        }
        if (stopping) {
            return NULL; /* head was read after stop: nothing more comes */
        }
        struct timespec pause = {0, 2000000}; /* 2 ms: a writer, not a real-time thread */
        nanosleep(&pause, NULL);
    }
}

static void keep_off_cpu(pthread_t thread, long avoid_cpu)
{
    if (avoid_cpu < 0) {
        return;
    }
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) != 0) {
        return;
    }
    CPU_CLR((size_t)avoid_cpu, &set);
    if (CPU_COUNT(&set) > 0) {
        (void)pthread_setaffinity_np(thread, sizeof set, &set);
    }
}

int recorder_open(recorder *r, const char *path, const char *channel, long avoid_cpu, char *message, size_t size)
{
    r->head = r->tail = 0;
    r->stop = 0;
    r->dropped = r->written = 0;
    r->write_failed = 0;
    r->channel = channel;
    r->path = path;
    r->running = 0;
    const char *slash = strrchr(path, '/');
    int dir_len = slash == NULL ? 0 : (int)(slash - path + 1);
    snprintf(r->tmp, sizeof r->tmp, "%.*s.gearsim-tmp-XXXXXX.log", dir_len, path);
    int fd = mkstemps(r->tmp, 4);
    if (fd < 0) {
        snprintf(message, size, "--log %s: cannot write there: %s", path, strerror(errno));
        return -1;
    }
    mode_t mask = umask(0);
    umask(mask);
    (void)fchmod(fd, 0666 & ~mask);
    r->file = fdopen(fd, "w");
    if (r->file == NULL) {
        snprintf(message, size, "--log %s: %s", path, strerror(errno));
        close(fd);
        unlink(r->tmp);
        return -1;
    }
    /* an ordinary thread, whatever the loop's scheduling (--fifo is inherited otherwise) */
    pthread_attr_t attr;
    struct sched_param none;
    memset(&none, 0, sizeof none);
    pthread_attr_init(&attr);
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_OTHER);
    pthread_attr_setschedparam(&attr, &none);
    int e = pthread_create(&r->thread, &attr, writer_main, r);
    pthread_attr_destroy(&attr);
    if (e != 0) {
        snprintf(message, size, "--log %s: cannot start the writer thread: %s", path, strerror(e));
        fclose(r->file);
        unlink(r->tmp);
        return -1;
    }
    keep_off_cpu(r->thread, avoid_cpu);
    r->running = 1;
    return 0;
}

int recorder_put(recorder *r, const gs_hil_frame *frame, double stamp_s, char direction)
{
    uint64_t head = r->head;
    uint64_t tail = __atomic_load_n(&r->tail, __ATOMIC_ACQUIRE);
    if (head - tail >= RECORDER_RING) {
        r->dropped++;
        return -1;
    }
    recorder_entry *e = &r->ring[head % RECORDER_RING];
    e->stamp_s = stamp_s;
    e->frame = *frame;
    e->direction = direction;
    __atomic_store_n(&r->head, head + 1u, __ATOMIC_RELEASE);
    return 0;
}

int recorder_close(recorder *r, int keep)
{
    if (!r->running) {
        return 0;
    }
    __atomic_store_n(&r->stop, 1, __ATOMIC_RELEASE);
    pthread_join(r->thread, NULL);
    r->running = 0;
    int bad = r->write_failed || fflush(r->file) != 0 || fsync(fileno(r->file)) != 0;
    bad |= fclose(r->file) != 0;
    if (bad || !keep || rename(r->tmp, r->path) != 0) {
        unlink(r->tmp);
        return bad ? -1 : 0;
    }
    return 0;
}
