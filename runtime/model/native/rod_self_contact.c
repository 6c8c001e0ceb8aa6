/*
 * Self-contact of a rod (contact.self; issue 32): the loops around the generated pair
 * kernels rod_contact_pair, _jac, _diagnostics and _bound (derive/contact_pair.py), in
 * the contact library beside rod_contact.c. rod_contact.h says what kvrod_self holds.
 *
 * Broad phase, each time forces, a Jacobian or energies are asked for (a pair list kept
 * from the last Jacobian would miss pairs that came into reach since): every segment's
 * bounding sphere about its midpoint, radius R = h/2 + r + CONTACT_CUTOFF delta/2,
 * projected on the axis in which the midpoints spread most, sorted, swept (a pair in
 * reach has its spheres overlapping: the bound kernel is the midpoints' distance minus
 * the half lengths and radii); the pairs found are checked with the bound kernel
 * (CONTACT_CUTOFF delta, as the obstacles' segments) and sorted (i, j) so that every
 * evaluation sums in the same order. Cost O(N log N) plus the pairs near each other.
 * Pairs of segments near along the rod are never paired (kvrod_self.near).
 *
 * The same loops serve the contact between the rods of an assembly (kvsys_pairs_*,
 * called by system.c): the segments of all its rods in one sweep (global segments
 * numbered rod after rod), the pairs' state indices in the system's state, the entries
 * within a segment into that rod's band of the system's Jacobian buffer.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "rod_contact_kernels.h"
#include "rod_layout.h"
#include "rod_assembly.h"
#include "rod_access.h"
#include "rod_contact.h"

typedef struct {
  const double* arg[16];
  double* res[8];
  casadi_int iw[8];
  double w[64];
} pwork;

/* the rods the pairs run over: a single rod (nrod 1, offset 0) or an assembly's */
typedef struct {
  const kvrod_self* S;
  int nrod, ntot;                 /* rods, segments of all of them */
  const kvrod_rod* const* rods;
  const int* off;                 /* per rod its first state index */
  const int* sg0;
  const kvrod_rod* one[1];        /* a single rod's storage for the above */
  int off1[1], sg1[2];
} sview;

static void view_of_rod(const kvrod_rod* rod, sview* V) {
  V->S = rod->contact->self;
  V->nrod = 1;
  V->ntot = rod->N;
  V->one[0] = rod;
  V->off1[0] = 0;
  V->sg1[0] = 0; V->sg1[1] = rod->N;
  V->rods = V->one; V->off = V->off1; V->sg0 = V->sg1;
}

static void view_of_system(const kvrod_self* S, sview* V) {
  V->S = S;
  V->nrod = S->nrod;
  V->ntot = S->sg0[S->nrod];
  V->rods = S->rods; V->off = S->off; V->sg0 = S->sg0;
}

/* global segment G (1-based) -> its rod (returned) and local segment *s */
static int seg_rod(const sview* V, int G, int* s) {
  int r = 0;
  while (r + 1 < V->nrod && G > V->sg0[r + 1]) ++r;
  *s = G - V->sg0[r];
  return r;
}

/* the position of segment G's start (end = 0) or end node (end = 1) in y */
static const double* seg_node(const sview* V, int G, int end, const double* y) {
  int s;
  const int r = seg_rod(V, G, &s);
  return y + V->off[r] + i_phi(V->rods[r], s - 1 + end);
}

/* segment G's law (CNT layout) */
static const double* sseg(const kvrod_self* S, int G) {
  return S->seg + (size_t)(G - 1) * NCNT;
}

/* the reference arc length of segment G's start (end = 0) or end node (m) */
static double seg_s0(const sview* V, int G, int end) {
  int s;
  const int r = seg_rod(V, G, &s);
  return V->S->s0[V->sg0[r] + r + s - 1 + end];
}

