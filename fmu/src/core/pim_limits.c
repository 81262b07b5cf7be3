/* pimodel C core: the table of pim_limits.h, exported for Python (pimodel._native.LIMITS). */
#include "pim_core.h"
#include "pim_asymmetric.h"
#include "pim_diagnosed.h"
#include "pim_diag_inverse.h"
#include "pim_estimator.h"
#include "pim_generalized.h"
#include "pim_limits.h"

#include <string.h>

typedef struct {
    const char *name;
    double value;
    int is_integer;
} pim_limit;

#define PIM_LIMIT_ROW(name, is_integer) {#name, (double)(name), is_integer},
static const pim_limit limits[] = {PIM_LIMITS(PIM_LIMIT_ROW) PIM_CODES(PIM_LIMIT_ROW)};
#undef PIM_LIMIT_ROW

#define PIM_NLIMITS ((int)(sizeof limits / sizeof limits[0]))

PIM_API int pim_limit_count(void) { return PIM_NLIMITS; }

PIM_API const char *pim_limit_name(int i) { return i >= 0 && i < PIM_NLIMITS ? limits[i].name : 0; }

PIM_API double pim_limit_value(int i) { return i >= 0 && i < PIM_NLIMITS ? limits[i].value : 0.0; }

PIM_API int pim_limit_is_integer(int i)
{
    return i >= 0 && i < PIM_NLIMITS ? limits[i].is_integer : 0;
}

PIM_API size_t pim_struct_size(const char *name)
{
    if (!name) return 0;
    if (!strcmp(name, "pim_asym")) return sizeof(pim_asym);
    if (!strcmp(name, "pim_diag")) return sizeof(pim_diag);
    if (!strcmp(name, "pim_dinv")) return sizeof(pim_dinv);
    return 0;
}
