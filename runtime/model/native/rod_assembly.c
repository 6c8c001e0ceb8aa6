/*
 * Assembly of the discrete rod from the per-element CasADi kernels (generated/rod_kernels.c,
 * rod_kernels_x4.c): residual, banded Jacobian, energies and diagnostics of the whole rod.
 * Written by hand (the loops are the project's own), compiled with the generated kernels
 * and the generated layout header (generated/rod_layout.h: cell sizes, offsets, band
 * widths, parameter offsets), so the loops are the only place that knows the cell-by-cell
 * layout; their size does not depend on the number of elements N. The CasADi MX assembly
 * (runtime/model/casadi_oracle.py) is the same rod for machines without a compiler and the
 * oracle this one is tested against.
 *
 * All functions return 0 on success and a negative code on bad arguments
 * (-1: N < 1, -2: ldab too small, -3: kernel failure, -4: cells outside the rod or
 * the band storage).
 */
#include <string.h>
#include "rod_kernels.h"
#include "rod_kernels_x4.h"
#include "rod_layout.h"
#include "rod_assembly.h"
#include "rod_access.h"
#include "rod_contact.h"


/* -sum_b C_b q_b over nb terms of 3 (C and q term after term), into out; the sums in
 * locals (out may alias C or q as far as the compiler knows: a store and a reload per
 * term otherwise), in the same order */
static inline void relax_resultant(int nb, const double* C, const double* q, double* out) {
  double a0 = 0.0, a1 = 0.0, a2 = 0.0;
  int b;
  for (b = 0; b < nb; ++b, C += 3, q += 3) {
    a0 -= C[0] * q[0];
    a1 -= C[1] * q[1];
    a2 -= C[2] * q[2];
  }
  out[0] = a0; out[1] = a1; out[2] = a2;
}

/* the resultant of the relaxation terms of segment i (joint: jq): -sum_b C_b q_b */
static void seg_nq(const kvrod_rod* r, int i, const double* y, double* nq) {
  relax_resultant(r->nb, segb(r, i, 0), y + i_qs(r, i), nq);
}
static void jnt_mq(const kvrod_rod* r, int j, const double* y, double* mq) {
  relax_resultant(r->nb, jntb(r, j, 0), y + i_qj(r, j), mq);
}

static const double kZero3[3] = {0.0, 0.0, 0.0};

/* The inputs of segment s's kernels (forces, their Jacobian, diagnostics):
 * a[stride * k] for input k (stride 1: a call's argument list; 4: lane l of a four-lane
 * call, a = a4 + l), with its relaxation resultant n_q written into nq. */
static void seg_args(const kvrod_rod* r, int s, const double* y, const double** a,
                     int stride, double* nq) {
  seg_nq(r, s, y, nq);
  a[0] = y + i_phi(r, s - 1); a[stride] = y + i_phi(r, s); a[2 * stride] = y + i_p(r, s);
  a[3 * stride] = y + i_v(r, s - 1); a[4 * stride] = y + i_v(r, s);
  a[5 * stride] = y + i_om(r, s); a[6 * stride] = segp(r, s); a[7 * stride] = nq;
}

/* lane l of a four-lane call of the kernels of joint j between segments j and j+1 (an
 * interior joint; joint_args covers the clamp joints), with its resultant m_q into mq */
static void jnt_lane(const kvrod_rod* r, int j, const double* y, const double** a4, int l,
                     double* mq) {
  jnt_mq(r, j, y, mq);
  a4[l] = y + i_p(r, j); a4[4 + l] = y + i_p(r, j + 1);
  a4[8 + l] = y + i_om(r, j); a4[12 + l] = y + i_om(r, j + 1);
  a4[16 + l] = jntp(r, j); a4[20 + l] = mq;
}

/* work memory large enough for every kernel (sizes: rod_layout.h) */
typedef struct {
  const double* arg[MAXARG];
  double* res[MAXRES];
  long long int iw[MAXIW];
  double w[MAXW];
} work_t;


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
    W->arg[0] = y + i_p(r, host(i)); W->arg[1] = nl + NL_F_FOLLOWER;
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
    W->arg[0] = y + i_p(r, i); W->arg[1] = sl + SL_M_DEAD;
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
  W->arg[0] = has_a ? y + i_p(r, j) : r->par + PAR_P_START;
  W->arg[1] = has_b ? y + i_p(r, j + 1) : r->par + PAR_P_END;
  W->arg[2] = has_a ? y + i_om(r, j) : r->par + PAR_OMEGA_START;
  W->arg[3] = has_b ? y + i_om(r, j + 1) : r->par + PAR_OMEGA_END;
  W->arg[4] = jntp(r, j);
  return 1;
}

int kvrod_n_state(int N, int nb) { return CELL0_BASE + CELL0_PER * nb + (CELL_BASE + CELL_PER * nb) * N; }
int kvrod_kl(int N, int nb) { return KL0 + KL1 * nb - (N == 1 ? KL_N1 : 0); }
int kvrod_ku(int N, int nb) { return KU0 + KU1 * nb - (N == 1 ? KU_N1 : 0); }
int kvrod_n_params(void) { return NPAR; }

/* a rod the assembly can work on: N >= 1, 0 <= nb <= MAX_NB, its band at least the
 * layout's (a wider band is fine) */
static int check_rod(const kvrod_rod* rod) {
  if (rod->N < 1 || rod->nb < 0 || rod->nb > MAX_NB) return -1;
  if (rod->coupled) {
    if (rod->nb) return -1;
    if (rod->kl < (rod->N == 1 ? KLC_1 : rod->N == 2 ? KLC_2 : KLC) ||
        rod->ku < (rod->N == 1 ? KUC_1 : rod->N == 2 ? KUC_2 : KUC)) return -2;
    return 0;
  }
  if (rod->kl < kvrod_kl(rod->N, rod->nb) || rod->ku < kvrod_ku(rod->N, rod->nb)) return -2;
  return 0;
}

/* ---- coupled sections (docs/design.md, section 10): segment i's kernels see its two
 * nodes, its own frame and those of its neighbours (segments i-1, i+1, or the clamp
 * frames, or itself where the joint is absent: its coupling weight is then 0) ---- */


/* a joint row for an absent joint (h = 1, U0 = 0: its coupling weight is 0) */
static const double kNoJoint[NJNT] = {1.0};

/* the quaternion and angular velocity on side a (k = i-1) or b (k = i+1) of segment i:
 * segment k, a clamp frame, or segment i itself (no joint there) */
static void c_side(const kvrod_rod* r, int i, int k, const double* y, const double** p,
                   const double** om, const double** jrow) {
  const int N = r->N, j = k < i ? i - 1 : i;   /* the joint between them, at node j */
  if (k >= 1 && k <= N) {
    *p = y + i_p(r, k); *om = y + i_om(r, k); *jrow = jntp(r, j);
  } else if (k == 0 && r->par[PAR_CLAMP_START] > 0.5) {
    *p = r->par + PAR_P_START; *om = r->par + PAR_OMEGA_START; *jrow = jntp(r, 0);
  } else if (k == N + 1 && r->par[PAR_CLAMP_END] > 0.5) {
    *p = r->par + PAR_P_END; *om = r->par + PAR_OMEGA_END; *jrow = jntp(r, N);
  } else {
    *p = y + i_p(r, i); *om = y + i_om(r, i); *jrow = kNoJoint;
  }
}

/* the moments applied at the free (unclamped) ends among segment i's nodes, scaled:
 * (dead, spatial; follower, material) at node N minus those at node 0 (the kernels'
 * m_end: a free end's condensation carries its moment, docs/design.md, section 10) */