/* the pair's parameters (PAIR layout) from its segments' laws */
static void pair_params(const double* a, const double* b, double* par) {
  const double ca = a[CNT_C], cb = b[CNT_C];
  par[PAIR_K] = fmin(a[CNT_K], b[CNT_K]);
  par[PAIR_DELTA] = fmin(a[CNT_DELTA], b[CNT_DELTA]);
  par[PAIR_C] = (ca > 0.0 && cb > 0.0) ? ca * cb / sqrt(ca * ca + cb * cb) : 0.0;
  par[PAIR_MU] = fmin(a[CNT_MU], b[CNT_MU]);
  par[PAIR_V_S] = fmax(a[CNT_V_S], b[CNT_V_S]);
  par[PAIR_R_1] = a[CNT_R];
  par[PAIR_R_2] = b[CNT_R];
  par[PAIR_L_X] = a[CNT_R] + b[CNT_R];
}

/* a pair's state indices (in the view's state) in kernel order: phi_a, phi_b, v_a, v_b,
   p_1, Omega_1, phi_c, phi_d, v_c, v_d, p_2, Omega_2; free[4]: whether nodes a, b, c, d
   have momentum rows (not held by their rod's own end condition); rod[2] the segments'
   rods */
typedef struct {
  int i, j, idx[12], free_[4], rod[2];
  double par[NPAIR];
} cpair;

static void pair_of(const sview* V, int i, int j, cpair* P) {
  const int seg[2] = {i, j};
  P->i = i; P->j = j;
  for (int q = 0; q < 2; ++q) {
    int s;
    const int r = seg_rod(V, seg[q], &s);
    const kvrod_rod* rod = V->rods[r];
    const int o = V->off[r];
    int* ix = P->idx + 6 * q;
    ix[0] = o + i_phi(rod, s - 1); ix[1] = o + i_phi(rod, s);
    ix[2] = o + i_v(rod, s - 1); ix[3] = o + i_v(rod, s);
    ix[4] = o + i_p(rod, s); ix[5] = o + i_om(rod, s);
    P->free_[2 * q] = !(node_held(rod, s - 1) > 0.5);
    P->free_[2 * q + 1] = !(node_held(rod, s) > 0.5);
    P->rod[q] = r;
  }
  pair_params(sseg(V->S, i), sseg(V->S, j), P->par);
}

static void pair_args(const cpair* P, const double* y, pwork* W) {
  for (int k = 0; k < 12; ++k) W->arg[k] = y + P->idx[k];
  W->arg[12] = P->par;
}

/* the residual rows of the pair's forces Q (f_a, f_b, T_1, f_c, f_d, T_2; -1: a held
   node's) */
static void pair_rows(const cpair* P, int* rows) {
  for (int k = 0; k < 3; ++k) {
    rows[PAIRQ_F_A + k] = P->free_[0] ? P->idx[2] + k : -1;
    rows[PAIRQ_F_B + k] = P->free_[1] ? P->idx[3] + k : -1;
    rows[PAIRQ_T_1 + k] = P->idx[5] + k;
    rows[PAIRQ_F_C + k] = P->free_[2] ? P->idx[8] + k : -1;
    rows[PAIRQ_F_D + k] = P->free_[3] ? P->idx[9] + k : -1;
    rows[PAIRQ_T_2 + k] = P->idx[11] + k;
  }
}

/* the state indices of the Jacobian's columns (PAIR_JAC_COLUMNS) and which segment
   (0: i, 1: j) each belongs to */
static void pair_cols(const cpair* P, int* cols, int* owner) {
  for (int k = 0; k < 3; ++k) {
    cols[PAIRJ_PHI_A + k] = P->idx[0] + k;
    cols[PAIRJ_PHI_B + k] = P->idx[1] + k;
    cols[PAIRJ_PHI_C + k] = P->idx[6] + k;
    cols[PAIRJ_PHI_D + k] = P->idx[7] + k;
    cols[PAIRJ_V_A + k] = P->idx[2] + k;
    cols[PAIRJ_V_B + k] = P->idx[3] + k;
    cols[PAIRJ_OMEGA_1 + k] = P->idx[5] + k;
    cols[PAIRJ_V_C + k] = P->idx[8] + k;
    cols[PAIRJ_V_D + k] = P->idx[9] + k;
    cols[PAIRJ_OMEGA_2 + k] = P->idx[11] + k;
  }
  for (int k = 0; k < 4; ++k) {
    cols[PAIRJ_P_1 + k] = P->idx[4] + k;
    cols[PAIRJ_P_2 + k] = P->idx[10] + k;
  }
  for (int c = 0; c < NPAIRJ; ++c)
    owner[c] = (c >= PAIRJ_PHI_C && c < PAIRJ_V_A) || c >= PAIRJ_V_C;
}

