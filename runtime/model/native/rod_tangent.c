/*
 * The tangent of the rod's residual (issue 34): for a state direction (dy, dy') and a
 * direction of the rod's numbers (drod: the derivatives of par, seg, jnt, nload, sload,
 * theta, segb, jntb, segc, jntc with respect to one problem parameter, in the layout of
 * kvrod_rod), the directional derivative
 *
 *     dF = F_y dy + F_y' dy' + F_p dp
 *
 * of kvrod_residual (rod_assembly.c) in one sweep over the elements: the generated
 * tangent kernels (generated/rod_tangent_kernels.c, derive/tangents.py: forward AD of
 * the residual's kernels on their SX graphs) for every kernel, and the derivative of
 * the assembly's own arithmetic (lumped masses, load sums, load factor, relaxation
 * rows, the relaxation resultants) written out here, term by term as rod_assembly.c
 * forms it. Every path of the residual is covered: Kelvin-Voigt and generalized
 * Maxwell rods (relaxation rows q' - (strain - q)/theta), coupled sections, clamped,
 * pinned and free ends (a held node's rows phi - r(t), v - v(t) with the derivatives of
 * r and v), dead and follower loads.
 *
 * Exact to rounding (no differences); tested against central differences of
 * kvrod_residual in state and parameter directions and against the CasADi oracle's
 * forward derivative (tests/runtime/test_residual_tangent.py).
 */
#include <string.h>
#include "rod_kernels.h"
#include "rod_tangent_kernels.h"
#include "rod_layout.h"
#include "rod_assembly.h"
#include "rod_access.h"
#include "rod_tangent.h"

#define TMAX(a, b) ((a) > (b) ? (a) : (b))

/* work memory for the nominal and the tangent kernels */
typedef struct {
  const double* arg[TMAX(MAXARG, ROD_TAN_MAXARG)];
  double* res[TMAX(MAXRES, ROD_TAN_MAXRES)];
  long long int iw[TMAX(MAXIW, ROD_TAN_MAXIW)];
  double w[TMAX(MAXW, ROD_TAN_MAXW)];
} twork_t;

/* zero seeds: an element's row of any table (or of par) when no parameter direction */
static const double kZ[512] = {0.0};
static const double kZero3t[3] = {0.0, 0.0, 0.0};

/* the parameter direction's rows, or zeros without one */
static inline const double* d_par(const kvrod_rod* d) { return d ? d->par : kZ; }
static inline const double* d_seg(const kvrod_rod* d, int i) { return d ? segp(d, i) : kZ; }
static inline const double* d_jnt(const kvrod_rod* d, int j) { return d ? jntp(d, j) : kZ; }
static inline const double* d_nl(const kvrod_rod* d, int i) { return d ? nlp(d, i) : kZ; }
static inline const double* d_sl(const kvrod_rod* d, int i) { return d ? slp(d, i) : kZ; }
static inline const double* d_segc(const kvrod_rod* d, int i) { return d ? segcp(d, i) : kZ; }
static inline const double* d_jntc(const kvrod_rod* d, int j) { return d ? jntcp(d, j) : kZ; }

/* d of the lumped node mass and length (node_mass, node_length of rod_access.h) */
static double dnode_mass(const kvrod_rod* r, const kvrod_rod* d, int i) {
  double m = 0.0;
  const double *s, *ds;
  if (!d) return 0.0;
  if (i >= 1) {
    s = segp(r, i); ds = segp(d, i);
    m += 0.5 * (ds[SEG_RHOA] * s[SEG_H] + s[SEG_RHOA] * ds[SEG_H]);
  }
  if (i < r->N) {
    s = segp(r, i + 1); ds = segp(d, i + 1);
    m += 0.5 * (ds[SEG_RHOA] * s[SEG_H] + s[SEG_RHOA] * ds[SEG_H]);
  }
  return m;
}

static double dnode_length(const kvrod_rod* r, const kvrod_rod* d, int i) {
  double l = 0.0;
  if (!d) return 0.0;
  if (i >= 1) l += 0.5 * segp(d, i)[SEG_H];
  if (i < r->N) l += 0.5 * segp(d, i + 1)[SEG_H];
  return l;
}