static void c_end_moment(const kvrod_rod* r, int i, double* m6) {
  const double ls = r->par[PAR_LOAD_SCALE];
  int k;
  for (k = 0; k < 6; ++k) m6[k] = 0.0;
  if (i == r->N && !(r->par[PAR_CLAMP_END] > 0.5))
    for (k = 0; k < 3; ++k) {
      m6[k] += ls * r->par[PAR_M_DEAD_END + k];
      m6[3 + k] += ls * r->par[PAR_M_FOLLOWER_END + k];
    }
  if (i == 1 && !(r->par[PAR_CLAMP_START] > 0.5))
    for (k = 0; k < 3; ++k) {
      m6[k] -= ls * r->par[PAR_M_DEAD_START + k];
      m6[3 + k] -= ls * r->par[PAR_M_FOLLOWER_START + k];
    }
}

/* the inputs of segment i's coupled kernels into a[0..14] (m6: room for its m_end) */
static void cseg_args(const kvrod_rod* r, int i, const double* y, const double** a,
                      double* m6) {
  a[0] = y + i_phi(r, i - 1); a[1] = y + i_phi(r, i);
  c_side(r, i, i - 1, y, &a[2], &a[7], &a[12]);
  a[3] = y + i_p(r, i);
  c_side(r, i, i + 1, y, &a[4], &a[9], &a[13]);
  a[5] = y + i_v(r, i - 1); a[6] = y + i_v(r, i);
  a[8] = y + i_om(r, i);
  a[10] = segp(r, i); a[11] = segcp(r, i);
  c_end_moment(r, i, m6);
  a[14] = m6;
}

/* gravity times the load factor (the kernels' g) */
static void c_gravity(const kvrod_rod* r, double* g) {
  int k;
  for (k = 0; k < 3; ++k) g[k] = r->par[PAR_LOAD_SCALE] * r->par[PAR_GRAVITY + k];
}

/* the inputs of segment i's coupled inertia kernel (9; then c_y, c_j for its Jacobian) */
static void cin_args(const kvrod_rod* r, int i, const double* y, const double* yp,
                     const double* g, const double** a) {
  a[0] = y + i_p(r, i); a[1] = y + i_om(r, i);
  a[2] = yp + i_p(r, i); a[3] = yp + i_om(r, i);
  a[4] = yp + i_v(r, i - 1); a[5] = yp + i_v(r, i);
  a[6] = segp(r, i); a[7] = segcp(r, i); a[8] = g;
}

/* the relaxation rows of one element: res = q' - (strain - q)/theta for each term
 * (strain = 0 for an absent clamp joint, whose terms then just decay); the strains in
 * locals and res apart from y, y' (restrict: no reload after every store; every
 * residual evaluates nb x 3 of these per element) */
static void relax_rows(const kvrod_rod* rod, const double* rates, int q0,
                       const double* strain, const double* y, const double* yp,
                       double* res) {
  const double s0 = strain ? strain[0] : 0.0, s1 = strain ? strain[1] : 0.0;
  const double s2 = strain ? strain[2] : 0.0;
  const double* restrict q = y + q0;
  const double* restrict qp = yp + q0;
  double* restrict r = res + q0;
  int b;
  for (b = 0; b < rod->nb; ++b, q += 3, qp += 3, r += 3) {
    const double rate = rates[b];
    r[0] = qp[0] - rate * (s0 - q[0]);
    r[1] = qp[1] - rate * (s1 - q[1]);
    r[2] = qp[2] - rate * (s2 - q[2]);
  }
}

/* the residual of a rod with coupled sections after its node rows: segment inertia
 * (with the mass centre's coupling to the nodes), external torques, the segments'
 * forces (with the couplings to their joints) and the joints' torques */
static int residual_coupled(const kvrod_rod* rod, const double* y, const double* yp,
                            double* res, work_t* W) {
  const int N = rod->N;
  const int free0 = !(node_held(rod, 0) > 0.5), freeN = !(node_held(rod, N) > 0.5);
  double r13[13], T[6], Q[15], g[3], m6[6];
  int i, j, k;
  c_gravity(rod, g);
  for (i = 1; i <= N; ++i) {
    cin_args(rod, i, y, yp, g, W->arg);
    W->res[0] = r13;
    if (rod_coupled_inertia(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (k = 0; k < 7; ++k) res[i_p(rod, i) + k] = r13[k];
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) res[i_v(rod, i - 1) + k] += r13[7 + k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) res[i_v(rod, i) + k] += r13[10 + k];
    if (segment_torque(rod, i, y, W, T)) return -3;
    for (k = 0; k < 3; ++k) res[i_om(rod, i) + k] -= T[k];
  }
  for (i = 1; i <= N; ++i) {
    cseg_args(rod, i, y, W->arg, m6);
    W->res[0] = Q;
    if (rod_coupled_segment_forces(W->arg, W->res, W->iw, W->w, 0)) return -3;
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) res[i_v(rod, i - 1) + k] -= Q[k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) res[i_v(rod, i) + k] -= Q[3 + k];
    if (i > 1) for (k = 0; k < 3; ++k) res[i_om(rod, i - 1) + k] -= Q[6 + k];
    for (k = 0; k < 3; ++k) res[i_om(rod, i) + k] -= Q[9 + k];
    if (i < N) for (k = 0; k < 3; ++k) res[i_om(rod, i + 1) + k] -= Q[12 + k];
  }
  for (j = 0; j <= N; ++j) {
    if (!joint_args(rod, j, y, W)) continue;
    W->arg[5] = jntcp(rod, j);
    W->res[0] = T;
    if (rod_coupled_joint_torques(W->arg, W->res, W->iw, W->w, 0)) return -3;
    if (j >= 1) for (k = 0; k < 3; ++k) res[i_om(rod, j) + k] -= T[k];
    if (j + 1 <= N) for (k = 0; k < 3; ++k) res[i_om(rod, j + 1) + k] -= T[3 + k];
  }
  return 0;
}