typedef struct {
  double lo;
  int s;
} skey;

static int by_lo(const void* a, const void* b) {
  const double x = ((const skey*)a)->lo, z = ((const skey*)b)->lo;
  if (x < z) return -1;
  if (x > z) return 1;
  return ((const skey*)a)->s - ((const skey*)b)->s;
}

static int by_pair(const void* a, const void* b) {
  const int* p = (const int*)a;
  const int* q = (const int*)b;
  return p[0] != q[0] ? p[0] - q[0] : p[1] - q[1];
}

/* the pairs in reach into S->pairs (global segments i < j); returns their number, -3 (a
   kernel failed) or -5 (more than paircap) */
static int find_pairs(const sview* V, const double* y, pwork* W) {
  const kvrod_self* S = V->S;
  const int N = V->ntot;
  /* midpoints' spread: the sweep's axis */
  double mean[3] = {0, 0, 0}, var[3] = {0, 0, 0};
  for (int s = 1; s <= N; ++s) {
    const double* a = seg_node(V, s, 0, y);
    const double* b = seg_node(V, s, 1, y);
    for (int k = 0; k < 3; ++k) mean[k] += 0.5 * (a[k] + b[k]) / N;
  }
  for (int s = 1; s <= N; ++s) {
    const double* a = seg_node(V, s, 0, y);
    const double* b = seg_node(V, s, 1, y);
    for (int k = 0; k < 3; ++k) {
      const double d = 0.5 * (a[k] + b[k]) - mean[k];
      var[k] += d * d;
    }
  }
  const int ax = var[0] >= var[1] ? (var[0] >= var[2] ? 0 : 2) : (var[1] >= var[2] ? 1 : 2);
  /* work: N keys (lo, s) to sort (2 doubles each), then R per segment (R[s], s = 1..N) */
  skey* keys = (skey*)S->key;
  double* R = S->key + 2 * (size_t)N;
  for (int s = 1; s <= N; ++s) {
    const double* a = seg_node(V, s, 0, y);
    const double* b = seg_node(V, s, 1, y);
    const double* g = sseg(S, s);
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (b[k] - a[k]) * (b[k] - a[k]);
    R[s] = 0.5 * sqrt(d2) + g[CNT_R] + 0.5 * CONTACT_CUTOFF * g[CNT_DELTA];
    keys[s - 1].lo = 0.5 * (a[ax] + b[ax]) - R[s];
    keys[s - 1].s = s;
  }
  qsort(keys, (size_t)N, sizeof(skey), by_lo);
  int np = 0;
  for (int u = 0; u < N; ++u) {
    const int si = keys[u].s;
    const double* a = seg_node(V, si, 0, y);
    const double* b = seg_node(V, si, 1, y);
    const double hi = keys[u].lo + 2.0 * R[si];
    for (int w = u + 1; w < N && keys[w].lo <= hi; ++w) {
      const int sj = keys[w].s;
      const int i = si < sj ? si : sj, j = si < sj ? sj : si;
      const double* gi = sseg(S, i);
      const double* gj = sseg(S, j);
      int li, lj;
      if (seg_rod(V, i, &li) == seg_rod(V, j, &lj)   /* near along one rod */
          && (j == i + 1 || seg_s0(V, j, 0) - seg_s0(V, i, 1)
                                < S->near * (gi[CNT_R] + gj[CNT_R])))
        continue;
      const double* c = seg_node(V, sj, 0, y);
      const double* d = seg_node(V, sj, 1, y);
      double m2 = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double dm = 0.5 * (c[k] + d[k] - a[k] - b[k]);
        m2 += dm * dm;
      }
      const double rr = R[si] + R[sj];
      if (m2 > rr * rr) continue;
      double par[NPAIR], glb;
      pair_params(gi, gj, par);
      W->arg[0] = seg_node(V, i, 0, y); W->arg[1] = seg_node(V, i, 1, y);
      W->arg[2] = seg_node(V, j, 0, y); W->arg[3] = seg_node(V, j, 1, y);
      W->arg[4] = par;
      W->res[0] = &glb;
      if (rod_contact_pair_bound(W->arg, W->res, W->iw, W->w, 0)) return -3;
      if (!(glb <= CONTACT_CUTOFF * par[PAIR_DELTA])) continue;
      if (np >= S->paircap) return -5;
      S->pairs[2 * np] = i;
      S->pairs[2 * np + 1] = j;
      ++np;
    }
  }
  qsort(S->pairs, (size_t)np, 2 * sizeof(int), by_pair);
  return np;
}

