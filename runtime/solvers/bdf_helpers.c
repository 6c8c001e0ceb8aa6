/* C helpers of runtime/bdf.py; see runtime/_bdf_c.py for why they exist and what they
   measurably gain. Compiled on first use into the kvrod cache (runtime/build.py). */
#include <math.h>
#include <string.h>
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

/* ---- Condensed Newton systems -------------------------------------------------------
   Kinematic rows eliminate unknowns: a block b of rows R_b involves only the columns
   e_b (eliminated, as many as the rows) and k_b (kept), M_b = J[R_b, e_b],
   K_b = J[R_b, k_b]; so d_e = M_b^-1 (res_R - K_b d_k) = g_b - G_b d_k. The kept rows
   and columns form the condensed matrix Jc = J[kept, kept] - sum_b J[kept, e_b] G_b
   (on the k_b columns), whose band is narrower and whose size is about half: for the
   rod, phi' = v and p' = 1/2 p*(0, Omega) eliminate v and p, leaving phi and Omega
   (6 unknowns per cell instead of 13). Its LU and solves read ~3-4x fewer bytes, which
   is what limits the Newton solves of long rods (memory bound). */
typedef struct {
    int n, kl, ku, ldab;             /* full band (J is read, never overwritten) */
    int nc, klc, kuc, ldc;           /* condensed band */
    int nb;                          /* eliminated blocks */
    const int *e_off, *e_sz, *r_off, *k_off, *k_sz;   /* per block, contiguous ranges */
    const int *keep_row, *keep_col;  /* nc: full row / column of a condensed index */
    const int *row2c, *col2c;        /* n: condensed index of a full row / column, or -1 */
    double *G, *Minv, *g;            /* per block: e x k, e x e, e (offsets 16 b, 16 b, 4 b) */
    double *abc; int *ipiv; int *prof;
    double *rc;                      /* nc */
    /* J[kept rows, e_b] per block, dense (w_nr[b] x e_sz[b], row-major) over the
       contiguous condensed rows w_r0[b] .. w_r0[b] + w_nr[b] - 1: the solves read these
       instead of the full band's columns (fewer bytes per Newton iteration) */
    const int *w_off, *w_r0, *w_nr;
    double *W;
} kv_cond;

#define J_(i, j) ab[(size_t)(kv + (i) - (j)) + (size_t)(j) * (size_t)c->ldab]
#define JC_(i, j) abc[(size_t)(kvc + (i) - (j)) + (size_t)(j) * (size_t)c->ldc]

static int inv_small(int m, const double *a, double *out)   /* m <= 4, Gauss-Jordan */
{
    double w[4][8];
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < 2 * m; ++j)
            w[i][j] = j < m ? a[i * m + j] : (j - m == i ? 1.0 : 0.0);
    for (int col = 0; col < m; ++col) {
        int p = col;
        for (int i = col + 1; i < m; ++i) if (fabs(w[i][col]) > fabs(w[p][col])) p = i;
        if (w[p][col] == 0.0) return 1;
        if (p != col) for (int j = 0; j < 2 * m; ++j) { double t = w[p][j]; w[p][j] = w[col][j]; w[col][j] = t; }
        double d = 1.0 / w[col][col];
        for (int j = 0; j < 2 * m; ++j) w[col][j] *= d;
        for (int i = 0; i < m; ++i) if (i != col) {
            double f = w[i][col];
            if (f != 0.0) for (int j = 0; j < 2 * m; ++j) w[i][j] -= f * w[col][j];
        }
    }
    for (int i = 0; i < m; ++i) for (int j = 0; j < m; ++j) out[i * m + j] = w[i][j + m];
    return 0;
}

/* Condense the full band J (ab) and factorise; returns LAPACK's info of the condensed
   LU, or -1 when a block M_b is singular. */
