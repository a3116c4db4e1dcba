/* benches/baselines/phase_ref.c as it is (its main renamed, its output captured by capture.c),
 * and its timed loops one at a time: each function below is the loop of phase_ref.c's main for
 * one quantity, line for line, returning ns per call, so that the harness can run nephele's
 * loop right after the C one. */
#include <stdio.h>
int ref_printf(const char *fmt, ...);
#define printf ref_printf
#define main phase_ref_main
#include "../../benches/baselines/phase_ref.c"
#undef main
#undef printf

static volatile float ref_sink;

double ref_hg_eval(long n) {
  float acc = 0; double t0 = now();
  for (long i = 0; i < n; i++) acc += hg_eval(0.85f, 2.f * rnd() - 1.f);
  ref_sink = acc; return (now() - t0) / n * 1e9;
}

double ref_hg_sample(long n) {
  float acc = 0; double t0 = now();
  for (long i = 0; i < n; i++) acc += hg_sample(0.85f, rnd());
  ref_sink = acc; return (now() - t0) / n * 1e9;
}

double ref_draine_sample(long n) {
  blend b = from_d(20.f); float acc = 0; double t0 = now();
  for (long i = 0; i < n; i++) acc += draine_sample(b.gd, b.a, rnd());
  ref_sink = acc; return (now() - t0) / n * 1e9;
}

double ref_blend_eval(long n) {
  blend b = from_d(20.f); float acc = 0; double t0 = now();
  for (long i = 0; i < n; i++) acc += blend_eval(b, 2.f * rnd() - 1.f);
  ref_sink = acc; return (now() - t0) / n * 1e9;
}

double ref_blend_sample(long n) {
  blend b = from_d(20.f); float acc = 0; double t0 = now();
  for (long i = 0; i < n; i++) acc += blend_sample(b, rnd(), rnd());
  ref_sink = acc; return (now() - t0) / n * 1e9;
}