static int pairs_residual(const sview* V, const double* y, double* res) {
  const kvrod_self* S = V->S;
  pwork W;
  cpair P;
  double Q[NPAIRQ];
  int rows[NPAIRQ];
  const int np = find_pairs(V, y, &W);
  if (np < 0) return np;
  for (int q = 0; q < np; ++q) {
    pair_of(V, S->pairs[2 * q], S->pairs[2 * q + 1], &P);
    pair_args(&P, y, &W);
    W.res[0] = Q;
    if (rod_contact_pair(W.arg, W.res, W.iw, W.w, 0)) return -3;
    pair_rows(&P, rows);
    for (int r = 0; r < NPAIRQ; ++r)
      if (rows[r] >= 0) res[rows[r]] -= Q[r];
  }
  return 0;
}

int kvrod_self_residual(const kvrod_rod* rod, const double* y, double* res) {
  sview V;
  view_of_rod(rod, &V);
  return pairs_residual(&V, y, res);
}

int kvsys_pairs_residual(const kvrod_self* S, const double* y, double* res) {
  sview V;
  view_of_system(S, &V);
  return pairs_residual(&V, y, res);
}

/* where the entries within each segment go: per segment (0: i, 1: j) of a pair, its
   rod's band storage ab (columns from col0, state indices from o: an entry (row, col)
   of the view's state is (row - o, col - o) of the band), or NULL: not written */
typedef struct {
  double* ab[2];
  int ldab[2], col0[2], o[2], kl[2], ku[2];
} bands;

static int pairs_band(const sview* V, const double* y, double cy,
                      int (*dest)(const sview*, const cpair*, void*, bands*), void* ctx) {
  const kvrod_self* S = V->S;
  pwork W;
  cpair P;
  bands B;
  double J[NPAIRQ * NPAIRJ];
  int rows[NPAIRQ], cols[NPAIRJ], owner[NPAIRJ];
  const int np = find_pairs(V, y, &W);
  if (np < 0) return np;
  for (int q = 0; q < np; ++q) {
    pair_of(V, S->pairs[2 * q], S->pairs[2 * q + 1], &P);
    if (!dest(V, &P, ctx, &B)) continue;
    pair_args(&P, y, &W);
    W.res[0] = J;
    if (rod_contact_pair_jac(W.arg, W.res, W.iw, W.w, 0)) return -3;
    pair_rows(&P, rows);
    pair_cols(&P, cols, owner);
    /* within segment i (rows 0..8, its columns) and within segment j (rows 9..17) */
    for (int c = 0; c < NPAIRJ; ++c) {
      const int o = owner[c];
      if (!B.ab[o]) continue;
      const int cc = cols[c] - B.o[o];
      double* col = B.ab[o] + (size_t)(cc - B.col0[o]) * (size_t)B.ldab[o]
                    + (size_t)(B.kl[o] + B.ku[o] - cc);
      for (int r = 9 * o; r < 9 * o + 9; ++r)
        if (rows[r] >= 0) col[rows[r] - B.o[o]] -= cy * J[r + NPAIRQ * c];
    }
  }
  return 0;
}

