/*
 * Contact of a rod with rigid obstacles (runtime/model/native/rod_contact.c; issue 32,
 * docs/design.md, section 14). The kernels are generated (generated/rod_contact_kernels.c
 * from derive/contact.py); this file holds the loops over obstacles and segments.
 *
 * A rod carries its obstacles in kvrod_rod.contact (NULL or nobs = 0: no contact, and
 * every function below adds nothing). Per obstacle: its kernel kind, its parameter vector
 * (NOBS values, its current pose first: written by runtime/model/contact.py as the
 * obstacle moves) and per segment the contact law's parameters (NCNT values: k, delta,
 * c, mu, v_s, r, h). All functions but kvrod_energies_contact are the contact library's
 * (rod_contact.c with the generated kernels); the rod library reaches them through the
 * pointers of kvrod_contact. The contact forces act on the nodes' momentum rows and the
 * segment's angular momentum rows, as the segment's internal forces do (none on the rows
 * of a node the rod's own end condition holds); they depend on the state y only.
 */
#ifndef KVROD_ROD_CONTACT_H
#define KVROD_ROD_CONTACT_H
#include "rod_assembly.h"

/* the kernel kinds (derive.contact.OBSTACLE_KINDS, in order) */
enum { KV_PLANE = 0, KV_SPHERE = 1, KV_CYLINDER = 2, KV_PIPE = 3, KV_NKINDS = 4 };

/* per obstacle values of kvrod_contact_values: the force (3, N) and moment (3, N m,
   about the obstacle's point c) the obstacle exerts on the rod (spatial), the contact
   energy E (J), the dissipated power P_diss (W: damping and friction), its friction part
   P_fric (W), the power of the obstacle's motion on the rod P_obs (W), the smallest gap
   g_min (m; of the quadrature points of all segments) and the number of
   segments in reach (bound below CONTACT_CUTOFF delta) */
#define NCV 12

/* self-contact of a rod (contact.self; rod_self_contact.c): the pairs of its segments
   that are not near each other along it, found by a sweep over the segments' bounding
   spheres along the axis in which the midpoints spread most, each pair's forces from the
   generated rod_contact_pair kernels. Per segment its law in the CNT layout (k, delta, c,
   mu, v_s, r, h: c the normal damping per length of the segment on a rigid obstacle,
   2 zeta sqrt(k rhoA); a pair takes c_1 c_2 / sqrt(c_1^2 + c_2^2) = 2 zeta sqrt(k m), m
   the reduced mass per length). The arrays marked work are scratch the caller owns. */
typedef struct {
  const double* seg;     /* N x NCNT: segment s at row s - 1 */
  const double* s0;      /* N + 1: the reference arc length of each node (m) */
  double near;           /* segments i < j with s0[j-1] - s0[i] < near (r_i + r_j) are not
                            paired (pi/2: a rod bent to its tightest keeps stretches
                            closer than pi r along it within 2 r) */
  double* key;           /* work, 3 N + 1 */
  int* pairs;            /* work, 2 paircap: the pairs in reach (i < j, 1-based) */
  int paircap;
  /* the Jacobian's entries between the two segments of a pair lie outside the rod's band
     (or outside its cells): kvrod_self_couplings writes them as the dynamic coupling rows
     of the rod's coupled band block (runtime/solvers/native/blocks.c: m2, srow2, er2,
     ec2, ev2, at most m2cap rows, nz2cap entries); the band is ab (ldab x n) */
  double* ab;
  int ldab;
  int* m2;
  int m2cap, nz2cap;
  int* srow2;
  int* er2;
  int* ec2;
  double* ev2;
  int* rowslot;          /* work, n: -1 */
  int* rowfill;          /* work, m2cap */
  int dropped;           /* pairs whose couplings did not fit at the last Jacobian */
  /* the contact between the rods of an assembly (system.c; nrod = 0: a single rod's,
     reached through that rod's kvrod_contact): its nrod rods, their state offsets off
     (nrod + 1) and first segments sg0 (nrod + 1: rod r's segments are the global
     segments sg0[r] + 1 .. sg0[r + 1], seg and s0 run over all rods, s0 holding rod r's
     nodes from sg0[r] + r); rowmap (n, or NULL: the row itself) where a momentum row's
     Jacobian entries go in the couplings: its own row, its master's (a node a joint ties
     to another: the system adds the node's momentum row to its master's) or -1 (a node
     a joint holds at ground: its rows are the support's); J the system's Jacobian
     buffer, rod r's band storage at J + ab_start[r] (leading dimension ldabs[r]) */
  int nrod;
  const kvrod_rod* const* rods;
  const int* off;
  const int* sg0;
  const int* rowmap;
  double* J;
  const long long* ab_start;
  const int* ldabs;
  double* last;          /* NSV: the values of the last kvrod_contact_energies (a single
                            rod's: kvrod_energies_contact's outputs; NULL: not kept) */
  double step_fraction;  /* the step bound by the approach speed (as an obstacle's: a
                            step closes at most this fraction of a pair's gap plus delta;
                            0: none) */
} kvrod_self;

