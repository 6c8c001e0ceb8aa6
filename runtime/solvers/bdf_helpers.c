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

typedef void (*dgbtrf_t)(int *m, int *n, int *kl, int *ku, double *ab, int *ldab,
                         int *ipiv, int *info);

/* LU of the band matrix in LAPACK storage by SciPy's dgbtrf; returns LAPACK's info.
   Then the nonzero profile of the factors per column j: prof[2j] = first stored row
   holding a nonzero of U (rows above are fill-in room left empty when pivoting does
   not use it), prof[2j+1] = number of multipliers of L up to the last nonzero. The
   solves read only the profile: less memory traffic at large n, where they are
   memory bound (the factors of N = 2000 are 11 MB). */
int kv_gbtrf(void *f, int n, int kl, int ku, double *ab, int ldab, int *ipiv, int *prof)
{
    int info = 0, m = n;
    const int kv = kl + ku;
    FTZ_ON
    ((dgbtrf_t)f)(&m, &n, &kl, &ku, ab, &ldab, ipiv, &info);
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