/* R(p) x (kind 0) or R(p)^T x (kind 1) and its tangent along (dp, dx) */
static int rotate_t(int kind, const double* p, const double* x, const double* dp,
                    const double* dx, twork_t* W, double* out, double* dout) {
  W->arg[0] = p; W->arg[1] = x;
  W->res[0] = out;
  if ((kind ? rod_rotate_transposed : rod_rotate)(W->arg, W->res, W->iw, W->w, 0)) return -3;
  W->arg[0] = p; W->arg[1] = x; W->arg[2] = dp; W->arg[3] = dx;
  W->res[0] = dout;
  if ((kind ? rod_rotate_transposed_tan : rod_rotate_tan)(W->arg, W->res, W->iw, W->w, 0))
    return -3;
  return 0;
}

/* the total external force on node i (node_force of rod_assembly.c) and its tangent */
static int tnode_force(const kvrod_rod* r, const kvrod_rod* d, int i, const double* y,
                       const double* dy, twork_t* W, double* f, double* df) {
  const double* par = r->par;
  const double* dpar = d_par(d);
  const double ls = par[PAR_LOAD_SCALE], dls = dpar[PAR_LOAD_SCALE];
  const double m = node_mass(r, i), l = node_length(r, i);
  const double dm = dnode_mass(r, d, i), dl = dnode_length(r, d, i);
  const double* nl = nlp(r, i);
  const double* dnl = d_nl(d, i);
  int k;
  for (k = 0; k < 3; ++k) {
    const double base = m * par[PAR_GRAVITY + k] + l * par[PAR_F_DIST + k] + nl[NL_F_DEAD + k];
    const double dbase = dm * par[PAR_GRAVITY + k] + m * dpar[PAR_GRAVITY + k]
                         + dl * par[PAR_F_DIST + k] + l * dpar[PAR_F_DIST + k]
                         + dnl[NL_F_DEAD + k];
    f[k] = ls * base;
    df[k] = dls * base + ls * dbase;
  }
  if (has_follower(nl + NL_F_FOLLOWER) || has_follower(dnl + NL_F_FOLLOWER)) {
    double Rf[3], dRf[3];
    const int op = i_p(r, host(i));
    if (rotate_t(0, y + op, nl + NL_F_FOLLOWER, dy + op, dnl + NL_F_FOLLOWER, W, Rf, dRf))
      return -3;
    for (k = 0; k < 3; ++k) {
      f[k] += ls * Rf[k];
      df[k] += dls * Rf[k] + ls * dRf[k];
    }
  }
  return 0;
}

/* the external torque on segment i (material; segment_torque of rod_assembly.c): its
 * tangent only */
static int tsegment_torque(const kvrod_rod* r, const kvrod_rod* d, int i, const double* y,
                           const double* dy, twork_t* W, double* dT) {
  const double ls = r->par[PAR_LOAD_SCALE], dls = d_par(d)[PAR_LOAD_SCALE];
  const double* sl = slp(r, i);
  const double* dsl = d_sl(d, i);
  int k;
  for (k = 0; k < 3; ++k) dT[k] = dls * sl[SL_M_FOLLOWER + k] + ls * dsl[SL_M_FOLLOWER + k];
  if (has_follower(sl + SL_M_DEAD) || has_follower(dsl + SL_M_DEAD)) {
    double RtM[3], dRtM[3];
    const int op = i_p(r, i);
    if (rotate_t(1, y + op, sl + SL_M_DEAD, dy + op, dsl + SL_M_DEAD, W, RtM, dRtM))
      return -3;
    for (k = 0; k < 3; ++k) dT[k] += dls * RtM[k] + ls * dRtM[k];
  }
  return 0;
}

