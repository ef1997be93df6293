/* Private to src/app: coupled models with `coupling: {method: arlequin}` (paper 004 section 3;
 * src/app/coupled_arlequin.c). coupled.c and dynamic.c dispatch here. */
#ifndef CUPID_APP_COUPLED_ARLEQUIN_H
#define CUPID_APP_COUPLED_ARLEQUIN_H

#include "app_internal.h"

/** 1 for a beam + peridynamics model with method arlequin. */
int cupid_app_is_arlequin(const cupid_job *job);
/** What the Arlequin coupling cannot do yet (model errors; called before anything is built). */
cupid_status cupid_app_arlequin_check(const cupid_job *job);
/** The layout against the built beam: each region's interface faces and the overlap slab on
 *  each (model errors otherwise), stored in job->arlequin_regions; the beam gives way in each
 *  region's core (cupid_coupling_deactivate()). */
cupid_status cupid_app_arlequin_prepare(cupid_job *job);
/** Constraints, loads, the coupled K, then the static solve, `evaluate` or the dynamics. */
cupid_status cupid_app_arlequin_run(cupid_job *job);
/** The weighted mass (paper 004 Eq. 14) for cupid_app_run_dynamic(): *M in K's pattern
 *  (consistent FE mass) or *m_lumped (lumped: true). */
cupid_status cupid_app_arlequin_mass(cupid_job *job, cupid_csr *M, double **m_lumped);

#endif
