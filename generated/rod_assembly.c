// GENERATED FILE - do not edit; regenerate with `kvrod generate`.
// source: derive/templates/rod_assembly.c.jinja
// derivation step: discrete_rod
// inputs sha256: 44a96a6a26db567e3b5b609e2024bdf98ff089d81f1ddc7591dad2505db52b90
// tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

/*
 * Assembly of the discrete rod from the per-element CasADi kernels in rod_kernels.c.
 * The loop is the only place that knows the cell-by-cell layout (generated/rod_layout.py);
 * its size does not depend on the number of elements N.
 *
 * All functions return 0 on success and a negative code on bad arguments
 * (-1: N < 1, -2: ldab too small, -3: kernel failure).
 */
#include <string.h>
#include "rod_kernels.h"
#include "rod_assembly.h"

#define CELL0 6
#define CELL 13
#define KL 19
#define KU 15

#define PAR_H 0
#define PAR_C_F 1
#define PAR_C_M 4
#define PAR_V_F 7
#define PAR_V_M 10
#define PAR_U0 13
#define PAR_RHOA 16
#define PAR_RHOI 17
#define PAR_GRAVITY 20
#define PAR_TIP_FORCE 23
#define PAR_TIP_MOMENT 26
#define PAR_LOAD_SCALE 29
#define PAR_P_START 30
#define PAR_P_END 34
#define PAR_FIX_START 38
#define PAR_CLAMP_START 39
#define PAR_FIX_END 40
#define PAR_CLAMP_END 41

/* indices of the fields of node i / segment i (i >= 1) in y */
static inline int cs(int i) { return i == 0 ? 0 : CELL0 + CELL * (i - 1); }
static inline int i_phi(int i) { return i == 0 ? 0 : cs(i) + 7; }
static inline int i_v(int i) { return i == 0 ? 3 : cs(i) + 10; }
static inline int i_p(int i) { return cs(i) + 0; }
static inline int i_om(int i) { return cs(i) + 4; }

static const double kZero3[3] = {0.0, 0.0, 0.0};

/* work memory large enough for every kernel */
#define MAXW 78
#define MAXIW 1
#define MAXARG 10
#define MAXRES 4
typedef struct {
  const double* arg[MAXARG];
  double* res[MAXRES];
  long long int iw[MAXIW];
  double w[MAXW];
} work_t;

static double node_mass(int N, int i, const double* par) {
  double m = par[PAR_RHOA] * par[PAR_H];
  return (i == 0 || i == N) ? 0.5 * m : m;
}

static double node_fixed(int N, int i, const double* par) {
  if (i == 0) return par[PAR_FIX_START];
  if (i == N) return par[PAR_FIX_END];
  return 0.0;
}

int kvrod_n_state(int N) { return CELL0 + CELL * N; }
int kvrod_kl(void) { return KL; }
int kvrod_ku(void) { return KU; }
int kvrod_n_params(void) { return 42; }