/* a single rod's band (cells s0..s1 in ab from column col0) */
typedef struct {
  double* ab;
  int ldab, col0, s0, s1;
} rod_band;

static int rod_dest(const sview* V, const cpair* P, void* ctx, bands* B) {
  const rod_band* R = (const rod_band*)ctx;
  const kvrod_rod* rod = V->rods[0];
  const int seg[2] = {P->i, P->j};
  int any = 0;
  for (int q = 0; q < 2; ++q) {
    const int in = seg[q] >= R->s0 && seg[q] <= R->s1;
    B->ab[q] = in ? R->ab : NULL;
    B->ldab[q] = R->ldab; B->col0[q] = R->col0; B->o[q] = 0;
    B->kl[q] = rod->kl; B->ku[q] = rod->ku;
    any |= in;
  }
  return any;
}

int kvrod_self_jacobian(const kvrod_rod* rod, const double* y, double cy, int ldab,
                        double* ab, int col0, int s0, int s1) {
  sview V;
  view_of_rod(rod, &V);
  rod_band R = {ab, ldab, col0, s0, s1};
  return pairs_band(&V, y, cy, rod_dest, &R);
}

/* an assembly: each segment's rod's band in the system's Jacobian buffer */
static int sys_dest(const sview* V, const cpair* P, void* ctx, bands* B) {
  (void) ctx;
  const kvrod_self* S = V->S;
  for (int q = 0; q < 2; ++q) {
    const int r = P->rod[q];
    B->ab[q] = S->J + S->ab_start[r];
    B->ldab[q] = S->ldabs[r]; B->col0[q] = 0; B->o[q] = V->off[r];
    B->kl[q] = V->rods[r]->kl; B->ku[q] = V->rods[r]->ku;
  }
  return 1;
}

int kvsys_pairs_jacobian(const kvrod_self* S, const double* y) {
  sview V;
  view_of_system(S, &V);
  return pairs_band(&V, y, 1.0, sys_dest, NULL);
}

/* the pair's rows in the couplings: pair_rows through S->rowmap */
static void coupling_rows(const kvrod_self* S, const cpair* P, int* rows) {
  pair_rows(P, rows);
  if (!S->rowmap) return;
  for (int r = 0; r < NPAIRQ; ++r)
    if (rows[r] >= 0) rows[r] = S->rowmap[rows[r]];
}

