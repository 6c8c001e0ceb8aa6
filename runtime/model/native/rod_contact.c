/*
 * Contact of a rod with rigid obstacles: the loops over obstacles and segments around the
 * generated kernels rod_contact_<kind>, _jac, _diagnostics and _bound (rod_contact.h says
 * what each function does; derive/contact.py derives the kernels). Written by hand,
 * compiled with the rod assembly. A segment whose gap bound exceeds CONTACT_CUTOFF delta
 * is skipped: every term of its kernels is below exp(-40) there (derive.contact), so the
 * culling changes nothing above round-off and keeps a rod far from every obstacle at the
 * cost of one bound kernel per segment and obstacle.
 */
#include <math.h>
#include <string.h>
#include "rod_contact_kernels.h"
#include "rod_layout.h"
#include "rod_assembly.h"
#include "rod_access.h"
#include "rod_contact.h"

typedef int (*ckernel)(const casadi_real** arg, casadi_real** res, casadi_int* iw,
                       casadi_real* w, int mem);

static const ckernel kForces[KV_NKINDS] = {rod_contact_plane, rod_contact_sphere,
                                           rod_contact_cylinder, rod_contact_pipe};
static const ckernel kJac[KV_NKINDS] = {rod_contact_plane_jac, rod_contact_sphere_jac,
                                        rod_contact_cylinder_jac, rod_contact_pipe_jac};
static const ckernel kDiag[KV_NKINDS] = {
    rod_contact_plane_diagnostics, rod_contact_sphere_diagnostics,
    rod_contact_cylinder_diagnostics, rod_contact_pipe_diagnostics};
static const ckernel kBound[KV_NKINDS] = {rod_contact_plane_bound, rod_contact_sphere_bound,
                                          rod_contact_cylinder_bound, rod_contact_pipe_bound};

typedef struct {
  const double* arg[16];
  double* res[8];
  casadi_int iw[8];
  double w[1024];
} cwork;

/* one segment's inputs: phi_a, phi_b, v_a, v_b, p, Omega (kernel order), obs, cnt */
typedef struct {
  int idx[6], free_ab[2];
  const double* obs;
  const double* cnt;
} cseg;

static int active(const kvrod_rod* rod) {
  return rod->contact != 0 && rod->contact->nobs > 0;
}

static const double* cnt_of(const kvrod_rod* rod, int o, int s) {
  return rod->contact->cnt + ((size_t)o * (size_t)rod->N + (size_t)(s - 1)) * NCNT;
}

static void seg_of(const kvrod_rod* rod, int o, int s, cseg* g) {
  g->idx[0] = i_phi(rod, s - 1); g->idx[1] = i_phi(rod, s);
  g->idx[2] = i_v(rod, s - 1); g->idx[3] = i_v(rod, s);
  g->idx[4] = i_p(rod, s); g->idx[5] = i_om(rod, s);
  g->free_ab[0] = !(node_held(rod, s - 1) > 0.5);
  g->free_ab[1] = !(node_held(rod, s) > 0.5);
  g->obs = rod->contact->obs + (size_t)o * NOBS;
  g->cnt = cnt_of(rod, o, s);
}

/* the kernel arguments: idx is (phi_a, phi_b, v_a, v_b, p, Omega) */
static void args_of(const cseg* g, const double* y, cwork* W) {
  for (int k = 0; k < 6; ++k) W->arg[k] = y + g->idx[k];
  W->arg[6] = g->obs;
  W->arg[7] = g->cnt;
}

/* A screen of the in-reach tests before the bound kernel, for planes: the plane's unit
   normal in space n and its offset (d(x) = n . x - off, the kernel's d by other
   arithmetic), so that a segment whose bound exceeds a threshold by far more than either
   computation's round-off (1e-9 of the magnitudes in it) is known to be out of reach
   without the kernel, and one whose bound lies below it by as much in reach. Where the
   screen does not decide, the kernel does: the same segments are in reach, bit for bit
   (the bound kernels were a third of the contact's cost on the bench's falling cable).
   Other kinds: no screen. */
