/* Band linear algebra and vector kernels of the BDF integrator: LU of a band matrix and
   its solves, the fused Newton update, weighted norms, the interpolant of a step.
   Why C and what it measurably gains: runtime/solvers/native/__init__.py. Compiled on
   first use, as one unit with condensed.c through step_loop.c (loader.py). */
#include <float.h>
#include <math.h>
#include <string.h>
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#include <emmintrin.h>
#define KV_STREAM 1                 /* non-temporal stores (kv_interp) */
#define FTZ_ON unsigned int csr_ = _mm_getcsr(); _mm_setcsr(csr_ | 0x8040u);
#define FTZ_OFF _mm_setcsr(csr_);
#else
#define FTZ_ON
#define FTZ_OFF
#define KV_STREAM 0
#endif

#if defined(__GNUC__)
#define KV_INLINE static inline __attribute__((always_inline))
#else
#define KV_INLINE static inline
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
   memory bound (the factors of N = 2000 are 11 MB). No FTZ handling (callers' job). */
static int gbtrf_raw(int n, int kl, int ku, double *ab, int ldab, int *ipiv, int *prof)
{
    const int kv = kl + ku;
    int info = gbtf2(n, kl, ku, ab, ldab, ipiv);
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

/* gbtrf_raw with flush-to-zero. */
int kv_gbtrf(int n, int kl, int ku, double *ab, int ldab, int *ipiv, int *prof)
{
    FTZ_ON
    int info = gbtrf_raw(n, kl, ku, ab, ldab, ipiv, prof);
    FTZ_OFF
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

/* The corrector update after a solve: d = scale * res (in res), ee -= d, yy -= d,
   ypw -= cj d; returns the sum of (d ewt)^2. */
static double newton_update(int n, double *res, double scale, const double *ewt,
                            double *ee, double *yy, double *ypw, double cj)
{
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        double d = res[i] * scale;
        double w = d * ewt[i];
        res[i] = d;
        s += w * w;
        ee[i] -= d;
        yy[i] -= d;
        ypw[i] -= cj * d;
    }
    return s;
}

/* One simplified-Newton update (IDA's corrector): d = scale * J^-1 res (in res),
   ee -= d, yy -= d, ypw -= cj d; returns the weighted RMS norm of d (ewt weights). */
double kv_newton(int n, int kl, int ku, const double *ab, int ldab, const int *ipiv,
                 const int *prof, double *res, double scale, const double *ewt,
                 double *ee, double *yy, double *ypw, double cj)
{
    FTZ_ON
    gbtrs(n, kl, ku, ab, ldab, ipiv, prof, res);
    double s = newton_update(n, res, scale, ewt, ee, yy, ypw, cj);
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
   out_yp (m, n) C order (out_yp NULL: y only). The coefficients are IDA's recurrences (bdf.py's
   _interp_coefficients); one call replaces about twenty NumPy calls per step. */
/* y = sum_j c_j phi_j, yp = sum_j d_j phi_j over components lo..hi-1, summed in j order
   per component; k a literal at the call sites, so that the j loop unrolls and the q
   loop vectorises */
KV_INLINE void interp_span(int k, int lo, int hi, const double *const *ph, const double *c,
                           const double *d, double *restrict y, double *restrict yp)
{
    for (int q = lo; q < hi; ++q) {
        double a = ph[0][q], b = 0.0;
        for (int j = 1; j <= k; ++j) { a += c[j] * ph[j][q]; b += d[j] * ph[j][q]; }
        y[q] = a;
        yp[q] = b;
    }
}

/* interp_span without y' (the same y, bit for bit) */
KV_INLINE void interp_span_y(int k, int lo, int hi, const double *const *ph, const double *c,
                             double *restrict y)
{
    for (int q = lo; q < hi; ++q) {
        double a = ph[0][q];
        for (int j = 1; j <= k; ++j) a += c[j] * ph[j][q];
        y[q] = a;
    }
}

#if KV_STREAM
/* interp_span on pairs from lo (16-byte aligned in y and yp) with non-temporal stores;
   returns the first component not done */
KV_INLINE int interp_stream(int k, int lo, int hi, const double *const *ph, const double *c,
                            const double *d, double *restrict y, double *restrict yp)
{
    int q = lo;
    for (; q + 1 < hi; q += 2) {
        double a0 = ph[0][q], a1 = ph[0][q + 1], b0 = 0.0, b1 = 0.0;
        for (int j = 1; j <= k; ++j) {
            const double p0 = ph[j][q], p1 = ph[j][q + 1];
            a0 += c[j] * p0; a1 += c[j] * p1;
            b0 += d[j] * p0; b1 += d[j] * p1;
        }
        _mm_stream_pd(y + q, _mm_set_pd(a1, a0));
        _mm_stream_pd(yp + q, _mm_set_pd(b1, b0));
    }
    return q;
}
#endif

/* c_j, d_j (j = 0 .. k) of the interpolant at t = tn + delt: IDA's recurrences */
KV_INLINE void interp_coefficients(int k, double delt, const double *psi, double *c,
                                   double *d)
{
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
}

/* kv_interp's y at t = tn itself (out_y, n), bit for bit: there c_j = 0 for j >= 1, so
   y = phi_0 + (+-0) + ... = phi_0 wherever phi_0 is finite and not zero; elsewhere (the
   sum of signed zeros, or a non-finite value) the sum as kv_interp forms it. Both are
   formed for every component and one is selected, without a branch: a rod's state
   interleaves exact zeros (the components a planar motion leaves at rest) with the
   others, and a branch per component mispredicted (~4 us per call at n = 1565 against
   ~1 us for the sums, which vectorise with k a literal). */
KV_INLINE void at_tn_span(int k, int n, const double *const *ph, const double *c,
                          double *restrict y)
{
    for (int q = 0; q < n; ++q) {
        const double a = ph[0][q];
        double s = a;
        for (int j = 1; j <= k; ++j) s += c[j] * ph[j][q];
        y[q] = (a != 0.0 && fabs(a) <= DBL_MAX) ? a : s;
    }
}

void kv_interp_at_tn(int k, int n, const double *psi, const double *phi, double *out_y)
{
    double c[6], d[6];
    const double *ph[6];
    interp_coefficients(k, 0.0, psi, c, d);
    for (int j = 0; j <= k; ++j) ph[j] = phi + (size_t)j * n;
    switch (k) {
    case 1: at_tn_span(1, n, ph, c, out_y); break;
    case 2: at_tn_span(2, n, ph, c, out_y); break;
    case 3: at_tn_span(3, n, ph, c, out_y); break;
    case 4: at_tn_span(4, n, ph, c, out_y); break;
    case 5: at_tn_span(5, n, ph, c, out_y); break;
    default: at_tn_span(k, n, ph, c, out_y); break;
    }
}

void kv_interp(int k, int n, int m, double tn, const double *psi, const double *phi,
               const double *ts, double *out_y, double *out_yp)
{
    double c[6], d[6];
    const double *ph[6];
    for (int j = 0; j <= k; ++j) ph[j] = phi + (size_t)j * n;
    for (int i = 0; i < m; ++i) {
        interp_coefficients(k, ts[i] - tn, psi, c, d);
        /* one pass over phi; outputs of a large state are stored past the cache (an
           output grid of full states at N = 4000 is 0.8 MB per time, which would
           otherwise evict the integrator's working set) */
        double *y = out_y + (size_t)i * n;
        if (!out_yp) {                   /* y only (no non-temporal path: small outputs) */
            switch (k) {
            case 1: interp_span_y(1, 0, n, ph, c, y); break;
            case 2: interp_span_y(2, 0, n, ph, c, y); break;
            case 3: interp_span_y(3, 0, n, ph, c, y); break;
            case 4: interp_span_y(4, 0, n, ph, c, y); break;
            case 5: interp_span_y(5, 0, n, ph, c, y); break;
            default: interp_span_y(k, 0, n, ph, c, y); break;
            }
            continue;
        }
        double *yp = out_yp + (size_t)i * n;
        int q = 0;
#if KV_STREAM
        if ((size_t)n * sizeof(double) >= ((size_t)1 << 18)) {
            for (; q < n && (((size_t)(y + q) | (size_t)(yp + q)) & 15); ++q)
                interp_span(k, q, q + 1, ph, c, d, y, yp);
            if ((((size_t)(y + q)) & 15) == 0 && (((size_t)(yp + q)) & 15) == 0) {
                switch (k) {
                case 1: q = interp_stream(1, q, n, ph, c, d, y, yp); break;
                case 2: q = interp_stream(2, q, n, ph, c, d, y, yp); break;
                case 3: q = interp_stream(3, q, n, ph, c, d, y, yp); break;
                case 4: q = interp_stream(4, q, n, ph, c, d, y, yp); break;
                case 5: q = interp_stream(5, q, n, ph, c, d, y, yp); break;
                default: q = interp_stream(k, q, n, ph, c, d, y, yp); break;
                }
            }
        }
#endif
        switch (k) {
        case 1: interp_span(1, q, n, ph, c, d, y, yp); break;
        case 2: interp_span(2, q, n, ph, c, d, y, yp); break;
        case 3: interp_span(3, q, n, ph, c, d, y, yp); break;
        case 4: interp_span(4, q, n, ph, c, d, y, yp); break;
        case 5: interp_span(5, q, n, ph, c, d, y, yp); break;
        default: interp_span(k, q, n, ph, c, d, y, yp); break;
        }
    }
#if KV_STREAM
    _mm_sfence();
#endif
}

