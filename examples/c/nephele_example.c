/* nephele from C: check the ABI, load transport tables from a file, ask their domain, evaluate
 * them point by point and in a batch, a phase model, the collector search, and show what bad
 * input gets back. Built and run by capi/tests/abi.rs (under AddressSanitizer and
 * UndefinedBehaviorSanitizer), which checks every number against the Rust runtime bit for bit.
 *
 *   cc -I capi/include examples/c/nephele_example.c target/release/libnephele_c.a -lm -lpthread -ldl
 *   ./a.out runtime/tables/mie10um/transport.ntt < points.txt
 * or, installed (scripts/install_capi.sh PREFIX):
 *   cc examples/c/nephele_example.c $(pkg-config --cflags --libs nephele) -lm
 *
 * stdin: one point per line, five f32 as hexadecimal bits (t, mu_L, depth, mu_V, psi_V).
 * stdout: "domain ..." (the tables' grid, g, groups); per point "order1 T c_x c_z sigma ...
 * outside" as hexadecimal bits and the NEPHELE_OUTSIDE_* flags, or "bad_point <status>" for a
 * point outside the slab; "batch ..." (the batch entry against the points one by one); one
 * line per phase value and per tabulated phase value; one "collector ..." line per viewpoint
 * and group of the collector search on a sphere of cloud (below); then "status <case> <code>"
 * lines for the bad input and "message <case> <text>" lines for what they say. */
#include <inttypes.h>
#include <math.h>
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

/* The renderer's cloud for the collector search: a sphere of radius R (m) and extinction
 * kappa (1/m) at the origin, lit by a sun toward SUN. A renderer's maps would answer from
 * textures filtered at sigma; a sphere is smooth at every scale. */
typedef struct {
    float radius;
    float kappa;
} Sphere;

static const float SUN[3] = {0.0f, 0.6f, 0.8f};

/* The light line through at (toward the sun) against the sphere: b = at . sun, and
 * disc = b^2 - (|at|^2 - R^2) > 0 where it crosses. */
static float line_disc(const Sphere *s, const float *at, float *b) {
    *b = at[0] * SUN[0] + at[1] * SUN[1] + at[2] * SUN[2];
    float c = at[0] * at[0] + at[1] * at[1] + at[2] * at[2] - s->radius * s->radius;
    return *b * *b - c;
}

/* Where the light line enters (the sun's side), the normal there, the chord. */
static int32_t sphere_filtered(void *user, const float *at, float sigma,
                               NepheleFilteredSurface *out) {
    const Sphere *s = user;
    (void)sigma;
    float b = 0;
    float disc = line_disc(s, at, &b);
    if (!(disc > 0.0f)) return 0;
    float h = sqrtf(disc);
    for (int k = 0; k < 3; k++) {
        out->entry[k] = at[k] + (h - b) * SUN[k];
        out->normal[k] = out->entry[k] / s->radius;
    }
    out->length = 2.0f * h;
    out->optical_length = s->kappa * out->length;
    return 1;
}

/* The sphere's disk across the light: covered, at R - rho from its edge. */
static int32_t sphere_lateral(void *user, const float *at, float sigma, NepheleLateral *out) {
    const Sphere *s = user;
    (void)sigma;
    float b = 0;
    if (!(line_disc(s, at, &b) > 0.0f)) return 0;
    float rho2 = at[0] * at[0] + at[1] * at[1] + at[2] * at[2] - b * b;
    out->coverage = 1.0f;
    out->edge_distance = s->radius - sqrtf(rho2 > 0.0f ? rho2 : 0.0f);
    return 1;
}

/* The sphere's optical depth to the sun: from at to where the light line enters it. */
static int32_t sphere_sun_depth(void *user, const float *at, float *out) {
    const Sphere *s = user;
    float b = 0;
    float disc = line_disc(s, at, &b);
    float d = disc > 0.0f ? sqrtf(disc) - b : 0.0f;
    *out = s->kappa * (d > 0.0f ? d : 0.0f);
    return 1;
}

/* The viewpoints of the collector search: four points inside the sphere, four views; the last
   four know the view ray's medium beyond p (1 to 2 mean free paths) and p's depth to the sun
   (1 mean free path). */
