/*
 * The tangent of an assembly's residual (runtime/model/native/system_tangent.c, issue 34):
 * dres <- F_y dy + F_y' dy' + F_p dp of kvsys_residual along a parameter direction
 * (kvsys_dir: the derivatives of every rod's arrays, of the links' parameters and
 * constants, of the bodies' parameters, of the supports' positions and of the bodies'
 * gravity; NULL: none). kvsys_sens_residual is the integrator's sensitivity residual
 * (step_loop.c's kv_sres_fn): ctx a kvsys_sens_ctx {sys, np, dirs[np]}.
 */
#ifndef KVROD_SYSTEM_TANGENT_H
#define KVROD_SYSTEM_TANGENT_H
#include "system.h"

typedef struct {
  const kvrod_rod* const* drod;  /* nrod derivative rods (NULL entries: none) */
  const double* dlpar;           /* nlink x NLNK */
  const double* dlconst;         /* nlink x 40 */
  const double* dbpar;           /* nbody x NBDY */
  const double* dhold_r;         /* nhold x 3 */
  double dgravity[3];
} kvsys_dir;

typedef struct {
  const kvsys* sys;
  int np;
  const kvsys_dir* dirs;         /* np directions */
} kvsys_sens_ctx;

int kvsys_residual_tangent(const kvsys* s, const kvsys_dir* d, double t, const double* y,
                           const double* yp, const double* dy, const double* dyp,
                           double* dres);
int kvsys_sens_residual(const void* ctx, double t, const double* y, const double* yp,
                        int ip, const double* s, const double* sp, double* out);

#endif