/* the relaxation resultant -sum_b C_b q_b of segment i (joint j) and its tangent */
static void tseg_nq(const kvrod_rod* r, const kvrod_rod* d, int i, const double* y,
                    const double* dy, double* nq, double* dnq) {
  int b, k;
  for (k = 0; k < 3; ++k) nq[k] = dnq[k] = 0.0;
  for (b = 0; b < r->nb; ++b) {
    const double* C = segb(r, i, b);
    const double* dC = d ? segb(d, i, b) : kZ;
    const int o = i_qs(r, i) + 3 * b;
    for (k = 0; k < 3; ++k) {
      nq[k] -= C[k] * y[o + k];
      dnq[k] -= dC[k] * y[o + k] + C[k] * dy[o + k];
    }
  }
}

static void tjnt_mq(const kvrod_rod* r, const kvrod_rod* d, int j, const double* y,
                    const double* dy, double* mq, double* dmq) {
  int b, k;
  for (k = 0; k < 3; ++k) mq[k] = dmq[k] = 0.0;
  for (b = 0; b < r->nb; ++b) {
    const double* C = jntb(r, j, b);
    const double* dC = d ? jntb(d, j, b) : kZ;
    const int o = i_qj(r, j) + 3 * b;
    for (k = 0; k < 3; ++k) {
      mq[k] -= C[k] * y[o + k];
      dmq[k] -= dC[k] * y[o + k] + C[k] * dy[o + k];
    }
  }
}

/* the tangent of the relaxation rows q' - (strain - q)/theta of one element (strain 0
 * for an absent clamp joint) */
static void trelax_rows(const kvrod_rod* r, const kvrod_rod* d, int q0, const double* strain,
                        const double* dstrain, const double* y, const double* dy,
                        const double* dyp, double* dres) {
  int b, k;
  for (b = 0; b < r->nb; ++b) {
    const double th = r->theta[b], dth = d ? d->theta[b] : 0.0;
    const double rate = 1.0 / th, drate = -dth / (th * th);
    for (k = 0; k < 3; ++k) {
      const int o = q0 + 3 * b + k;
      const double e = (strain ? strain[k] : 0.0) - y[o];
      const double de = (dstrain ? dstrain[k] : 0.0) - dy[o];
      dres[o] += dyp[o] - drate * e - rate * de;
    }
  }
}

/* the joint at node j: (p_a, p_b, Omega_a, Omega_b, jnt) and their seeds into a[0..4],
 * a[6..10] (a[5], a[11]: the caller's); 0 where the joint is absent */
static int tjoint_args(const kvrod_rod* r, const kvrod_rod* d, int j, const double* y,
                       const double* dy, const double** a) {
  const int N = r->N, has_a = j >= 1, has_b = j + 1 <= N;
  const double* dpar = d_par(d);
  if (j == 0 && !(r->par[PAR_CLAMP_START] > 0.5)) return 0;
  if (j == N && !(r->par[PAR_CLAMP_END] > 0.5)) return 0;
  a[0] = has_a ? y + i_p(r, j) : r->par + PAR_P_START;
  a[1] = has_b ? y + i_p(r, j + 1) : r->par + PAR_P_END;
  a[2] = has_a ? y + i_om(r, j) : r->par + PAR_OMEGA_START;
  a[3] = has_b ? y + i_om(r, j + 1) : r->par + PAR_OMEGA_END;
  a[4] = jntp(r, j);
  a[6] = has_a ? dy + i_p(r, j) : dpar + PAR_P_START;
  a[7] = has_b ? dy + i_p(r, j + 1) : dpar + PAR_P_END;
  a[8] = has_a ? dy + i_om(r, j) : dpar + PAR_OMEGA_START;
  a[9] = has_b ? dy + i_om(r, j + 1) : dpar + PAR_OMEGA_END;
  a[10] = d_jnt(d, j);
  return 1;
}

/* ---- coupled sections (rod_assembly.c: c_side, c_end_moment, cseg_args) ---- */

static const double kNoJointT[NJNT] = {1.0};

