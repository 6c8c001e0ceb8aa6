/*
 * An assembly of rods coupled by holds, links and bodies: residual, Jacobian (into the
 * rods' band blocks and the couplings) and energies (system.h says what the tables hold;
 * runtime/model/system.py builds them). Written by hand, compiled with the rod assembly
 * and the generated kernels. A rod's own rows come from kvrod_residual /
 * kvrod_jacobian_band unchanged; the system only adds and replaces rows, so a rod of an
 * assembly is computed exactly as a single rod is.
 */
#include <math.h>
#include <string.h>
#include "rod_kernels.h"
#include "rod_layout.h"
#include "rod_assembly.h"
#include "rod_contact.h"
#include "system.h"

typedef struct {
  const double* arg[24];
  double* res[8];
  casadi_int iw[64];
  casadi_real w[8192];
} sys_work;

#define LINK_NIN 12
#define LINK_NQ 18
#define LINK_NX 40
#define BODY_NR 6
#define BODY_NX 10

/* the inputs of link k (the state where its index is >= 0, else its constants): phi_a,
   phi_b, v_a, v_b, p_a1, p_a2, p_b1, p_b2, Omega_a1, Omega_a2, Omega_b1, Omega_b2, lnk */
static void link_args(const kvsys* s, int k, const double* y, const double** a) {
  static const int co[LINK_NIN] = {0, 3, 6, 9, 12, 16, 20, 24, 28, 31, 34, 37};
  const int* ix = s->lidx + (size_t)k * LINK_NIN;
  const double* c = s->lconst + (size_t)k * LINK_NX;
  for (int q = 0; q < LINK_NIN; ++q) a[q] = ix[q] >= 0 ? y + ix[q] : c + co[q];
  a[LINK_NIN] = s->lpar + (size_t)k * NLNK;
}

static int link_forces(const kvsys* s, int k, const double* y, double* Q, sys_work* W) {
  link_args(s, k, y, W->arg);
  W->res[0] = Q;
  return rod_link_forces(W->arg, W->res, W->iw, W->w, 0) ? -3 : 0;
}

/* body b's inputs: v, v', p, Omega, Omega', gravity, bdy */
static void body_args(const kvsys* s, int b, const double* y, const double* yp,
                      const double** a) {
  const int* ix = s->bidx + 3 * b;
  a[0] = y + ix[0]; a[1] = yp + ix[0];
  a[2] = y + ix[1];
  a[3] = y + ix[2]; a[4] = yp + ix[2];
  a[5] = s->gravity;
  a[6] = s->bpar + (size_t)b * NBDY;
}

/* the residual before the holds act: the rods' own (each as a single rod computes it),
   the links', the bodies' */
static int free_residual(const kvsys* s, double t, const double* y, const double* yp,
                         double* res, sys_work* W) {
  for (int r = 0; r < s->nrod; ++r) {
    const int o = s->off[r];
    const int rc = kvrod_residual(s->rod[r], t, y + o, yp + o, res + o);
    if (rc) return rc;
  }
  double Q[LINK_NQ];
  for (int k = 0; k < s->nlink; ++k) {
    if (link_forces(s, k, y, Q, W)) return -3;
    const int* row = s->lrow + (size_t)k * LINK_NQ;
    for (int q = 0; q < LINK_NQ; ++q)
      if (row[q] >= 0) res[row[q]] -= Q[q];
  }
  double rb[BODY_NR];
  for (int b = 0; b < s->nbody; ++b) {
    body_args(s, b, y, yp, W->arg);
    W->res[0] = rb;
    if (rod_body_inertia(W->arg, W->res, W->iw, W->w, 0)) return -3;
    const int* row = s->brow + (size_t)b * BODY_NR;
    for (int q = 0; q < BODY_NR; ++q)
      if (row[q] >= 0) res[row[q]] += rb[q];
  }
  return s->pairs ? s->pair_residual(s->pairs, y, res) : 0;
}