typedef struct {
  int on;
  double n[3], off, mag;
} cscreen;

static void screen_of(int kind, const double* obs, cscreen* sc) {
  sc->on = 0;
  if (kind != KV_PLANE) return;
  const double* q = obs + OBS_Q;
  const double* a = obs + OBS_AXIS;
  const double* pt = obs + OBS_POINT;
  const double* c = obs + OBS_C;
  const double qq = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  const double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
  if (!(qq > 0.0) || !(aa > 0.0)) return;
  double u[3], cr[3];
  const double la = sqrt(aa);
  for (int k = 0; k < 3; ++k) u[k] = a[k] / la;
  const double* v = q + 1;      /* the local normal u in space: R(q) u, q of any norm */
  const double s = q[0] * q[0] - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double vu = v[0] * u[0] + v[1] * u[1] + v[2] * u[2];
  cr[0] = v[1] * u[2] - v[2] * u[1];
  cr[1] = v[2] * u[0] - v[0] * u[2];
  cr[2] = v[0] * u[1] - v[1] * u[0];
  sc->off = 0.0;
  sc->mag = 0.0;
  for (int k = 0; k < 3; ++k) {
    sc->n[k] = (s * u[k] + 2.0 * vu * v[k] + 2.0 * q[0] * cr[k]) / qq;
    sc->off += sc->n[k] * c[k] + u[k] * pt[k];
    sc->mag += fabs(c[k]) + fabs(pt[k]);
  }
  sc->on = isfinite(sc->off) && isfinite(sc->mag) && isfinite(sc->n[0])
           && isfinite(sc->n[1]) && isfinite(sc->n[2]);
}

/* the screen's verdict on segment (pa, pb) of contact radius r: 1 its gap bound is above
   thresh for sure, -1 at most thresh for sure, 0 too near to tell (the kernel decides) */
static int screen(const cscreen* sc, const double* pa, const double* pb, double r,
                  double thresh) {
  if (!sc || !sc->on) return 0;
  double d = 0.0, uu = 0.0, mag = sc->mag + fabs(r) + fabs(thresh);
  for (int k = 0; k < 3; ++k) {
    const double m = 0.5 * (pa[k] + pb[k]), u = pb[k] - pa[k];
    d += sc->n[k] * m;
    uu += u * u;
    mag += fabs(m) + fabs(u);
  }
  /* the bound is d(m) - r - |u|/2: compared with thresh through D = d(m) - r - thresh
     against |u|/2 (squared), D taken low and high by the margin */
  const double D = d - sc->off - r - thresh, tol = 1e-9 * mag, lo = D - tol, hi = D + tol;
  if (lo > 0.0 && 4.0 * lo * lo > uu * (1.0 + 1e-9)) return 1;
  if (hi <= 0.0 || 4.0 * hi * hi * (1.0 + 1e-9) < uu) return -1;
  return 0;
}

/* the gap's lower bound of the segment (m) */
static int bound_of(int kind, const double* pa, const double* pb, const double* obs,
                    const double* cnt, cwork* W, double* g) {
  W->arg[0] = pa; W->arg[1] = pb; W->arg[2] = obs; W->arg[3] = cnt;
  W->res[0] = g;
  return kBound[kind](W->arg, W->res, W->iw, W->w, 0) ? -3 : 0;
}

/* whether segment g is in reach (its bound at most CONTACT_CUTOFF delta); *glb <- bound
   (sc not NULL: screened first; a segment the screen decides gets the threshold as *glb,
   which its bound exceeds (out of reach) or does not (in reach)) */
