// nephele from C++: the C ABI behind a small RAII wrapper, as an engine would hold it. Checks
// the ABI, loads tables from a file, prints their domain, evaluates one point, then a batch of
// points held inside the engine's own structs, shared among two std::threads on one handle,
// and checks that the batch answers as the points one by one. Exits non-zero on any failure.
//
//   cmake -S examples/cpp -B build -DCMAKE_PREFIX_PATH=PREFIX && cmake --build build
//   build/nephele_cpp runtime/tables/mie10um/transport.ntt
#include <nephele.h>

#include <cstdio>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

// A failed call as an exception carrying the library's message.
void check(NepheleStatus s, const char *what) {
    if (s != NEPHELE_STATUS_OK)
        throw std::runtime_error(std::string(what) + ": " + nephele_last_error());
}

// Loaded tables, released with the handle.
struct TablesDeleter {
    void operator()(NepheleTables *t) const { nephele_tables_free(t); }
};
using Tables = std::unique_ptr<NepheleTables, TablesDeleter>;

Tables load(const char *path) {
    NepheleTables *t = nullptr;
    check(nephele_tables_from_file(path, &t), path);
    return Tables(t);
}

// A pixel's sample in the engine: the slab point sits inside it.
struct Sample {
    int pixel;
    NepheleSlabPoint at;
    float weight;
};

}  // namespace

int main(int argc, char **argv) try {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s transport.ntt\n", argv[0]);
        return 2;
    }
    if (!NEPHELE_ABI_COMPATIBLE()) {
        std::fprintf(stderr, "libnephele_c has ABI %u, built for %u\n", nephele_abi_version(),
                     NEPHELE_ABI_VERSION);
        return 2;
    }
    std::printf("nephele %s (ABI %u)\n", nephele_version(), nephele_abi_version());
    Tables tables = load(argv[1]);
    NepheleDomain d{};
    check(nephele_tables_domain(tables.get(), &d), "domain");
    std::printf("domain: t %g..%g mfp, mu_L %g..%g, g = %.4f, %zu groups\n", d.thickness_min,
                d.thickness_max, d.mu_l_min, d.mu_l_max, d.mean_cosine, d.groups);

    // Points over the grid and past it (t to 1000 mfp), inside the engine's samples.
    std::vector<Sample> samples;
    for (int i = 0; i < 4000; i++) {
        float u = float(i) / 4000.0f;
        float t = 0.5f * std::pow(2000.0f, u);
        samples.push_back({i, {t, 0.15f + 0.85f * u, t * (1.0f - u), 1.0f - 2.0f * u, 3.0f * u},
                           1.0f});
    }
    const size_t n = samples.size(), g = d.groups;
    std::vector<NepheleTransport> batch(n * g), single(n * g);
    std::vector<uint32_t> outside(n);
    // Two threads, one handle, each its own half of the batch.
    std::vector<std::thread> workers;
    // Messages are per thread: each worker keeps its own.
    std::string failed[2];
    for (int k = 0; k < 2; k++) {
        workers.emplace_back([&, k] {
            size_t first = n * k / 2, count = n * (k + 1) / 2 - first;
            if (nephele_evaluate_batch(tables.get(), &samples[first].at, count, sizeof(Sample),
                                       &batch[first * g], 0, nullptr,
                                       &outside[first]) != NEPHELE_STATUS_OK)
                failed[k] = nephele_last_error();
        });
    }
    for (auto &w : workers) w.join();
    for (const auto &f : failed)
        if (!f.empty()) throw std::runtime_error("batch: " + f);
    for (size_t i = 0; i < n; i++)
        check(nephele_evaluate_all(tables.get(), &samples[i].at, &single[i * g], g), "point");
    if (std::memcmp(batch.data(), single.data(), batch.size() * sizeof batch[0]) != 0)
        throw std::runtime_error("the batch differs from the points one by one");
    size_t past = 0;
    for (uint32_t f : outside) past += (f & NEPHELE_OUTSIDE_THICKER) != 0;
    std::printf("batch of %zu points on 2 threads = one by one; %zu past the thickest slab\n", n,
                past);

    // A point outside the slab is refused, with the coordinate named.
    NepheleSlabPoint sunless{4.0f, -0.2f, 1.0f, 0.3f, 0.0f};
    NepheleTransport one{};
    if (nephele_evaluate(tables.get(), 0, &sunless, &one) != NEPHELE_STATUS_BAD_POINT)
        throw std::runtime_error("a sun below the horizon was answered");
    std::printf("refused: %s\n", nephele_last_error());
    return 0;
} catch (const std::exception &e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
}
