/* benches/baselines/phase_ref.c as it is, its main callable as phase_ref_main and its output
 * captured (capture.c). */
#include <stdio.h>
int ref_printf(const char *fmt, ...);
#define printf ref_printf
#define main phase_ref_main
#include "../../benches/baselines/phase_ref.c"