static int in_reach(int kind, const cseg* g, const double* y, cwork* W, int* yes,
                    double* glb, const cscreen* sc) {
  const double thresh = CONTACT_CUTOFF * g->cnt[CNT_DELTA];
  const int verdict = screen(sc, y + g->idx[0], y + g->idx[1], g->cnt[CNT_R], thresh);
  if (verdict) {
    *yes = verdict < 0;
    *glb = thresh;
    return 0;
  }
  if (bound_of(kind, y + g->idx[0], y + g->idx[1], g->obs, g->cnt, W, glb)) return -3;
  *yes = *glb <= thresh;
  return 0;
}

static int obstacle_residual(const kvrod_rod* rod, const double* y, double* res) {
  if (!active(rod)) return 0;
  const kvrod_contact* C = rod->contact;
  cwork W;
  cseg g;
  double Q[NCNTQ], glb;
  int yes;
  for (int o = 0; o < C->nobs; ++o) {
    const int kind = C->kind[o];
    if (kind < 0 || kind >= KV_NKINDS) return -4;
    cscreen sc;
    screen_of(kind, rod->contact->obs + (size_t)o * NOBS, &sc);
    for (int s = 1; s <= rod->N; ++s) {
      seg_of(rod, o, s, &g);
      if (in_reach(kind, &g, y, &W, &yes, &glb, &sc)) return -3;
      if (!yes) continue;
      args_of(&g, y, &W);
      W.res[0] = Q;
      if (kForces[kind](W.arg, W.res, W.iw, W.w, 0)) return -3;
      for (int k = 0; k < 3; ++k) {
        if (g.free_ab[0]) res[g.idx[2] + k] -= Q[CNTQ_F_A + k];
        if (g.free_ab[1]) res[g.idx[3] + k] -= Q[CNTQ_F_B + k];
        res[g.idx[5] + k] -= Q[CNTQ_T + k];
      }
    }
  }
  return 0;
}

int kvrod_contact_residual(const kvrod_rod* rod, const double* y, double* res) {
  if (!rod->contact) return 0;
  const int rc = obstacle_residual(rod, y, res);
  return rc || !rod->contact->self ? rc : kvrod_self_residual(rod, y, res);
}

static int obstacle_jacobian(const kvrod_rod* rod, const double* y, double cy, int ldab,
                             double* ab, int col0, int s0, int s1) {
  if (!active(rod) || cy == 0.0) return 0;
  const kvrod_contact* C = rod->contact;
  const int kl = rod->kl, ku = rod->ku;
  cwork W;
  cseg g;
  double J[NCNTQ * NCNTJ], glb;
  int yes, rows[NCNTQ], cols[NCNTJ];
  if (s0 < 1) s0 = 1;
  if (s1 > rod->N) s1 = rod->N;
  for (int o = 0; o < C->nobs; ++o) {
    const int kind = C->kind[o];
    if (kind < 0 || kind >= KV_NKINDS) return -4;
    cscreen sc;
    screen_of(kind, rod->contact->obs + (size_t)o * NOBS, &sc);
    for (int s = s0; s <= s1; ++s) {
      seg_of(rod, o, s, &g);
      if (in_reach(kind, &g, y, &W, &yes, &glb, &sc)) return -3;
      if (!yes) continue;
      args_of(&g, y, &W);
      W.res[0] = J;
      if (kJac[kind](W.arg, W.res, W.iw, W.w, 0)) return -3;
      /* rows: f_a on v_a, f_b on v_b, T on Omega; columns: phi_a, phi_b, p, v_a, v_b,
         Omega (CNTJ_*) */
      for (int k = 0; k < 3; ++k) {
        rows[CNTQ_F_A + k] = g.free_ab[0] ? g.idx[2] + k : -1;
        rows[CNTQ_F_B + k] = g.free_ab[1] ? g.idx[3] + k : -1;
        rows[CNTQ_T + k] = g.idx[5] + k;
        cols[CNTJ_PHI_A + k] = g.idx[0] + k;
        cols[CNTJ_PHI_B + k] = g.idx[1] + k;
        cols[CNTJ_V_A + k] = g.idx[2] + k;
        cols[CNTJ_V_B + k] = g.idx[3] + k;
        cols[CNTJ_OMEGA + k] = g.idx[5] + k;
      }
      for (int k = 0; k < 4; ++k) cols[CNTJ_P + k] = g.idx[4] + k;
      for (int c = 0; c < NCNTJ; ++c) {
        const int cc = cols[c];
        double* col = ab + (size_t)(cc - col0) * (size_t)ldab + (size_t)(kl + ku - cc);
        for (int r = 0; r < NCNTQ; ++r)
          if (rows[r] >= 0) col[rows[r]] -= cy * J[r + NCNTQ * c];
      }
    }
  }
  return 0;
}