static int pairs_couplings(const sview* V, const double* y) {
  kvrod_self* S = (kvrod_self*)V->S;
  pwork W;
  cpair P;
  double J[NPAIRQ * NPAIRJ];
  int rows[NPAIRQ], cols[NPAIRJ], owner[NPAIRJ];
  *S->m2 = 0;
  S->er2[0] = 0;
  S->dropped = 0;
  if (S->m2cap <= 0) return 0;
  const int np = find_pairs(V, y, &W);
  if (np < 0) return np;
  /* pass 1: the rows (merged by global row) and their entry counts, pairs taken in order
     while both fit */
  int m = 0, nz = 0, last = np;
  for (int q = 0; q < np; ++q) {
    pair_of(V, S->pairs[2 * q], S->pairs[2 * q + 1], &P);
    coupling_rows(S, &P, rows);
    int newrows = 0;
    for (int r = 0; r < NPAIRQ; ++r)
      if (rows[r] >= 0 && S->rowslot[rows[r]] < 0) ++newrows;
    int add = 0;
    for (int r = 0; r < NPAIRQ; ++r) add += rows[r] >= 0 ? NPAIRJ / 2 : 0;
    if (m + newrows > S->m2cap || nz + add > S->nz2cap) { last = q; break; }
    for (int r = 0; r < NPAIRQ; ++r) {
      if (rows[r] < 0) continue;
      if (S->rowslot[rows[r]] < 0) {
        S->rowslot[rows[r]] = m;
        S->srow2[m] = rows[r];
        S->rowfill[m] = 0;
        ++m;
      }
    }
    /* row r of segment o meets the other segment's columns: 19 of them */
    for (int r = 0; r < NPAIRQ; ++r)
      if (rows[r] >= 0) S->rowfill[S->rowslot[rows[r]]] += NPAIRJ / 2;
    nz += add;
  }
  S->dropped = np - last;
  /* CSR offsets; rowfill becomes each row's cursor */
  S->er2[0] = 0;
  for (int t = 0; t < m; ++t) {
    S->er2[t + 1] = S->er2[t] + S->rowfill[t];
    S->rowfill[t] = S->er2[t];
  }
  /* pass 2: the entries */
  for (int q = 0; q < last; ++q) {
    pair_of(V, S->pairs[2 * q], S->pairs[2 * q + 1], &P);
    pair_args(&P, y, &W);
    W.res[0] = J;
    if (rod_contact_pair_jac(W.arg, W.res, W.iw, W.w, 0)) {
      for (int t = 0; t < m; ++t) S->rowslot[S->srow2[t]] = -1;
      return -3;
    }
    coupling_rows(S, &P, rows);
    pair_cols(&P, cols, owner);
    for (int r = 0; r < NPAIRQ; ++r) {
      if (rows[r] < 0) continue;
      const int o = r >= 9;
      int* cur = S->rowfill + S->rowslot[rows[r]];
      for (int c = 0; c < NPAIRJ; ++c) {
        if (owner[c] == o) continue;
        S->ec2[*cur] = cols[c];
        S->ev2[*cur] = -J[r + NPAIRQ * c];
        ++*cur;
      }
    }
  }
  for (int t = 0; t < m; ++t) S->rowslot[S->srow2[t]] = -1;
  *S->m2 = m;
  return 0;
}

int kvrod_self_couplings(const kvrod_rod* rod, const double* y) {
  sview V;
  view_of_rod(rod, &V);
  return pairs_couplings(&V, y);
}

int kvsys_pairs_couplings(kvrod_self* S, const double* y) {
  sview V;
  view_of_system(S, &V);
  return pairs_couplings(&V, y);
}

static int pairs_values(const sview* V, const double* y, double* v) {
  const kvrod_self* S = V->S;
  pwork W;
  cpair P;
  double E, Pd, g, Pf, st[2], Wc, F[3];
  memset(v, 0, sizeof(double) * NSV);
  v[3] = HUGE_VAL;
  const int np = find_pairs(V, y, &W);
  if (np < 0) return np;
  for (int q = 0; q < np; ++q) {
    pair_of(V, S->pairs[2 * q], S->pairs[2 * q + 1], &P);
    pair_args(&P, y, &W);
    W.res[0] = &E; W.res[1] = &Pd; W.res[2] = &g; W.res[3] = &Pf;
    W.res[4] = st; W.res[5] = &Wc; W.res[6] = F;
    if (rod_contact_pair_diagnostics(W.arg, W.res, W.iw, W.w, 0)) return -3;
    v[0] += E; v[1] += Pd; v[2] += Pf;
    if (g < v[3]) v[3] = g;
    v[5] += sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]);
  }
  v[4] = np;
  return 0;
}

int kvrod_self_values(const kvrod_rod* rod, const double* y, double* v) {
  sview V;
  view_of_rod(rod, &V);
  return pairs_values(&V, y, v);
}

int kvsys_pairs_values(const kvrod_self* S, const double* y, double* v) {
  sview V;
  view_of_system(S, &V);
  return pairs_values(&V, y, v);
}

static double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

/* the distance (m) between segments p1 q1 and p2 q2 (Ericson, Real-Time Collision
   Detection, 5.1.9): the step bound's gap, exact where the pair kernel's bound (the
   midpoints' distance minus the half lengths) lies up to a segment length below it */
