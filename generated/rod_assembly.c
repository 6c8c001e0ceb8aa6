// GENERATED FILE - do not edit; regenerate with `kvrod generate`.
// source: derive/templates/rod_assembly.c.jinja
// derivation step: discrete_rod
// inputs sha256: bddd5467fea5d4cd1547447d1edfb28b48a25b4dd560096c8999424ef16e32fd
// tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

/*
 * Assembly of the discrete rod from the per-element CasADi kernels in rod_kernels.c.
 * The loops are the only place that knows the cell-by-cell layout (generated/rod_layout.py);
 * their size does not depend on the number of elements N.
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
#define NSEG 14
#define NJNT 10
#define NNL 6
#define NSL 6
#define NDIAG 5

#define PAR_LOAD_SCALE 0
#define PAR_GRAVITY 1
#define PAR_F_DIST 4
#define PAR_FIX_START 7
#define PAR_CLAMP_START 8
#define PAR_FIX_END 9
#define PAR_CLAMP_END 10
#define PAR_R_START 11
#define PAR_V_START 14
#define PAR_P_START 17
#define PAR_OMEGA_START 21
#define PAR_R_END 24
#define PAR_V_END 27
#define PAR_P_END 30
#define PAR_OMEGA_END 34

#define SEG_H 0
#define SEG_C_F 1
#define SEG_V_F 4
#define SEG_V0 7
#define SEG_RHOA 10
#define SEG_RHOI 11

#define JNT_H 0
#define JNT_C_M 1
#define JNT_V_M 4
#define JNT_U0 7

#define NL_F_DEAD 0
#define NL_F_FOLLOWER 3

#define SL_M_DEAD 0
#define SL_M_FOLLOWER 3

/* indices of the fields of node i / segment i (i >= 1) in y */
static inline int cs(int i) { return i == 0 ? 0 : CELL0 + CELL * (i - 1); }
static inline int i_phi(int i) { return i == 0 ? 0 : cs(i) + 7; }
static inline int i_v(int i) { return i == 0 ? 3 : cs(i) + 10; }
static inline int i_p(int i) { return cs(i) + 0; }
static inline int i_om(int i) { return cs(i) + 4; }

/* per-element data: segment i = 1..N, joint j = 0..N, node i = 0..N */
static inline const double* segp(const kvrod_rod* r, int i) {
  return r->seg + (size_t)(i - 1) * NSEG;
}
static inline const double* jntp(const kvrod_rod* r, int j) {
  return r->jnt + (size_t)j * NJNT;
}
static inline const double* nlp(const kvrod_rod* r, int i) {
  return r->nload + (size_t)i * NNL;
}
static inline const double* slp(const kvrod_rod* r, int i) {
  return r->sload + (size_t)(i - 1) * NSL;
}

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

/* lumped node mass (kg) and length (m): half of each adjacent segment */
static double node_mass(const kvrod_rod* r, int i) {
  double m = 0.0;
  if (i >= 1) m += 0.5 * segp(r, i)[SEG_RHOA] * segp(r, i)[SEG_H];
  if (i < r->N) m += 0.5 * segp(r, i + 1)[SEG_RHOA] * segp(r, i + 1)[SEG_H];
  return m;
}

static double node_length(const kvrod_rod* r, int i) {
  double l = 0.0;
  if (i >= 1) l += 0.5 * segp(r, i)[SEG_H];
  if (i < r->N) l += 0.5 * segp(r, i + 1)[SEG_H];
  return l;
}

static double node_held(const kvrod_rod* r, int i) {
  if (i == 0) return r->par[PAR_FIX_START];
  if (i == r->N) return r->par[PAR_FIX_END];
  return 0.0;
}

/* the segment whose frame carries node i's follower force */
static inline int host(int i) { return i >= 1 ? i : 1; }

static const double* held_v(const kvrod_rod* r, int i) {
  return r->par + (i == 0 ? PAR_V_START : PAR_V_END);
}

static int has_follower(const double* f) { return f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0; }

