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
/* the largest step (s) that moves no segment toward an obstacle by more than
   step_fraction (max(gap, 0) + delta) at the segments' and obstacles' current velocities
   (HUGE_VAL: no bound) */
double kvrod_contact_max_step(const kvrod_rod* rod, const double* y);
/* the same as the step loop's kv_maxstep_fn (ctx: the kvrod_rod) */
double kvrod_max_step(const void* ctx, double t, const double* y, const double* yp);
/* the quadrature points of the segments in reach, at most cap rows of 6: obstacle,
   segment, x (3), gap (m); returns the number of rows there are (> cap: truncated) */
int kvrod_contact_points(const kvrod_rod* rod, const double* y, double* out, int cap);
/* (rod library, rod_assembly.c) kvrod_energies with the per obstacle values after each
   state's NDIAG scalars (stride NDIAG + NCV nobs) */
int kvrod_energies_contact(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                           const double* yps, double* out);

#endif
