/* Newton systems of coupled band blocks (kv_blocks, blocks.py): J = A + P_S^T E, A block
   diagonal with banded blocks (each rod of an assembly, condensed or band-factored as a
   single rod's J), E the couplings, nonzero only in a few rows S (the joints' rows).
   One unit with band.c and condensed.c, through step_loop.c.

   Why Woodbury on the rows, not a sparse LU of the whole J: every block keeps the
   factorisation a single rod has (condensed, block tridiagonal, in cache), so an
   assembly of k rods costs about k rods plus the couplings; a general sparse LU would
   forgo the condensation and its fill-reducing order would have to be found anew.
   With Z = A^-1 P_S^T (column s: a solve of s's block with the unit vector e_s, zero
   outside that block) and the capacitance C = I + E Z (m x m, m = |S|):
       J^-1 r = x - Z C^-1 (E x),  x = A^-1 r.
   The factorisation costs the blocks' factorisations, m block solves and the small LU of
   C; a solve one solve per block, a sparse product, an m x m solve and m axpys over a
   block each. J is singular exactly when C is (A regular: its blocks carry the mass,
   cj M, or identities on held rows). */

typedef struct {
    int n, nb;
    const int *off;                  /* nb + 1: first unknown of each block */
    const int *kl, *ku, *ldab;       /* per block band sizes */
    double *const *ab;               /* per block band storage (Fortran, ldab x n_b) */
    kv_cond *const *cond;            /* per block: condensed system, or NULL: band LU */
    int *const *ipiv;                /* per block (band LU) */
    int *const *prof;
    int m;                           /* coupling rows */
    const int *srow, *sblk;          /* m: global row of each, its block */
    const int *er;                   /* m + 1: E's rows in CSR */
    const int *ec, *ecb;             /* nnz: global column, its block */
    double *ev;                      /* nnz: values (written with the Jacobian) */
    const int *bs0;                  /* nb + 1: the coupling rows of block b are */
    const int *bsl;                  /*   bsl[bs0[b] .. bs0[b + 1] - 1] (indices s) */
    double *Z;                       /* columns A^-1 e_s over s's block, at zo[s] */
    const long long *zo;
    double *C;                       /* m x m column-major: the capacitance, then its LU */
    int *cpiv;                       /* m */
    double *w;                       /* m: work */
} kv_blocks;

static int blocks_solve_block(const kv_blocks *B, int b, double *x)
{
    const int n = B->off[b + 1] - B->off[b];
    if (n == 0) return 0;
    if (B->cond[b]) cond_solve_raw(B->cond[b], B->ab[b], x);
    else gbtrs(n, B->kl[b], B->ku[b], B->ab[b], B->ldab[b], B->ipiv[b], B->prof[b], x);
    return 0;
}

/* LU with partial pivoting of the m x m column-major C, in place; 0 or 1 + the step of
   a zero pivot */
static int blocks_lu(int m, double *C, int *piv)
{
    for (int k = 0; k < m; ++k) {
        int p = k;
        double big = fabs(C[k + (size_t)k * m]);
        for (int i = k + 1; i < m; ++i) {
            const double v = fabs(C[i + (size_t)k * m]);
            if (v > big) { big = v; p = i; }
        }
        piv[k] = p;
        if (!(big > 0.0) || !isfinite(big)) return k + 1;
        if (p != k)
            for (int j = 0; j < m; ++j) {
                const double t = C[k + (size_t)j * m];
                C[k + (size_t)j * m] = C[p + (size_t)j * m];
                C[p + (size_t)j * m] = t;
            }
        const double r = 1.0 / C[k + (size_t)k * m];
        for (int i = k + 1; i < m; ++i) C[i + (size_t)k * m] *= r;
        for (int j = k + 1; j < m; ++j) {
            const double a = C[k + (size_t)j * m];
            if (a != 0.0)
                for (int i = k + 1; i < m; ++i)
                    C[i + (size_t)j * m] -= C[i + (size_t)k * m] * a;
        }
    }
    return 0;
}

/* x <- C^-1 x with blocks_lu's factors: the interchanges first (they swapped whole rows,
   the multipliers of earlier columns too: LAPACK's getrf/getrs convention), then L, U */