int kvsys_residual(const kvsys* s, double t, const double* y, const double* yp,
                   double* res) {
  sys_work W;
  const int rc = free_residual(s, t, y, yp, res, &W);
  if (rc) return rc;
  /* the slaves' momentum rows into their masters', then the held rows replaced */
  for (int h = 0; h < s->nhold; ++h) {
    const int* H = s->hold + 4 * h;
    if (H[3] >= 0)
      for (int k = 0; k < 3; ++k) res[H[3] + k] += res[H[1] + k];
  }
  for (int h = 0; h < s->nhold; ++h) {
    const int* H = s->hold + 4 * h;
    for (int k = 0; k < 3; ++k) {
      if (H[2] >= 0) {
        res[H[0] + k] = y[H[0] + k] - y[H[2] + k];
        res[H[1] + k] = y[H[1] + k] - y[H[3] + k];
      } else {
        res[H[0] + k] = y[H[0] + k] - s->hold_r[3 * h + k];
        res[H[1] + k] = y[H[1] + k];
      }
    }
  }
  return 0;
}

static int rod_of(const kvsys* s, int gi) {
  int r = 0;
  while (r + 1 < s->nrod && gi >= s->off[r + 1]) ++r;
  return r;
}

/* zero global row gi in its rod's band and put 1 on its diagonal */
static void identity_row(const kvsys* s, int gi) {
  const int r = rod_of(s, gi);
  const kvrod_rod* rod = s->rod[r];
  const int n = s->off[r + 1] - s->off[r], i = gi - s->off[r];
  const int kl = rod->kl, ku = rod->ku, ld = s->ldab[r];
  double* ab = s->J + s->ab_start[r];
  const int j0 = i - kl > 0 ? i - kl : 0, j1 = i + ku < n - 1 ? i + ku : n - 1;
  for (int j = j0; j <= j1; ++j) ab[(size_t)(kl + ku + i - j) + (size_t)j * ld] = 0.0;
  ab[(size_t)(kl + ku) + (size_t)i * ld] = 1.0;
}

int kvsys_jacobian(const kvsys* s, double t, const double* y, const double* yp, double cj,
                   void* blocks) {
  (void) blocks;
  sys_work W;
  for (int r = 0; r < s->nrod; ++r) {
    const int o = s->off[r];
    double* ab = s->J + s->ab_start[r];
    memset(ab, 0, sizeof(double) * (size_t) s->ldab[r] * (size_t) (s->off[r + 1] - o));
    const int rc = kvrod_jacobian_band(s->rod[r], t, y + o, yp + o, 1.0, cj, s->ldab[r],
                                       ab);
    if (rc) return rc;
  }
  memset(s->J + s->ev_start, 0, sizeof(double) * (size_t) s->nev);
  double JQ[LINK_NQ * LINK_NX];
  for (int k = 0; k < s->nlink; ++k) {
    link_args(s, k, y, W.arg);
    W.res[0] = JQ;
    if (rod_link_forces_jac(W.arg, W.res, W.iw, W.w, 0)) return -3;
    const long long* dst = s->ldst + (size_t)k * LINK_NQ * LINK_NX;
    /* JQ column-major (CasADi): entry (q, x) at q + x LINK_NQ; dst row-major */
    for (int q = 0; q < LINK_NQ; ++q)
      for (int x = 0; x < LINK_NX; ++x) {
        const long long d = dst[q * LINK_NX + x];
        if (d >= 0) s->J[d] -= JQ[q + x * LINK_NQ];
      }
  }
  double JB[BODY_NR * BODY_NX];
  const double cy = 1.0;
  for (int b = 0; b < s->nbody; ++b) {
    body_args(s, b, y, yp, W.arg);
    W.arg[7] = &cy; W.arg[8] = &cj;
    W.res[0] = JB;
    if (rod_body_inertia_jac(W.arg, W.res, W.iw, W.w, 0)) return -3;
    const long long* dst = s->bdst + (size_t)b * BODY_NR * BODY_NX;
    for (int q = 0; q < BODY_NR; ++q)
      for (int x = 0; x < BODY_NX; ++x) {
        const long long d = dst[q * BODY_NX + x];
        if (d >= 0) s->J[d] += JB[q + x * BODY_NR];
      }
  }
  if (s->pairs && s->pair_jacobian(s->pairs, y)) return -3;
  /* the holds: the slaves' momentum rows into their masters', then the held rows */
  for (int q = 0; q < s->ncopy; ++q) s->J[s->copy_dst[q]] += s->J[s->copy_src[q]];
  for (int q = 0; q < s->nzero; ++q) s->J[s->zero[q]] = 0.0;
  for (int h = 0; h < s->nhold; ++h) {
    const int* H = s->hold + 4 * h;
    for (int k = 0; k < 3; ++k) {
      identity_row(s, H[0] + k);
      identity_row(s, H[1] + k);
    }
    if (H[2] >= 0)
      for (int q = 0; q < 6; ++q) s->J[s->hold_e[6 * h + q]] = -1.0;
  }
  return s->pairs && s->pair_couplings(s->pairs, y) ? -3 : 0;
}

