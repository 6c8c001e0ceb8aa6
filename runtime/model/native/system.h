/*
 * C API of an assembly of rods (runtime/model/native/system.c; runtime/model/system.py
 * builds the struct and says what each table holds; docs/design.md, section 12).
 *
 * The state is the rods' states one after the other (rod r from off[r]). Three kinds of
 * coupling act on it:
 * - holds: a node's position and velocity rows replaced by those of a support (ground:
 *   phi - r, v - 0) or of a tie to another node, its group's master (phi - phi_m,
 *   v - v_m; the node's momentum row, computed as if free, added to the master's: the
 *   joint's force cancels between the two, which is index reduction without a
 *   multiplier);
 * - links (generated rod_link_* kernels): joint stiffness and damping between frames and
 *   nodes of any rods or the ground (welds, hinges, rotational and 6x6 springs);
 * - bodies (generated rod_body_* kernels): rigid bodies welded at a node.
 * The rows of a held node get the links' and bodies' forces before the hold acts on them:
 * a slave passes them to its master, a support carries them (its reaction).
 * The Jacobian goes into one buffer: every rod's band storage, then the values of the
 * couplings E (runtime/solvers/native/blocks.c); the destination of every entry is
 * precomputed (flat index into that buffer).
 */
#ifndef KVROD_SYSTEM_H
#define KVROD_SYSTEM_H
#include "rod_assembly.h"
#include "rod_contact.h"

typedef struct {
  int n, nrod;
  const kvrod_rod* const* rod;   /* per rod */
  const int* off;                /* nrod + 1 state offsets */
  double* J;                     /* the Jacobian buffer (blocks' bands, then E) */
  const long long* ab_start;     /* nrod: where rod r's band storage starts in J */
  const int* ldab;               /* nrod */
  /* holds: per hold 4 ints (global phi row, global v row, master phi, master v; the
     masters -1 for a support), ground position (3 per hold) */
  int nhold;
  const int* hold;
  const double* hold_r;
  const long long* hold_e;       /* per hold 6: E slots (flat in J) of the -1 entries
                                    (slave rows, master columns); -1 for a support */
  /* the slaves' momentum rows into their masters': residual rows (per hold: the slave's
     v row into the master's, 3 rows; see hold) and the Jacobian's entries (src flat in
     J -> dst flat in J), then the entries of the held rows outside their bands zeroed */
  int ncopy;
  const long long* copy_src;
  const long long* copy_dst;
  int nzero;
  const long long* zero;
  long long ev_start;            /* the couplings' values: J[ev_start .. + nev) */
  int nev;
  /* links: per link 12 global indices (phi_a, phi_b, v_a, v_b, p_a1, p_a2, p_b1, p_b2,
     Omega_a1, Omega_a2, Omega_b1, Omega_b2; -1: a constant in lconst), their residual
     rows (18: f_a, f_b, T_a1, T_a2, T_b1, T_b2; -1: none, e.g. a support or an absent
     frame), the parameters (NLNK each), the constants (40 per link: the inputs in the
     order above, used where the index is -1) and the Jacobian's destinations (18 x 40
     per link, row-major; -1: dropped) */
  int nlink;
  const int* lidx;
  const int* lrow;
  const double* lpar;
  const double* lconst;
  const long long* ldst;
  /* bodies: per body 3 global indices (the node's v, the segment's p and Omega), their
     residual rows (6: the node's momentum, the segment's angular momentum; -1: none), the
     parameters (NBDY each), the Jacobian's destinations (6 x 10, row-major) */
  int nbody;
  const int* bidx;
  const int* brow;
  const double* bpar;
  const long long* bdst;
  double gravity[3];             /* scaled gravity acting on the bodies (m/s^2) */
  int nextra;                    /* extras per state of kvsys_energies (see there) */
  double* scratch;               /* n doubles of work (the holds' free rows) */
  /* the contact between the rods' segments (contact.self; NULL: none): the pairs over
     all rods (kvrod_self with nrod > 0) and the contact library's kvsys_pairs_*
     (rod_contact.h; the rod library reaches them through these pointers). Their forces
     join the free residual (before the holds act), their energy W and their
     dissipation 2D; their Jacobian's entries within a segment its rod's band (before the
     slaves' rows move to their masters'), those between two segments the blocks'
     dynamic couplings */
  kvrod_self* pairs;
  int (*pair_residual)(const kvrod_self* S, const double* y, double* res);
  int (*pair_jacobian)(const kvrod_self* S, const double* y);
  int (*pair_couplings)(kvrod_self* S, const double* y);
  int (*pair_values)(const kvrod_self* S, const double* y, double* v);
  double (*pair_max_step)(const kvrod_self* S, const double* y);
} kvsys;

int kvsys_residual(const kvsys* s, double t, const double* y, const double* yp, double* res);
int kvsys_jacobian(const kvsys* s, double t, const double* y, const double* yp, double cj,
                   void* blocks);
double kvsys_max_step(const void* ctx, double t, const double* y, const double* yp);
int kvsys_energies(const kvsys* s, int m, const double* ts, const double* ys,
                   const double* yps, double* out);
int kvsys_link_values(const kvsys* s, int k, const double* y, double* Q, double* diag);

#endif