static void tc_side(const kvrod_rod* r, const kvrod_rod* d, int i, int k, const double* y,
                    const double* dy, const double** a, int ip, int iom, int ij, int off) {
  const int N = r->N, j = k < i ? i - 1 : i;
  const double* dpar = d_par(d);
  if (k >= 1 && k <= N) {
    a[ip] = y + i_p(r, k); a[iom] = y + i_om(r, k); a[ij] = jntp(r, j);
    a[ip + off] = dy + i_p(r, k); a[iom + off] = dy + i_om(r, k); a[ij + off] = d_jnt(d, j);
  } else if (k == 0 && r->par[PAR_CLAMP_START] > 0.5) {
    a[ip] = r->par + PAR_P_START; a[iom] = r->par + PAR_OMEGA_START; a[ij] = jntp(r, 0);
    a[ip + off] = dpar + PAR_P_START; a[iom + off] = dpar + PAR_OMEGA_START;
    a[ij + off] = d_jnt(d, 0);
  } else if (k == N + 1 && r->par[PAR_CLAMP_END] > 0.5) {
    a[ip] = r->par + PAR_P_END; a[iom] = r->par + PAR_OMEGA_END; a[ij] = jntp(r, N);
    a[ip + off] = dpar + PAR_P_END; a[iom + off] = dpar + PAR_OMEGA_END;
    a[ij + off] = d_jnt(d, N);
  } else {
    a[ip] = y + i_p(r, i); a[iom] = y + i_om(r, i); a[ij] = kNoJointT;
    a[ip + off] = dy + i_p(r, i); a[iom + off] = dy + i_om(r, i); a[ij + off] = kZ;
  }
}

/* the free ends' moments of segment i (c_end_moment) and their tangent */
static void tc_end_moment(const kvrod_rod* r, const kvrod_rod* d, int i, double* m6,
                          double* dm6) {
  const double* par = r->par;
  const double* dpar = d_par(d);
  const double ls = par[PAR_LOAD_SCALE], dls = dpar[PAR_LOAD_SCALE];
  int k;
  for (k = 0; k < 6; ++k) m6[k] = dm6[k] = 0.0;
  if (i == r->N && !(par[PAR_CLAMP_END] > 0.5))
    for (k = 0; k < 3; ++k) {
      m6[k] += ls * par[PAR_M_DEAD_END + k];
      m6[3 + k] += ls * par[PAR_M_FOLLOWER_END + k];
      dm6[k] += dls * par[PAR_M_DEAD_END + k] + ls * dpar[PAR_M_DEAD_END + k];
      dm6[3 + k] += dls * par[PAR_M_FOLLOWER_END + k] + ls * dpar[PAR_M_FOLLOWER_END + k];
    }
  if (i == 1 && !(par[PAR_CLAMP_START] > 0.5))
    for (k = 0; k < 3; ++k) {
      m6[k] -= ls * par[PAR_M_DEAD_START + k];
      m6[3 + k] -= ls * par[PAR_M_FOLLOWER_START + k];
      dm6[k] -= dls * par[PAR_M_DEAD_START + k] + ls * dpar[PAR_M_DEAD_START + k];
      dm6[3 + k] -= dls * par[PAR_M_FOLLOWER_START + k]
                    + ls * dpar[PAR_M_FOLLOWER_START + k];
    }
}

