/* The envelope parameters of GeneralizedPI and AsymmetricPI (pim_generalized.h). */
#ifndef PIM_SHARED_ENVELOPE_CHECK_H
#define PIM_SHARED_ENVELOPE_CHECK_H

/* An envelope's kind (0..3) and coefficients, named <prefix>_kind, <prefix>_c0..c3. */
static inline int envelope_check(pim_unit *u, const char *prefix, int kind, const double *c)
{
    if (kind < PIM_ENV_POLY2 || kind > PIM_ENV_TANH_INV)
        return unit_error(u, "parameter %s_kind = %d out of range: 0 poly2, 1 tanh, 2 poly2_inv, "
                             "3 tanh_inv", prefix, kind);
    const char *msg = pim_envelope_check(kind, c);
    if (msg)
        return unit_error(u, "parameters %s_c0..%s_c3 = (%g, %g, %g, %g): %s", prefix, prefix,
                          c[0], c[1], c[2], c[3], msg);
    return 0;
}

#endif /* PIM_SHARED_ENVELOPE_CHECK_H */
