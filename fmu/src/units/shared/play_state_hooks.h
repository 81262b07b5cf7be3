/* The state hooks of a unit whose only states are its play states z (PIHysteresis, InversePI,
 * GeneralizedPI, AsymmetricPI, CreepOperator): rollback and FMU state check (play_states.h). */
#ifndef PIM_SHARED_PLAY_STATE_HOOKS_H
#define PIM_SHARED_PLAY_STATE_HOOKS_H
#include "play_states.h"

typedef plays_saved model_saved;

static void model_save(const pim_unit *u, model_saved *s) { plays_save(u, s); }
static void model_restore(pim_unit *u, const model_saved *s) { plays_restore(u, s); }
static int model_check_states(pim_unit *u, pim_unit *s) { return plays_check_states(u, s); }

#endif /* PIM_SHARED_PLAY_STATE_HOOKS_H */