/* link k's forces Q (18) and its diagnostics (W, D, e 6, resultant 6: 14 values) */
int kvsys_link_values(const kvsys* s, int k, const double* y, double* Q, double* diag) {
  sys_work W;
  if (k < 0 || k >= s->nlink) return -4;
  if (link_forces(s, k, y, Q, &W)) return -3;
  link_args(s, k, y, W.arg);
  W.res[0] = diag; W.res[1] = diag + 1; W.res[2] = diag + 2; W.res[3] = diag + 8;
  return rod_link_diagnostics(W.arg, W.res, W.iw, W.w, 0) ? -3 : 0;
}

/* per state: T, W, 2D, P_ext, P_bc (the rods', the links', the bodies'), then for a single
   state (m = 1: the output samples; the audit's quadrature asks for 3 and reads the
   energies only) the extras: every rod's 12 support values (kvrod_diagnostics), every
   hold's free momentum row (3: the force the support or the tie exerts on that node's
   rod, inertia included), every link's force on node a and moment on side a (6, spatial:
   f_a and R(p_a1) T_a1 + R(p_a2) T_a2), then, on obstacles, each obstacle's NCV values
   (obstacle_values below), and with pairs their NSV values last (kvsys_pairs_values);
   nextra says how many; NaN where not computed. */
/* the step loop's kv_maxstep_fn of an assembly: the smallest of its rods' contact step
   bounds (kvrod_contact_max_step) and its pairs' (kvsys_pairs_max_step); HUGE_VAL when
   nothing touches anything */
double kvsys_max_step(const void* ctx, double t, const double* y, const double* yp) {
  (void) t; (void) yp;
  const kvsys* s = (const kvsys*) ctx;
  double h = HUGE_VAL;
  for (int r = 0; r < s->nrod; ++r) {
    const kvrod_rod* rod = s->rod[r];
    if (rod->contact == NULL || rod->contact->nobs == 0 || rod->contact->max_step == NULL)
      continue;
    const double hr = rod->contact->max_step(rod, y + s->off[r]);
    if (hr < h) h = hr;
  }
  if (s->pairs && s->pair_max_step) {
    const double hp = s->pair_max_step(s->pairs, y);
    if (hp < h) h = hp;
  }
  return h;
}

/* the per obstacle values (rod_contact.h, NCV: force, moment about the obstacle's point,
   energy, dissipation, its friction part, the obstacle's power, the smallest gap, the
   segments in reach) of the whole assembly into v (nv = NCV nobs): sums over the rods
   that touch obstacles, the smallest gap of any rod (every such rod sees all nobs) */
static int obstacle_values(const kvsys* s, const double* y, double* v, int nv) {
  const int nobs = nv / NCV;
  double w[NCV * nobs];
  for (int q = 0; q < nv; ++q) v[q] = (q % NCV == 10) ? HUGE_VAL : 0.0;
  for (int r = 0; r < s->nrod; ++r) {
    const kvrod_rod* rod = s->rod[r];
    if (rod->contact == NULL || rod->contact->nobs != nobs || rod->contact->values == NULL)
      continue;
    if (rod->contact->values(rod, y + s->off[r], w)) return -3;
    for (int q = 0; q < nv; ++q)
      v[q] = (q % NCV == 10) ? fmin(v[q], w[q]) : v[q] + w[q];
  }
  return 0;
}

