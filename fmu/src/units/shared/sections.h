/* Chains of second-order sections of the diagnosed model's units, checked by one rule:
 * DiagnosedModel's linear-part elements (lti_element_b, _a) and Wiener prefilter
 * (wiener_element_b, _a), DiagnosedInverse's prefilter (section) and post sections
 * (post_section). */
#ifndef PIM_SHARED_SECTIONS_H
#define PIM_SHARED_SECTIONS_H

/* A chain's storage: b and a in two arrays (PIM_DIAG_SECTION = 3 coefficients per section
 * each) or interleaved in one (b_name == a_name: b0 b1 b2 a0 a1 a2 per section). */
typedef struct {
    const char *count_name; /* the count's parameter, e.g. "n_sections" */
    int count, max;         /* its value and largest value */
    int nsec;               /* sections to check (count, or count + 1 with a base section) */
    const char *what;       /* e.g. "prefilter coefficient", in the not-finite message */
    const char *b_name, *a_name;
    const double *b, *a;
    int pole_check;         /* a section may not have a pole at z = 1 (no rest state) */
} sections_chain;

/* The count in 0..max, each coefficient finite, each a0 = 1 and (pole_check) no pole at z = 1,
 * in the order of the storage, with the variable, index (1-based) and value in the message. */
static int sections_check(pim_unit *u, const sections_chain *c)
{
    if (c->count < 0 || c->count > c->max)
        return unit_error(u, "parameter %s = %d out of range: 0 <= %s <= %d", c->count_name,
                          c->count, c->count_name, c->max);
    const int one = c->b == c->a; /* one array, b0 b1 b2 a0 a1 a2 per section */
    /* the storage order of b0 b1 b2 a0 a1 a2 (0..5): in one array as is, in two interleaved */
    static const int order_one[6] = {0, 1, 2, 3, 4, 5}, order_two[6] = {0, 3, 1, 4, 2, 5};
    const int *order = one ? order_one : order_two;
    const int stride = one ? 6 : PIM_DIAG_SECTION;
    for (int s = 0; s < c->nsec; ++s) {
        const double *b = c->b + stride * s, *a = c->a + stride * s + (one ? 3 : 0);
        const int ib = stride * s + 1, ia = stride * s + (one ? 3 : 0) + 1; /* of b0, a0 */
        for (int e = 0; e < 6; ++e) {
            const int k = order[e], is_a = k >= 3, j = is_a ? k - 3 : k;
            const double x = is_a ? a[j] : b[j];
            const char *name = is_a ? c->a_name : c->b_name;
            const int idx = (is_a ? ia : ib) + j;
            if (!isfinite(x))
                return unit_error(u, "%s %s[%d] = %g is not finite", c->what, name, idx, x);
            if (k == 3 && x != 1.0) {
                if (one)
                    return unit_error(u, "parameter %s[%d] = %g: each section's a0 must be 1 "
                                         "(b0 b1 b2 a0 a1 a2 per section)", name, idx, x);
                return unit_error(u, "parameter %s[%d] = %g: each section's denominator must be "
                                     "normalised (%s[%d] = 1)", name, idx, x, name, idx);
            }
            if (k == 5 && c->pole_check && a[0] + a[1] + a[2] == 0.0)
                return unit_error(u, "parameters %s[%d..%d] = (%g, %g, %g): the section has a "
                                     "pole at z = 1 (%s), no rest state", name, ia, ia + 2, a[0],
                                  a[1], a[2], one ? "a0 + a1 + a2 = 0" :
                                  "the coefficients sum to 0");
        }
    }
    return 0;
}

#endif /* PIM_SHARED_SECTIONS_H */