struct kvrod_contact_s {
  int nobs;
  const int* kind;       /* nobs kernel kinds */
  const double* obs;     /* nobs x NOBS */
  const double* cnt;     /* nobs x N x NCNT (segment s at row s - 1) */
  double step_fraction;  /* the step bound: a step moves a segment toward an obstacle by
                            at most this fraction of its gap plus delta (0: no bound) */
  /* the contact library's functions below (runtime/model/build.py compiles it apart, on
     the first problem with obstacles: the rod library without contact stays as small and
     as quick to compile as before); the rod assembly calls them through these */
  int (*residual)(const kvrod_rod* rod, const double* y, double* res);
  int (*jacobian)(const kvrod_rod* rod, const double* y, double cy, int ldab, double* ab,
                  int col0, int s0, int s1);
  int (*energies)(const kvrod_rod* rod, const double* y, double* e);
  int (*values)(const kvrod_rod* rod, const double* y, double* out);
  double (*max_step)(const kvrod_rod* rod, const double* y);
  kvrod_self* self;      /* self-contact (NULL: off) */
  int (*couplings)(const kvrod_rod* rod, const double* y);
  /* the error test's tolerances near an obstacle (kvrod_contact_error_weights): the
     contact's rate sqrt(k / rho A) (1/s; 0: the run's own tolerances everywhere) */
  double tolerance_rate;
  int (*energies_values)(const kvrod_rod* rod, const double* y, double* e, double* out);
};

/* res[rows] -= Q of every segment in reach of an obstacle */
int kvrod_contact_residual(const kvrod_rod* rod, const double* y, double* res);
/* cy dQ/dy of segments s0..s1 (1..N) subtracted into band storage holding columns col0..
   (kvrod_jacobian_band_cells' storage) */
int kvrod_contact_jacobian(const kvrod_rod* rod, const double* y, double cy, int ldab,
                           double* ab, int col0, int s0, int s1);
/* e[1] += E, e[2] += P_diss, e[3] += P_obs (kvrod_diagnostics' first scalars); the
   contact forces on the held end nodes (which the residual leaves to the supports) taken
   by the supports: subtracted from their reactions (e + NDIAG_E) and, times the held
   node's velocity, from the boundary power e[4] */
int kvrod_contact_energies(const kvrod_rod* rod, const double* y, double* e);
/* out (nobs x NCV) <- the values above */
int kvrod_contact_values(const kvrod_rod* rod, const double* y, double* out);
/* kvrod_contact_energies and kvrod_contact_values in one pass over the segments (the
   same values, bit for bit: what kvrod_energies_contact calls) */
int kvrod_contact_energies_values(const kvrod_rod* rod, const double* y, double* e,
                                  double* out);
/* the largest step (s) that moves no segment toward an obstacle by more than
   step_fraction (max(gap, 0) + delta) at the segments' and obstacles' current velocities
   (HUGE_VAL: no bound) */
double kvrod_contact_max_step(const kvrod_rod* rod, const double* y);
/* the same as the step loop's kv_maxstep_fn (ctx: the kvrod_rod) */
double kvrod_max_step(const void* ctx, double t, const double* y, const double* yp);
/* the error test's weights near obstacles: for every segment whose gap bound is within
   its length (or its contact radius, the larger) of an obstacle, the absolute tolerance
   of its nodes' velocities becomes at least tolerance_rate times their positions' and
   that of its angular velocity tolerance_rate times its rotation's; w = 1/(rtol |y| +
   atol) of the step loop's error test, changed in place (entries 0 stay 0). Returns 0,
   -3 when a kernel fails, -4 for an unknown kind */
