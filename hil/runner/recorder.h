/*
 * The runner's own recording (docs/hil-runner.md, "Recording"): every frame
 * received and sent, in rig time, as candump -L lines with the direction
 * field (R received, T sent), written by a thread of its own. The paced loop
 * only copies a record into a lock-free single-producer single-consumer
 * ring; when the ring is full the record is dropped and counted, so the
 * recording never blocks the loop. The file is written to a temporary name
 * beside the target and renamed over it when the run ends.
 */
#ifndef GEARSIM_HIL_RUNNER_RECORDER_H
#define GEARSIM_HIL_RUNNER_RECORDER_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "gearsim/hil.h"

#define RECORDER_RING 65536u /* records (a power of two): 65 ms of 1 MHz bus load at 1 kHz... plenty */

typedef struct {
    double stamp_s;
    gs_hil_frame frame;
    char direction; /* 'R' or 'T' */
} recorder_entry;

typedef struct {
    recorder_entry ring[RECORDER_RING];
    uint64_t head; /* written by the loop only (release) */
    uint64_t tail; /* written by the writer only (release) */
    int stop;      /* set by the loop at the end (release) */
    uint64_t dropped;
    uint64_t written;
    int write_failed;
    FILE *file;
    const char *channel;
    const char *path;
    char tmp[4096 + 64];
    pthread_t thread;
    int running;
} recorder;

/* Open the temporary file beside path and start the writer thread (pinned
 * off avoid_cpu when it is >= 0). Returns 0, or -1 with one line in message. */
int recorder_open(recorder *r, const char *path, const char *channel, long avoid_cpu, char *message, size_t size);

/* From the paced loop: never blocks, never allocates. 0, or -1 when the ring
 * was full (the record is dropped and counted). */
int recorder_put(recorder *r, const gs_hil_frame *frame, double stamp_s, char direction);

/* Stop the writer after it has written every record, close the file and
 * rename it over the target (keep != 0) or remove it. Returns 0, or -1 when
 * writing failed (the target is left as it was). */
int recorder_close(recorder *r, int keep);

#endif