static int residual_own(const kvrod_rod* rod, const double* y, const double* yp,
                        double* res) {
  const int N = rod->N;
  if (check_rod(rod)) return check_rod(rod);
  work_t W;
  double T[6], f[3], m, held;
  int i, j, k, l, nl;
  /* nodes: kinematics and momentum, or the prescribed position and velocity */
  for (i = 0; i <= N; ++i) {
    m = node_mass(rod, i); held = node_held(rod, i);
    if (node_force(rod, i, y, &W, f)) return -3;
    W.arg[0] = y + i_phi(rod, i); W.arg[1] = y + i_v(rod, i);
    W.arg[2] = yp + i_phi(rod, i); W.arg[3] = yp + i_v(rod, i);
    W.arg[4] = &m; W.arg[5] = f; W.arg[6] = &held;
    W.arg[7] = i == 0 || i == N ? held_r(rod, i) : kZero3;
    W.arg[8] = i == 0 || i == N ? held_v(rod, i) : kZero3;
    W.res[0] = res + i_phi(rod, i);
    if (rod_node_inertia(W.arg, W.res, W.iw, W.w, 0)) return -3;
  }
  if (rod->coupled) return residual_coupled(rod, y, yp, res, &W);
  /* segments: kinematics, angular momentum, external torques */
  for (i = 1; i <= N; ++i) {
    W.arg[0] = y + i_p(rod, i); W.arg[1] = y + i_om(rod, i);
    W.arg[2] = yp + i_p(rod, i); W.arg[3] = yp + i_om(rod, i);
    W.arg[4] = segp(rod, i);
    W.res[0] = res + i_p(rod, i);
    if (rod_segment_inertia(W.arg, W.res, W.iw, W.w, 0)) return -3;
    if (segment_torque(rod, i, y, &W, T)) return -3;
    for (k = 0; k < 3; ++k) res[i_om(rod, i) + k] -= T[k];
  }
  /* internal forces of the segments: elastic + viscous (none on a held node's rows);
   * four segments per kernel call (rod_segment_forces_x4: bit for bit the scalar
   * kernel), then added segment by segment in order */
  const int free0 = !(node_held(rod, 0) > 0.5), freeN = !(node_held(rod, N) > 0.5);
  /* a generalized Maxwell rod (nb > 0) takes the strains of its relaxation rows from the
   * force (torque) kernels' second output (rod_segment_forces_strain: the same values as
   * the branch kernels' dV; a strain kernel of its own formed them again) */
  double Q4[4][9], nq4[4][3], dV4[4][3];
  const double* a4[4 * 8];
  double* r4[8];
  double rates[MAX_NB];       /* 1/theta_b once, not per element (the same values) */
  for (k = 0; k < rod->nb; ++k) rates[k] = 1.0 / rod->theta[k];
  for (i = 1; i <= N; i += nl) {
    nl = N - i + 1 >= 4 ? 4 : 1;
    if (nl == 4) {
      for (l = 0; l < 4; ++l) {
        seg_args(rod, i + l, y, a4 + l, 4, nq4[l]);
        r4[l] = Q4[l];
        r4[4 + l] = dV4[l];
      }
      if (rod->nb ? rod_segment_forces_strain_x4(a4, r4) : rod_segment_forces_x4(a4, r4))
        return -3;
    } else {
      seg_args(rod, i, y, W.arg, 1, nq4[0]);
      W.res[0] = Q4[0];
      W.res[1] = dV4[0];
      if (rod->nb ? rod_segment_forces_strain(W.arg, W.res, W.iw, W.w, 0)
                  : rod_segment_forces(W.arg, W.res, W.iw, W.w, 0))
        return -3;
    }
    for (l = 0; l < nl; ++l) {
      const int s = i + l;
      const double* Q = Q4[l];
      if (rod->nb) relax_rows(rod, rates, i_qs(rod, s), dV4[l], y, yp, res);
      double* ra = res + i_v(rod, s - 1);
      double* rb = res + i_v(rod, s);
      double* ro = res + i_om(rod, s);
      if (s - 1 > 0 || free0) for (k = 0; k < 3; ++k) ra[k] -= Q[k];
      if (s < N || freeN) for (k = 0; k < 3; ++k) rb[k] -= Q[3 + k];
      for (k = 0; k < 3; ++k) ro[k] -= Q[6 + k];
    }
  }
  /* internal torques of the joints (and the clamp joints against the end frames); four
   * interior joints per kernel call where they come in fours (rod_joint_torques_x4),
   * then added joint by joint in order */
  double T4[4][6], mq4[4][3];
  for (j = 0; j <= N; j += nl) {
    nl = j >= 1 && j + 3 <= N - 1 ? 4 : 1;
    if (nl == 4) {
      for (l = 0; l < 4; ++l) {
        jnt_lane(rod, j + l, y, a4, l, mq4[l]);
        r4[l] = T4[l];
        r4[4 + l] = dV4[l];
      }
      if (rod->nb ? rod_joint_torques_strain_x4(a4, r4) : rod_joint_torques_x4(a4, r4))
        return -3;
    } else {
      if (!joint_args(rod, j, y, &W)) {
        relax_rows(rod, rates, i_qj(rod, j), 0, y, yp, res);
        continue;
      }
      jnt_mq(rod, j, y, mq4[0]);
      W.arg[5] = mq4[0];
      W.res[0] = T4[0];
      W.res[1] = dV4[0];
      if (rod->nb ? rod_joint_torques_strain(W.arg, W.res, W.iw, W.w, 0)
                  : rod_joint_torques(W.arg, W.res, W.iw, W.w, 0))
        return -3;
    }
    for (l = 0; l < nl; ++l) {
      const int jj = j + l;
      const double* T = T4[l];
      if (jj >= 1) for (k = 0; k < 3; ++k) res[i_om(rod, jj) + k] -= T[k];
      if (jj + 1 <= N) for (k = 0; k < 3; ++k) res[i_om(rod, jj + 1) + k] -= T[3 + k];
      if (rod->nb) relax_rows(rod, rates, i_qj(rod, jj), dV4[l], y, yp, res);
    }
  }
  return 0;
}

/* the caller's band storage: columns col0 .. of J from ab (J(i, j) in column j - col0,
 * row kl + ku + i - j); need: kvrod_rod.relax_need for kvrod_jacobian_band_cells_relaxed,
 * else NULL (every entry formed) */
typedef struct {
  double* ab;
  int ldab, col0;
  const unsigned char* need;
} band_t;

/* whether column (row) k of the relaxation terms is formed in full */
#define NEED_COL(B, k) (!(B)->need || ((B)->need[k] & 1))
#define NEED_ROW(B, k) (!(B)->need || ((B)->need[k] & 2))

/* whether any of the m relaxation unknowns from q0 is wanted beyond its diagonal (else
 * their branch kernel need not run: statics reads no relaxation row or column) */
static int need_any(const band_t* B, int q0, int m) {
  int k;
  if (!B->need) return 1;
  for (k = 0; k < m; ++k)
    if (B->need[q0 + k]) return 1;
  return 0;
}

#define AB(r, c) \
  B->ab[(size_t)(rod->kl + rod->ku + (r) - (c)) + (size_t)((c) - B->col0) * (size_t)B->ldab]

/* only the diagonal of an element's relaxation rows from q0 (need_any: none wanted
 * beyond it), as the full rows form it: cy / theta_b + cj */
static void relax_diagonal(const kvrod_rod* rod, int q0, double cy, double cj,
                           const band_t* B) {
  int b, k;
  for (b = 0; b < rod->nb; ++b) {
    const double rate = 1.0 / rod->theta[b];
    for (k = 0; k < 3; ++k) AB(q0 + 3 * b + k, q0 + 3 * b + k) += cy * rate + cj;
  }
}