/* total external force on node i (spatial), scaled by load_scale */
static int node_force(const kvrod_rod* r, int i, const double* y, work_t* W, double* f) {
  const double* par = r->par;
  const double ls = par[PAR_LOAD_SCALE], m = node_mass(r, i), l = node_length(r, i);
  const double* nl = nlp(r, i);
  int k;
  for (k = 0; k < 3; ++k)
    f[k] = ls * (m * par[PAR_GRAVITY + k] + l * par[PAR_F_DIST + k] + nl[NL_F_DEAD + k]);
  if (has_follower(nl + NL_F_FOLLOWER)) {
    double Rf[3];
    W->arg[0] = y + i_p(host(i)); W->arg[1] = nl + NL_F_FOLLOWER;
    W->res[0] = Rf;
    if (rod_rotate(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (k = 0; k < 3; ++k) f[k] += ls * Rf[k];
  }
  return 0;
}

/* external torque on segment i (material), scaled by load_scale */
static int segment_torque(const kvrod_rod* r, int i, const double* y, work_t* W, double* T) {
  const double ls = r->par[PAR_LOAD_SCALE];
  const double* sl = slp(r, i);
  int k;
  for (k = 0; k < 3; ++k) T[k] = ls * sl[SL_M_FOLLOWER + k];
  if (has_follower(sl + SL_M_DEAD)) {
    double RtM[3];
    W->arg[0] = y + i_p(i); W->arg[1] = sl + SL_M_DEAD;
    W->res[0] = RtM;
    if (rod_rotate_transposed(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (k = 0; k < 3; ++k) T[k] += ls * RtM[k];
  }
  return 0;
}

/* the joint at node j: (p_a, p_b, Omega_a, Omega_b) from the state or the clamp frames */
static int joint_args(const kvrod_rod* r, int j, const double* y, work_t* W) {
  const int N = r->N, has_a = j >= 1, has_b = j + 1 <= N;
  if (j == 0 && !(r->par[PAR_CLAMP_START] > 0.5)) return 0;
  if (j == N && !(r->par[PAR_CLAMP_END] > 0.5)) return 0;
  W->arg[0] = has_a ? y + i_p(j) : r->par + PAR_P_START;
  W->arg[1] = has_b ? y + i_p(j + 1) : r->par + PAR_P_END;
  W->arg[2] = has_a ? y + i_om(j) : r->par + PAR_OMEGA_START;
  W->arg[3] = has_b ? y + i_om(j + 1) : r->par + PAR_OMEGA_END;
  W->arg[4] = jntp(r, j);
  return 1;
}

int kvrod_n_state(int N) { return CELL0 + CELL * N; }
int kvrod_kl(void) { return KL; }
int kvrod_ku(void) { return KU; }
int kvrod_n_params(void) { return 37; }

int kvrod_residual(const kvrod_rod* rod, double t, const double* y, const double* yp,
                   double* res) {
  (void) t;
  const int N = rod->N;
  if (N < 1) return -1;
  work_t W;
  double Q[9], T[6], f[3], m, held;
  int i, j, k;
  /* nodes: kinematics and momentum, or the prescribed position and velocity */
  for (i = 0; i <= N; ++i) {
    m = node_mass(rod, i); held = node_held(rod, i);
    if (node_force(rod, i, y, &W, f)) return -3;
    W.arg[0] = y + i_phi(i); W.arg[1] = y + i_v(i);
    W.arg[2] = yp + i_phi(i); W.arg[3] = yp + i_v(i);
    W.arg[4] = &m; W.arg[5] = f; W.arg[6] = &held;
    W.arg[7] = i == 0 || i == N ? held_v(rod, i) : kZero3;
    W.res[0] = res + i_phi(i);
    if (rod_node_inertia(W.arg, W.res, W.iw, W.w, 0)) return -3;
  }
  /* segments: kinematics, angular momentum, external torques */
  for (i = 1; i <= N; ++i) {
    W.arg[0] = y + i_p(i); W.arg[1] = y + i_om(i);
    W.arg[2] = yp + i_p(i); W.arg[3] = yp + i_om(i);
    W.arg[4] = segp(rod, i);
    W.res[0] = res + i_p(i);
    if (rod_segment_inertia(W.arg, W.res, W.iw, W.w, 0)) return -3;
    if (segment_torque(rod, i, y, &W, T)) return -3;
    for (k = 0; k < 3; ++k) res[i_om(i) + k] -= T[k];
  }
  /* internal forces of the segments: elastic + viscous (none on a held node's rows) */
  const int free0 = !(node_held(rod, 0) > 0.5), freeN = !(node_held(rod, N) > 0.5);
  for (i = 1; i <= N; ++i) {
    W.arg[0] = y + i_phi(i - 1); W.arg[1] = y + i_phi(i); W.arg[2] = y + i_p(i);
    W.arg[3] = y + i_v(i - 1); W.arg[4] = y + i_v(i); W.arg[5] = y + i_om(i);
    W.arg[6] = segp(rod, i);
    W.res[0] = Q;
    if (rod_segment_forces(W.arg, W.res, W.iw, W.w, 0)) return -3;
    double* ra = res + i_v(i - 1);
    double* rb = res + i_v(i);
    double* ro = res + i_om(i);
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) ra[k] -= Q[k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) rb[k] -= Q[3 + k];
    for (k = 0; k < 3; ++k) ro[k] -= Q[6 + k];
  }
  /* internal torques of the joints (and the clamp joints against the end frames) */
  for (j = 0; j <= N; ++j) {
    if (!joint_args(rod, j, y, &W)) continue;
    W.res[0] = T;
    if (rod_joint_torques(W.arg, W.res, W.iw, W.w, 0)) return -3;
    if (j >= 1) for (k = 0; k < 3; ++k) res[i_om(j) + k] -= T[k];
    if (j + 1 <= N) for (k = 0; k < 3; ++k) res[i_om(j + 1) + k] -= T[3 + k];
  }
  return 0;
}

#define AB(r, c) ab[(size_t)(KL + KU + (r) - (c)) + (size_t)(c) * (size_t)ldab]

/* the contributions of one element to cy dF/dy + cj dF/dy' (band storage) */
static int jac_node(const kvrod_rod* rod, int i, const double* y, const double* yp,
                    double cy, double cj, int ldab, double* ab, work_t* W, double* J) {
  const int N = rod->N;
  double m = node_mass(rod, i), held = node_held(rod, i), f[3];
  int r, c;
  if (node_force(rod, i, y, W, f)) return -3;
  W->arg[0] = y + i_phi(i); W->arg[1] = y + i_v(i);
  W->arg[2] = yp + i_phi(i); W->arg[3] = yp + i_v(i);
  W->arg[4] = &m; W->arg[5] = f; W->arg[6] = &held;
  W->arg[7] = i == 0 || i == N ? held_v(rod, i) : kZero3;
  W->arg[8] = &cy; W->arg[9] = &cj;
  W->res[0] = J;
  if (rod_node_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int o = i_phi(i);
  for (c = 0; c < 6; ++c) for (r = 0; r < 6; ++r) AB(o + r, o + c) += J[r + 6 * c];
  /* follower force: R(p_host) f depends on the host segment's quaternion */
  const double* nl = nlp(rod, i);
  if (cy != 0.0 && !(held > 0.5) && has_follower(nl + NL_F_FOLLOWER)) {
    const double s = cy * rod->par[PAR_LOAD_SCALE];
    const int op = i_p(host(i));
    W->arg[0] = y + op; W->arg[1] = nl + NL_F_FOLLOWER;
    W->res[0] = J;
    if (rod_rotate_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (c = 0; c < 4; ++c)
      for (r = 0; r < 3; ++r) AB(i_v(i) + r, op + c) -= s * J[r + 3 * c];
  }
  return 0;
}

static int jac_segment_inertia(const kvrod_rod* rod, int i, const double* y,
                               const double* yp, double cy, double cj, int ldab, double* ab,
                               work_t* W, double* J) {
  int r, c;
  W->arg[0] = y + i_p(i); W->arg[1] = y + i_om(i);
  W->arg[2] = yp + i_p(i); W->arg[3] = yp + i_om(i);
  W->arg[4] = segp(rod, i); W->arg[5] = &cy; W->arg[6] = &cj;
  W->res[0] = J;
  if (rod_segment_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int o = i_p(i);
  for (c = 0; c < 7; ++c) for (r = 0; r < 7; ++r) AB(o + r, o + c) += J[r + 7 * c];
  const double* sl = slp(rod, i);
  if (cy != 0.0 && has_follower(sl + SL_M_DEAD)) {
    /* dead moment: the material torque R(p)^T M depends on p */
    const double s = cy * rod->par[PAR_LOAD_SCALE];
    W->arg[0] = y + i_p(i); W->arg[1] = sl + SL_M_DEAD;
    W->res[0] = J;
    if (rod_rotate_transposed_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (c = 0; c < 4; ++c)
      for (r = 0; r < 3; ++r) AB(i_om(i) + r, o + c) -= s * J[r + 3 * c];
  }
  return 0;
}

/* reduced segment Jacobian (6 x 13): rows (force on node b, torque), columns
 * (phi_b, p, v_b, Omega); force on node a = -force on node b and the phi_a, v_a columns
 * are the negated phi_b, v_b columns. */
static int jac_segment(const kvrod_rod* rod, int i, const double* y, double cy, int ldab,
                       double* ab, work_t* W, double* J) {
  const int N = rod->N;
  int rb[6], ra[3], cb[13], cpart[13], r, c;
  W->arg[0] = y + i_phi(i - 1); W->arg[1] = y + i_phi(i); W->arg[2] = y + i_p(i);
  W->arg[3] = y + i_v(i - 1); W->arg[4] = y + i_v(i); W->arg[5] = y + i_om(i);
  W->arg[6] = segp(rod, i);
  W->res[0] = J;
  if (rod_segment_forces_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int use_a = (i - 1 > 0 || !(node_held(rod, 0) > 0.5));
  const int use_b = (i < N || !(node_held(rod, N) > 0.5));
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

/* joint j sits at node j: between segments j and j+1, or a clamp frame and a segment */
static int jac_joint(const kvrod_rod* rod, int j, const double* y, double cy, int ldab,
                     double* ab, work_t* W, double* J) {
  const int N = rod->N, has_a = j >= 1, has_b = j + 1 <= N;
  int jrows[6], jcols[14], r, c;
  if (!joint_args(rod, j, y, W)) return 0;
  W->res[0] = J;
  if (rod_joint_torques_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  for (r = 0; r < 3; ++r) {
    jrows[r] = has_a ? i_om(j) + r : -1;
    jrows[3 + r] = has_b ? i_om(j + 1) + r : -1;
    jcols[8 + r] = has_a ? i_om(j) + r : -1;
    jcols[11 + r] = has_b ? i_om(j + 1) + r : -1;
  }
  for (r = 0; r < 4; ++r) {
    jcols[r] = has_a ? i_p(j) + r : -1;
    jcols[4 + r] = has_b ? i_p(j + 1) + r : -1;
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

int kvrod_jacobian_band(const kvrod_rod* rod, double t, const double* y, const double* yp,
                        double cy, double cj, int ldab, double* ab) {
  (void) t;
  const int N = rod->N;
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
    if (jac_node(rod, i, y, yp, cy, cj, ldab, ab, &W, J)) return -3;
    if (i >= 1 && jac_segment_inertia(rod, i, y, yp, cy, cj, ldab, ab, &W, J)) return -3;
    if (cy == 0.0) continue;
    if (i >= 1 && jac_segment(rod, i, y, cy, ldab, ab, &W, J)) return -3;
    if (jac_joint(rod, i, y, cy, ldab, ab, &W, J)) return -3;
  }
  return 0;
}

/* energies and powers of one state; per-element strains and resultants if out_el != 0
 * (V (3N), F (3N), U (3(N+1)), M (3(N+1))) */
static int energies_one(const kvrod_rod* rod, const double* y, const double* yp,
                        double* e, double* out_el, work_t* W) {
  const int N = rod->N;
  double Tk, Wel, Dd, S3[3], R3[3], Q[9], T6[6], f[3], m, Fint[2][3] = {{0, 0, 0}, {0, 0, 0}};
  double* oV = out_el;
  double* oF = out_el ? oV + 3 * N : 0;
  double* oU = out_el ? oF + 3 * N : 0;
  double* oM = out_el ? oU + 3 * (N + 1) : 0;
  int i, j, k;
  for (k = 0; k < NDIAG; ++k) e[k] = 0.0;
  for (i = 0; i <= N; ++i) {            /* kinetic energy and power of the nodes' loads */
    m = node_mass(rod, i);
    W->arg[0] = y + i_v(i); W->arg[1] = &m;
    W->res[0] = &Tk;
    if (rod_node_kinetic(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[0] += Tk;
    if (node_force(rod, i, y, W, f)) return -3;
    for (k = 0; k < 3; ++k) e[3] += f[k] * y[i_v(i) + k];
  }
  for (i = 1; i <= N; ++i) {
    W->arg[0] = y + i_om(i); W->arg[1] = segp(rod, i);
    W->res[0] = &Tk;
    if (rod_segment_kinetic(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[0] += Tk;
    if (segment_torque(rod, i, y, W, S3)) return -3;
    for (k = 0; k < 3; ++k) e[3] += S3[k] * y[i_om(i) + k];
    W->arg[0] = y + i_phi(i - 1); W->arg[1] = y + i_phi(i); W->arg[2] = y + i_p(i);
    W->arg[3] = y + i_v(i - 1); W->arg[4] = y + i_v(i); W->arg[5] = y + i_om(i);
    W->arg[6] = segp(rod, i);
    W->res[0] = &Wel; W->res[1] = &Dd; W->res[2] = S3; W->res[3] = R3;
    if (rod_segment_diagnostics(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[1] += Wel; e[2] += 2.0 * Dd;
    if (out_el)
      for (k = 0; k < 3; ++k) { oV[3 * (i - 1) + k] = S3[k]; oF[3 * (i - 1) + k] = R3[k]; }
    if (i == 1 || i == N) {             /* internal forces on the end nodes (reactions) */
      W->res[0] = Q;
      if (rod_segment_forces(W->arg, W->res, W->iw, W->w, 0)) return -3;
      for (k = 0; k < 3; ++k) {
        if (i == 1) Fint[0][k] += Q[k];
        if (i == N) Fint[1][k] += Q[3 + k];
      }
    }
  }
  for (j = 0; j <= N; ++j) {
    if (!joint_args(rod, j, y, W)) continue;
    W->res[0] = &Wel; W->res[1] = &Dd; W->res[2] = S3; W->res[3] = R3;
    if (rod_joint_diagnostics(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[1] += Wel; e[2] += 2.0 * Dd;
    if (out_el) for (k = 0; k < 3; ++k) { oU[3 * j + k] = S3[k]; oM[3 * j + k] = R3[k]; }
    if (j == 0 || j == N) {             /* power of the clamp frames' prescribed rotation */
      if (!joint_args(rod, j, y, W)) continue;
      W->res[0] = T6;
      if (rod_joint_torques(W->arg, W->res, W->iw, W->w, 0)) return -3;
      const double* om = rod->par + (j == 0 ? PAR_OMEGA_START : PAR_OMEGA_END);
      const double* Tc = j == 0 ? T6 : T6 + 3;
      for (k = 0; k < 3; ++k) e[4] -= Tc[k] * om[k];
    }
  }
  for (j = 0; j < 2; ++j) {             /* power of the held nodes' prescribed motion */
    i = j == 0 ? 0 : N;
    if (!(node_held(rod, i) > 0.5)) continue;
    m = node_mass(rod, i);
    if (node_force(rod, i, y, W, f)) return -3;
    for (k = 0; k < 3; ++k)
      e[4] += (m * yp[i_v(i) + k] - f[k] - Fint[j][k]) * y[i_v(i) + k];
  }
  return 0;
}

int kvrod_diagnostics(const kvrod_rod* rod, double t, const double* y, const double* yp,
                      double* out) {
  (void) t;
  const int N = rod->N;
  if (N < 1) return -1;
  work_t W;
  memset(out, 0, sizeof(double) * (size_t)(NDIAG + 6 * N + 6 * (N + 1)));
  return energies_one(rod, y, yp, out, out + NDIAG, &W);
}

int kvrod_energies(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                   const double* yps, double* out) {
  (void) ts;
  const int N = rod->N;
  const size_t n = (size_t) kvrod_n_state(N);
  if (N < 1) return -1;
  work_t W;
  int k;
  for (k = 0; k < m; ++k)
    if (energies_one(rod, ys + k * n, yps + k * n, out + (size_t)k * NDIAG, 0, &W)) return -3;
  return 0;
}