static void viewpoint(int i, NepheleViewpoint *v) {
    static const float views[4][3] = {
        {0.0f, 0.0f, 1.0f}, {0.6f, 0.0f, 0.8f}, {0.0f, -0.6f, -0.8f}, {1.0f, 0.0f, 0.0f}};
    float k = (float)(i / 4);
    v->position[0] = 120.0f * k - 150.0f;
    v->position[1] = 60.0f * k - 80.0f;
    v->position[2] = 50.0f * k - 100.0f;
    memcpy(v->view, views[i % 4], sizeof v->view);
    v->behind_min = i >= 12 ? 1.0f : 0.0f;
    v->behind_max = i >= 12 ? 2.0f : INFINITY;
    v->sun_depth = i >= 12 ? 1.0f : INFINITY;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s transport.ntt < points\n", argv[0]);
        return 2;
    }
    if (!NEPHELE_ABI_COMPATIBLE()) {
        fprintf(stderr, "libnephele_c has ABI %u, this program was built for %u\n",
                nephele_abi_version(), NEPHELE_ABI_VERSION);
        return 2;
    }
    size_t len = 0;
    uint8_t *bytes = read_file(argv[1], &len);
    if (!bytes) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 2;
    }
    NepheleTables *tables = NULL;
    if (check(nephele_tables_from_file(argv[1], &tables), "load")) return 1;
    NepheleDomain domain;
    if (check(nephele_tables_domain(tables, &domain), "domain")) return 1;
    size_t groups = domain.groups;
    printf("domain %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %zu %u\n",
           bits(domain.thickness_min), bits(domain.thickness_max), bits(domain.mu_l_min),
           bits(domain.mu_l_max), bits(domain.mean_cosine), domain.groups, domain.has_collector);

    /* Every point: order 1, T, c, sigma of every group and where it lies outside the grid. The
       points inside the slab are kept, inside a struct of the renderer's own, for the batch. */
    typedef struct {
        int pixel;
        NepheleSlabPoint at;
    } Sample;
    size_t cap = 1024, n = 0;
    Sample *samples = malloc(cap * sizeof *samples);
    NepheleTransport *one_by_one = malloc(cap * NEPHELE_MAX_GROUPS * sizeof *one_by_one);
    float *order1_one = malloc(cap * sizeof *order1_one);
    NepheleTransport out[NEPHELE_MAX_GROUPS];
    unsigned int p[5];
    while (scanf("%x %x %x %x %x", &p[0], &p[1], &p[2], &p[3], &p[4]) == 5) {
        NepheleSlabPoint at = {from_bits(p[0]), from_bits(p[1]), from_bits(p[2]),
                               from_bits(p[3]), from_bits(p[4])};
        float o1 = 0;
        uint32_t outside = 0;
        NepheleStatus s = nephele_order1(tables, &at, &o1);
        if (s == NEPHELE_STATUS_BAD_POINT) {
            /* Refused alike by every entry, with the message naming the coordinate. */
            if (nephele_evaluate_all(tables, &at, out, NEPHELE_MAX_GROUPS) != s ||
                nephele_outside(tables, &at, &outside) != s || nephele_last_error()[0] == 0)
                return 1;
            printf("bad_point %d\n", (int)s);
            continue;
        }
        if (check(s, "order1") ||
            check(nephele_evaluate_all(tables, &at, out, NEPHELE_MAX_GROUPS), "evaluate_all") ||
            check(nephele_outside(tables, &at, &outside), "outside"))
            return 1;
        printf("%08" PRIx32, bits(o1));
        for (size_t g = 0; g < groups; g++)
            printf(" %08" PRIx32 " %08" PRIx32 " %08" PRIx32 " %08" PRIx32, bits(out[g].t),
                   bits(out[g].c_x), bits(out[g].c_z), bits(out[g].sigma));
        printf(" %u\n", outside);
        if (n == cap) {
            cap *= 2;
            samples = realloc(samples, cap * sizeof *samples);
            one_by_one = realloc(one_by_one, cap * NEPHELE_MAX_GROUPS * sizeof *one_by_one);
            order1_one = realloc(order1_one, cap * sizeof *order1_one);
        }
        samples[n].pixel = (int)n;
        samples[n].at = at;
        memcpy(&one_by_one[n * groups], out, groups * sizeof *out);
        order1_one[n] = o1;
        n++;
    }

    /* The batch entry over the kept points, read from inside the Sample structs (a stride of
       sizeof(Sample)), written packed: bit for bit the answers one by one. */
    NepheleTransport *batch = malloc((n + 1) * groups * sizeof *batch);
    float *order1_batch = malloc((n + 1) * sizeof *order1_batch);
    uint32_t *flags = malloc((n + 1) * sizeof *flags);
    if (check(nephele_evaluate_batch(tables, &samples[0].at, n, sizeof(Sample), batch, 0,
                                     order1_batch, flags),
              "evaluate_batch"))
        return 1;
    int same = memcmp(batch, one_by_one, n * groups * sizeof *batch) == 0 &&
               memcmp(order1_batch, order1_one, n * sizeof *order1_batch) == 0;
    printf("batch %zu %d\n", n, same);

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

    /* A tabulated phase function (as a Mie table would come): HG g = 0.85 every 0.5 degrees. */
    double theta[361], table[361];
    for (int i = 0; i <= 360; i++) {
        theta[i] = 0.5 * (double)i;
        double d = 1.0 + 0.85 * 0.85 - 2.0 * 0.85 * cos(theta[i] * 3.14159265358979323846 / 180.0);
        table[i] = (1.0 - 0.85 * 0.85) / (4.0 * 3.14159265358979323846 * d * sqrt(d));
    }
    NephelePhase *tabulated = NULL;
    if (check(nephele_phase_tabulated(theta, table, 361, &tabulated), "tabulated")) return 1;
    for (int i = 0; i <= 8; i++) {
        float mu = -1.0f + 0.25f * (float)i, xi = 0.125f * (float)i, p_mu = 0, s = 0;
        if (check(nephele_phase_eval(tabulated, mu, &p_mu), "tabulated eval") ||
            check(nephele_phase_sample(tabulated, xi, &s), "tabulated sample"))
            return 1;
        printf("tabulated %08" PRIx32 " %08" PRIx32 "\n", bits(p_mu), bits(s));
    }
    nephele_phase_free(tabulated);

    /* The collector search of every group on the sphere, and what the finite cloud keeps. */
    Sphere sphere = {500.0f, 0.05f};
    NepheleLitSurface surface = {&sphere, sphere_filtered, sphere_lateral, sphere_sun_depth,
                                 sphere.radius};
    NepheleSearchOptions options;
    NepheleFiniteCloud finite;
    NepheleCollector found[NEPHELE_MAX_GROUPS];
    if (check(nephele_search_options_for_tables(tables, &options), "options") ||
        check(nephele_finite_cloud_for_tables(tables, &finite), "finite"))
        return 1;
    for (int i = 0; i < 16; i++) {
        NepheleViewpoint v;
        viewpoint(i, &v);
        if (check(nephele_find_collectors(tables, &surface, &v, &SUN, &options, found,
                                          NEPHELE_MAX_GROUPS),
                  "find_collectors"))
            return 1;
        for (size_t g = 0; g < groups; g++) {
            const NepheleCollector *c = &found[g];
            NepheleKept kept = {1.0f, INFINITY, 1.0f};
            if (c->found && check(nephele_finite_cloud(tables, g, &surface, c, &finite, &kept),
                                  "finite_cloud"))
                return 1;
            printf("collector %d %zu %d %u %d %u", i, g, c->found, c->reads, c->converged,
                   c->clamps);
            const float f[] = {c->transport.t, c->transport.c_x, c->transport.c_z,
                               c->transport.sigma, c->centre[0], c->centre[1], c->centre[2],
                               c->sigma, c->extinction, kept.factor, kept.radius, kept.coverage};
            for (size_t k = 0; k < sizeof f / sizeof f[0]; k++) printf(" %08" PRIx32, bits(f[k]));
            printf("\n");
        }
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
    NepheleViewpoint v0;
    viewpoint(0, &v0);
    NepheleLitSurface no_callback = surface;
    no_callback.filtered = NULL;
    const float tilted[3] = {0.0f, 0.7f, 0.8f};
    NepheleCollector none = {0};
    NepheleKept kept;
    printf("status null_surface %d\n",
           (int)nephele_find_collector(tables, 0, NULL, &v0, &SUN, &options, found));
    printf("status null_callback %d\n",
           (int)nephele_find_collector(tables, 0, &no_callback, &v0, &SUN, &options, found));
    printf("status collector_group %d\n",
           (int)nephele_find_collector(tables, groups, &surface, &v0, &SUN, &options, found));
    printf("status not_unit_sun %d\n",
           (int)nephele_find_collector(tables, 0, &surface, &v0, &tilted, &options, found));
    printf("status short_collectors %d\n",
           (int)nephele_find_collectors(tables, &surface, &v0, &SUN, &options, found, 1));
    theta[10] = theta[9]; /* not increasing */
    printf("status bad_table %d\n", (int)nephele_phase_tabulated(theta, table, 361, &tabulated));

    /* Points outside the slab, by each entry; a batch holding one writes nothing. */
    const float nan = NAN, inf = INFINITY;
    const NepheleSlabPoint outside_slab[] = {
        {4.0f, 1.5f, 1.0f, 0.3f, 0.0f}, {4.0f, 0.5f, 1.0f, 2.0f, 0.0f},
        {4.0f, nan, 1.0f, 0.3f, 0.0f},  {inf, 0.5f, 1.0f, 0.3f, 0.0f},
        {4.0f, 0.5f, 5.0f, 0.3f, 0.0f}, {4.0f, 0.5f, 1.0f, 0.3f, -inf}};
    for (int i = 0; i < 6; i++) {
        printf("status point_%d %d %d %d\n", i,
               (int)nephele_evaluate(tables, 0, &outside_slab[i], &one),
               (int)nephele_order1(tables, &outside_slab[i], &v),
               (int)nephele_view_weight(&outside_slab[i], 0.5f, &v));
        printf("message point_%d %s\n", i, nephele_last_error());
    }
    NepheleSlabPoint mixed[3] = {at, at, outside_slab[0]};
    NepheleTransport untouched[3 * NEPHELE_MAX_GROUPS];
    memset(untouched, 0x7f, sizeof untouched);
    printf("status batch_bad_point %d\n",
           (int)nephele_evaluate_batch(tables, mixed, 3, 0, untouched, 0, NULL, NULL));
    printf("message batch_bad_point %s\n", nephele_last_error());
    printf("status batch_untouched %d\n", untouched[0].t == untouched[3 * groups - 1].sigma &&
                                              bits(untouched[0].t) == 0x7f7f7f7fu);
    printf("status batch_stride %d\n",
           (int)nephele_evaluate_batch(tables, mixed, 2, 3, untouched, 0, NULL, NULL));
    /* A failed call's message stays until the next call; a call that succeeds clears it. */
    nephele_phase_hg(1.5f, &phase);
    int had = nephele_last_error()[0] != 0;
    nephele_tables_groups(tables, &groups);
    printf("status cleared %d\n", had && nephele_last_error()[0] == 0);
    /* What the refused loads say: a file cut short, a foreign file, a missing file. */
    nephele_tables_from_bytes(bytes, len / 2, &bad);
    printf("message truncated %s\n", nephele_last_error());
    const char foreign[] = "NEPHTT\r\nthis is text after the magic, long enough to hold a header";
    nephele_tables_from_bytes((const uint8_t *)foreign, sizeof foreign, &bad);
    printf("message foreign %s\n", nephele_last_error());
    printf("status missing_file %d\n", (int)nephele_tables_from_file("/nonexistent/x.ntt", &bad));
    printf("message missing_file %s\n", nephele_last_error());
    printf("status not_found %d\n",
           (int)nephele_finite_cloud(tables, 0, &surface, &none, &finite, &kept));
    if (bad != NULL) {
        fprintf(stderr, "a refused load wrote its output\n");
        return 1;
    }

    nephele_phase_free(phase);
    nephele_tables_free(tables);
    nephele_tables_free(NULL);
    free(bytes);
    free(samples);
    free(one_by_one);
    free(order1_one);
    free(batch);
    free(order1_batch);
    free(flags);
    return 0;
}
