/* C helpers of runtime/bdf.py; see runtime/_bdf_c.py for why they exist and what they
   measurably gain. Compiled on first use into the kvrod cache (runtime/build.py). */
#include <math.h>
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#define FTZ_ON unsigned int csr_ = _mm_getcsr(); _mm_setcsr(csr_ | 0x8040u);
#define FTZ_OFF _mm_setcsr(csr_);
#else
#define FTZ_ON
#define FTZ_OFF
#endif

/* LU with partial pivoting of a band matrix in LAPACK band storage: LAPACK's unblocked
   dgbtf2, which is what dgbtrf runs for kvrod's bands (kl < 32, its block size), with the
   same storage, pivots (1-based) and info. Written here, not called from SciPy, so that
   a run does not import scipy.linalg (0.18-0.27 s of every process start). A(i, j)
   (0-based) is ab[kv + i - j + j ldab], kv = kl + ku; rows 0..kl-1 of the storage hold
   the fill-in of the row interchanges. */
#define A_(i, j) ab[(size_t)(kv + (i) - (j)) + (size_t)(j) * (size_t)ldab]
static int gbtf2(int n, int kl, int ku, double *ab, int ldab, int *ipiv)
{
    const int kv = kl + ku;
    int info = 0, ju = 0;
    /* fill-in room of columns ku+1 .. kv-1 that the loop below does not clear */
    for (int j = ku + 1; j < (kv < n ? kv : n); ++j)
        for (int i = kv - j; i < kl; ++i)
            ab[(size_t)i + (size_t)j * ldab] = 0.0;
    for (int j = 0; j < n; ++j) {
        if (j + kv < n)
            for (int i = 0; i < kl; ++i) ab[(size_t)i + (size_t)(j + kv) * ldab] = 0.0;
        const int km = kl < n - 1 - j ? kl : n - 1 - j;
        int p = 0;
        double big = fabs(A_(j, j));
        for (int i = 1; i <= km; ++i) {
            double v = fabs(A_(j + i, j));
            if (v > big) { big = v; p = i; }
        }
        ipiv[j] = j + p + 1;
        if (A_(j + p, j) == 0.0) {
            if (info == 0) info = j + 1;
            continue;
        }
        int last = j + ku + p < n - 1 ? j + ku + p : n - 1;
        if (last > ju) ju = last;
        if (p != 0)
            for (int c = j; c <= ju; ++c) {
                double t = A_(j + p, c);
                A_(j + p, c) = A_(j, c);
                A_(j, c) = t;
            }
        if (km > 0) {
            const double r = 1.0 / A_(j, j);
            double *l = &A_(j + 1, j);
            for (int i = 0; i < km; ++i) l[i] *= r;
            for (int c = j + 1; c <= ju; ++c) {
                const double t = A_(j, c);
                if (t != 0.0) {
                    double *col = &A_(j + 1, c);
                    for (int i = 0; i < km; ++i) col[i] -= l[i] * t;
                }
            }
        }
    }
    return info;
}
#undef A_

/* LU of the band matrix in LAPACK storage (gbtf2 above); returns LAPACK's info.
   Then the nonzero profile of the factors per column j: prof[2j] = first stored row
   holding a nonzero of U (rows above are fill-in room left empty when pivoting does
   not use it), prof[2j+1] = number of multipliers of L up to the last nonzero. The
   solves read only the profile: less memory traffic at large n, where they are
   memory bound (the factors of N = 2000 are 11 MB). */
int kv_gbtrf(int n, int kl, int ku, double *ab, int ldab, int *ipiv, int *prof)
{
    const int kv = kl + ku;
    FTZ_ON
    int info = gbtf2(n, kl, ku, ab, ldab, ipiv);
    FTZ_OFF
    for (int j = 0; j < n; ++j) {
        const double *c = ab + (size_t)j * ldab;
        int r0 = 0;
        while (r0 < kv && c[r0] == 0.0) ++r0;
        int lm = n - 1 - j < kl ? n - 1 - j : kl;
        while (lm > 0 && c[kv + lm] == 0.0) --lm;
        prof[2 * j] = r0;
        prof[2 * j + 1] = lm;
    }
    return info;
}