static double segment_distance(const double* p1, const double* q1, const double* p2,
                               const double* q2) {
  double d1[3], d2[3], r[3], a = 0.0, e = 0.0, f = 0.0, c = 0.0, b = 0.0;
  for (int k = 0; k < 3; ++k) {
    d1[k] = q1[k] - p1[k]; d2[k] = q2[k] - p2[k]; r[k] = p1[k] - p2[k];
    a += d1[k] * d1[k]; e += d2[k] * d2[k]; f += d2[k] * r[k];
    c += d1[k] * r[k]; b += d1[k] * d2[k];
  }
  double s = 0.0, t = 0.0;
  if (a > 0.0 && e > 0.0) {
    const double den = a * e - b * b;
    s = den > 0.0 ? clamp01((b * f - c * e) / den) : 0.0;
    t = (b * s + f) / e;
    if (t < 0.0) { t = 0.0; s = clamp01(-c / a); }
    else if (t > 1.0) { t = 1.0; s = clamp01((b - c) / a); }
  } else if (a > 0.0) {
    s = clamp01(-c / a);
  } else if (e > 0.0) {
    t = clamp01(f / e);
  }
  double d2s = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double x = p1[k] + s * d1[k] - p2[k] - t * d2[k];
    d2s += x * x;
  }
  return sqrt(d2s);
}