int kvrod_contact_jacobian(const kvrod_rod* rod, const double* y, double cy, int ldab,
                           double* ab, int col0, int s0, int s1) {
  if (!rod->contact) return 0;
  const int rc = obstacle_jacobian(rod, y, cy, ldab, ab, col0, s0, s1);
  return rc || !rod->contact->self || cy == 0.0
             ? rc : kvrod_self_jacobian(rod, y, cy, ldab, ab, col0, s0, s1);
}

/* segment s's diagnostics with obstacle o: E, P_diss, F_obs (3), M_obs (3), P_obs, g_min,
   points (NQ x 4, column-major), P_fric */
typedef struct {
  double E, P_diss, F[3], M[3], P_obs, g_min, points[NQ * 4], P_fric;
} cdiag;

static int diag_of(int kind, const cseg* g, const double* y, cwork* W, cdiag* d) {
  args_of(g, y, W);
  W->res[0] = &d->E; W->res[1] = &d->P_diss; W->res[2] = d->F; W->res[3] = d->M;
  W->res[4] = &d->P_obs; W->res[5] = &d->g_min; W->res[6] = d->points;
  W->res[7] = &d->P_fric;
  return kDiag[kind](W->arg, W->res, W->iw, W->w, 0) ? -3 : 0;
}

/* obstacle o's NCV values (rod_contact.h) into v */
/* exact_gap: the smallest gap evaluated also on segments out of reach whose bound lies
   below the smallest so far (the values' g_min; the energies need no gap) */
static int obstacle_values(const kvrod_rod* rod, int o, const double* y, cwork* W,
                           double* v, int exact_gap) {
  const int kind = rod->contact->kind[o];
  cseg g;
  cdiag d;
  double glb;
  int yes;
  if (kind < 0 || kind >= KV_NKINDS) return -4;
  cscreen sc;
  screen_of(kind, rod->contact->obs + (size_t)o * NOBS, &sc);
  memset(v, 0, sizeof(double) * NCV);
  v[10] = HUGE_VAL;
  int far = 0;
  for (int s = 1; s <= rod->N; ++s) {
    seg_of(rod, o, s, &g);
    if (in_reach(kind, &g, y, W, &yes, &glb, &sc)) return -3;
    if (!yes) {
      far = 1;
      if (!exact_gap && glb < v[10]) v[10] = glb;
      continue;
    }
    if (diag_of(kind, &g, y, W, &d)) return -3;
    for (int k = 0; k < 3; ++k) { v[k] -= d.F[k]; v[3 + k] -= d.M[k]; }
    v[6] += d.E; v[7] += d.P_diss; v[8] += d.P_fric; v[9] += d.P_obs;
    if (d.g_min < v[10]) v[10] = d.g_min;
    v[11] += 1.0;
  }
  /* the exact smallest gap of the segments out of reach: only those whose bound is below
     the smallest gap so far can hold it (the bound is below the gap), so with a segment
     in reach hardly any is evaluated */
  for (int s = 1; exact_gap && far && s <= rod->N; ++s) {
    seg_of(rod, o, s, &g);
    if (in_reach(kind, &g, y, W, &yes, &glb, NULL)) return -3;
    if (yes || !(glb < v[10])) continue;
    if (diag_of(kind, &g, y, W, &d)) return -3;
    if (d.g_min < v[10]) v[10] = d.g_min;
  }
  return 0;
}