int kvsys_energies(const kvsys* s, int m, const double* ts, const double* ys,
                   const double* yps, double* out) {
  sys_work W;
  const int nen = 5 + s->nextra;
  double e[NDIAG];
  for (int k = 0; k < m; ++k) {
    const double* y = ys + (size_t)k * s->n;
    const double* yp = yps + (size_t)k * s->n;
    double* o = out + (size_t)k * nen;
    for (int q = 0; q < nen; ++q) o[q] = q < 5 ? 0.0 : NAN;
    int x = 5;
    for (int r = 0; r < s->nrod; ++r) {
      const int off = s->off[r];
      if (kvrod_energies(s->rod[r], 1, ts + k, y + off, yp + off, e)) return -3;
      for (int q = 0; q < 5; ++q) o[q] += e[q];
      if (m == 1)
        for (int q = 0; q < 12; ++q) o[x + q] = e[5 + q];
      x += 12;
    }
    double Q[LINK_NQ], d[14];
    for (int l = 0; l < s->nlink; ++l) {
      if (kvsys_link_values(s, l, y, Q, d)) return -3;
      o[1] += d[0];
      o[2] += 2.0 * d[1];
    }
    for (int b = 0; b < s->nbody; ++b) {
      double T[2];
      const int* ix = s->bidx + 3 * b;       /* rod_body_kinetic: v, p, Omega, g, bdy */
      W.arg[0] = y + ix[0]; W.arg[1] = y + ix[1]; W.arg[2] = y + ix[2];
      W.arg[3] = s->gravity; W.arg[4] = s->bpar + (size_t)b * NBDY;
      W.res[0] = T; W.res[1] = T + 1;
      if (rod_body_kinetic(W.arg, W.res, W.iw, W.w, 0)) return -3;
      o[0] += T[0];
      o[3] += T[1];
    }
    double pv[NSV];
    if (s->pairs) {
      if (s->pair_values(s->pairs, y, pv)) return -3;
      o[1] += pv[0];
      o[2] += pv[1];
    }
    if (m != 1) continue;
    if (s->nhold) {
      const int rc = free_residual(s, ts[k], y, yp, s->scratch, &W);
      if (rc) return rc;
      for (int h = 0; h < s->nhold; ++h)
        for (int q = 0; q < 3; ++q) o[x + 3 * h + q] = s->scratch[s->hold[4 * h + 1] + q];
    }
    x += 3 * s->nhold;
    for (int l = 0; l < s->nlink; ++l) {
      double M[3] = {0.0, 0.0, 0.0}, Rm[3];
      if (kvsys_link_values(s, l, y, Q, d)) return -3;
      const double* pa[2];
      link_args(s, l, y, W.arg);
      pa[0] = W.arg[4]; pa[1] = W.arg[5];
      for (int side = 0; side < 2; ++side) {
        const double* p = pa[side];
        if (p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0 && p[3] == 0.0) continue;
        W.arg[0] = p; W.arg[1] = Q + 6 + 3 * side;
        W.res[0] = Rm;
        if (rod_rotate(W.arg, W.res, W.iw, W.w, 0)) return -3;
        for (int q = 0; q < 3; ++q) M[q] += Rm[q];
      }
      for (int q = 0; q < 3; ++q) { o[x + 6 * l + q] = Q[q]; o[x + 6 * l + 3 + q] = M[q]; }
    }
    x += 6 * s->nlink;
    const int npv = s->pairs ? NSV : 0;
    if (x < nen - npv && obstacle_values(s, y, o + x, nen - npv - x)) return -3;
    /* the pairs' values: the last NSV extras */
    if (s->pairs)
      for (int q = 0; q < NSV; ++q) o[nen - NSV + q] = pv[q];
  }
  return 0;
}
