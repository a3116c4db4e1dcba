/* nephele from C: load transport tables, evaluate them and a phase model, and show what bad
 * input gets back. Built and run by capi/tests/abi.rs (under AddressSanitizer and
 * UndefinedBehaviorSanitizer), which checks every number against the Rust runtime bit for bit.
 *
 *   cc -I capi/include examples/c/nephele_example.c target/release/libnephele_c.a -lm -lpthread -ldl
 *   ./a.out runtime/tables/mie10um/transport.ntt < points.txt
 *
 * stdin: one point per line, five f32 as hexadecimal bits (t, mu_L, depth, mu_V, psi_V).
 * stdout: per point "order1 T c_x c_z sigma ..." as hexadecimal bits; then one line per
 * phase value; then "status <case> <code>" lines for the bad input. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nephele.h"

static uint32_t bits(float f) {
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float from_bits(uint32_t u) {
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* The whole file, or NULL. */
static uint8_t *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *data = malloc((size_t)n);
    if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
        free(data);
        data = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return data;
}

static int check(NepheleStatus s, const char *what) {
    if (s != NEPHELE_STATUS_OK) {
        fprintf(stderr, "%s: status %d: %s\n", what, (int)s, nephele_last_error());
        return 1;
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s transport.ntt < points\n", argv[0]);
        return 2;
    }
    size_t len = 0;
    uint8_t *bytes = read_file(argv[1], &len);
    if (!bytes) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 2;
    }
    NepheleTables *tables = NULL;
    if (check(nephele_tables_from_bytes(bytes, len, &tables), "load")) return 1;
    size_t groups = 0;
    if (check(nephele_tables_groups(tables, &groups), "groups")) return 1;

    /* Every point: order 1 and T, c, sigma of every group. */
    NepheleTransport out[NEPHELE_MAX_GROUPS];
    unsigned int p[5];
    while (scanf("%x %x %x %x %x", &p[0], &p[1], &p[2], &p[3], &p[4]) == 5) {
        NepheleSlabPoint at = {from_bits(p[0]), from_bits(p[1]), from_bits(p[2]),
                               from_bits(p[3]), from_bits(p[4])};
        float o1 = 0;
        if (check(nephele_order1(tables, &at, &o1), "order1")) return 1;
        if (check(nephele_evaluate_all(tables, &at, out, NEPHELE_MAX_GROUPS), "evaluate_all")) return 1;
        printf("%08" PRIx32, bits(o1));
        for (size_t g = 0; g < groups; g++)
            printf(" %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32, bits(out[g].t),
                   bits(out[g].c_x), bits(out[g].c_z), bits(out[g].sigma));
        printf("\n");
    }

    /* A phase model: HG + Draine for 10 um droplets, evaluated and sampled. */
    NephelePhase *phase = NULL;
    if (check(nephele_phase_hg_draine_diameter(10.0, &phase), "phase")) return 1;
    for (int i = 0; i <= 8; i++) {
        float mu = -1.0f + 0.25f * (float)i, xi = 0.125f * (float)i, p_mu = 0, pdf = 0, s = 0;
        if (check(nephele_phase_eval(phase, mu, &p_mu), "eval") ||
            check(nephele_phase_pdf(phase, mu, &pdf), "pdf") ||
            check(nephele_phase_sample(phase, xi, &s), "sample"))
            return 1;
        printf("phase %08" PRIx32 " %08" PRIx32 " %08" PRIx32 "\n", bits(p_mu), bits(pdf), bits(s));
    }

    /* Bad input: each call must return its status code, never crash. */
    NepheleTables *bad = NULL;
    NepheleSlabPoint at = {4.0f, 0.5f, 1.0f, 0.3f, 0.0f};
    NepheleTransport one;
    float v = 0;
    printf("status null_bytes %d\n", (int)nephele_tables_from_bytes(NULL, 10, &bad));
    printf("status null_out %d\n", (int)nephele_tables_from_bytes(bytes, len, NULL));
    printf("status truncated %d\n", (int)nephele_tables_from_bytes(bytes, len / 2, &bad));
    printf("status empty %d\n", (int)nephele_tables_from_bytes(bytes, 0, &bad));
    uint8_t *flipped = malloc(len);
    memcpy(flipped, bytes, len);
    flipped[len / 3] ^= 0x10;
    printf("status corrupt %d\n", (int)nephele_tables_from_bytes(flipped, len, &bad));
    memcpy(flipped, bytes, len);
    flipped[8] = 9; /* the format version (little-endian u32 after the 8-byte magic) */
    /* The message is valid until the next call: read it after the call returns. */
    NepheleStatus version = nephele_tables_from_bytes(flipped, len, &bad);
    printf("status version %d %s\n", (int)version, nephele_last_error());
    free(flipped);
    printf("status null_tables %d\n", (int)nephele_evaluate(NULL, 0, &at, &one));
    printf("status null_point %d\n", (int)nephele_evaluate(tables, 0, NULL, &one));
    printf("status bad_group %d\n", (int)nephele_evaluate(tables, groups, &at, &one));
    printf("status short_out %d\n", (int)nephele_evaluate_all(tables, &at, out, groups - 1));
    printf("status bad_g %d\n", (int)nephele_phase_hg(1.5f, &phase));
    printf("status bad_mu %d\n", (int)nephele_phase_eval(phase, 2.0f, &v));
    printf("status bad_diameter %d\n", (int)nephele_phase_hg_draine_diameter(-1.0, &phase));
    if (bad != NULL) {
        fprintf(stderr, "a refused load wrote its output\n");
        return 1;
    }

    nephele_phase_free(phase);
    nephele_tables_free(tables);
    nephele_tables_free(NULL);
    free(bytes);
    return 0;
}