int kvrod_contact_values(const kvrod_rod* rod, const double* y, double* out) {
  if (!active(rod)) return 0;
  cwork W;
  for (int o = 0; o < rod->contact->nobs; ++o) {
    const int rc = obstacle_values(rod, o, y, &W, out + (size_t)o * NCV, 1);
    if (rc) return rc;
  }
  return 0;
}

/* the contact forces on the held end nodes: their rows are the end condition's, so the
   residual leaves these forces to the supports, which take them: each support's reaction
   (e + NDIAG_E, per held end its force then its moment) loses them (R = m a - f - F_int -
   f_contact), and the boundary power e[4] (R . v of the held node) with them */
static int support_forces(const kvrod_rod* rod, const double* y, cwork* W, double* e) {
  const kvrod_contact* C = rod->contact;
  cseg g;
  double Q[NCNTQ], glb;
  int yes;
  for (int o = 0; o < C->nobs; ++o) {
    const int kind = C->kind[o];
    if (kind < 0 || kind >= KV_NKINDS) return -4;
    cscreen sc;
    screen_of(kind, rod->contact->obs + (size_t)o * NOBS, &sc);
    for (int end = 0; end < 2; ++end) {
      seg_of(rod, o, end == 0 ? 1 : rod->N, &g);
      if (g.free_ab[end]) continue;
      if (in_reach(kind, &g, y, W, &yes, &glb, &sc)) return -3;
      if (!yes) continue;
      args_of(&g, y, W);
      W->res[0] = Q;
      if (kForces[kind](W->arg, W->res, W->iw, W->w, 0)) return -3;
      const double* f = Q + (end == 0 ? CNTQ_F_A : CNTQ_F_B);
      const double* v = y + g.idx[2 + end];
      double* R = e + NDIAG_E + 6 * end;
      for (int k = 0; k < 3; ++k) {
        R[k] -= f[k];
        e[4] -= f[k] * v[k];
      }
    }
  }
  return 0;
}

/* kvrod_contact_energies, and with out (not NULL) kvrod_contact_values in the same pass
   (the energies' terms do not depend on how the smallest gap is found) */
static int energies_values(const kvrod_rod* rod, const double* y, double* e, double* out) {
  if (!rod->contact) return 0;
  cwork W;
  double v[NCV];
  for (int o = 0; active(rod) && o < rod->contact->nobs; ++o) {
    double* vo = out ? out + (size_t)o * NCV : v;
    const int rc = obstacle_values(rod, o, y, &W, vo, out != 0);
    if (rc) return rc;
    e[1] += vo[6];
    e[2] += vo[7];
    e[3] += vo[9];
  }
  if (rod->contact->self) {
    double sv[NSV];
    const int rc = kvrod_self_values(rod, y, sv);
    if (rc) return rc;
    e[1] += sv[0];
    e[2] += sv[1];
    if (rod->contact->self->last) memcpy(rod->contact->self->last, sv, sizeof sv);
  }
  return support_forces(rod, y, &W, e);
}

int kvrod_contact_energies(const kvrod_rod* rod, const double* y, double* e) {
  return energies_values(rod, y, e, 0);
}

int kvrod_contact_energies_values(const kvrod_rod* rod, const double* y, double* e,
                                  double* out) {
  return energies_values(rod, y, e, out);
}

/* q <- q + h/2 (0, w) * q (the obstacle's orientation a short time h later, first order;
   the kernels take a quaternion of any norm) */
static void turn(double* q, const double* w, double h) {
  const double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
  q[0] = q0 + 0.5 * h * (-w[0] * q1 - w[1] * q2 - w[2] * q3);
  q[1] = q1 + 0.5 * h * (w[0] * q0 + w[1] * q3 - w[2] * q2);
  q[2] = q2 + 0.5 * h * (w[1] * q0 + w[2] * q1 - w[0] * q3);
  q[3] = q3 + 0.5 * h * (w[2] * q0 + w[0] * q2 - w[1] * q1);
}

