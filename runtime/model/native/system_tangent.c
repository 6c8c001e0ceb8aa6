/*
 * The tangent of an assembly's residual (issue 34; system.c's kvsys_residual
 * differentiated term by term): every rod's own rows by kvrod_residual_tangent
 * (rod_tangent.c), the links' and bodies' by the generated tangent kernels
 * (rod_link_forces_tan, rod_body_inertia_tan: derive/tangents.py), then the holds as
 * kvsys_residual applies them (a slave's momentum rows into its master's, the held rows
 * replaced by phi - phi_m, v - v_m or phi - r, v). Written beside system.c, which it
 * reads through its tables only (system.h).
 */
#include <string.h>
#include "rod_kernels.h"
#include "rod_tangent_kernels.h"
#include "rod_layout.h"
#include "rod_assembly.h"
#include "rod_tangent.h"
#include "system.h"
#include "system_tangent.h"

#define T_NIN 12
#define T_NQ 18
#define T_NX 40

typedef struct {
  const double* arg[2 * T_NIN + 2];
  double* res[4];
  long long int iw[ROD_TAN_MAXIW];
  double w[ROD_TAN_MAXW];
} tsys_work;

static const double kZs[128] = {0.0};

int kvsys_residual_tangent(const kvsys* s, const kvsys_dir* d, double t, const double* y,
                           const double* yp, const double* dy, const double* dyp,
                           double* dres) {
  static const int co[T_NIN] = {0, 3, 6, 9, 12, 16, 20, 24, 28, 31, 34, 37};
  tsys_work W;
  if (NLNK > 128 || NBDY > 128 || T_NX > 128) return -1;
  for (int r = 0; r < s->nrod; ++r) {
    const int o = s->off[r];
    const kvrod_rod* dr = d ? d->drod[r] : 0;
    const int rc = kvrod_residual_tangent(s->rod[r], dr, t, y + o, yp + o, dy + o, dyp + o,
                                          dres + o);
    if (rc) return rc;
  }
  double dQ[T_NQ];
  for (int k = 0; k < s->nlink; ++k) {
    const int* ix = s->lidx + (size_t)k * T_NIN;
    const double* c = s->lconst + (size_t)k * T_NX;
    const double* dc = d ? d->dlconst + (size_t)k * T_NX : kZs;
    for (int q = 0; q < T_NIN; ++q) {
      W.arg[q] = ix[q] >= 0 ? y + ix[q] : c + co[q];
      W.arg[T_NIN + 1 + q] = ix[q] >= 0 ? dy + ix[q] : (d ? dc + co[q] : kZs);
    }
    W.arg[T_NIN] = s->lpar + (size_t)k * NLNK;
    W.arg[2 * T_NIN + 1] = d ? d->dlpar + (size_t)k * NLNK : kZs;
    W.res[0] = dQ;
    if (rod_link_forces_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
    const int* row = s->lrow + (size_t)k * T_NQ;
    for (int q = 0; q < T_NQ; ++q)
      if (row[q] >= 0) dres[row[q]] -= dQ[q];
  }
  double drb[6];
  for (int b = 0; b < s->nbody; ++b) {
    const int* ix = s->bidx + 3 * b;      /* v, v', p, Omega, Omega', g, bdy + seeds */
    W.arg[0] = y + ix[0]; W.arg[1] = yp + ix[0]; W.arg[2] = y + ix[1];
    W.arg[3] = y + ix[2]; W.arg[4] = yp + ix[2]; W.arg[5] = s->gravity;
    W.arg[6] = s->bpar + (size_t)b * NBDY;
    W.arg[7] = dy + ix[0]; W.arg[8] = dyp + ix[0]; W.arg[9] = dy + ix[1];
    W.arg[10] = dy + ix[2]; W.arg[11] = dyp + ix[2];
    W.arg[12] = d ? d->dgravity : kZs;
    W.arg[13] = d ? d->dbpar + (size_t)b * NBDY : kZs;
    W.res[0] = drb;
    if (rod_body_inertia_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
    const int* row = s->brow + (size_t)b * 6;
    for (int q = 0; q < 6; ++q)
      if (row[q] >= 0) dres[row[q]] += drb[q];
  }
  for (int h = 0; h < s->nhold; ++h) {
    const int* H = s->hold + 4 * h;
    if (H[3] >= 0)
      for (int k = 0; k < 3; ++k) dres[H[3] + k] += dres[H[1] + k];
  }
  for (int h = 0; h < s->nhold; ++h) {
    const int* H = s->hold + 4 * h;
    for (int k = 0; k < 3; ++k) {
      if (H[2] >= 0) {
        dres[H[0] + k] = dy[H[0] + k] - dy[H[2] + k];
        dres[H[1] + k] = dy[H[1] + k] - dy[H[3] + k];
      } else {
        dres[H[0] + k] = dy[H[0] + k] - (d ? d->dhold_r[3 * h + k] : 0.0);
        dres[H[1] + k] = dy[H[1] + k];
      }
    }
  }
  return 0;
}

int kvsys_sens_residual(const void* ctx, double t, const double* y, const double* yp,
                        int ip, const double* s, const double* sp, double* out) {
  const kvsys_sens_ctx* c = (const kvsys_sens_ctx*)ctx;
  if (ip >= c->np) return -1;
  return kvsys_residual_tangent(c->sys, ip >= 0 ? c->dirs + ip : 0, t, y, yp, s, sp, out);
}
