/* benches/baselines/slab_ref.c as it is, its main callable as slab_ref_main and its output
 * captured (capture.c). */
#include <stdio.h>
int ref_printf(const char *fmt, ...);
#define printf ref_printf
#define main slab_ref_main
#include "../../benches/baselines/slab_ref.c"
