/* The rod's ODE form for SUNDIALS through CasADi, on kvrod's own compiled kernels.
 *
 * Build "kernels" of bench/idas_script.py: CasADi external functions `rod_ode` and its
 * Jacobian `jac_rod_ode` (CasADi's external-function C API, integrator signature
 * (t, x, z, p, u) -> (ode, alg, quad, zero)) over kvrod_residual and kvrod_jacobian_band
 * of runtime/model/native/rod_assembly.c, compiled together with generated/rod_kernels.c
 * (and rod_kernels_x4.c) into one shared library whose size does not depend on N.
 *
 * The rod (its arrays; for a generalized Maxwell rod also its nb relaxation terms: times
 * theta and moduli segb, jntb, whose internal strains q are state entries with rows
 * q' - (strain - q)/theta, dF/dq' = 1), the scaling and the Jacobian pattern are handed
 * over at run time by kv_setup (from Python, ctypes) before casadi.external loads the
 * library; each rod gets its own copy of the library file, so globals are per rod.
 *
 * ode_k = -g(y)_{d_k} / (D_{d_k} s_k) with y_{d_k} = s_k x_k and the other (algebraic)
 * entries of y fixed; g(y) = F(t, y, 0). The Jacobian entry e (row k, column j) is
 * coef_e * (dF/dy)[d_k, d_j] with coef_e = -s_j / (D_{d_k} s_k), read from the band.
 */
#include <stdlib.h>
#include <string.h>

#include "rod_assembly.h"

typedef long long int casadi_int;
typedef double casadi_real;
#define EXPORT __attribute__((visibility("default")))

static kvrod_rod rod;
static int n = 0, nx = 0, ldab = 0;
static casadi_int nnz = 0;
static const int *di;              /* nx: state index of x_k */
static const double *xscale;       /* nx: s_k */
static const double *odefac;       /* nx: -1 / (D[d_k] s_k) */
static const double *yfix;         /* n: y with the fixed entries */
static const casadi_int *jsrc;     /* nnz: index into the band array (column-major) */
static const double *jcoef;        /* nnz */
static const casadi_int *sp_x, *sp_x0, *sp_xn, *sp_nx, *sp_jac;
static double *y = NULL, *yp = NULL, *r = NULL, *ab = NULL;
static const casadi_int sp_scalar[3] = {1, 1, 1}, sp_empty[3] = {0, 1, 1},
                        sp_00[3] = {0, 0, 1};

/* sparsity arrays (CasADi format) in `sp`: {nx,1,1} (dense x), {nx,1,0,0} (x-sized, no
   entries), {nx,0,1}, {0,nx,1}, then the nx x nx Jacobian pattern. */
EXPORT int kv_setup(int N, const double *par, const double *seg, const double *jnt,
                    const double *nload, const double *sload, int n_state, int n_x,
                    int ld, const int *d_idx, const double *s, const double *fac,
                    const double *y_fixed, casadi_int n_nz, const casadi_int *src,
                    const double *coef, const casadi_int *sp, int nb,
                    const double *theta, const double *segb, const double *jntb) {
  rod.N = N;
  rod.nb = nb;                   /* relaxation terms (0: Kelvin-Voigt, pointers unused) */
  rod.kl = kvrod_kl(N, nb);      /* the band the caller allocated (ldab = 2 kl + ku + 1) */
  rod.ku = kvrod_ku(N, nb);
  if (ld < 2 * rod.kl + rod.ku + 1) return 2;
  rod.par = par;
  rod.seg = seg;
  rod.jnt = jnt;
  rod.nload = nload;
  rod.sload = sload;
  rod.theta = theta;
  rod.segb = segb;
  rod.jntb = jntb;
  n = n_state;
  nx = n_x;
  ldab = ld;
  di = d_idx;
  xscale = s;
  odefac = fac;
  yfix = y_fixed;
  nnz = n_nz;
  jsrc = src;
  jcoef = coef;
  sp_x = sp;
  sp_x0 = sp + 3;
  sp_xn = sp + 7;
  sp_nx = sp + 10;
  sp_jac = sp + 13;
  free(y);
  free(ab);
  y = (double *)malloc(sizeof(double) * 3 * (size_t)n);
  ab = (double *)malloc(sizeof(double) * (size_t)ldab * (size_t)n);
  if (!y || !ab) return 1;
  yp = y + n;
  r = y + 2 * n;
  memset(yp, 0, sizeof(double) * (size_t)n);
  return 0;
}

static void state(const casadi_real *x) {
  int k;
  memcpy(y, yfix, sizeof(double) * (size_t)n);
  if (x)
    for (k = 0; k < nx; ++k) y[di[k]] = xscale[k] * x[k];
  else
    for (k = 0; k < nx; ++k) y[di[k]] = 0.0;
}

