/* The static Newton iteration's model work in C (runtime/model/statics.py, RodStatics;
   included by step_loop.c): the static residual at rest, the static band Jacobian
   gathered from the rod's band Jacobian and factorised, and the retraction of a Newton
   step. solve_static (runtime/solvers/statics.py) keeps the Newton algorithm itself.

   Why C: at a few elements each Newton iteration was ~40 NumPy calls around two kernel
   calls (~80 us at N = 4, two thirds of it call overhead; a tiny sweep point spends
   half its time there). The arithmetic is NumPy's, operation by operation, so the
   results are the same bits (tests/runtime/test_statics_native.py):
   - the gather adds the products ab[src] w[widx] into a zeroed band in index order,
     as np.bincount does;
   - the retraction rounds as runtime.model.statics._rotate: its reductions over the
     last axis of length 3 and 4 sum in order, as NumPy's add.reduce does there, sin and
     cos from libm (NumPy's float64 sin and cos are libm's). */
#include <math.h>
#include <string.h>

typedef struct {
    int n, ns, ldab, kl, ku, lds;       /* full state, static unknowns, band shapes */
    int nvel, nrow, nfix, nplan, nw, nphi, nrot;
    double t;
    void *res, *jac, *ctx;              /* kvrod_residual, kvrod_jacobian_band, kvrod_rod */
    const int *vel;                     /* velocity indices (zero at rest) */
    const int *rows;                    /* static_rows: the residual rows kept */
    const int *fixed;                   /* fixed static columns (held ends) */
    const long long *src, *widx, *dst;  /* the gather plan (RodStatics._gather_plan) */
    const int *wsrc;                    /* rotation weights: y0[wsrc] * wsign */
    const double *wsign;
    const int *phi, *phi_cols;          /* positions: y[phi] += dx[phi_cols] */
    const int *p_index, *theta;         /* quaternions (nrot x 4), rotation vectors (x 3) */
    double *y0, *zeros, *r, *w, *ab, *abs;   /* work: n, n, n, 1 + nw, ldab n, lds ns */
    int *ipiv, *prof;
} kv_static;

size_t kv_static_sizeof(void) { return sizeof(kv_static); }

static void at_rest(kv_static *P, const double *y)
{
    memcpy(P->y0, y, sizeof(double) * (size_t)P->n);
    for (int k = 0; k < P->nvel; ++k) P->y0[P->vel[k]] = 0.0;
}

/* out (ns) <- the force/torque balance at rest (RodStatics.static_residual, less the
   gauge's forces, which Python adds); the kernel's return code */
int kv_static_residual(kv_static *P, const double *y, double *out)
{
    at_rest(P, y);
    int rc = ((int (*)(const void *, double, const double *, const double *, double *))
              P->res)(P->ctx, P->t, P->y0, P->zeros, P->r);
    if (rc) return rc;
    for (int i = 0; i < P->nrow; ++i) out[i] = P->r[P->rows[i]];
    for (int k = 0; k < P->nfix; ++k) out[P->fixed[k]] = 0.0;
    return 0;
}

/* abs <- the static band Jacobian at y (RodStatics.static_jacobian_band, less the
   gauge's stiffness); the kernel's return code */
int kv_static_jacobian(kv_static *P, const double *y)
{
    at_rest(P, y);
    int rc = ((int (*)(const void *, double, const double *, const double *, double, double,
                       int, double *))P->jac)(P->ctx, P->t, P->y0, P->zeros, 1.0, 0.0,
                                               P->ldab, P->ab);
    if (rc) return rc;
    P->w[0] = 1.0;
    for (int k = 0; k < P->nw; ++k) P->w[1 + k] = P->y0[P->wsrc[k]] * P->wsign[k];
    double *out = P->abs;
    memset(out, 0, sizeof(double) * (size_t)P->lds * (size_t)P->ns);
    for (int k = 0; k < P->nplan; ++k) {
        const double v = P->ab[P->src[k]] * P->w[P->widx[k]];
        out[P->dst[k]] += v;
    }
    const int diag = P->kl + P->ku;
    for (int k = 0; k < P->nfix; ++k) out[diag + (size_t)P->fixed[k] * P->lds] += 1.0;
    return 0;
}

