/*
 * C API of the discrete rod (runtime/model/native/rod_assembly.c; layout:
 * generated/rod_layout.h and generated/rod_layout.py).
 *
 * A rod is described by kvrod_rod: N elements, the global parameter vector (PARAMS), the
 * per-segment parameters (N rows of SEGMENT_PARAMS), the per-joint parameters (N+1 rows of
 * JOINT_PARAMS, joint j at node j), the node loads (N+1 rows of NODE_LOADS) and the
 * segment loads (N rows of SEGMENT_LOADS), all row-major; for a generalized Maxwell rod
 * also nb relaxation terms: their times theta (nb) and moduli C_b of every segment
 * (N x nb x 3) and joint ((N+1) x nb x 3); nb = 0 for Kelvin-Voigt (the pointers unused);
 * for a rod with coupled sections (coupled = 1, nb = 0) the rows of COUPLED_SEGMENT_PARAMS
 * and COUPLED_JOINT_PARAMS (docs/design.md, section 10).
 * y, yp: state and its time derivative (length kvrod_n_state(N, nb)); res: the residual
 * F(t, y, y') (same length). Band storage is LAPACK dgbtrf's with the rod's kl, ku
 * (at least kvrod_kl(N, nb), kvrod_ku(N, nb)): ab has ldab >= 2*kl+ku+1 rows and n
 * columns (Fortran order), element (i, j) at ab[kl + ku + i - j + j*ldab].
 * Return value 0 on success, negative on error (-1: N < 1 or nb outside 0..MAX_NB (rod_layout.h),
 * -2: band too narrow, -3: kernel failure, -4: cells outside the rod or the storage).
 */
#ifndef KVROD_ROD_ASSEMBLY_H
#define KVROD_ROD_ASSEMBLY_H
#ifdef __cplusplus
extern "C" {
#endif

typedef struct kvrod_contact_s kvrod_contact;   /* rod_contact.h */

typedef struct {
  int N;                  /* number of elements (segments) */
  int nb;                 /* number of relaxation terms (0: Kelvin-Voigt) */
  int kl, ku;             /* band widths of the caller's band storage */
  const double* par;      /* global parameters: NPAR values (rod_layout.h) */
  const double* seg;      /* N x NSEG segment parameters */
  const double* jnt;      /* (N+1) x NJNT joint parameters */
  const double* nload;    /* (N+1) x NNL node loads */
  const double* sload;    /* N x NSL segment loads */
  const double* theta;    /* nb relaxation times (s) */
  const double* segb;     /* N x nb x 3 moduli of the relaxation terms on segments (N) */
  const double* jntb;     /* (N+1) x nb x 3 moduli on joints (N m^2) */
  int coupled;            /* 1: coupled sections (nb = 0): the kernels rod_coupled_* with
                             segc, jntc instead of the diagonal ones; band KLC, KUC */
  const double* segc;     /* N x NSEGC coupled segment parameters (coupled only) */
  const double* jntc;     /* (N+1) x NJNTC coupled joint parameters (coupled only) */
  const kvrod_contact* contact;   /* obstacles the rod touches (NULL: none; rod_contact.h):
                                     their forces are part of the residual, the Jacobian
                                     and the energies below */
  const unsigned char* relax_need; /* read by kvrod_jacobian_band_cells_relaxed only: per
                                      state index, bit 0: its column, bit 1: its row is
                                      wanted in full (else only its diagonal entry);
                                      NULL: everything in full */
} kvrod_rod;

int kvrod_n_state(int N, int nb);
int kvrod_kl(int N, int nb);
int kvrod_ku(int N, int nb);
int kvrod_n_params(void);

/* F(t, y, y') = 0 in IDA form */
int kvrod_residual(const kvrod_rod* rod, double t, const double* y, const double* yp,
                   double* res);

/* ab <- cy dF/dy + cj dF/dy' */
int kvrod_jacobian_band(const kvrod_rod* rod, double t, const double* y, const double* yp,
                        double cy, double cj, int ldab, double* ab);

/* The same, element by element: the contributions of elements i0..i1 (element i: node i,
 * segment i, joint i; cell i of the layout) to cy dF/dy + cj dF/dy', into band storage
 * that holds columns col0.. of J (J(i, j) at ab[kl + ku + i - j + (j - col0)*ldab]).
 * Element i adds to the columns of cells i-1..i+1 and zeroes those of cell i+1 first (and
 * of cell 0 when i0 = 0), so after elements 0..i the columns of cells <= i-1 are final:
 * a caller can factor cell by cell behind the sweep, holding a few cells of columns
 * (col0 at most the first column of cell i0-1; -4 otherwise or for i0, i1 outside 0..N).
 * kvrod_jacobian_band is kvrod_jacobian_band_cells(..., 0, 0, N). */
int kvrod_jacobian_band_cells(const kvrod_rod* rod, double t, const double* y,
                              const double* yp, double cy, double cj, int ldab, double* ab,
                              int col0, int i0, int i1);

/* kvrod_jacobian_band_cells for a caller that eliminates a generalized Maxwell rod's
 * internal strains by their declared structure (runtime/solvers/native/relaxation.py:
 * of an internal strain's row and column it reads the diagonal entry, the first term's
 * rows and one reference column per strain, the rows and columns marked in
 * rod->relax_need): the entries of the unmarked rows and columns off the diagonal are
 * neither formed nor cleared (their storage keeps what it held). Every entry it forms
 * is that of kvrod_jacobian_band_cells, bit for bit. */
int kvrod_jacobian_band_cells_relaxed(const kvrod_rod* rod, double t, const double* y,
                                      const double* yp, double cy, double cj, int ldab,
                                      double* ab, int col0, int i0, int i1);
/* kvrod_jacobian_band_cells_relaxed over the whole rod (statics: it reads no relaxation
 * row or column, relax_need 0 on them; an element's branch kernel then does not run) */
int kvrod_jacobian_band_relaxed(const kvrod_rod* rod, double t, const double* y,
                                const double* yp, double cy, double cj, int ldab, double* ab);

/* out <- [the NDIAG scalars: kinetic, elastic, 2D, external power, boundary power, then the
 *         supports' force and moment at s = 0 and s = L (12, spatial); V (3N), F (3N),
 *         U (3(N+1)), M (3(N+1))] */
int kvrod_diagnostics(const kvrod_rod* rod, double t, const double* y, const double* yp,
                      double* out);

/* out[k] <- the NDIAG scalars of kvrod_diagnostics of the m states
 * ys[k*n .. (k+1)*n), yps[...] (the energy quadrature of a step in one call) */
int kvrod_energies(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                   const double* yps, double* out);

/* kvrod_energies' 2D (out[k NDIAG + 2]) and powers P_ext, P_bc (out[k NDIAG + 3, 4]) alone,
 * bit for bit, for the energy audit's quadrature points (the kinetic energy and the
 * supports' moments are left 0). With obstacles the stride is kvrod_energies_contact's
 * (NDIAG + NCV nobs), the contact's terms added as there and the obstacles' values not
 * written; with self-contact it is kvrod_energies_contact itself */
int kvrod_audit_powers(const kvrod_rod* rod, int m, const double* ts, const double* ys,
                       const double* yps, double* out);

#ifdef __cplusplus
}
#endif
#endif