static double norm3(const double* a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

double kvrod_contact_max_step(const kvrod_rod* rod, const double* y) {
  /* the self-contact pairs' bound (rod_self_contact.c), then the obstacles' */
  const double hself = rod->contact && rod->contact->self ? kvrod_self_max_step(rod, y)
                                                          : HUGE_VAL;
  if (!active(rod) || !(rod->contact->step_fraction > 0.0)) return hself;
  const kvrod_contact* C = rod->contact;
  cwork W;
  cseg g;
  double hmax = hself, obs2[NOBS];
  for (int o = 0; o < C->nobs; ++o) {
    const int kind = C->kind[o];
    if (kind < 0 || kind >= KV_NKINDS) return HUGE_VAL;
    const double* obs = C->obs + (size_t)o * NOBS;
    const double vo = norm3(obs + OBS_V);
    for (int s = 1; s <= rod->N; ++s) {
      seg_of(rod, o, s, &g);
      const double* pa = y + g.idx[0];
      const double* pb = y + g.idx[1];
      const double* va = y + g.idx[2];
      const double* vb = y + g.idx[3];
      const double delta = g.cnt[CNT_DELTA];
      /* the speed scale: the nodes' and the obstacle's point's (its turn is taken by
         the same difference, over the same short time) */
      double speed = norm3(va);
      const double sb = norm3(vb);
      if (sb > speed) speed = sb;
      if (vo > speed) speed = vo;
      const double wo = norm3(obs + OBS_W);
      if (!(speed > 0.0) && !(wo > 0.0)) continue;
      double g0, g1;
      if (bound_of(kind, pa, pb, obs, g.cnt, &W, &g0)) return HUGE_VAL;
      /* a segment in contact already (the force within e^-3 of the linear law's) is the
         error test's: the bound keeps steps from jumping into contact, not through it */
      if (g0 < 3.0 * delta) continue;
      /* the bound's rate along the motion, by a difference over the time in which the
         fastest point moves a thousandth of the contact radius (the bound is smooth on
         that scale; a shorter travel would leave the difference to round-off) */
      double travel = 1e-3 * g.cnt[CNT_R];
      if (travel < delta) travel = delta;
      const double dt = travel / (speed > 0.0 ? speed : wo * travel);
      double qa[3], qb[3];
      for (int k = 0; k < 3; ++k) { qa[k] = pa[k] + dt * va[k]; qb[k] = pb[k] + dt * vb[k]; }
      memcpy(obs2, obs, sizeof(double) * NOBS);
      for (int k = 0; k < 3; ++k) obs2[OBS_C + k] += dt * obs[OBS_V + k];
      turn(obs2 + OBS_Q, obs + OBS_W, dt);
      if (bound_of(kind, qa, qb, obs2, g.cnt, &W, &g1)) return HUGE_VAL;
      const double approach = (g0 - g1) / dt;        /* > 0: closing */
      if (!(approach > 0.0)) continue;
      /* the impact's own time scale c/k (= 2 zeta sqrt(m/k), the damped contact
         spring's): in contact the error test resolves the impact on steps of that size,
         a bound by delta alone would ask for far smaller ones on a stiff contact */
      const double k = g.cnt[CNT_K], c = g.cnt[CNT_C];
      const double tc = (k > 0.0 && c > 0.0) ? c / k : 0.0;
      const double h = C->step_fraction * (((g0 > 0.0 ? g0 : 0.0) + delta) / approach + tc);
      if (h < hmax) hmax = h;
    }
  }
  return hmax;
}

double kvrod_max_step(const void* ctx, double t, const double* y, const double* yp) {
  (void) t; (void) yp;
  return kvrod_contact_max_step((const kvrod_rod*) ctx, y);
}

/* the weight 1/(rtol |y_q| + max(atol_q, a)) of an unknown the error test controls
   (w_q = 0: left out, stays out) */
static void loosen(double* w, int q, const double* y, double rtol, const double* atol,
                   double a) {
  if (w[q] == 0.0) return;
  const double tol = atol[q] > a ? atol[q] : a;
  w[q] = 1.0 / (rtol * fabs(y[q]) + tol);
}

int kvrod_contact_error_weights(const kvrod_rod* rod, const double* y, double rtol,
                                const double* atol, double* w) {
  if (!active(rod) || !(rod->contact->tolerance_rate > 0.0)) return 0;
  const kvrod_contact* C = rod->contact;
  const double rate = C->tolerance_rate;
  cwork W;
  cseg g;
  int touching = 0;
  for (int o = 0; o < C->nobs; ++o) {
    const int kind = C->kind[o];
    if (kind < 0 || kind >= KV_NKINDS) return -4;
    cscreen sc;
    screen_of(kind, rod->contact->obs + (size_t)o * NOBS, &sc);
    const double* obs = C->obs + (size_t)o * NOBS;
    for (int s = 1; s <= rod->N; ++s) {
      seg_of(rod, o, s, &g);
      double g0;
      double band = g.cnt[CNT_H];
      if (g.cnt[CNT_R] > band) band = g.cnt[CNT_R];
      const int verdict = screen(&sc, y + g.idx[0], y + g.idx[1], g.cnt[CNT_R], band);
      if (verdict > 0) continue;
      if (!verdict) {
        if (bound_of(kind, y + g.idx[0], y + g.idx[1], obs, g.cnt, &W, &g0)) return -3;
        if (g0 > band) continue;
      }
      touching = 1;
      /* the nodes' velocities at the positions' tolerance times the contact's rate */
      for (int e = 0; e < 2; ++e)
        for (int k = 0; k < 3; ++k)
          loosen(w, g.idx[2 + e] + k, y, rtol, atol, rate * atol[g.idx[e] + k]);
    }
  }
  /* a rod near an obstacle: every segment's angular velocity at its rotation's tolerance
     times the contact's rate (the bending waves the contact sends along the rod) */
  for (int s = 1; touching && s <= rod->N; ++s) {
    const int ip = i_p(rod, s), io = i_om(rod, s);
    double ap = atol[ip];
    for (int k = 1; k < 4; ++k)
      if (atol[ip + k] < ap) ap = atol[ip + k];
    for (int k = 0; k < 3; ++k) loosen(w, io + k, y, rtol, atol, rate * ap);
  }
  return 0;
}

int kvrod_error_weights(const void* ctx, const double* y, double rtol, const double* atol,
                        double* w) {
  return kvrod_contact_error_weights((const kvrod_rod*) ctx, y, rtol, atol, w);
}

int kvrod_contact_points(const kvrod_rod* rod, const double* y, double* out, int cap) {
  if (!active(rod)) return 0;
  const kvrod_contact* C = rod->contact;
  cwork W;
  cseg g;
  cdiag d;
  double glb;
  int yes, n = 0;
  for (int o = 0; o < C->nobs; ++o) {
    const int kind = C->kind[o];
    if (kind < 0 || kind >= KV_NKINDS) return -4;
    cscreen sc;
    screen_of(kind, rod->contact->obs + (size_t)o * NOBS, &sc);
    for (int s = 1; s <= rod->N; ++s) {
      seg_of(rod, o, s, &g);
      if (in_reach(kind, &g, y, &W, &yes, &glb, &sc)) return -3;
      if (!yes) continue;
      if (diag_of(kind, &g, y, &W, &d)) return -3;
      for (int q = 0; q < NQ; ++q) {
        const double gap = d.points[q + 3 * NQ];
        /* touching: the normal force is within e^-3 of its linear law's */
        if (gap > 3.0 * g.cnt[CNT_DELTA]) continue;
        if (n < cap) {
          double* row = out + (size_t)n * 6;
          row[0] = o; row[1] = s;
          for (int k = 0; k < 3; ++k) row[2 + k] = d.points[q + k * NQ];
          row[5] = gap;
        }
        ++n;
      }
    }
  }
  return n;
}