/* the contributions of one element to cy dF/dy + cj dF/dy' (band storage) */
static int jac_node(const kvrod_rod* rod, int i, const double* y, const double* yp,
                    double cy, double cj, const band_t* B, work_t* W, double* J) {
  const int N = rod->N;
  double m = node_mass(rod, i), held = node_held(rod, i), f[3];
  int r, c;
  if (node_force(rod, i, y, W, f)) return -3;
  W->arg[0] = y + i_phi(rod, i); W->arg[1] = y + i_v(rod, i);
  W->arg[2] = yp + i_phi(rod, i); W->arg[3] = yp + i_v(rod, i);
  W->arg[4] = &m; W->arg[5] = f; W->arg[6] = &held;
  W->arg[7] = i == 0 || i == N ? held_r(rod, i) : kZero3;
  W->arg[8] = i == 0 || i == N ? held_v(rod, i) : kZero3;
  W->arg[9] = &cy; W->arg[10] = &cj;
  W->res[0] = J;
  if (rod_node_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int o = i_phi(rod, i);
  for (c = 0; c < 6; ++c) for (r = 0; r < 6; ++r) AB(o + r, o + c) += J[r + 6 * c];
  /* follower force: R(p_host) f depends on the host segment's quaternion */
  const double* nl = nlp(rod, i);
  if (cy != 0.0 && !(held > 0.5) && has_follower(nl + NL_F_FOLLOWER)) {
    const double s = cy * rod->par[PAR_LOAD_SCALE];
    const int op = i_p(rod, host(i));
    W->arg[0] = y + op; W->arg[1] = nl + NL_F_FOLLOWER;
    W->res[0] = J;
    if (rod_rotate_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (c = 0; c < 4; ++c)
      for (r = 0; r < 3; ++r) AB(i_v(rod, i) + r, op + c) -= s * J[r + 3 * c];
  }
  return 0;
}

static int jac_segment_inertia(const kvrod_rod* rod, int i, const double* y,
                               const double* yp, double cy, double cj, const band_t* B,
                               work_t* W, double* J) {
  int r, c;
  W->arg[0] = y + i_p(rod, i); W->arg[1] = y + i_om(rod, i);
  W->arg[2] = yp + i_p(rod, i); W->arg[3] = yp + i_om(rod, i);
  W->arg[4] = segp(rod, i); W->arg[5] = &cy; W->arg[6] = &cj;
  W->res[0] = J;
  if (rod_segment_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  const int o = i_p(rod, i);
  for (c = 0; c < 7; ++c) for (r = 0; r < 7; ++r) AB(o + r, o + c) += J[r + 7 * c];
  const double* sl = slp(rod, i);
  if (cy != 0.0 && has_follower(sl + SL_M_DEAD)) {
    /* dead moment: the material torque R(p)^T M depends on p */
    const double s = cy * rod->par[PAR_LOAD_SCALE];
    W->arg[0] = y + i_p(rod, i); W->arg[1] = sl + SL_M_DEAD;
    W->res[0] = J;
    if (rod_rotate_transposed_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (c = 0; c < 4; ++c)
      for (r = 0; r < 3; ++r) AB(i_om(rod, i) + r, o + c) -= s * J[r + 3 * c];
  }
  return 0;
}

/* reduced segment Jacobian (6 x 13): rows (force on node b, torque), columns
 * (phi_b, p, v_b, Omega); force on node a = -force on node b and the phi_a, v_a columns
 * are the negated phi_b, v_b columns. With relaxation terms also the coupling of the
 * forces to the segment's internal strains q_b (through n_q = -sum C_b q_b) and the
 * relaxation rows q_b' - (dV - q_b)/theta_b. */
static int jac_segment(const kvrod_rod* rod, int i, const double* y, double cy, double cj,
                       const band_t* B, work_t* W, double* J, const double* Jx) {
  const int N = rod->N;
  int rb[6], ra[3], cb[13], cpart[13], r, c, b, k;
  double nq[3];
  const double* Jk = Jx;         /* the kernel's result, if evaluated already (x4) */
  if (!Jk) {
    seg_args(rod, i, y, W->arg, 1, nq);
    W->res[0] = J;
    if (rod_segment_forces_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    Jk = J;
  }
  const int use_a = (i - 1 > 0 || !(node_held(rod, 0) > 0.5));
  const int use_b = (i < N || !(node_held(rod, N) > 0.5));
  for (r = 0; r < 3; ++r) {
    rb[r] = use_b ? i_v(rod, i) + r : -1;
    rb[3 + r] = i_om(rod, i) + r;
    ra[r] = use_a ? i_v(rod, i - 1) + r : -1;
    cb[r] = i_phi(rod, i) + r; cpart[r] = i_phi(rod, i - 1) + r;
    cb[7 + r] = i_v(rod, i) + r; cpart[7 + r] = i_v(rod, i - 1) + r;
    cb[10 + r] = i_om(rod, i) + r; cpart[10 + r] = -1;
  }
  for (r = 0; r < 4; ++r) { cb[3 + r] = i_p(rod, i) + r; cpart[3 + r] = -1; }
  for (c = 0; c < 13; ++c) {
    const int c2 = cpart[c];
    for (r = 0; r < 6; ++r) {
      const double val = cy * Jk[r + 6 * c];
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
  if (!rod->nb) return 0;
  if (!need_any(B, i_qs(rod, i), 3 * rod->nb)) {
    relax_diagonal(rod, i_qs(rod, i), cy, cj, B);
    return 0;
  }
  double dV[3], dVx[21], G[18];
  W->arg[0] = y + i_phi(rod, i - 1); W->arg[1] = y + i_phi(rod, i);
  W->arg[2] = y + i_p(rod, i); W->arg[3] = segp(rod, i);
  W->res[0] = dV; W->res[1] = dVx; W->res[2] = G;
  if (rod_segment_branch(W->arg, W->res, W->iw, W->w, 0)) return -3;
  for (b = 0; b < rod->nb; ++b) {
    const double* C = segb(rod, i, b);
    const double rate = 1.0 / rod->theta[b];
    const int q0 = i_qs(rod, i) + 3 * b;
    for (k = 0; k < 3; ++k) {
      /* forces on the q columns: res -= Q, dQ/dq_bk = -C_bk G[:, k] */
      if (NEED_COL(B, q0 + k))
        for (r = 0; r < 6; ++r) {
          const double val = cy * C[k] * G[r + 6 * k];
          if (rb[r] >= 0) AB(rb[r], q0 + k) += val;
          if (r < 3 && ra[r] >= 0) AB(ra[r], q0 + k) -= val;
        }
      /* relaxation row: d/dq = rate, d/dq' = 1, d/d(phi_b, p) = -rate d dV/d(phi_b, p) */
      AB(q0 + k, q0 + k) += cy * rate + cj;
      if (NEED_ROW(B, q0 + k))
        for (c = 0; c < 7; ++c) {
          const double val = -cy * rate * dVx[k + 3 * c];
          AB(q0 + k, c < 3 ? i_phi(rod, i) + c : i_p(rod, i) + c - 3) += val;
          if (c < 3) AB(q0 + k, i_phi(rod, i - 1) + c) -= val;
        }
    }
  }
  return 0;
}

/* joint j's torque Jacobian Jk (6 rows: the omega rows of segments j, j+1; 14 columns:
   p_j, p_j+1, omega_j, omega_j+1; column-major) into the band, times -cy; a side the
   joint does not have (a clamp frame) is skipped (index -1 in jrows, jcols, which are
   returned for the relaxation terms). Diagonal and coupled joints alike. */
static void scatter_joint(const kvrod_rod* rod, int j, double cy, const band_t* B,
                          const double* Jk, int jrows[6], int jcols[14]) {
  const int has_a = j >= 1, has_b = j + 1 <= rod->N;
  int r, c;
  for (r = 0; r < 3; ++r) {
    jrows[r] = has_a ? i_om(rod, j) + r : -1;
    jrows[3 + r] = has_b ? i_om(rod, j + 1) + r : -1;
    jcols[8 + r] = has_a ? i_om(rod, j) + r : -1;
    jcols[11 + r] = has_b ? i_om(rod, j + 1) + r : -1;
  }
  for (r = 0; r < 4; ++r) {
    jcols[r] = has_a ? i_p(rod, j) + r : -1;
    jcols[4 + r] = has_b ? i_p(rod, j + 1) + r : -1;
  }
  for (c = 0; c < 14; ++c) {
    if (jcols[c] < 0) continue;
    for (r = 0; r < 6; ++r)
      if (jrows[r] >= 0) AB(jrows[r], jcols[c]) -= cy * Jk[r + 6 * c];
  }
}

/* joint j sits at node j: between segments j and j+1, or a clamp frame and a segment */
static int jac_joint(const kvrod_rod* rod, int j, const double* y, double cy, double cj,
                     const band_t* B, work_t* W, double* J, const double* Jx) {
  int jrows[6], jcols[14], r, c, b, k;
  double mq[3];
  if (!joint_args(rod, j, y, W)) {          /* absent clamp joint: its terms only decay */
    for (b = 0; b < rod->nb; ++b)
      for (k = 0; k < 3; ++k) {
        const int o = i_qj(rod, j) + 3 * b + k;
        AB(o, o) += cy / rod->theta[b] + cj;
      }
    return 0;
  }
  const double* Jk = Jx;         /* the kernel's result, if evaluated already (x4) */
  if (!Jk) {
    jnt_mq(rod, j, y, mq);
    W->arg[5] = mq;
    W->res[0] = J;
    if (rod_joint_torques_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    Jk = J;
  }
  scatter_joint(rod, j, cy, B, Jk, jrows, jcols);
  if (!rod->nb) return 0;
  if (!need_any(B, i_qj(rod, j), 3 * rod->nb)) {
    relax_diagonal(rod, i_qj(rod, j), cy, cj, B);
    return 0;
  }
  double dU[3], dUx[24], G[18];
  W->arg[2] = jntp(rod, j);                 /* (p_a, p_b) are still in arg[0], arg[1] */
  W->res[0] = dU; W->res[1] = dUx; W->res[2] = G;
  if (rod_joint_branch(W->arg, W->res, W->iw, W->w, 0)) return -3;
  for (b = 0; b < rod->nb; ++b) {
    const double* C = jntb(rod, j, b);
    const double rate = 1.0 / rod->theta[b];
    const int q0 = i_qj(rod, j) + 3 * b;
    for (k = 0; k < 3; ++k) {
      if (NEED_COL(B, q0 + k))
        for (r = 0; r < 6; ++r)
          if (jrows[r] >= 0) AB(jrows[r], q0 + k) += cy * C[k] * G[r + 6 * k];
      AB(q0 + k, q0 + k) += cy * rate + cj;
      if (NEED_ROW(B, q0 + k))
        for (c = 0; c < 8; ++c)
          if (jcols[c] >= 0) AB(q0 + k, jcols[c]) -= cy * rate * dUx[k + 3 * c];
    }
  }
  return 0;
}

/* coupled sections: segment i's inertia (13 x 13: rows and columns p, Omega, v_a, v_b;
 * the rows of held nodes are theirs) and the dead moment's dependence on p */
static int jac_cinertia(const kvrod_rod* rod, int i, const double* y, const double* yp,
                        double cy, double cj, const band_t* B, work_t* W, double* J) {
  const int N = rod->N;
  int idx[13], rows[13], r, c;
  double g[3];
  c_gravity(rod, g);
  cin_args(rod, i, y, yp, g, W->arg);
  W->arg[9] = &cy; W->arg[10] = &cj;
  W->res[0] = J;
  if (rod_coupled_inertia_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  for (r = 0; r < 7; ++r) idx[r] = rows[r] = i_p(rod, i) + r;
  for (r = 0; r < 3; ++r) {
    idx[7 + r] = i_v(rod, i - 1) + r;
    idx[10 + r] = i_v(rod, i) + r;
    rows[7 + r] = (i - 1 > 0 || !(node_held(rod, 0) > 0.5)) ? idx[7 + r] : -1;
    rows[10 + r] = (i < N || !(node_held(rod, N) > 0.5)) ? idx[10 + r] : -1;
  }
  for (c = 0; c < 13; ++c)
    for (r = 0; r < 13; ++r)
      if (rows[r] >= 0) AB(rows[r], idx[c]) += J[r + 13 * c];
  const double* sl = slp(rod, i);
  if (cy != 0.0 && has_follower(sl + SL_M_DEAD)) {
    const double s = cy * rod->par[PAR_LOAD_SCALE];
    const int o = i_p(rod, i);
    W->arg[0] = y + o; W->arg[1] = sl + SL_M_DEAD;
    W->res[0] = J;
    if (rod_rotate_transposed_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (c = 0; c < 4; ++c)
      for (r = 0; r < 3; ++r) AB(i_om(rod, i) + r, o + c) -= s * J[r + 3 * c];
  }
  return 0;
}

/* coupled sections: segment i's forces (15 rows: nodes i-1, i, segments i-1, i, i+1)
 * over 33 columns (phi_a, phi_b, p_a, p, p_b, v_a, v_b, Omega_a, Omega, Omega_b); the
 * neighbours' columns exist only where they are segments of the rod */
static int jac_cseg(const kvrod_rod* rod, int i, const double* y, double cy,
                    const band_t* B, work_t* W, double* J) {
  const int N = rod->N, has_a = i > 1, has_b = i < N;
  int rows[15], cols[33], r, c;
  double m6[6];
  cseg_args(rod, i, y, W->arg, m6);
  W->res[0] = J;
  if (rod_coupled_segment_forces_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  for (r = 0; r < 3; ++r) {
    rows[r] = (i - 1 > 0 || !(node_held(rod, 0) > 0.5)) ? i_v(rod, i - 1) + r : -1;
    rows[3 + r] = (i < N || !(node_held(rod, N) > 0.5)) ? i_v(rod, i) + r : -1;
    rows[6 + r] = has_a ? i_om(rod, i - 1) + r : -1;
    rows[9 + r] = i_om(rod, i) + r;
    rows[12 + r] = has_b ? i_om(rod, i + 1) + r : -1;
    cols[r] = i_phi(rod, i - 1) + r; cols[3 + r] = i_phi(rod, i) + r;
    cols[18 + r] = i_v(rod, i - 1) + r; cols[21 + r] = i_v(rod, i) + r;
    cols[24 + r] = has_a ? i_om(rod, i - 1) + r : -1;
    cols[27 + r] = i_om(rod, i) + r;
    cols[30 + r] = has_b ? i_om(rod, i + 1) + r : -1;
  }
  for (r = 0; r < 4; ++r) {
    cols[6 + r] = has_a ? i_p(rod, i - 1) + r : -1;
    cols[10 + r] = i_p(rod, i) + r;
    cols[14 + r] = has_b ? i_p(rod, i + 1) + r : -1;
  }
  for (c = 0; c < 33; ++c) {
    if (cols[c] < 0) continue;
    for (r = 0; r < 15; ++r)
      if (rows[r] >= 0) AB(rows[r], cols[c]) -= cy * J[r + 15 * c];
  }
  return 0;
}

/* coupled sections: joint j with its full C_MM, V_MM (as jac_joint, no relaxation) */
static int jac_cjoint(const kvrod_rod* rod, int j, const double* y, double cy,
                      const band_t* B, work_t* W, double* J) {
  int jrows[6], jcols[14];
  if (!joint_args(rod, j, y, W)) return 0;
  W->arg[5] = jntcp(rod, j);
  W->res[0] = J;
  if (rod_coupled_joint_torques_jac(W->arg, W->res, W->iw, W->w, 0)) return -3;
  scatter_joint(rod, j, cy, B, J, jrows, jcols);
  return 0;
}

static void zero_cell(const kvrod_rod* rod, int i, const band_t* B) {
  const int c0 = cs(rod, i), c1 = i == 0 ? c0size(rod) : c0 + csize(rod);
  int c;
  /* band rows kl .. 2kl+ku only; rows 0 .. kl-1 are dgbtrf workspace; of a column not
   * needed in full (relax_need) only the diagonal entry, the one formed */
  for (c = c0; c < c1; ++c) {
    if (!NEED_COL(B, c)) {
      AB(c, c) = 0.0;
      continue;
    }
    memset(B->ab + (size_t)(c - B->col0) * (size_t)B->ldab + rod->kl, 0,
           sizeof(double) * (rod->kl + rod->ku + 1));
  }
}

static int jacobian_cells_own(const kvrod_rod* rod, const double* y, const double* yp,
                             double cy, double cj, int ldab, double* ab, int col0, int i0,
                             int i1, const unsigned char* need) {
  const int N = rod->N;
  if (check_rod(rod)) return check_rod(rod);
  if (ldab < 2 * rod->kl + rod->ku + 1) return -2;
  if (i0 < 0 || i1 > N || col0 < 0 || col0 > cs(rod, i0 > 0 ? i0 - 1 : 0)) return -4;
  work_t W;
  double J[MAXJAC];
  const band_t band = {ab, ldab, col0, need}, *B = &band;
  int i, b, k, l, g0 = -1, gj = 0;
  /* the segment and joint kernels of elements g0..g0+3, four per call (x4, bit for bit
   * the scalar kernels); their terms are then added element by element as without */
  double JS[4][6 * 13], JJ[4][6 * 14], q4[4][3];
  const double* a4[4 * 8];
  double* r4[4];
  /* one sweep over the cells; the columns of cell i+1 are zeroed just before the
   * elements of cell i (which reach one cell ahead) are added: cache friendly */
  if (i0 == 0) zero_cell(rod, 0, B);
  if (rod->coupled) {      /* element i: node i, segment i (reaching cells i-1..i+1), joint i */
    for (i = i0; i <= i1; ++i) {
      if (i + 1 <= N) zero_cell(rod, i + 1, B);
      if (jac_node(rod, i, y, yp, cy, cj, B, &W, J)) return -3;
      if (i >= 1 && jac_cinertia(rod, i, y, yp, cy, cj, B, &W, J)) return -3;
      if (cy == 0.0) continue;
      if (i >= 1 && jac_cseg(rod, i, y, cy, B, &W, J)) return -3;
      if (jac_cjoint(rod, i, y, cy, B, &W, J)) return -3;
    }
    return 0;
  }
  for (i = i0; i <= i1; ++i) {
    if (cy != 0.0 && i >= 1 && i + 3 <= i1 && (g0 < 0 || i >= g0 + 4)) {
      g0 = i;
      for (l = 0; l < 4; ++l) {
        seg_args(rod, i + l, y, a4 + l, 4, q4[l]);
        r4[l] = JS[l];
      }
      if (rod_segment_forces_jac_x4(a4, r4)) return -3;
      gj = i + 3 <= N - 1;               /* joints i..i+3 all between two segments */
      if (gj) {
        for (l = 0; l < 4; ++l) {
          jnt_lane(rod, i + l, y, a4, l, q4[l]);
          r4[l] = JJ[l];
        }
        if (rod_joint_torques_jac_x4(a4, r4)) return -3;
      }
    }
    const int in_g = g0 >= 0 && i >= g0 && i < g0 + 4;
    if (i + 1 <= N) zero_cell(rod, i + 1, B);
    if (jac_node(rod, i, y, yp, cy, cj, B, &W, J)) return -3;
    if (i >= 1 && jac_segment_inertia(rod, i, y, yp, cy, cj, B, &W, J)) return -3;
    if (cy == 0.0) {            /* dF/dy' only: the relaxation rows' identity */
      for (b = 0; b < 3 * rod->nb; ++b) {
        if (i >= 1) { k = i_qs(rod, i) + b; AB(k, k) += cj; }
        k = i_qj(rod, i) + b; AB(k, k) += cj;
      }
      continue;
    }
    if (i >= 1 && jac_segment(rod, i, y, cy, cj, B, &W, J, in_g ? JS[i - g0] : 0)) return -3;
    if (jac_joint(rod, i, y, cy, cj, B, &W, J, in_g && gj ? JJ[i - g0] : 0)) return -3;
  }
  return 0;
}

/* the rod's own terms, then its contact with obstacles through the contact library
   (rod_contact.h; segment i is part of element i: it reaches the columns of cells i-1 and
   i, as the segment's internal forces do) */
static int has_contact(const kvrod_rod* rod) {
  return rod->contact && (rod->contact->nobs > 0 || rod->contact->self);
}

int kvrod_residual(const kvrod_rod* rod, double t, const double* y, const double* yp,
                   double* res) {
  (void) t;
  const int rc = residual_own(rod, y, yp, res);
  return rc || !has_contact(rod) ? rc : rod->contact->residual(rod, y, res);
}

int kvrod_jacobian_band_cells(const kvrod_rod* rod, double t, const double* y,
                              const double* yp, double cy, double cj, int ldab, double* ab,
                              int col0, int i0, int i1) {
  (void) t;
  const int rc = jacobian_cells_own(rod, y, yp, cy, cj, ldab, ab, col0, i0, i1, NULL);
  return rc || !has_contact(rod) ? rc
                                 : rod->contact->jacobian(rod, y, cy, ldab, ab, col0, i0, i1);
}

int kvrod_jacobian_band_relaxed(const kvrod_rod* rod, double t, const double* y,
                                const double* yp, double cy, double cj, int ldab, double* ab) {
  return kvrod_jacobian_band_cells_relaxed(rod, t, y, yp, cy, cj, ldab, ab, 0, 0, rod->N);
}

int kvrod_jacobian_band_cells_relaxed(const kvrod_rod* rod, double t, const double* y,
                                      const double* yp, double cy, double cj, int ldab,
                                      double* ab, int col0, int i0, int i1) {
  (void) t;
  const int rc = jacobian_cells_own(rod, y, yp, cy, cj, ldab, ab, col0, i0, i1,
                                    rod->relax_need);
  return rc || !has_contact(rod) ? rc
                                 : rod->contact->jacobian(rod, y, cy, ldab, ab, col0, i0, i1);
}

int kvrod_jacobian_band(const kvrod_rod* rod, double t, const double* y, const double* yp,
                        double cy, double cj, int ldab, double* ab) {
  return kvrod_jacobian_band_cells(rod, t, y, yp, cy, cj, ldab, ab, 0, 0, rod->N);
}

int kvrod_jacobian_system(const void* ctx, double t, const double* y, const double* yp,
                          double cj, void* blocks) {
  (void) blocks;
  const kvrod_rod* rod = (const kvrod_rod*) ctx;
  if (!rod->contact || !rod->contact->self || !rod->contact->couplings) return -4;
  const kvrod_self* S = rod->contact->self;
  const int n = kvrod_n_state(rod->N, rod->nb);
  memset(S->ab, 0, sizeof(double) * (size_t) S->ldab * (size_t) n);
  const int rc = kvrod_jacobian_band(rod, t, y, yp, 1.0, cj, S->ldab, S->ab);
  return rc ? rc : rod->contact->couplings(rod, y);
}

/* the stored energy and twice the dissipation rate of the relaxation terms of one
 * element beyond what its kernel reports (the kernel has W = l/2 dV^T C_F dV with the
 * instantaneous C_F = C_inf + sum C_b): l/2 C_b ((dV - q)^2 - dV^2) and l C_b/theta (dV - q)^2 */
static void relax_energy(const kvrod_rod* rod, const double* C0, size_t stride, double l,
                         const double* dV, const double* q, double* e) {
  /* the sums in locals, in the same order (e may alias the inputs as far as the compiler
   * knows: a store and a reload per term otherwise; the audit evaluates this per element
   * at every step) */
  double e1 = e[1], e2 = e[2];
  int b, k;
  for (b = 0; b < rod->nb; ++b) {
    const double* C = C0 + stride * (size_t)b;
    for (k = 0; k < 3; ++k) {
      const double x = dV[k] - q[3 * b + k];
      e1 += 0.5 * l * C[k] * (x * x - dV[k] * dV[k]);
      e2 += l * C[k] / rod->theta[b] * x * x;
    }
  }
  e[1] = e1;
  e[2] = e2;
}

/* energies and powers of one state; per-element strains and resultants if out_el != 0
 * (V (3N), F (3N), U (3(N+1)), M (3(N+1))); powers_only (a rod without coupled sections):
 * only what the energy audit integrates, 2D (e[2]) and the powers (e[3], e[4]), with the
 * same arithmetic (W comes with D; the kinetic energy and the supports' moments are not
 * evaluated: e[0] and the moments are left 0) */
static int energies_coupled(const kvrod_rod* rod, const double* y, const double* yp,
                            double* e, double* out_el, work_t* W);

static int energies_one(const kvrod_rod* rod, const double* y, const double* yp,
                        double* e, double* out_el, work_t* W, int powers_only) {
  if (rod->coupled) return energies_coupled(rod, y, yp, e, out_el, W);
  const int N = rod->N;
  double Tk, Q[9], T6[6], f[3], m, nq[3], dX[3];
  double Fint[2][3] = {{0, 0, 0}, {0, 0, 0}};
  double* oV = out_el;
  double* oF = out_el ? oV + 3 * N : 0;
  double* oU = out_el ? oF + 3 * N : 0;
  double* oM = out_el ? oU + 3 * (N + 1) : 0;
  int i, j, k;
  for (k = 0; k < NDIAG; ++k) e[k] = 0.0;
  for (i = 0; i <= N; ++i) {            /* kinetic energy and power of the nodes' loads */
    if (!powers_only) {
      m = node_mass(rod, i);
      W->arg[0] = y + i_v(rod, i); W->arg[1] = &m;
      W->res[0] = &Tk;
      if (rod_node_kinetic(W->arg, W->res, W->iw, W->w, 0)) return -3;
      e[0] += Tk;
    }
    if (node_force(rod, i, y, W, f)) return -3;
    for (k = 0; k < 3; ++k) e[3] += f[k] * y[i_v(rod, i) + k];
  }
  /* segments: four per diagnostics call where they come in fours
   * (rod_segment_diagnostics_x4: bit for bit the scalar kernel), then added segment by
   * segment in order, as the energy audit evaluates this three times a step */
  double W4[4], D4[4], S4[4][3], R4[4][3], nq4[4][3], T3[3];
  const double* a4[4 * 8];
  double* r4[4 * 4];
  int l, nl;
  for (i = 1; i <= N; i += nl) {
    nl = N - i + 1 >= 4 ? 4 : 1;
    if (nl == 4) {
      for (l = 0; l < 4; ++l) {
        seg_args(rod, i + l, y, a4 + l, 4, nq4[l]);
        r4[l] = W4 + l; r4[4 + l] = D4 + l; r4[8 + l] = S4[l]; r4[12 + l] = R4[l];
      }
      if (rod_segment_diagnostics_x4(a4, r4)) return -3;
    }
    for (l = 0; l < nl; ++l) {
      const int s = i + l;
      if (!powers_only) {
        W->arg[0] = y + i_om(rod, s); W->arg[1] = segp(rod, s);
        W->res[0] = &Tk;
        if (rod_segment_kinetic(W->arg, W->res, W->iw, W->w, 0)) return -3;
        e[0] += Tk;
      }
      if (segment_torque(rod, s, y, W, T3)) return -3;
      for (k = 0; k < 3; ++k) e[3] += T3[k] * y[i_om(rod, s) + k];
      const int ends = s == 1 || s == N;
      if (nl == 1 || ends) seg_args(rod, s, y, W->arg, 1, nq);
      if (nl == 1) {
        W->res[0] = W4; W->res[1] = D4; W->res[2] = S4[0]; W->res[3] = R4[0];
        if (rod_segment_diagnostics(W->arg, W->res, W->iw, W->w, 0)) return -3;
      }
      const double *S3 = S4[l], *R3 = R4[l];
      e[1] += W4[l]; e[2] += 2.0 * D4[l];
      if (rod->nb) {
        for (k = 0; k < 3; ++k) dX[k] = S3[k] - segp(rod, s)[SEG_V0 + k];
        relax_energy(rod, segb(rod, s, 0), 3, segp(rod, s)[SEG_H], dX, y + i_qs(rod, s), e);
      }
      if (out_el)
        for (k = 0; k < 3; ++k) { oV[3 * (s - 1) + k] = S3[k]; oF[3 * (s - 1) + k] = R3[k]; }
      if (ends) {                       /* internal forces on the end nodes (reactions) */
        W->res[0] = Q;
        if (rod_segment_forces(W->arg, W->res, W->iw, W->w, 0)) return -3;
        for (k = 0; k < 3; ++k) {
          if (s == 1) Fint[0][k] += Q[k];
          if (s == N) Fint[1][k] += Q[3 + k];
        }
      }
    }
  }
  /* joints: four interior joints per diagnostics call where they come in fours
   * (rod_joint_diagnostics_x4), then added joint by joint in order */
  for (j = 0; j <= N; j += nl) {
    nl = j >= 1 && j + 3 <= N - 1 ? 4 : 1;
    if (nl == 4) {
      for (l = 0; l < 4; ++l) {
        jnt_lane(rod, j + l, y, a4, l, nq4[l]);
        r4[l] = W4 + l; r4[4 + l] = D4 + l; r4[8 + l] = S4[l]; r4[12 + l] = R4[l];
      }
      if (rod_joint_diagnostics_x4(a4, r4)) return -3;
    } else {
      if (!joint_args(rod, j, y, W)) continue;
      jnt_mq(rod, j, y, nq);
      W->arg[5] = nq;
      W->res[0] = W4; W->res[1] = D4; W->res[2] = S4[0]; W->res[3] = R4[0];
      if (rod_joint_diagnostics(W->arg, W->res, W->iw, W->w, 0)) return -3;
    }
    for (l = 0; l < nl; ++l) {
      const int jj = j + l;
      const double *S3 = S4[l], *R3 = R4[l];
      e[1] += W4[l]; e[2] += 2.0 * D4[l];
      if (rod->nb) {
        for (k = 0; k < 3; ++k) dX[k] = S3[k] - jntp(rod, jj)[JNT_U0 + k];
        relax_energy(rod, jntb(rod, jj, 0), 3, jntp(rod, jj)[JNT_H], dX, y + i_qj(rod, jj), e);
      }
      if (out_el) for (k = 0; k < 3; ++k) { oU[3 * jj + k] = S3[k]; oM[3 * jj + k] = R3[k]; }
      if (jj == 0 || jj == N) {         /* the clamp's moment and its power (nl = 1) */
        W->res[0] = T6;
        if (rod_joint_torques(W->arg, W->res, W->iw, W->w, 0)) return -3;
        const double* om = rod->par + (jj == 0 ? PAR_OMEGA_START : PAR_OMEGA_END);
        const double* pc = rod->par + (jj == 0 ? PAR_P_START : PAR_P_END);
        double mTc[3];
        const double* Tc = jj == 0 ? T6 : T6 + 3;  /* the joint's torque on the clamp frame */
        for (k = 0; k < 3; ++k) { e[4] -= Tc[k] * om[k]; mTc[k] = -Tc[k]; }
        if (powers_only) continue;
        W->arg[0] = pc; W->arg[1] = mTc;    /* the support's moment, spatial */
        W->res[0] = e + NDIAG_E + (jj == 0 ? 3 : 9);
        if (rod_rotate(W->arg, W->res, W->iw, W->w, 0)) return -3;
      }
    }
  }
  for (j = 0; j < 2; ++j) {             /* the supports' forces and their power */
    i = j == 0 ? 0 : N;
    if (!(node_held(rod, i) > 0.5)) continue;
    m = node_mass(rod, i);
    if (node_force(rod, i, y, W, f)) return -3;
    double* R = e + NDIAG_E + 6 * j;
    const double* a = held_a(rod, i);
    for (k = 0; k < 3; ++k) {
      R[k] = m * a[k] - f[k] - Fint[j][k];
      e[4] += R[k] * y[i_v(rod, i) + k];
    }
  }
  return 0;
}

/* energies_one for a rod with coupled sections: the segments' kinetic energy with the
 * mass centre's coupling and the power of gravity at it, the couplings' energy and
 * dissipation, their shares of the joints' moments, and their torques on the clamp
 * frames (part of the clamps' moments and of the boundary power) */
static int energies_coupled(const kvrod_rod* rod, const double* y, const double* yp,
                            double* e, double* out_el, work_t* W) {
  const int N = rod->N;
  double Tk, Pg, Wel, Dd, S3[3], R3[3], Ma[3], Mb[3], Q[15], T6[6], f[3], m, g[3], r13[13];
  double m6[6], Pm;
  double Fint[2][3] = {{0, 0, 0}, {0, 0, 0}}, Tclamp[2][3] = {{0, 0, 0}, {0, 0, 0}};
  double Fin[2][3] = {{0, 0, 0}, {0, 0, 0}};
  double* oV = out_el;
  double* oF = out_el ? oV + 3 * N : 0;
  double* oU = out_el ? oF + 3 * N : 0;
  double* oM = out_el ? oU + 3 * (N + 1) : 0;
  int i, j, k;
  for (k = 0; k < NDIAG; ++k) e[k] = 0.0;
  c_gravity(rod, g);
  for (i = 0; i <= N; ++i) {
    m = node_mass(rod, i);
    W->arg[0] = y + i_v(rod, i); W->arg[1] = &m;
    W->res[0] = &Tk;
    if (rod_node_kinetic(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[0] += Tk;
    if (node_force(rod, i, y, W, f)) return -3;
    for (k = 0; k < 3; ++k) e[3] += f[k] * y[i_v(rod, i) + k];
  }
  if (out_el) memset(oM, 0, sizeof(double) * 3 * (size_t)(N + 1));
  for (i = 1; i <= N; ++i) {
    W->arg[0] = y + i_v(rod, i - 1); W->arg[1] = y + i_v(rod, i);
    W->arg[2] = y + i_p(rod, i); W->arg[3] = y + i_om(rod, i);
    W->arg[4] = segp(rod, i); W->arg[5] = segcp(rod, i); W->arg[6] = g;
    W->res[0] = &Tk; W->res[1] = &Pg;
    if (rod_coupled_kinetic(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[0] += Tk; e[3] += Pg;
    if (segment_torque(rod, i, y, W, S3)) return -3;
    for (k = 0; k < 3; ++k) e[3] += S3[k] * y[i_om(rod, i) + k];
    cseg_args(rod, i, y, W->arg, m6);
    W->res[0] = &Wel; W->res[1] = &Dd; W->res[2] = S3; W->res[3] = R3;
    W->res[4] = Ma; W->res[5] = Mb; W->res[6] = &Pm;
    if (rod_coupled_segment_diagnostics(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[1] += Wel; e[2] += 2.0 * Dd; e[3] += Pm;
    if (out_el)
      for (k = 0; k < 3; ++k) {
        oV[3 * (i - 1) + k] = S3[k]; oF[3 * (i - 1) + k] = R3[k];
        oM[3 * (i - 1) + k] += Ma[k]; oM[3 * i + k] += Mb[k];
      }
    if (i == 1 || i == N) {   /* forces on the end nodes, torques on the clamp frames */
      W->res[0] = Q;
      if (rod_coupled_segment_forces(W->arg, W->res, W->iw, W->w, 0)) return -3;
      for (k = 0; k < 3; ++k) {
        if (i == 1) { Fint[0][k] += Q[k]; Tclamp[0][k] += Q[6 + k]; }
        if (i == N) { Fint[1][k] += Q[3 + k]; Tclamp[1][k] += Q[12 + k]; }
      }
      cin_args(rod, i, y, yp, g, W->arg);   /* the mass centre's inertia on the end nodes */
      W->res[0] = r13;
      if (rod_coupled_inertia(W->arg, W->res, W->iw, W->w, 0)) return -3;
      for (k = 0; k < 3; ++k) {
        if (i == 1) Fin[0][k] += r13[7 + k];
        if (i == N) Fin[1][k] += r13[10 + k];
      }
    }
  }
  for (j = 0; j <= N; ++j) {
    if (!joint_args(rod, j, y, W)) continue;
    W->arg[5] = jntcp(rod, j);
    W->res[0] = &Wel; W->res[1] = &Dd; W->res[2] = S3; W->res[3] = R3;
    if (rod_coupled_joint_diagnostics(W->arg, W->res, W->iw, W->w, 0)) return -3;
    e[1] += Wel; e[2] += 2.0 * Dd;
    if (out_el) for (k = 0; k < 3; ++k) { oU[3 * j + k] = S3[k]; oM[3 * j + k] += R3[k]; }
    if (j == 0 || j == N) {             /* the clamp's moment and its power */
      W->res[0] = T6;
      if (rod_coupled_joint_torques(W->arg, W->res, W->iw, W->w, 0)) return -3;
      const double* om = rod->par + (j == 0 ? PAR_OMEGA_START : PAR_OMEGA_END);
      const double* pc = rod->par + (j == 0 ? PAR_P_START : PAR_P_END);
      double mTc[3];
      const double* Tc = j == 0 ? T6 : T6 + 3;
      const double* Ts = Tclamp[j == 0 ? 0 : 1];
      for (k = 0; k < 3; ++k) {
        e[4] -= (Tc[k] + Ts[k]) * om[k];
        mTc[k] = -(Tc[k] + Ts[k]);
      }
      W->arg[0] = pc; W->arg[1] = mTc;
      W->res[0] = e + NDIAG_E + (j == 0 ? 3 : 9);
      if (rod_rotate(W->arg, W->res, W->iw, W->w, 0)) return -3;
    }
  }
  for (j = 0; j < 2; ++j) {
    i = j == 0 ? 0 : N;
    if (!(node_held(rod, i) > 0.5)) continue;
    m = node_mass(rod, i);
    if (node_force(rod, i, y, W, f)) return -3;
    double* R = e + NDIAG_E + 6 * j;
    const double* a = held_a(rod, i);
    for (k = 0; k < 3; ++k) {
      R[k] = m * a[k] + Fin[j][k] - f[k] - Fint[j][k];
      e[4] += R[k] * y[i_v(rod, i) + k];
    }
  }
  return 0;
}

int kvrod_diagnostics(const kvrod_rod* rod, double t, const double* y, const double* yp,
                      double* out) {
  (void) t;
  const int N = rod->N;
  if (check_rod(rod)) return check_rod(rod);
  work_t W;
  memset(out, 0, sizeof(double) * (size_t)(NDIAG + 6 * N + 6 * (N + 1)));
  const int rc = energies_one(rod, y, yp, out, out + NDIAG, &W, 0);
  return rc || !has_contact(rod) ? rc : rod->contact->energies(rod, y, out);
}

int kvrod_energies(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                   const double* yps, double* out) {
  (void) ts;
  if (check_rod(rod)) return check_rod(rod);
  const size_t n = (size_t) kvrod_n_state(rod->N, rod->nb);
  work_t W;
  int k;
  for (k = 0; k < m; ++k) {
    if (energies_one(rod, ys + k * n, yps + k * n, out + (size_t)k * NDIAG, 0, &W, 0))
      return -3;
    if (has_contact(rod) && rod->contact->energies(rod, ys + k * n, out + (size_t)k * NDIAG))
      return -3;
  }
  return 0;
}

int kvrod_audit_powers(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                       const double* yps, double* out) {
  if (check_rod(rod)) return check_rod(rod);
  if (has_contact(rod) && rod->contact->self)   /* the pairs' values kept: the full ones */
    return kvrod_energies_contact(rod, m, ts, ys, yps, out);
  const size_t n = (size_t) kvrod_n_state(rod->N, rod->nb);
  const int nobs = has_contact(rod) ? rod->contact->nobs : 0;
  const size_t stride = (size_t)NDIAG + (size_t)NCV * (size_t)nobs;
  work_t W;
  for (int k = 0; k < m; ++k) {
    double* o = out + (size_t)k * stride;
    const double* y = ys + (size_t)k * n;
    if (energies_one(rod, y, yps + (size_t)k * n, o, 0, &W, 1)) return -3;
    /* the obstacles' E, P_diss, P_obs and the supports' share of the contact forces, as
       kvrod_energies_contact adds them (the same sums in the same order) without the
       obstacles' values (the exact smallest gap's second pass) */
    if (has_contact(rod) && rod->contact->energies(rod, y, o)) return -3;
  }
  return 0;
}

int kvrod_energies_contact(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                           const double* yps, double* out) {
  if (check_rod(rod)) return check_rod(rod);
  const size_t n = (size_t) kvrod_n_state(rod->N, rod->nb);
  const int nobs = has_contact(rod) ? rod->contact->nobs : 0;
  const kvrod_self* S = has_contact(rod) ? rod->contact->self : NULL;
  if (S && !S->last) return -4;
  const size_t stride = (size_t)NDIAG + (size_t)NCV * (size_t)nobs + (S ? NSV : 0);
  work_t W;
  for (int k = 0; k < m; ++k) {
    double* o = out + (size_t)k * stride;
    const double* y = ys + (size_t)k * n;
    if (!nobs) {
      const int rc = kvrod_energies(rod, 1, ts + k, y, yps + (size_t)k * n, o);
      if (rc) return rc;
    } else {
      /* kvrod_energies' sums with the obstacles' values from the same pass */
      if (energies_one(rod, y, yps + (size_t)k * n, o, 0, &W, 0)) return -3;
      if (rod->contact->energies_values(rod, y, o, o + NDIAG)) return -3;
    }
    /* the pairs' values the energies just computed (kvrod_contact_energies keeps them) */
    if (S) memcpy(o + NDIAG + (size_t)NCV * (size_t)nobs, S->last, sizeof(double) * NSV);
  }
  return 0;
}
