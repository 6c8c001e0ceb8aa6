/*
 * The tangent of the rod's residual (runtime/model/native/rod_tangent.c, issue 34):
 * dres <- F_y dy + F_y' dy' + F_p dp, where drod holds the derivatives of the rod's
 * arrays along one parameter direction dp (kvrod_rod's layout; NULL: none). Returns 0,
 * or -1 (bad rod or a drod of another shape), -3 (kernel failure).
 *
 * kvrod_sens_residual is the same as the integrator's sensitivity residual
 * (step_loop.c's kv_sres_fn): ctx a kvrod_sens_ctx {rod, np, drods[np]}; ip < 0: no
 * parameter direction.
 */
#ifndef KVROD_ROD_TANGENT_H
#define KVROD_ROD_TANGENT_H
#include "rod_assembly.h"
#ifdef __cplusplus
extern "C" {
#endif

int kvrod_residual_tangent(const kvrod_rod* rod, const kvrod_rod* drod, double t,
                           const double* y, const double* yp, const double* dy,
                           const double* dyp, double* dres);

int kvrod_sens_residual(const void* ctx, double t, const double* y, const double* yp,
                        int ip, const double* s, const double* sp, double* out);

#ifdef __cplusplus
}
#endif
#endif