int kvrod_residual(int N, const double* par, double t, const double* y, const double* yp,
                   double* res) {
  (void) t;
  if (N < 1) return -1;
  work_t W;
  double Q[9], T[6];
  int i, k;
  /* inertia, kinematics and external loads */
  for (i = 0; i <= N; ++i) {
    double m = node_mass(N, i, par), tip = (i == N), fixed = node_fixed(N, i, par);
    W.arg[0] = y + i_phi(i); W.arg[1] = y + i_v(i);
    W.arg[2] = yp + i_phi(i); W.arg[3] = yp + i_v(i);
    W.arg[4] = &m; W.arg[5] = &tip; W.arg[6] = &fixed; W.arg[7] = par;
    W.res[0] = res + i_phi(i);
    if (rod_node_inertia(W.arg, W.res, W.iw, W.w, 0)) return -3;
  }
  for (i = 1; i <= N; ++i) {
    W.arg[0] = y + i_p(i); W.arg[1] = y + i_om(i);
    W.arg[2] = yp + i_p(i); W.arg[3] = yp + i_om(i);
    W.arg[4] = par;
    W.res[0] = res + i_p(i);
    if (rod_segment_inertia(W.arg, W.res, W.iw, W.w, 0)) return -3;
  }
  /* dead tip moment on the last segment */
  W.arg[0] = y + i_p(N); W.arg[1] = par;
  W.res[0] = T;
  if (rod_tip_moment(W.arg, W.res, W.iw, W.w, 0)) return -3;
  for (k = 0; k < 3; ++k) res[i_om(N) + k] -= T[k];
  /* internal forces of the segments: elastic + viscous */
  const int free0 = !(par[PAR_FIX_START] > 0.5), freeN = !(par[PAR_FIX_END] > 0.5);
  for (i = 1; i <= N; ++i) {
    W.arg[0] = y + i_phi(i - 1); W.arg[1] = y + i_phi(i); W.arg[2] = y + i_p(i);
    W.arg[3] = y + i_v(i - 1); W.arg[4] = y + i_v(i); W.arg[5] = y + i_om(i);
    W.arg[6] = par;
    W.res[0] = Q;
    if (rod_segment_forces(W.arg, W.res, W.iw, W.w, 0)) return -3;
    double* ra = res + i_v(i - 1);
    double* rb = res + i_v(i);
    double* ro = res + i_om(i);
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) ra[k] -= Q[k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) rb[k] -= Q[3 + k];
    for (k = 0; k < 3; ++k) ro[k] -= Q[6 + k];
  }
  /* internal torques of the joints */
  double h = par[PAR_H], hh = 0.5 * par[PAR_H];
  for (i = 1; i < N; ++i) {
    W.arg[0] = y + i_p(i); W.arg[1] = y + i_p(i + 1);
    W.arg[2] = y + i_om(i); W.arg[3] = y + i_om(i + 1); W.arg[4] = &h; W.arg[5] = par;
    W.res[0] = T;
    if (rod_joint_torques(W.arg, W.res, W.iw, W.w, 0)) return -3;
    for (k = 0; k < 3; ++k) { res[i_om(i) + k] -= T[k]; res[i_om(i + 1) + k] -= T[3 + k]; }
  }
  if (par[PAR_CLAMP_START] > 0.5) {
    W.arg[0] = par + PAR_P_START; W.arg[1] = y + i_p(1);
    W.arg[2] = kZero3; W.arg[3] = y + i_om(1); W.arg[4] = &hh; W.arg[5] = par;
    W.res[0] = T;
    if (rod_joint_torques(W.arg, W.res, W.iw, W.w, 0)) return -3;
    for (k = 0; k < 3; ++k) res[i_om(1) + k] -= T[3 + k];
  }
  if (par[PAR_CLAMP_END] > 0.5) {
    W.arg[0] = y + i_p(N); W.arg[1] = par + PAR_P_END;
    W.arg[2] = y + i_om(N); W.arg[3] = kZero3; W.arg[4] = &hh; W.arg[5] = par;
    W.res[0] = T;
    if (rod_joint_torques(W.arg, W.res, W.iw, W.w, 0)) return -3;
    for (k = 0; k < 3; ++k) res[i_om(N) + k] -= T[k];
  }
  return 0;
}

#define AB(r, c) ab[(size_t)(KL + KU + (r) - (c)) + (size_t)(c) * (size_t)ldab]