static int tangent_coupled(const kvrod_rod* r, const kvrod_rod* d, const double* y,
                           const double* yp, const double* dy, const double* dyp,
                           double* dres, twork_t* W) {
  const int N = r->N;
  const int free0 = !(node_held(r, 0) > 0.5), freeN = !(node_held(r, N) > 0.5);
  const double* par = r->par;
  const double* dpar = d_par(d);
  double dr13[13], dT[6], dQ[15], g[3], dg[3], m6[6], dm6[6];
  int i, j, k;
  for (k = 0; k < 3; ++k) {
    g[k] = par[PAR_LOAD_SCALE] * par[PAR_GRAVITY + k];
    dg[k] = dpar[PAR_LOAD_SCALE] * par[PAR_GRAVITY + k]
            + par[PAR_LOAD_SCALE] * dpar[PAR_GRAVITY + k];
  }
  for (i = 1; i <= N; ++i) {
    const double** a = W->arg;
    a[0] = y + i_p(r, i); a[1] = y + i_om(r, i);
    a[2] = yp + i_p(r, i); a[3] = yp + i_om(r, i);
    a[4] = yp + i_v(r, i - 1); a[5] = yp + i_v(r, i);
    a[6] = segp(r, i); a[7] = segcp(r, i); a[8] = g;
    a[9] = dy + i_p(r, i); a[10] = dy + i_om(r, i);
    a[11] = dyp + i_p(r, i); a[12] = dyp + i_om(r, i);
    a[13] = dyp + i_v(r, i - 1); a[14] = dyp + i_v(r, i);
    a[15] = d_seg(d, i); a[16] = d_segc(d, i); a[17] = dg;
    W->res[0] = dr13;
    if (rod_coupled_inertia_tan(W->arg, W->res, W->iw, W->w, 0)) return -3;
    for (k = 0; k < 7; ++k) dres[i_p(r, i) + k] += dr13[k];
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) dres[i_v(r, i - 1) + k] += dr13[7 + k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) dres[i_v(r, i) + k] += dr13[10 + k];
    if (tsegment_torque(r, d, i, y, dy, W, dT)) return -3;
    for (k = 0; k < 3; ++k) dres[i_om(r, i) + k] -= dT[k];
  }
  for (i = 1; i <= N; ++i) {
    const double** a = W->arg;
    a[0] = y + i_phi(r, i - 1); a[1] = y + i_phi(r, i);
    a[15] = dy + i_phi(r, i - 1); a[16] = dy + i_phi(r, i);
    tc_side(r, d, i, i - 1, y, dy, a, 2, 7, 12, 15);
    a[3] = y + i_p(r, i); a[18] = dy + i_p(r, i);
    tc_side(r, d, i, i + 1, y, dy, a, 4, 9, 13, 15);
    a[5] = y + i_v(r, i - 1); a[6] = y + i_v(r, i);
    a[20] = dy + i_v(r, i - 1); a[21] = dy + i_v(r, i);
    a[8] = y + i_om(r, i); a[23] = dy + i_om(r, i);
    a[10] = segp(r, i); a[11] = segcp(r, i);
    a[25] = d_seg(d, i); a[26] = d_segc(d, i);
    tc_end_moment(r, d, i, m6, dm6);
    a[14] = m6; a[29] = dm6;
    W->res[0] = dQ;
    if (rod_coupled_segment_forces_tan(W->arg, W->res, W->iw, W->w, 0)) return -3;
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) dres[i_v(r, i - 1) + k] -= dQ[k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) dres[i_v(r, i) + k] -= dQ[3 + k];
    if (i > 1) for (k = 0; k < 3; ++k) dres[i_om(r, i - 1) + k] -= dQ[6 + k];
    for (k = 0; k < 3; ++k) dres[i_om(r, i) + k] -= dQ[9 + k];
    if (i < N) for (k = 0; k < 3; ++k) dres[i_om(r, i + 1) + k] -= dQ[12 + k];
  }
  for (j = 0; j <= N; ++j) {
    const double** a = W->arg;
    if (!tjoint_args(r, d, j, y, dy, a)) continue;
    a[5] = jntcp(r, j); a[11] = d_jntc(d, j);
    W->res[0] = dT;
    if (rod_coupled_joint_torques_tan(W->arg, W->res, W->iw, W->w, 0)) return -3;
    if (j >= 1) for (k = 0; k < 3; ++k) dres[i_om(r, j) + k] -= dT[k];
    if (j + 1 <= N) for (k = 0; k < 3; ++k) dres[i_om(r, j + 1) + k] -= dT[3 + k];
  }
  return 0;
}