static const char *dyn_in[5] = {"t", "x", "z", "p", "u"};
static const char *dyn_out[4] = {"ode", "alg", "quad", "zero"};

/* ---- rod_ode: (t, x, z, p, u) -> (ode, alg, quad, zero) ---- */
EXPORT int rod_ode(const casadi_real **arg, casadi_real **res, casadi_int *iw,
                   casadi_real *w, int mem) {
  int k;
  double t = arg[0] ? arg[0][0] : 0.0;
  (void)iw;
  (void)w;
  (void)mem;
  state(arg[1]);
  if (kvrod_residual(&rod, t, y, yp, r)) return 1;
  if (res[0])
    for (k = 0; k < nx; ++k) res[0][k] = odefac[k] * r[di[k]];
  return 0;
}
EXPORT casadi_int rod_ode_n_in(void) { return 5; }
EXPORT casadi_int rod_ode_n_out(void) { return 4; }
EXPORT const char *rod_ode_name_in(casadi_int i) { return i >= 0 && i < 5 ? dyn_in[i] : 0; }
EXPORT const char *rod_ode_name_out(casadi_int i) {
  return i >= 0 && i < 4 ? dyn_out[i] : 0;
}
EXPORT const casadi_int *rod_ode_sparsity_in(casadi_int i) {
  return i == 0 ? sp_scalar : i == 1 ? sp_x : (i < 5 ? sp_empty : 0);
}
EXPORT const casadi_int *rod_ode_sparsity_out(casadi_int i) {
  return i == 0 ? sp_x : (i < 4 ? sp_empty : 0);
}
EXPORT int rod_ode_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                        casadi_int *sz_w) {
  if (sz_arg) *sz_arg = 5;
  if (sz_res) *sz_res = 4;
  if (sz_iw) *sz_iw = 0;
  if (sz_w) *sz_w = 0;
  return 0;
}

/* ---- jac_rod_ode: (t, x, z, p, u, out_ode, out_alg, out_quad, out_zero) ->
        jac_<out>_<in> for out in (ode, alg, quad, zero), in in (t, x, z, p, u) ---- */
static const char *jac_in[9] = {"t", "x", "z", "p", "u",
                                "out_ode", "out_alg", "out_quad", "out_zero"};
static char jac_out_names[20][16];

EXPORT int jac_rod_ode(const casadi_real **arg, casadi_real **res, casadi_int *iw,
                       casadi_real *w, int mem) {
  casadi_int e;
  double t = arg[0] ? arg[0][0] : 0.0;
  (void)iw;
  (void)w;
  (void)mem;
  if (!res[1]) return 0;
  state(arg[1]);
  memset(ab, 0, sizeof(double) * (size_t)ldab * (size_t)n);
  if (kvrod_jacobian_band(&rod, t, y, yp, 1.0, 0.0, ldab, ab)) return 1;
  for (e = 0; e < nnz; ++e) res[1][e] = jcoef[e] * ab[jsrc[e]];
  return 0;
}
EXPORT casadi_int jac_rod_ode_n_in(void) { return 9; }
EXPORT casadi_int jac_rod_ode_n_out(void) { return 20; }
EXPORT const char *jac_rod_ode_name_in(casadi_int i) {
  return i >= 0 && i < 9 ? jac_in[i] : 0;
}
EXPORT const char *jac_rod_ode_name_out(casadi_int i) {
  if (i < 0 || i >= 20) return 0;
  if (!jac_out_names[i][0]) {
    strcpy(jac_out_names[i], "jac_");
    strcat(jac_out_names[i], dyn_out[i / 5]);
    strcat(jac_out_names[i], "_");
    strcat(jac_out_names[i], dyn_in[i % 5]);
  }
  return jac_out_names[i];
}
EXPORT const casadi_int *jac_rod_ode_sparsity_in(casadi_int i) {
  if (i == 0) return sp_scalar;
  if (i == 1) return sp_x;
  if (i == 5) return sp_x0;
  return i < 9 ? sp_empty : 0;
}
EXPORT const casadi_int *jac_rod_ode_sparsity_out(casadi_int i) {
  casadi_int o = i / 5, j = i % 5;
  if (i < 0 || i >= 20) return 0;
  if (o == 0) return j == 0 ? sp_x0 : j == 1 ? sp_jac : sp_xn;
  return j == 0 ? sp_empty : j == 1 ? sp_nx : sp_00;
}
EXPORT int jac_rod_ode_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                            casadi_int *sz_w) {
  if (sz_arg) *sz_arg = 9;
  if (sz_res) *sz_res = 20;
  if (sz_iw) *sz_iw = 0;
  if (sz_w) *sz_w = 0;
  return 0;
}
