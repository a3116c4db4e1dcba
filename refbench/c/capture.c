/* What the baselines print, kept in a buffer for the harness to read (their printf is renamed to
 * ref_printf by phase.c and slab.c): the baselines themselves are compiled unchanged. */
#include <stdarg.h>
#include <stdio.h>

static char out[1 << 16];
static size_t len;

int ref_printf(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(out + len, sizeof out - len, fmt, ap);
  va_end(ap);
  if (n > 0) len = len + (size_t)n < sizeof out ? len + (size_t)n : sizeof out - 1;
  return n;
}

const char *ref_output(void) { return out; }

void ref_clear(void) { len = 0; out[0] = 0; }