int kvrod_residual_tangent(const kvrod_rod* rod, const kvrod_rod* drod, double t,
                           const double* y, const double* yp, const double* dy,
                           const double* dyp, double* dres) {
  (void) t;
  const int N = rod->N;
  const kvrod_rod* d = drod;
  if (rod->N < 1 || rod->nb < 0 || rod->nb > MAX_NB || (rod->coupled && rod->nb)) return -1;
  if (d && (d->N != rod->N || d->nb != rod->nb || d->coupled != rod->coupled)) return -1;
  if (NSEG > 512 || NJNT > 512 || NPAR > 512 || NNL > 512 || NSL > 512) return -1;
  if (rod->coupled && (NSEGC > 512 || NJNTC > 512)) return -1;
  twork_t W;
  const double* dpar = d_par(d);
  double f[3], df[3], m, dm, held, dr6[6], dr7[7], dT[6], dQ[9], nq[3], dnq[3];
  double sv[3], dsv[3], svx[24], G[18];
  int i, j, k;
  memset(dres, 0, sizeof(double) * (size_t)kvrod_n_state(N, rod->nb));
  /* nodes: kinematics and momentum, or the prescribed position and velocity */
  for (i = 0; i <= N; ++i) {
    const double** a = W.arg;
    const int end = i == 0 || i == N;
    m = node_mass(rod, i); dm = dnode_mass(rod, d, i); held = node_held(rod, i);
    if (tnode_force(rod, d, i, y, dy, &W, f, df)) return -3;
    a[0] = y + i_phi(rod, i); a[1] = y + i_v(rod, i);
    a[2] = yp + i_phi(rod, i); a[3] = yp + i_v(rod, i);
    a[4] = &m; a[5] = f; a[6] = &held;
    a[7] = end ? held_r(rod, i) : kZero3t;
    a[8] = end ? held_v(rod, i) : kZero3t;
    a[9] = dy + i_phi(rod, i); a[10] = dy + i_v(rod, i);
    a[11] = dyp + i_phi(rod, i); a[12] = dyp + i_v(rod, i);
    a[13] = &dm; a[14] = df; a[15] = kZ;
    a[16] = end ? dpar + (i == 0 ? PAR_R_START : PAR_R_END) : kZ;
    a[17] = end ? dpar + (i == 0 ? PAR_V_START : PAR_V_END) : kZ;
    W.res[0] = dr6;
    if (rod_node_inertia_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
    for (k = 0; k < 3; ++k) {
      dres[i_phi(rod, i) + k] += dr6[k];
      dres[i_v(rod, i) + k] += dr6[3 + k];
    }
  }
  if (rod->coupled) return tangent_coupled(rod, d, y, yp, dy, dyp, dres, &W);
  /* segments: kinematics, angular momentum, external torques */
  for (i = 1; i <= N; ++i) {
    const double** a = W.arg;
    a[0] = y + i_p(rod, i); a[1] = y + i_om(rod, i);
    a[2] = yp + i_p(rod, i); a[3] = yp + i_om(rod, i);
    a[4] = segp(rod, i);
    a[5] = dy + i_p(rod, i); a[6] = dy + i_om(rod, i);
    a[7] = dyp + i_p(rod, i); a[8] = dyp + i_om(rod, i);
    a[9] = d_seg(d, i);
    W.res[0] = dr7;
    if (rod_segment_inertia_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
    for (k = 0; k < 7; ++k) dres[i_p(rod, i) + k] += dr7[k];
    if (tsegment_torque(rod, d, i, y, dy, &W, dT)) return -3;
    for (k = 0; k < 3; ++k) dres[i_om(rod, i) + k] -= dT[k];
  }
  /* internal forces of the segments (none on a held node's rows), relaxation rows */
  const int free0 = !(node_held(rod, 0) > 0.5), freeN = !(node_held(rod, N) > 0.5);
  for (i = 1; i <= N; ++i) {
    const double** a = W.arg;
    tseg_nq(rod, d, i, y, dy, nq, dnq);
    a[0] = y + i_phi(rod, i - 1); a[1] = y + i_phi(rod, i); a[2] = y + i_p(rod, i);
    a[3] = y + i_v(rod, i - 1); a[4] = y + i_v(rod, i); a[5] = y + i_om(rod, i);
    a[6] = segp(rod, i); a[7] = nq;
    a[8] = dy + i_phi(rod, i - 1); a[9] = dy + i_phi(rod, i); a[10] = dy + i_p(rod, i);
    a[11] = dy + i_v(rod, i - 1); a[12] = dy + i_v(rod, i); a[13] = dy + i_om(rod, i);
    a[14] = d_seg(d, i); a[15] = dnq;
    W.res[0] = dQ;
    if (rod_segment_forces_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
    if (i - 1 > 0 || free0) for (k = 0; k < 3; ++k) dres[i_v(rod, i - 1) + k] -= dQ[k];
    if (i < N || freeN) for (k = 0; k < 3; ++k) dres[i_v(rod, i) + k] -= dQ[3 + k];
    for (k = 0; k < 3; ++k) dres[i_om(rod, i) + k] -= dQ[6 + k];
    if (rod->nb) {
      a[0] = y + i_phi(rod, i - 1); a[1] = y + i_phi(rod, i);
      a[2] = y + i_p(rod, i); a[3] = segp(rod, i);
      W.res[0] = sv; W.res[1] = svx; W.res[2] = G;
      if (rod_segment_branch(W.arg, W.res, W.iw, W.w, 0)) return -3;
      a[0] = y + i_phi(rod, i - 1); a[1] = y + i_phi(rod, i);
      a[2] = y + i_p(rod, i); a[3] = segp(rod, i);
      a[4] = dy + i_phi(rod, i - 1); a[5] = dy + i_phi(rod, i);
      a[6] = dy + i_p(rod, i); a[7] = d_seg(d, i);
      W.res[0] = dsv;
      if (rod_segment_branch_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
      trelax_rows(rod, d, i_qs(rod, i), sv, dsv, y, dy, dyp, dres);
    }
  }
  /* internal torques of the joints (and the clamp joints against the end frames) */
  for (j = 0; j <= N; ++j) {
    const double** a = W.arg;
    if (!tjoint_args(rod, d, j, y, dy, a)) {
      trelax_rows(rod, d, i_qj(rod, j), 0, 0, y, dy, dyp, dres);
      continue;
    }
    tjnt_mq(rod, d, j, y, dy, nq, dnq);
    a[5] = nq; a[11] = dnq;
    W.res[0] = dT;
    if (rod_joint_torques_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
    if (j >= 1) for (k = 0; k < 3; ++k) dres[i_om(rod, j) + k] -= dT[k];
    if (j + 1 <= N) for (k = 0; k < 3; ++k) dres[i_om(rod, j + 1) + k] -= dT[3 + k];
    if (rod->nb) {
      const double *pa = a[0], *pb = a[1], *jn = a[4], *dpa = a[6], *dpb = a[7],
                   *djn = a[10];
      a[0] = pa; a[1] = pb; a[2] = jn;
      W.res[0] = sv; W.res[1] = svx; W.res[2] = G;
      if (rod_joint_branch(W.arg, W.res, W.iw, W.w, 0)) return -3;
      a[0] = pa; a[1] = pb; a[2] = jn; a[3] = dpa; a[4] = dpb; a[5] = djn;
      W.res[0] = dsv;
      if (rod_joint_branch_tan(W.arg, W.res, W.iw, W.w, 0)) return -3;
      trelax_rows(rod, d, i_qj(rod, j), sv, dsv, y, dy, dyp, dres);
    }
  }
  return 0;
}

/* ---- the sensitivity residual of the integrator (runtime/solvers/native/step_loop.c:
 * kv_sres_fn): parameter ip's direction is drods[ip] ---- */
typedef struct {
  const kvrod_rod* rod;
  int np;
  const kvrod_rod* drods;     /* np derivative rods */
} kvrod_sens_ctx;

int kvrod_sens_residual(const void* ctx, double t, const double* y, const double* yp,
                        int ip, const double* s, const double* sp, double* out) {
  const kvrod_sens_ctx* c = (const kvrod_sens_ctx*)ctx;
  if (ip >= c->np) return -1;
  return kvrod_residual_tangent(c->rod, ip >= 0 ? c->drods + ip : 0, t, y, yp, s, sp, out);
}