/* the pairs' step bound (rod_contact.h says what it bounds) */
static double pairs_max_step(const sview* V, const double* y) {
  const kvrod_self* S = V->S;
  const double frac = S->step_fraction;
  const int N = V->ntot;
  if (!(frac > 0.0) || N < 2) return HUGE_VAL;
  /* the nodes' velocities about their mean (every segment's two nodes) */
  double mean[3] = {0, 0, 0}, umax = 0.0, hmax = 0.0, rmax = 0.0, dmax = 0.0;
  for (int G = 1; G <= N; ++G)
    for (int e = 0; e < 2; ++e) {
      int s;
      const int r = seg_rod(V, G, &s);
      const double* v = y + V->off[r] + i_v(V->rods[r], s - 1 + e);
      for (int k = 0; k < 3; ++k) mean[k] += v[k] / (2.0 * N);
    }
  for (int G = 1; G <= N; ++G) {
    int s;
    const int r = seg_rod(V, G, &s);
    for (int e = 0; e < 2; ++e) {
      const double* v = y + V->off[r] + i_v(V->rods[r], s - 1 + e);
      double u2 = 0.0;
      for (int k = 0; k < 3; ++k) u2 += (v[k] - mean[k]) * (v[k] - mean[k]);
      if (u2 > umax * umax) umax = sqrt(u2);
    }
    const double* a = seg_node(V, G, 0, y);
    const double* b = seg_node(V, G, 1, y);
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (b[k] - a[k]) * (b[k] - a[k]);
    const double* g = sseg(S, G);
    if (sqrt(d2) > hmax) hmax = sqrt(d2);
    if (g[CNT_R] > rmax) rmax = g[CNT_R];
    if (g[CNT_DELTA] > dmax) dmax = g[CNT_DELTA];
  }
  if (!(umax > 0.0)) return HUGE_VAL;          /* a rigid translation: nothing closes */
  const double D = 2.0 * hmax + 4.0 * rmax + CONTACT_CUTOFF * dmax;
  double hbound = frac * D / (2.0 * umax);     /* the pairs beyond the horizon */
  /* the sweep of rod_self_contact's broad phase with spheres grown by D / 2: a pair whose
     spheres overlap has its bound below D */
  pwork W;
  skey* keys = (skey*)S->key;
  double* R = S->key + 2 * (size_t)N;
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int G = 1; G <= N; ++G) {
    const double* a = seg_node(V, G, 0, y);
    for (int k = 0; k < 3; ++k) { lo[k] = fmin(lo[k], a[k]); hi[k] = fmax(hi[k], a[k]); }
  }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  for (int G = 1; G <= N; ++G) {
    const double* a = seg_node(V, G, 0, y);
    const double* b = seg_node(V, G, 1, y);
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (b[k] - a[k]) * (b[k] - a[k]);
    R[G] = 0.5 * sqrt(d2) + sseg(S, G)[CNT_R] + 0.5 * D;
    keys[G - 1].lo = 0.5 * (a[axis] + b[axis]) - R[G];
    keys[G - 1].s = G;
  }
  qsort(keys, (size_t)N, sizeof(skey), by_lo);
  for (int u = 0; u < N; ++u) {
    const int si = keys[u].s;
    const double top = keys[u].lo + 2.0 * R[si];
    for (int w = u + 1; w < N && keys[w].lo <= top; ++w) {
      const int sj = keys[w].s;
      const int i = si < sj ? si : sj, j = si < sj ? sj : si;
      const double* gi = sseg(S, i);
      const double* gj = sseg(S, j);
      int li, lj;
      if (seg_rod(V, i, &li) == seg_rod(V, j, &lj)
          && (j == i + 1 || seg_s0(V, j, 0) - seg_s0(V, i, 1)
                                < S->near * (gi[CNT_R] + gj[CNT_R])))
        continue;
      const double* pos[4] = {seg_node(V, i, 0, y), seg_node(V, i, 1, y),
                              seg_node(V, j, 0, y), seg_node(V, j, 1, y)};
      const double* vel[4];
      double speed = 0.0;
      for (int q = 0; q < 4; ++q) {
        int s;
        const int G = q < 2 ? i : j;
        const int r = seg_rod(V, G, &s);
        vel[q] = y + V->off[r] + i_v(V->rods[r], s - 1 + (q & 1));
        const double sp = sqrt(vel[q][0] * vel[q][0] + vel[q][1] * vel[q][1]
                               + vel[q][2] * vel[q][2]);
        if (sp > speed) speed = sp;
      }
      if (!(speed > 0.0)) continue;
      double par[NPAIR], glb;
      pair_params(gi, gj, par);
      for (int q = 0; q < 4; ++q) W.arg[q] = pos[q];
      W.arg[4] = par;
      W.res[0] = &glb;
      if (rod_contact_pair_bound(W.arg, W.res, W.iw, W.w, 0)) return HUGE_VAL;
      if (glb > D) continue;                   /* beyond the horizon: hbound */
      const double delta = par[PAIR_DELTA], rr = par[PAIR_R_1] + par[PAIR_R_2];
      const double g0 = segment_distance(pos[0], pos[1], pos[2], pos[3]) - rr;
      if (g0 < 3.0 * delta) continue;          /* in contact: the error test's */
      /* the gap's rate by a difference over the time in which the fastest node moves a
         thousandth of the smaller radius (rod_contact.c's rule) */
      double travel = 1e-3 * fmin(par[PAIR_R_1], par[PAIR_R_2]);
      if (travel < delta) travel = delta;
      const double dt = travel / speed;
      double moved[4][3];
      for (int q = 0; q < 4; ++q)
        for (int k = 0; k < 3; ++k) moved[q][k] = pos[q][k] + dt * vel[q][k];
      const double g1 = segment_distance(moved[0], moved[1], moved[2], moved[3]) - rr;
      const double approach = (g0 - g1) / dt;
      if (!(approach > 0.0)) continue;
      const double k = par[PAIR_K], c = par[PAIR_C];
      const double tc = (k > 0.0 && c > 0.0) ? c / k : 0.0;
      const double h = frac * ((g0 + delta) / approach + tc);
      if (h < hbound) hbound = h;
    }
  }
  return hbound;
}

double kvrod_self_max_step(const kvrod_rod* rod, const double* y) {
  sview V;
  view_of_rod(rod, &V);
  return pairs_max_step(&V, y);
}

double kvsys_pairs_max_step(const kvrod_self* S, const double* y) {
  sview V;
  view_of_system(S, &V);
  return pairs_max_step(&V, y);
}
