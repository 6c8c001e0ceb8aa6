// GENERATED FILE - do not edit; regenerate with `kvrod generate`.
// source: derive/templates/rod_assembly.h.jinja
// derivation step: discrete_rod
// inputs sha256: 0642b256e9cead5361d59e1dd3ccbe3519a8fca84b3c47e84a376b9888571a18
// tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

/*
 * C API of the discrete rod (layout: generated/rod_layout.py).
 *
 * N: number of elements; par: parameter vector (rod_layout.PARAMS); y, yp: state and its
 * time derivative (length kvrod_n_state(N)); res: residual F(t, y, y') (same length).
 * Band storage is LAPACK dgbtrf's: ab has ldab >= 2*KL+KU+1 rows and n columns (Fortran
 * order), element (i, j) of the matrix at ab[KL + KU + i - j + j*ldab].
 * Return value 0 on success, negative on error.
 */
#ifndef KVROD_ROD_ASSEMBLY_H
#define KVROD_ROD_ASSEMBLY_H
#ifdef __cplusplus
extern "C" {
#endif

int kvrod_n_state(int N);
int kvrod_kl(void);
int kvrod_ku(void);
int kvrod_n_params(void);

/* F(t, y, y') = 0 in IDA form */
int kvrod_residual(int N, const double* par, double t, const double* y, const double* yp,
                   double* res);

/* ab <- dF/dy + cj dF/dy' */
int kvrod_jacobian_band(int N, const double* par, double t, const double* y,
                        const double* yp, double cj, int ldab, double* ab);

/* ab <- cy dF/dy + cj dF/dy' */
int kvrod_jacobian_band2(int N, const double* par, double t, const double* y,
                         const double* yp, double cy, double cj, int ldab, double* ab);

/* out <- [kinetic, elastic, 2D, external power, V (3N), F (3N), U (3(N+1)), M (3(N+1))] */
int kvrod_diagnostics(int N, const double* par, double t, const double* y, const double* yp,
                      double* out);

#ifdef __cplusplus
}
#endif
#endif