int kvrod_contact_error_weights(const kvrod_rod* rod, const double* y, double rtol,
                                const double* atol, double* w);
/* the same as the step loop's kv_errw_fn (ctx: the kvrod_rod) */
int kvrod_error_weights(const void* ctx, const double* y, double rtol, const double* atol,
                        double* w);
/* the quadrature points of the segments in reach, at most cap rows of 6: obstacle,
   segment, x (3), gap (m); returns the number of rows there are (> cap: truncated) */
int kvrod_contact_points(const kvrod_rod* rod, const double* y, double* out, int cap);
/* the self-contact pairs' Jacobian entries between their two segments (the entries
   within a segment are kvrod_contact_jacobian's) into the dynamic coupling rows of
   kvrod_self: -dQ/dy; rows with the same global row merged; returns 0, -3 when a kernel
   fails (pairs beyond the capacity are left out of the couplings: counted in dropped) */
int kvrod_self_couplings(const kvrod_rod* rod, const double* y);
/* the self-contact parts of kvrod_contact_residual and kvrod_contact_jacobian (the
   entries within each segment of a pair whose segment lies in s0..s1) */
int kvrod_self_residual(const kvrod_rod* rod, const double* y, double* res);
int kvrod_self_jacobian(const kvrod_rod* rod, const double* y, double cy, int ldab,
                        double* ab, int col0, int s0, int s1);
/* self-contact energies: e[1] += E, e[2] += P_diss over the pairs in reach; v (NSV) the
   pairs' values (rod_self_contact.c): E (J), P_diss (W), its friction part P_fric (W),
   the smallest gap (m; HUGE_VAL: no pair), the number of pairs in reach, the sum of the
   magnitudes of the pairs' forces |F_12| (N) */
#define NSV 6
int kvrod_self_values(const kvrod_rod* rod, const double* y, double* v);
/* the contact between the rods of an assembly (kvrod_self with nrod > 0; y and res the
   system's state and residual): the forces into res before the system's holds act on
   it; the Jacobian's entries within each segment (cy = 1) into its rod's band in S->J
   and those between the two segments of a pair into the dynamic couplings (rows mapped
   by S->rowmap); the values (NSV) of the pairs in reach */
int kvsys_pairs_residual(const kvrod_self* S, const double* y, double* res);
int kvsys_pairs_jacobian(const kvrod_self* S, const double* y);
int kvsys_pairs_couplings(kvrod_self* S, const double* y);
int kvsys_pairs_values(const kvrod_self* S, const double* y, double* v);
/* the largest step (s) that closes no pair's gap by more than S->step_fraction of it
   plus delta at the nodes' current velocities, for pairs within a horizon D (twice the
   longest segment, four largest radii and CONTACT_CUTOFF delta) found by the sweep;
   pairs farther apart close at most twice the largest node speed about the mean
   velocity, which bounds the step by step_fraction D / that (HUGE_VAL: no bound); a
   single rod's (through kvrod_contact_max_step) and an assembly's */
double kvrod_self_max_step(const kvrod_rod* rod, const double* y);
double kvsys_pairs_max_step(const kvrod_self* S, const double* y);
/* (rod library, rod_assembly.c) the Newton matrix of a rod with self-contact into its
   coupled band block: the band (kvrod_jacobian_band with cy = 1) and the couplings; the
   step loop's kv_sysjac_fn (ctx: the kvrod_rod; blocks unused: kvrod_self points into
   them) */
int kvrod_jacobian_system(const void* ctx, double t, const double* y, const double* yp,
                          double cj, void* blocks);
/* (rod library, rod_assembly.c) kvrod_energies with the per obstacle values after each
   state's NDIAG scalars, then with self-contact the pairs' NSV values (stride NDIAG +
   NCV nobs (+ NSV)) */
int kvrod_energies_contact(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                           const double* yps, double* out);

#endif