/* LU of abs in place (kv_gbtrf: info > 0 singular) and solves with it (b overwritten) */
int kv_static_factor(kv_static *P)
{
    return kv_gbtrf(P->ns, P->kl, P->ku, P->abs, P->lds, P->ipiv, P->prof);
}

void kv_static_solve(kv_static *P, double *b)
{
    kv_gbtrs(P->ns, P->kl, P->ku, P->abs, P->lds, P->ipiv, P->prof, b);
}

/* y1 <- y with positions moved by dx and quaternions p <- p exp(dtheta / 2), normalised
   (RodStatics.static_retract, runtime.model.statics._rotate) */
void kv_static_retract(kv_static *P, const double *y, const double *dx, double *y1)
{
    memcpy(y1, y, sizeof(double) * (size_t)P->n);
    for (int k = 0; k < P->nphi; ++k) y1[P->phi[k]] += dx[P->phi_cols[k]];
    for (int i = 0; i < P->nrot; ++i) {
        const int *pi = P->p_index + 4 * i;
        const double *th = dx;
        const double t0 = th[P->theta[3 * i]], t1 = th[P->theta[3 * i + 1]],
                     t2 = th[P->theta[3 * i + 2]];
        const double a = sqrt((t0 * t0 + t1 * t1) + t2 * t2);
        const double b0 = cos(a / 2);
        const double sinc = a > 1e-8 ? sin(a / 2) / (a > 0 ? a : 1.0) : 0.5 - a * a / 48;
        const double bv[3] = {sinc * t0, sinc * t1, sinc * t2};
        const double a0 = y1[pi[0]], av[3] = {y1[pi[1]], y1[pi[2]], y1[pi[3]]};
        double o[4];
        o[0] = a0 * b0 - ((av[0] * bv[0] + av[1] * bv[1]) + av[2] * bv[2]);
        o[1] = a0 * bv[0] + b0 * av[0] + (av[1] * bv[2] - av[2] * bv[1]);
        o[2] = a0 * bv[1] + b0 * av[1] + (av[2] * bv[0] - av[0] * bv[2]);
        o[3] = a0 * bv[2] + b0 * av[2] + (av[0] * bv[1] - av[1] * bv[0]);
        const double nrm = sqrt(((o[0] * o[0] + o[1] * o[1]) + o[2] * o[2]) + o[3] * o[3]);
        for (int c = 0; c < 4; ++c) y1[pi[c]] = o[c] / nrm;
    }
}

/* One full Newton trial in one call (solve_static's common case: no gauge): the static
   band Jacobian at y and its LU (kept for more solves, as kv_static_factor), dx =
   -J^-1 f (f: the residual at y, n_s), y_try = the retraction of y by dx and res = the
   residual at y_try: what RodStatics' methods compute one NumPy call after another, the
   same operations (the same bits); the norms stay with solve_static. Returns 0; 1: the
   Jacobian's kernel failed, 2: J singular, 3: dx not finite (y_try and res not formed),
   4: the residual's kernel failed; aux[0]: the kernel's code or LAPACK's info. */
int kv_static_trial(kv_static *P, const double *y, const double *f, double *dx,
                    double *y_try, double *res, int *aux)
{
    int rc = kv_static_jacobian(P, y);
    if (rc) { aux[0] = rc; return 1; }
    rc = kv_static_factor(P);
    if (rc) { aux[0] = rc; return 2; }
    memcpy(dx, f, sizeof(double) * (size_t)P->ns);
    kv_static_solve(P, dx);
    int finite = 1;
    for (int i = 0; i < P->ns; ++i) {
        dx[i] = -dx[i];
        finite &= isfinite(dx[i]) != 0;
    }
    if (!finite) return 3;
    kv_static_retract(P, y, dx, y_try);
    rc = kv_static_residual(P, y_try, res);
    if (rc) { aux[0] = rc; return 4; }
    return 0;
}