int kv_cond_factor(kv_cond *c, const double *ab)
{
    const int kv = c->kl + c->ku, kvc = c->klc + c->kuc;
    double *abc = c->abc;
    FTZ_ON
    memset(abc, 0, sizeof(double) * (size_t)c->ldc * (size_t)c->nc);
    for (int cc = 0; cc < c->nc; ++cc) {               /* J[kept, kept] */
        const int j = c->keep_col[cc];
        const int i0 = j - c->ku < 0 ? 0 : j - c->ku;
        const int i1 = j + c->kl > c->n - 1 ? c->n - 1 : j + c->kl;
        for (int i = i0; i <= i1; ++i) {
            const int rc = c->row2c[i];
            if (rc >= 0) JC_(rc, cc) = J_(i, j);
        }
    }
    for (int b = 0; b < c->nb; ++b) {                   /* - J[kept, e_b] G_b */
        const int es = c->e_sz[b], ks = c->k_sz[b], e0 = c->e_off[b], r0 = c->r_off[b],
                  k0 = c->k_off[b];
        double M[16], K[16], *Mi = c->Minv + 16 * b, *G = c->G + 16 * b;
        for (int i = 0; i < es; ++i) {
            for (int m = 0; m < es; ++m) M[i * es + m] = J_(r0 + i, e0 + m);
            for (int m = 0; m < ks; ++m) K[i * ks + m] = J_(r0 + i, k0 + m);
        }
        if (inv_small(es, M, Mi)) { FTZ_OFF return -1; }
        for (int i = 0; i < es; ++i)
            for (int m = 0; m < ks; ++m) {
                double s = 0.0;
                for (int q = 0; q < es; ++q) s += Mi[i * es + q] * K[q * ks + m];
                G[i * ks + m] = s;
            }
        double *W = c->W + c->w_off[b];
        const int nr = c->w_nr[b], rc0 = c->w_r0[b];
        for (int r = 0; r < nr; ++r) {
            const int i = c->keep_row[rc0 + r];
            for (int q = 0; q < es; ++q) {
                const int j = e0 + q;
                W[r * es + q] = (i - j > c->kl || j - i > c->ku) ? 0.0 : J_(i, j);
            }
            for (int m = 0; m < ks; ++m) {
                double s = 0.0;
                for (int q = 0; q < es; ++q) s += W[r * es + q] * G[q * ks + m];
                if (s != 0.0) JC_(rc0 + r, c->col2c[k0 + m]) -= s;
            }
        }
    }
    FTZ_OFF
    return kv_gbtrf(c->nc, c->klc, c->kuc, abc, c->ldc, c->ipiv, c->prof);
}

/* res <- J^-1 res through the condensed factors (J from ab, as factorised). */
static void cond_solve(kv_cond *c, const double *ab, double *res)
{
    (void)ab;
    for (int b = 0; b < c->nb; ++b) {                   /* g_b = M_b^-1 res[R_b] */
        const int es = c->e_sz[b], r0 = c->r_off[b];
        const double *Mi = c->Minv + 16 * b;
        double *g = c->g + 4 * b;
        for (int i = 0; i < es; ++i) {
            double s = 0.0;
            for (int q = 0; q < es; ++q) s += Mi[i * es + q] * res[r0 + q];
            g[i] = s;
        }
    }
    for (int cc = 0; cc < c->nc; ++cc) c->rc[cc] = res[c->keep_row[cc]];
    for (int b = 0; b < c->nb; ++b) {                   /* rc -= J[kept, e_b] g_b */
        const int es = c->e_sz[b], nr = c->w_nr[b];
        const double *g = c->g + 4 * b, *W = c->W + c->w_off[b];
        double *rc = c->rc + c->w_r0[b];
        for (int r = 0; r < nr; ++r) {
            double s = 0.0;
            for (int q = 0; q < es; ++q) s += W[r * es + q] * g[q];
            rc[r] -= s;
        }
    }
    gbtrs(c->nc, c->klc, c->kuc, c->abc, c->ldc, c->ipiv, c->prof, c->rc);
    for (int cc = 0; cc < c->nc; ++cc) res[c->keep_col[cc]] = c->rc[cc];
    for (int b = 0; b < c->nb; ++b) {                   /* d_e = g_b - G_b d_k */
        const int es = c->e_sz[b], ks = c->k_sz[b], e0 = c->e_off[b], k0 = c->k_off[b];
        const double *G = c->G + 16 * b, *g = c->g + 4 * b;
        for (int i = 0; i < es; ++i) {
            double s = g[i];
            for (int m = 0; m < ks; ++m) s -= G[i * ks + m] * res[k0 + m];
            res[e0 + i] = s;
        }
    }
}
#undef J_
#undef JC_

void kv_cond_solve(kv_cond *c, const double *ab, double *res)
{
    FTZ_ON
    cond_solve(c, ab, res);
    FTZ_OFF
}

/* kv_newton on the condensed factors. */
double kv_cond_newton(kv_cond *c, const double *ab, double *res, double scale,
                      const double *ewt, double *ee, double *yy, double *ypw, double cj)
{
    const int n = c->n;
    FTZ_ON
    cond_solve(c, ab, res);
    double s = newton_update(n, res, scale, ewt, ee, yy, ypw, cj);
    FTZ_OFF
    return n > 0 ? sqrt(s / n) : 0.0;
}