static void blocks_lu_solve(int m, const double *C, const int *piv, double *x)
{
    for (int k = 0; k < m; ++k) {
        const int p = piv[k];
        if (p != k) { const double t = x[k]; x[k] = x[p]; x[p] = t; }
    }
    for (int k = 0; k < m; ++k) {
        const double xk = x[k];
        if (xk != 0.0)
            for (int i = k + 1; i < m; ++i) x[i] -= C[i + (size_t)k * m] * xk;
    }
    for (int k = m - 1; k >= 0; --k) {
        x[k] /= C[k + (size_t)k * m];
        const double xk = x[k];
        if (xk != 0.0)
            for (int i = 0; i < k; ++i) x[i] -= C[i + (size_t)k * m] * xk;
    }
}

/* Factorise every block (its ab, filled by the Jacobian), then Z and C. Returns 0; > 0
   when a block or C is singular (the block's info, or 1 + the step of C). */
int blocks_factor_raw(kv_blocks *B)
{
    for (int b = 0; b < B->nb; ++b) {
        const int n = B->off[b + 1] - B->off[b];
        if (n == 0) continue;
        const int info = B->cond[b] ? cond_factor_raw(B->cond[b], B->ab[b])
            : gbtrf_raw(n, B->kl[b], B->ku[b], B->ab[b], B->ldab[b], B->ipiv[b],
                        B->prof[b]);
        if (info) return info;
    }
    const int m = B->m;
    if (m == 0) return 0;
    for (int s = 0; s < m; ++s) {
        const int b = B->sblk[s];
        const int n = B->off[b + 1] - B->off[b];
        double *z = B->Z + B->zo[s];
        memset(z, 0, sizeof(double) * (size_t)n);
        z[B->srow[s] - B->off[b]] = 1.0;
        blocks_solve_block(B, b, z);
    }
    double *C = B->C;
    memset(C, 0, sizeof(double) * (size_t)m * (size_t)m);
    for (int i = 0; i < m; ++i) {
        C[i + (size_t)i * m] = 1.0;
        for (int q = B->er[i]; q < B->er[i + 1]; ++q) {
            const double v = B->ev[q];
            if (v == 0.0) continue;
            const int cb = B->ecb[q], col = B->ec[q] - B->off[cb];
            for (int t = B->bs0[cb]; t < B->bs0[cb + 1]; ++t) {
                const int s = B->bsl[t];
                C[i + (size_t)s * m] += v * B->Z[B->zo[s] + col];
            }
        }
    }
    const int info = blocks_lu(m, C, B->cpiv);
    return info ? 1 + info : 0;
}

/* x <- J^-1 x through the factors of blocks_factor_raw */
void blocks_solve_raw(kv_blocks *B, double *x)
{
    for (int b = 0; b < B->nb; ++b) blocks_solve_block(B, b, x + B->off[b]);
    const int m = B->m;
    if (m == 0) return;
    double *w = B->w;
    for (int i = 0; i < m; ++i) {
        double s = 0.0;
        for (int q = B->er[i]; q < B->er[i + 1]; ++q) s += B->ev[q] * x[B->ec[q]];
        w[i] = s;
    }
    blocks_lu_solve(m, B->C, B->cpiv, w);
    for (int s = 0; s < m; ++s) {
        const double ws = w[s];
        if (ws == 0.0) continue;
        const int b = B->sblk[s];
        const int n = B->off[b + 1] - B->off[b];
        const double *z = B->Z + B->zo[s];
        double *xb = x + B->off[b];
        for (int k = 0; k < n; ++k) xb[k] -= z[k] * ws;
    }
}

double blocks_newton_raw(kv_blocks *B, double *res, double scale, const double *ewt,
                         double *ee, double *yy, double *ypw, double cj)
{
    blocks_solve_raw(B, res);
    const double s = newton_update(B->n, res, scale, ewt, ee, yy, ypw, cj);
    return B->n > 0 ? sqrt(s / B->n) : 0.0;
}

int kv_blocks_factor(kv_blocks *B)
{
    FTZ_ON
    const int info = blocks_factor_raw(B);
    FTZ_OFF
    return info;
}

void kv_blocks_solve(kv_blocks *B, double *x)
{
    FTZ_ON
    blocks_solve_raw(B, x);
    FTZ_OFF
}

double kv_blocks_newton(kv_blocks *B, double *res, double scale, const double *ewt,
                        double *ee, double *yy, double *ypw, double cj)
{
    FTZ_ON
    const double r = blocks_newton_raw(B, res, scale, ewt, ee, yy, ypw, cj);
    FTZ_OFF
    return r;
}
