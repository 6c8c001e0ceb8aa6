/*
 * Where the rod's unknowns and numbers are (generated/rod_layout.h): the indices of a
 * node's, segment's and joint's fields in the state, the rows of the per-element
 * arrays, the lumped node masses and lengths and the held ends' prescribed values.
 * Shared by the residual's assembly (rod_assembly.c) and its tangent (rod_tangent.c);
 * every function takes a kvrod_rod, which for the tangent may also hold the derivatives
 * of the arrays (the same layout).
 */
#ifndef KVROD_ROD_ACCESS_H
#define KVROD_ROD_ACCESS_H
#include <stddef.h>
#include "rod_layout.h"
#include "rod_assembly.h"

/* indices of the fields of node i / segment i (i >= 1) / joint j in y */
static inline int c0size(const kvrod_rod* r) { return CELL0_BASE + CELL0_PER * r->nb; }
static inline int csize(const kvrod_rod* r) { return CELL_BASE + CELL_PER * r->nb; }
static inline int cs(const kvrod_rod* r, int i) {
  return i == 0 ? 0 : c0size(r) + csize(r) * (i - 1);
}
static inline int i_phi(const kvrod_rod* r, int i) {
  return i == 0 ? CELL0_PHI_BASE + CELL0_PHI_PER * r->nb
                : cs(r, i) + CELL_PHI_BASE + CELL_PHI_PER * r->nb;
}
static inline int i_v(const kvrod_rod* r, int i) {
  return i == 0 ? CELL0_V_BASE + CELL0_V_PER * r->nb
                : cs(r, i) + CELL_V_BASE + CELL_V_PER * r->nb;
}
static inline int i_p(const kvrod_rod* r, int i) {
  return cs(r, i) + CELL_P_BASE + CELL_P_PER * r->nb;
}
static inline int i_om(const kvrod_rod* r, int i) {
  return cs(r, i) + CELL_OMEGA_BASE + CELL_OMEGA_PER * r->nb;
}
/* internal strains: segment i's 3 nb values and joint j's 3 nb values (term b at 3b) */
static inline int i_qs(const kvrod_rod* r, int i) {
  return cs(r, i) + CELL_Q_SEGMENT_BASE + CELL_Q_SEGMENT_PER * r->nb;
}
static inline int i_qj(const kvrod_rod* r, int j) {
  return j == 0 ? CELL0_Q_JOINT_BASE + CELL0_Q_JOINT_PER * r->nb
                : cs(r, j) + CELL_Q_JOINT_BASE + CELL_Q_JOINT_PER * r->nb;
}

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
/* moduli C_b (3) of relaxation term b on segment i / joint j */
static inline const double* segb(const kvrod_rod* r, int i, int b) {
  return r->segb + ((size_t)(i - 1) * (size_t)r->nb + (size_t)b) * 3;
}
static inline const double* jntb(const kvrod_rod* r, int j, int b) {
  return r->jntb + ((size_t)j * (size_t)r->nb + (size_t)b) * 3;
}

/* lumped node mass (kg) and length (m): half of each adjacent segment */
static inline double node_mass(const kvrod_rod* r, int i) {
  double m = 0.0;
  if (i >= 1) m += 0.5 * segp(r, i)[SEG_RHOA] * segp(r, i)[SEG_H];
  if (i < r->N) m += 0.5 * segp(r, i + 1)[SEG_RHOA] * segp(r, i + 1)[SEG_H];
  return m;
}

static inline double node_length(const kvrod_rod* r, int i) {
  double l = 0.0;
  if (i >= 1) l += 0.5 * segp(r, i)[SEG_H];
  if (i < r->N) l += 0.5 * segp(r, i + 1)[SEG_H];
  return l;
}

static inline double node_held(const kvrod_rod* r, int i) {
  if (i == 0) return r->par[PAR_FIX_START];
  if (i == r->N) return r->par[PAR_FIX_END];
  return 0.0;
}

/* the segment whose frame carries node i's follower force */
static inline int host(int i) { return i >= 1 ? i : 1; }

static inline const double* held_r(const kvrod_rod* r, int i) {
  return r->par + (i == 0 ? PAR_R_START : PAR_R_END);
}

static inline const double* held_v(const kvrod_rod* r, int i) {
  return r->par + (i == 0 ? PAR_V_START : PAR_V_END);
}

static inline const double* held_a(const kvrod_rod* r, int i) {
  return r->par + (i == 0 ? PAR_A_START : PAR_A_END);
}

static inline int has_follower(const double* f) { return f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0; }

/* coupled sections: the rows of the coupled tables */
static inline const double* segcp(const kvrod_rod* r, int i) {
  return r->segc + (size_t)(i - 1) * NSEGC;
}
static inline const double* jntcp(const kvrod_rod* r, int j) {
  return r->jntc + (size_t)j * NJNTC;
}

#endif