/* b <- A^-1 b with dgbtrf's factors (LAPACK dgbtrs, TRANS = 'N'), over the profile. */
static void gbtrs(int n, int kl, int ku, const double *ab, int ldab, const int *ipiv,
                  const int *prof, double *b)
{
    const int kv = kl + ku;
    for (int j = 0; j < n - 1; ++j) {
        int lm = prof[2 * j + 1];
        int l = ipiv[j] - 1;
        double bj = b[l];
        if (l != j) { b[l] = b[j]; b[j] = bj; }
        if (bj != 0.0) {
            const double *c = ab + (size_t)j * ldab + kv + 1;
            double *bb = b + j + 1;
            for (int i = 0; i < lm; ++i) bb[i] -= c[i] * bj;
        }
    }
    for (int j = n - 1; j >= 0; --j) {
        if (b[j] != 0.0) {
            const double *c = ab + (size_t)j * ldab + kv - j;  /* c[i] = U(i, j) */
            double bj = b[j] / c[j];
            b[j] = bj;
            int i0 = j - kv + prof[2 * j];
            if (i0 < 0) i0 = 0;
            for (int i = i0; i < j; ++i) b[i] -= c[i] * bj;
        }
    }
}

/* b <- A^-1 b (LAPACK dgbtrs) with kv_gbtrf's factors and profile. */
void kv_gbtrs(int n, int kl, int ku, const double *ab, int ldab, const int *ipiv,
              const int *prof, double *b)
{
    FTZ_ON
    gbtrs(n, kl, ku, ab, ldab, ipiv, prof, b);
    FTZ_OFF
}

/* One simplified-Newton update (IDA's corrector): d = scale * J^-1 res (in res),
   ee -= d, yy -= d, ypw -= cj d; returns the weighted RMS norm of d (ewt weights). */
double kv_newton(int n, int kl, int ku, const double *ab, int ldab, const int *ipiv,
                 const int *prof, double *res, double scale, const double *ewt,
                 double *ee, double *yy, double *ypw, double cj)
{
    double s = 0.0;
    FTZ_ON
    gbtrs(n, kl, ku, ab, ldab, ipiv, prof, res);
    for (int i = 0; i < n; ++i) {
        double d = res[i] * scale;
        double w = d * ewt[i];
        res[i] = d;
        s += w * w;
        ee[i] -= d;
        yy[i] -= d;
        ypw[i] -= cj * d;
    }
    FTZ_OFF
    return n > 0 ? sqrt(s / n) : 0.0;
}

/* Weighted RMS norm sqrt(sum((v_i w_i)^2) / n); with a != NULL of (a + v). Squares of
   tiny (but normal) weighted entries underflow into subnormals: flushed here. */
double kv_wrms(int n, const double *v, const double *a, const double *w)
{
    double s = 0.0;
    FTZ_ON
    if (a) {
        for (int i = 0; i < n; ++i) { double t = (v[i] + a[i]) * w[i]; s += t * t; }
    } else {
        for (int i = 0; i < n; ++i) { double t = v[i] * w[i]; s += t * t; }
    }
    FTZ_OFF
    return n > 0 ? sqrt(s / n) : 0.0;
}

/* IDA's interpolant of one step at m times (BDFDenseOutput.values): y(t_i) = sum_j
   c_j(t_i) phi_j and y'(t_i) = sum_j d_j(t_i) phi_j, phi (k+1, n) C order, out_y and
   out_yp (m, n) C order. The coefficients are IDA's recurrences (bdf.py's
   _interp_coefficients); one call replaces about twenty NumPy calls per step. */
void kv_interp(int k, int n, int m, double tn, const double *psi, const double *phi,
               const double *ts, double *out_y, double *out_yp)
{
    double c[6], d[6];
    for (int i = 0; i < m; ++i) {
        const double delt = ts[i] - tn;
        double cs = 1.0, ds = 0.0, gs = delt / psi[0];
        c[0] = 1.0;
        d[0] = 0.0;
        for (int j = 1; j <= k; ++j) {
            ds = ds * gs + cs / psi[j - 1];
            cs = cs * gs;
            if (j < k) gs = (delt + psi[j - 1]) / psi[j];
            c[j] = cs;
            d[j] = ds;
        }
        double *y = out_y + (size_t)i * n, *yp = out_yp + (size_t)i * n;
        for (int q = 0; q < n; ++q) { y[q] = phi[q]; yp[q] = 0.0; }
        for (int j = 1; j <= k; ++j) {
            const double *pj = phi + (size_t)j * n;
            const double cj = c[j], dj = d[j];
            for (int q = 0; q < n; ++q) { y[q] += cj * pj[q]; yp[q] += dj * pj[q]; }
        }
    }
}
