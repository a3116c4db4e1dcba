/* One tables handle shared by the caller's threads: nephele_evaluate_batch over N points on one
 * thread, then over the same points shared among T threads, each claiming chunks of 1024
 * points from a shared counter until none is left (so that a thread slowed by the machine
 * takes fewer). Checks that every answer is the same bits, and prints the points per second
 * of each (the library starts no threads of its own; this is how a renderer shares a batch).
 *
 *   cc -O2 -I capi/include examples/c/nephele_threads.c target/release/libnephele_c.a \
 *      -lm -lpthread -ldl -o threads
 *   ./threads runtime/tables/mie10um/transport.ntt 200000 2 5
 *
 * Arguments: tables, points N, threads T, rounds (one and T threads alternately; the fastest of
 * each is kept).
 * stdout: "identical 1", "one_thread <points/s>", "threads <T> <points/s>", "ratio <x>". */
#define _POSIX_C_SOURCE 200112L
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nephele.h"

enum { CHUNK = 1024 };

typedef struct {
    const NepheleTables *tables;
    const NepheleSlabPoint *points;
    NepheleTransport *out;
    size_t count, groups;
    size_t *next; /* the first point not yet claimed, shared */
    NepheleStatus status;
    char message[256]; /* the worker's own last error: messages are per thread */
} Range;

static void *run_range(void *arg) {
    Range *r = arg;
    r->status = NEPHELE_STATUS_OK;
    for (;;) {
        size_t first = __atomic_fetch_add(r->next, (size_t)CHUNK, __ATOMIC_RELAXED);
        if (first >= r->count || r->status != NEPHELE_STATUS_OK) break;
        size_t n = r->count - first < CHUNK ? r->count - first : CHUNK;
        r->status = nephele_evaluate_batch(r->tables, r->points + first, n, 0,
                                           r->out + first * r->groups, 0, NULL, NULL);
        if (r->status != NEPHELE_STATUS_OK)
            snprintf(r->message, sizeof r->message, "%s", nephele_last_error());
    }
    return NULL;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The seconds of one pass over all points on `threads` threads. */
static double timed(Range *proto, size_t n, int threads) {
    {
        pthread_t ids[64];
        Range ranges[64];
        size_t next = 0;
        double start = now();
        for (int i = 0; i < threads; i++) {
            ranges[i] = *proto;
            ranges[i].count = n;
            ranges[i].next = &next;
            pthread_create(&ids[i], NULL, run_range, &ranges[i]);
        }
        for (int i = 0; i < threads; i++) {
            pthread_join(ids[i], NULL);
            if (ranges[i].status != NEPHELE_STATUS_OK) {
                fprintf(stderr, "thread %d: %s\n", i, ranges[i].message);
                exit(1);
            }
        }
        return now() - start;
    }
}

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: %s transport.ntt points threads rounds\n", argv[0]);
        return 2;
    }
    size_t n = (size_t)strtoull(argv[2], NULL, 10);
    int threads = atoi(argv[3]), rounds = atoi(argv[4]);
    if (n == 0 || threads < 1 || threads > 64 || rounds < 1) {
        fprintf(stderr, "points >= 1, 1 <= threads <= 64, rounds >= 1\n");
        return 2;
    }
    NepheleTables *tables = NULL;
    NepheleDomain domain;
    if (nephele_tables_from_file(argv[1], &tables) != NEPHELE_STATUS_OK ||
        nephele_tables_domain(tables, &domain) != NEPHELE_STATUS_OK) {
        fprintf(stderr, "%s\n", nephele_last_error());
        return 1;
    }
    /* Points over the tables' grid (xorshift, reproducible). */
    NepheleSlabPoint *points = malloc(n * sizeof *points);
    uint64_t s = 0x9E3779B97F4A7C15ull;
    for (size_t i = 0; i < n; i++) {
        float r[5];
        for (int k = 0; k < 5; k++) {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            r[k] = (float)(s >> 40) / (float)(1u << 24);
        }
        float t = domain.thickness_min * powf(domain.thickness_max / domain.thickness_min, r[0]);
        points[i] = (NepheleSlabPoint){t, domain.mu_l_min + (1.0f - domain.mu_l_min) * r[1],
                                       t * r[2], 2.0f * r[3] - 1.0f, 3.1415926f * r[4]};
    }
    size_t g = domain.groups;
    NepheleTransport *one = malloc(n * g * sizeof *one), *many = malloc(n * g * sizeof *many);
    /* One thread and T threads alternately, the fastest of each kept: a machine whose clock
       drifts slows both alike. */
    Range single = {tables, points, one, n, g, NULL, NEPHELE_STATUS_OK, ""}, split = single;
    split.out = many;
    double t1 = INFINITY, tn = INFINITY;
    for (int k = 0; k < rounds; k++) {
        double a = timed(&single, n, 1), b = timed(&split, n, threads);
        t1 = a < t1 ? a : t1;
        tn = b < tn ? b : tn;
    }
    printf("identical %d\n", memcmp(one, many, n * g * sizeof *one) == 0);
    printf("one_thread %.0f\n", (double)n / t1);
    printf("threads %d %.0f\n", threads, (double)n / tn);
    printf("ratio %.3f\n", t1 / tn);
    free(points);
    free(one);
    free(many);
    nephele_tables_free(tables);
    return 0;
}
