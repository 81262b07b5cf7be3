/* The play states z of the units that keep them in a field `double z[PIM_MAX_PLAYS]` (fields.h):
 * PIHysteresis, InversePI, GeneralizedPI, AsymmetricPI, RateDependentPI, CreepOperator (its
 * lags).  Initial value, FMU state check and the rollback of a step. */
#ifndef PIM_SHARED_PLAY_STATES_H
#define PIM_SHARED_PLAY_STATES_H

/* The play states at z0 (setup). */
static inline void plays_at_z0(pim_unit *u)
{
    for (int i = 0; i < u->n; ++i) u->z[i] = u->z0;
}

/* The play states of a loaded FMU state s, finite. */
static inline int plays_check_states(pim_unit *u, const pim_unit *s)
{
    if (!unit_all_finite(s->z, (size_t)s->n))
        return unit_error(u, "FMU state rejected: a play state z is not finite");
    return 0;
}

/* The play states a step changes (saved for its rollback). */
typedef struct {
    double z[PIM_MAX_PLAYS];
} plays_saved;

static inline void plays_save(const pim_unit *u, plays_saved *s)
{
    for (int i = 0; i < u->n; ++i) s->z[i] = u->z[i];
}

static inline void plays_restore(pim_unit *u, const plays_saved *s)
{
    memcpy(u->z, s->z, (size_t)u->n * sizeof(double));
}

#endif /* PIM_SHARED_PLAY_STATES_H */
