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
    int *bs0;                        /* nb + 1: the coupling rows of block b are */
    int *bsl;                        /*   bsl[bs0[b] .. bs0[b + 1] - 1] (indices s) */
    double *Z;                       /* columns A^-1 e_s over s's block, at zo[s] */
    long long *zo;
    double *C;                       /* m x m column-major: the capacitance, then its LU */
    int *cpiv;                       /* m */
    double *w;                       /* m: work */
    /* dynamic couplings (contact pairs: rows that change from one Jacobian to the next),
       appended to the fixed ones as further Woodbury rows (a row may repeat one of S: the
       two rank updates add): m2 rows srow2, E2 in CSR er2 (m2 + 1), ec2, ev2, written
       with the Jacobian; at most m2cap rows and nz2cap entries. With m2cap > 0 the
       arrays Z, zo, C, cpiv, w, bs0, bsl hold m + m2cap rows (zcap doubles of Z), and
       sblk2, ecb2 are work of m2cap and nz2cap */
    int m2, m2cap, nz2cap;
    int *srow2, *er2, *ec2, *sblk2, *ecb2;
    double *ev2;
    long long zcap;
    int mtot;                        /* m + m2 of the last factorisation */
} kv_blocks;

static int blocks_block_of(const kv_blocks *B, int i)
{
    int lo = 0, hi = B->nb;                  /* off[lo] <= i < off[hi] */
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (B->off[mid] <= i) lo = mid; else hi = mid;
    }
    return lo;
}

/* coupling row s of all (fixed, then dynamic): its global row and block */
static inline int brow(const kv_blocks *B, int s)
{
    return s < B->m ? B->srow[s] : B->srow2[s - B->m];
}

static inline int bblk(const kv_blocks *B, int s)
{
    return s < B->m ? B->sblk[s] : B->sblk2[s - B->m];
}

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

/* the rows by block and the offsets of Z's columns for the current coupling rows (the
   fixed and the dynamic ones); -1 when Z's capacity is exceeded */
static int blocks_layout(kv_blocks *B)
{
    const int M = B->m + B->m2;
    for (int t = 0; t < B->m2; ++t) B->sblk2[t] = blocks_block_of(B, B->srow2[t]);
    for (int q = 0; q < (B->m2 ? B->er2[B->m2] : 0); ++q)
        B->ecb2[q] = blocks_block_of(B, B->ec2[q]);
    int *cnt = B->bs0;                       /* bs0[b + 1] counts, then prefix sums */
    for (int b = 0; b <= B->nb; ++b) cnt[b] = 0;
    for (int s = 0; s < M; ++s) cnt[bblk(B, s) + 1]++;
    for (int b = 0; b < B->nb; ++b) cnt[b + 1] += cnt[b];
    long long z = 0;
    for (int s = 0; s < M; ++s) {
        const int b = bblk(B, s);
        B->zo[s] = z;
        z += B->off[b + 1] - B->off[b];
    }
    if (B->m2 && z > B->zcap) return -1;
    /* bsl: the rows of block b at bs0[b] .. bs0[b + 1] - 1, in order */
    for (int b = 0, k = 0; b < B->nb; ++b)
        for (int s = 0; s < M; ++s)
            if (bblk(B, s) == b) B->bsl[k++] = s;
    B->mtot = M;
    return 0;
}

/* Factorise every block (its ab, filled by the Jacobian), then Z and C. Returns 0; > 0
   when a block or C is singular (the block's info, or 1 + the step of C); -1 when the
   dynamic couplings exceed their capacity. */
int blocks_factor_raw(kv_blocks *B)
{
    for (int b = 0; b < B->nb; ++b) {
        const int n = B->off[b + 1] - B->off[b];
        if (n == 0) continue;
        /* cj 0: a block's solves are plain J^-1 (cond_solve_raw), which does not read
           the factorised cj (kv_cond.q_cjf) */
        const int info = B->cond[b] ? cond_factor_raw(B->cond[b], B->ab[b], 0.0)
            : gbtrf_raw(n, B->kl[b], B->ku[b], B->ab[b], B->ldab[b], B->ipiv[b],
                        B->prof[b]);
        if (info) return info;
    }
    if (B->m2cap && blocks_layout(B)) return -1;
    const int m = B->m2cap ? B->mtot : B->m;
    B->mtot = m;
    if (m == 0) return 0;
    for (int s = 0; s < m; ++s) {
        const int b = bblk(B, s);
        const int n = B->off[b + 1] - B->off[b];
        double *z = B->Z + B->zo[s];
        memset(z, 0, sizeof(double) * (size_t)n);
        z[brow(B, s) - B->off[b]] = 1.0;
        blocks_solve_block(B, b, z);
    }
    double *C = B->C;
    memset(C, 0, sizeof(double) * (size_t)m * (size_t)m);
    for (int i = 0; i < m; ++i) {
        C[i + (size_t)i * m] = 1.0;
        const int fixed = i < B->m;
        const int q0 = fixed ? B->er[i] : B->er2[i - B->m];
        const int q1 = fixed ? B->er[i + 1] : B->er2[i - B->m + 1];
        for (int q = q0; q < q1; ++q) {
            const double v = fixed ? B->ev[q] : B->ev2[q];
            if (v == 0.0) continue;
            const int cb = fixed ? B->ecb[q] : B->ecb2[q];
            const int col = (fixed ? B->ec[q] : B->ec2[q]) - B->off[cb];
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
    const int m = B->mtot;
    if (m == 0) return;
    double *w = B->w;
    for (int i = 0; i < m; ++i) {
        double s = 0.0;
        if (i < B->m)
            for (int q = B->er[i]; q < B->er[i + 1]; ++q) s += B->ev[q] * x[B->ec[q]];
        else
            for (int q = B->er2[i - B->m]; q < B->er2[i - B->m + 1]; ++q)
                s += B->ev2[q] * x[B->ec2[q]];
        w[i] = s;
    }
    blocks_lu_solve(m, B->C, B->cpiv, w);
    for (int s = 0; s < m; ++s) {
        const double ws = w[s];
        if (ws == 0.0) continue;
        const int b = bblk(B, s);
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