/* the contributions of one element to cy dF/dy + cj dF/dy' (band storage) */
static int jac_node(int N, int i, const double* par, const double* y, const double* yp,
                    double cy, double cj, int ldab, double* ab, work_t* W, double* J) {
  double m = node_mass(N, i, par), tip = (i == N), fixed = node_fixed(N, i, par);
  int r, c;
  W->arg[0] = y + i_phi(i); W->arg[1] = y + i_v(i);
  W->arg[2] = yp + i_phi(i); W->arg[3] = yp + i_v(i);
  W->arg[4] = &m; W->arg[5] = &tip; W->arg[6] = &fixed; W->arg[7] = par;
  W->arg[8] = &cy; W->arg[9] = &cj;
  W->res[0] = J;
  if (rod_node_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int o = i_phi(i);
  for (c = 0; c < 6; ++c) for (r = 0; r < 6; ++r) AB(o + r, o + c) += J[r + 6 * c];
  return 0;
}

static int jac_segment_inertia(int N, int i, const double* par, const double* y,
                               const double* yp, double cy, double cj, int ldab, double* ab,
                               work_t* W, double* J) {
  int r, c;
  W->arg[0] = y + i_p(i); W->arg[1] = y + i_om(i);
  W->arg[2] = yp + i_p(i); W->arg[3] = yp + i_om(i);
  W->arg[4] = par; W->arg[5] = &cy; W->arg[6] = &cj;
  W->res[0] = J;
  if (rod_segment_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int o = i_p(i);
  for (c = 0; c < 7; ++c) for (r = 0; r < 7; ++r) AB(o + r, o + c) += J[r + 7 * c];
  if (i == N && cy != 0.0) {
    /* dead tip moment: material torque R(p)^T M depends on p */
    W->arg[0] = y + i_p(i); W->arg[1] = par;
    W->res[0] = J;
    if (rod_tip_moment_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (c = 0; c < 4; ++c)
      for (r = 0; r < 3; ++r) AB(i_om(i) + r, o + c) -= cy * J[r + 3 * c];
  }
  return 0;
}

/* reduced segment Jacobian (6 x 13): rows (force on node b, torque), columns
 * (phi_b, p, v_b, Omega); force on node a = -force on node b and the phi_a, v_a columns
 * are the negated phi_b, v_b columns. */
static int jac_segment(int N, int i, const double* par, const double* y, double cy,
                       int ldab, double* ab, work_t* W, double* J) {
  int rb[6], ra[3], cb[13], cpart[13], r, c;
  W->arg[0] = y + i_phi(i - 1); W->arg[1] = y + i_phi(i); W->arg[2] = y + i_p(i);
  W->arg[3] = y + i_v(i - 1); W->arg[4] = y + i_v(i); W->arg[5] = y + i_om(i);
  W->arg[6] = par;
  W->res[0] = J;
  if (rod_segment_forces_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int use_a = (i - 1 > 0 || !(par[PAR_FIX_START] > 0.5));
  const int use_b = (i < N || !(par[PAR_FIX_END] > 0.5));
  for (r = 0; r < 3; ++r) {
    rb[r] = use_b ? i_v(i) + r : -1;
    rb[3 + r] = i_om(i) + r;
    ra[r] = use_a ? i_v(i - 1) + r : -1;
    cb[r] = i_phi(i) + r; cpart[r] = i_phi(i - 1) + r;
    cb[7 + r] = i_v(i) + r; cpart[7 + r] = i_v(i - 1) + r;
    cb[10 + r] = i_om(i) + r; cpart[10 + r] = -1;
  }
  for (r = 0; r < 4; ++r) { cb[3 + r] = i_p(i) + r; cpart[3 + r] = -1; }
  for (c = 0; c < 13; ++c) {
    const int c2 = cpart[c];
    for (r = 0; r < 6; ++r) {
      const double val = cy * J[r + 6 * c];
      if (rb[r] >= 0) {
        AB(rb[r], cb[c]) -= val;
        if (c2 >= 0) AB(rb[r], c2) += val;
      }
      if (r < 3 && ra[r] >= 0) {
        AB(ra[r], cb[c]) += val;
        if (c2 >= 0) AB(ra[r], c2) -= val;
      }
    }
  }
  return 0;
}

/* joint i sits at node i: between segments i and i+1, or a clamp frame and a segment */
static int jac_joint(int N, int i, const double* par, const double* y, double cy, int ldab,
                     double* ab, work_t* W, double* J) {
  const int has_a = i >= 1, has_b = i + 1 <= N;
  int jrows[6], jcols[14], r, c;
  if (i == 0 && !(par[PAR_CLAMP_START] > 0.5)) return 0;
  if (i == N && !(par[PAR_CLAMP_END] > 0.5)) return 0;
  double hj = (has_a && has_b) ? par[PAR_H] : 0.5 * par[PAR_H];
  W->arg[0] = has_a ? y + i_p(i) : par + PAR_P_START;
  W->arg[1] = has_b ? y + i_p(i + 1) : par + PAR_P_END;
  W->arg[2] = has_a ? y + i_om(i) : kZero3;
  W->arg[3] = has_b ? y + i_om(i + 1) : kZero3;
  W->arg[4] = &hj; W->arg[5] = par;
  W->res[0] = J;
  if (rod_joint_torques_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  for (r = 0; r < 3; ++r) {
    jrows[r] = has_a ? i_om(i) + r : -1;
    jrows[3 + r] = has_b ? i_om(i + 1) + r : -1;
    jcols[8 + r] = has_a ? i_om(i) + r : -1;
    jcols[11 + r] = has_b ? i_om(i + 1) + r : -1;
  }
  for (r = 0; r < 4; ++r) {
    jcols[r] = has_a ? i_p(i) + r : -1;
    jcols[4 + r] = has_b ? i_p(i + 1) + r : -1;
  }
  for (c = 0; c < 14; ++c) {
    if (jcols[c] < 0) continue;
    for (r = 0; r < 6; ++r)
      if (jrows[r] >= 0) AB(jrows[r], jcols[c]) -= cy * J[r + 6 * c];
  }
  return 0;
}

static void zero_cell(int i, int ldab, double* ab) {
  const int c0 = cs(i), c1 = i == 0 ? CELL0 : c0 + CELL;
  int c;
  /* band rows KL .. 2KL+KU only; rows 0 .. KL-1 are dgbtrf workspace */
  for (c = c0; c < c1; ++c)
    memset(ab + (size_t)c * (size_t)ldab + KL, 0, sizeof(double) * (KL + KU + 1));
}

int kvrod_jacobian_band2(int N, const double* par, double t, const double* y,
                         const double* yp, double cy, double cj, int ldab, double* ab) {
  (void) t;
  if (N < 1) return -1;
  if (ldab < 2 * KL + KU + 1) return -2;
  work_t W;
  double J[84];
  int i;
  /* one sweep over the cells; the columns of cell i+1 are zeroed just before the
   * elements of cell i (which reach one cell ahead) are added: cache friendly */
  zero_cell(0, ldab, ab);
  for (i = 0; i <= N; ++i) {
    if (i + 1 <= N) zero_cell(i + 1, ldab, ab);
    if (jac_node(N, i, par, y, yp, cy, cj, ldab, ab, &W, J)) return -3;
    if (i >= 1 && jac_segment_inertia(N, i, par, y, yp, cy, cj, ldab, ab, &W, J)) return -3;
    if (cy == 0.0) continue;
    if (i >= 1 && jac_segment(N, i, par, y, cy, ldab, ab, &W, J)) return -3;
    if (jac_joint(N, i, par, y, cy, ldab, ab, &W, J)) return -3;
  }
  return 0;
}

int kvrod_jacobian_band(int N, const double* par, double t, const double* y,
                        const double* yp, double cj, int ldab, double* ab) {
  return kvrod_jacobian_band2(N, par, t, y, yp, 1.0, cj, ldab, ab);
}

int kvrod_diagnostics(int N, const double* par, double t, const double* y, const double* yp,
                      double* out) {
  (void) t; (void) yp;
  if (N < 1) return -1;
  work_t W;
  double Tk, Pw, Wel, Dd, S3[3], R3[3];
  const int ns = 4;
  double* oV = out + ns;
  double* oF = oV + 3 * N;
  double* oU = oF + 3 * N;
  double* oM = oU + 3 * (N + 1);
  int i, k;
  memset(out, 0, sizeof(double) * (size_t)(ns + 6 * N + 6 * (N + 1)));
  for (i = 0; i <= N; ++i) {
    double m = node_mass(N, i, par), tip = (i == N);
    W.arg[0] = y + i_v(i); W.arg[1] = &m; W.arg[2] = &tip; W.arg[3] = par;
    W.res[0] = &Tk; W.res[1] = &Pw;
    if (rod_node_kinetic(W.arg, W.res, W.iw, W.w, 0)) return -3;
    out[0] += Tk;
    if (!(node_fixed(N, i, par) > 0.5)) out[3] += Pw;
  }
  for (i = 1; i <= N; ++i) {
    double tip = (i == N);
    W.arg[0] = y + i_p(i); W.arg[1] = y + i_om(i); W.arg[2] = &tip; W.arg[3] = par;
    W.res[0] = &Tk; W.res[1] = &Pw;
    if (rod_segment_kinetic(W.arg, W.res, W.iw, W.w, 0)) return -3;
    out[0] += Tk; out[3] += Pw;
    W.arg[0] = y + i_phi(i - 1); W.arg[1] = y + i_phi(i); W.arg[2] = y + i_p(i);
    W.arg[3] = y + i_v(i - 1); W.arg[4] = y + i_v(i); W.arg[5] = y + i_om(i);
    W.arg[6] = par;
    W.res[0] = &Wel; W.res[1] = &Dd; W.res[2] = S3; W.res[3] = R3;
    if (rod_segment_diagnostics(W.arg, W.res, W.iw, W.w, 0)) return -3;
    out[1] += Wel; out[2] += 2.0 * Dd;
    for (k = 0; k < 3; ++k) { oV[3 * (i - 1) + k] = S3[k]; oF[3 * (i - 1) + k] = R3[k]; }
  }
  double h = par[PAR_H], hh = 0.5 * par[PAR_H];
  for (i = 0; i <= N; ++i) {
    const int has_a = i >= 1, has_b = i + 1 <= N;
    if (i == 0 && !(par[PAR_CLAMP_START] > 0.5)) continue;
    if (i == N && !(par[PAR_CLAMP_END] > 0.5)) continue;
    W.arg[0] = has_a ? y + i_p(i) : par + PAR_P_START;
    W.arg[1] = has_b ? y + i_p(i + 1) : par + PAR_P_END;
    W.arg[2] = has_a ? y + i_om(i) : kZero3;
    W.arg[3] = has_b ? y + i_om(i + 1) : kZero3;
    W.arg[4] = (has_a && has_b) ? &h : &hh; W.arg[5] = par;
    W.res[0] = &Wel; W.res[1] = &Dd; W.res[2] = S3; W.res[3] = R3;
    if (rod_joint_diagnostics(W.arg, W.res, W.iw, W.w, 0)) return -3;
    out[1] += Wel; out[2] += 2.0 * Dd;
    for (k = 0; k < 3; ++k) { oU[3 * i + k] = S3[k]; oM[3 * i + k] = R3[k]; }
  }
  return 0;
}
