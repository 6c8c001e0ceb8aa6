/* Condensed Newton systems of the BDF integrator (CondensedNewton in condensed.py): one
   unit with band.c (whose band LU and Newton update it uses), through step_loop.c. */
/* ---- Condensed Newton systems -------------------------------------------------------
   Kinematic rows eliminate unknowns: a block b of rows R_b involves only the columns
   e_b (eliminated, as many as the rows) and k_b (kept), M_b = J[R_b, e_b],
   K_b = J[R_b, k_b]; so d_e = M_b^-1 (res_R - K_b d_k) = g_b - G_b d_k. The kept rows
   and columns form the condensed matrix Jc = J[kept, kept] - sum_b J[kept, e_b] G_b
   (on the k_b columns), whose band is narrower and whose size is about half: for the
   rod, phi' = v and p' = 1/2 p*(0, Omega) eliminate v and p, leaving phi and Omega
   (6 unknowns per cell instead of 13). Its LU and solves read ~3-4x fewer bytes, which
   is what limits the Newton solves of long rods (memory bound).

   Two ways to factorise Jc (chosen once, by CondensedNewton in condensed.py):
   - band (bt = 0): Jc is scattered into LAPACK band storage abc and factorised by
     gbtf2 (any structure);
   - block tridiagonal (bt = 1): when the state splits into contiguous cells such that
     every block lies in one cell and every kept row of cell k couples (in J's
     structural pattern, so also in Jc) only to cells k-1 .. k+1 -- the rod, whose
     couplings are nearest-neighbour: cell 0 = node 0, cell k = segment k, node k and
     joint k. Jc is then block tridiagonal with rows of blocks (L_k, A_k, C_k), and its
     block LU without pivoting between cells (block Thomas, pivoting inside each
     diagonal block) is D_0 = A_0, D_k = A_k - L_k X_{k-1}, X_k = D_k^-1 C_k. The blocks
     are assembled per cell straight from J (no condensed band to clear and scatter
     into), and the solve is two sweeps over the cells of small dense products (6 x 6
     for Kelvin-Voigt cells, written for compile-time sizes): forward
     z_k = D_k^-1 (rc_k - L_k z_{k-1}), backward x_k = z_k - X_k x_{k+1}, with the
     gather of the kept residual, the fill products, the eliminated unknowns and the
     Newton update fused into them. Large diagonal blocks of the iteration matrix
     (mass-dominated at large cj, stiffness at small cj) keep the unpivoted block
     elimination stable; each diagonal block's pivots are checked (zero or non-finite:
     info > 0, the caller shrinks the step). */
typedef struct {
    int n, kl, ku, ldab;             /* full band (J is read, never overwritten) */
    int nc, klc, kuc, ldc;           /* condensed band (bt = 0) */
    int nb;                          /* eliminated blocks, ordered by position */
    const int *e_off, *e_sz, *r_off, *k_off, *k_sz;   /* per block, contiguous ranges */
    const int *keep_row, *keep_col;  /* nc: full row / column of a condensed index */
    const int *row2c, *col2c;        /* n: condensed index of a full row / column, or -1 */
    double *G, *Minv, *g;            /* per block: e x k, e x e, e (offsets 16 b, 16 b, 4 b) */
    double *abc; int *ipiv; int *prof;
    double *rc;                      /* nc: condensed right-hand side / solution */
    /* bt = 0: J[kept rows, e_b] per block, dense (w_nr[b] x e_sz[b], row-major) over the
       contiguous condensed rows w_r0[b] .. w_r0[b] + w_nr[b] - 1: the solves read these
       instead of the full band's columns (fewer bytes per Newton iteration) */
    const int *w_off, *w_r0, *w_nr;
    double *W;
    /* bt = 1: cells k = 0 .. ncell-1 (the tables are ncell + 1 long, last = the end):
       cf[k] first full index, cs[k] first condensed index (m_k = cs[k+1] - cs[k] kept
       unknowns), cb[k] first block, ce[k] first eliminated unknown (in block order; eo[b]
       is that of block b). Per cell, column-major, ne3 = ce[min(k+2, ncell)] -
       ce[max(k-1, 0)] eliminated unknowns of cells k-1 .. k+1, mp = m_{k-1} (0 at k = 0),
       mn = m_{k+1} (0 at the last cell):
         F + fo[k]: W_k = J[kept rows of k, eliminated columns of cells k-1..k+1]
                    (m_k x ne3), then L_k (m_k x mp), D_k^-1 (m_k x m_k);
         X + xo[k]: X_k = D_k^-1 C_k (m_k x mn).
       ge (ne): g_b of every block, in block order. T: workspace of mmax (2 mmax + 3)
       doubles. */
    int bt, ncell, mmax;
    const int *cf, *cs, *cb, *ce, *eo;
    const long long *fo, *xo;
    double *F, *X, *ge, *T;
    /* the kept rows of cell k as runs of consecutive state indices (bt = 1): runs
       rp[k] .. rp[k+1] - 1, run q = rows run[3q] .. + run[3q+2] - 1, at local row
       run[3q+1]; the rod's cells have two runs (Omega and q_segment; v and q_joint). A
       column of J is then copied run by run (contiguous in band storage). */
    const int *rp, *run;
    const int *ecol;                 /* ne: the eliminated columns, in block order */
    /* per cell, 1 for a Kelvin-Voigt rod's interior cell: 6 kept and 7 eliminated
       unknowns in it and in its neighbours (mp = m = mn = 6, ne3 = 21), its 6 kept rows
       in two runs of 3, the blocks of each of the three p (4 x 3) then v (3 x 3,
       structurally diagonal): the fixed-size fast path */
    const int *kv6;
    /* per block (NULL: none): 0, or M_b and K_b are structurally diagonal (e = k; the
       rod's phi' = v rows: M = -I, K = cj I) and then block_elim sets 1 when they are
       diagonal in this J (M_b^-1 and G_b diagonal: cheaper products), else 2 */
    int *diag;
    /* the first column of J held by the ab the block path reads (0: all of J; a window of
       columns while the C step loop factors cell by cell behind the Jacobian's sweep) */
    int col0;
    /* ---- relaxation blocks (nq > 0; bt = 1 only; relaxation.py builds the tables) ----
       A relaxation block q: rows = columns q_off[q] .. + q_sz[q] - 1, diagonal in them
       (D), and else involving only first-stage unknowns, its sources x (q_src[q_so[q]
       .. q_so[q+1]-1], full columns; q_tgt: the condensed column of a kept one, else
       -1 - its position in ecol): D dq + A dx = r_q, so dq = g_q - A' dx with
       g_q = D^-1 r_q, A' = D^-1 A. The kept rows that involve q see J[kept, x] -
       J[kept, q] A' and r - J[kept, q] g_q: the first stage then runs unchanged on
       them.
       The structure of a block (relaxation.RelaxationBlock; the rod's internal strains
       q_bk' = (strain_k(x) - q_bk) / theta_b): q_sz = B c unknowns, row u = b c + k
       (c = q_nch[q] strains k, B terms b); the rows of strain k are multiples of its
       first row: A[u, :] = nu_u A[k, :] (q_nu: theta_0 / theta_b), and the columns of
       strain k multiples of one: J[r, u] = mu_u J[r, ref_k] (q_mu: the term's modulus
       over that of ref_k, the term of the largest modulus) for every other row r. So
       A' = kappa E, kappa_u = nu_u / D_u, E = A[0 .. c-1, :] (c x ns, the first term's
       rows: q_A + q_ao[q], column s at s c), and J[kept, q] A' = J[kept, ref] sigma E
       with sigma_k = sum_b mu_bk kappa_bk; J[kept, q] g_q = J[kept, ref] gh,
       gh_k = sum_b mu_bk g_bk. Per row (at q_eo[q]): q_nu, q_mu (from the tables),
       q_dinv (D^-1), q_kap (kappa), q_g (g_q), q_dc and q_kc (D^-1 and kappa at the
       current cj, D + cj - q_cjf: below);
       per strain (at q_co[q], c each): q_gh.
       Tables per cell k (ncell + 1 long, offsets into lists):
         q_cb: the blocks lying in cell k (their g_q is formed a cell ahead of the
               forward sweep);
         q_fk/q_fl: the blocks whose D^-1, kappa, E the factorisation forms at cell k
               (the first cell whose rows involve them: all they read is in its window);
         q_kb: the range of blocks [q_kb[2k], q_kb[2k+1]) that the cell's kept rows
               involve, their reference columns q_kcol[q_kco[k] .. q_kco[k+1]-1] (c per
               block, in block order, so that their gh are consecutive) and q_W +
               q_kwo[k]: J[the cell's kept rows, those columns] (m_k x their number,
               column-major);
         q_bk/q_bl: the blocks whose dq the backward sweep finishes at cell k (the
               lowest cell of their sources);
       and q_ucell/q_ustep: the cells in the order of the fused Newton update, each after
       the backward step q_ustep (its last access).
       q_cjf: the cj of the factorised J. A relaxation row's coefficient of q' is 1 (the
       rod's q_b' - (strain - q_b)/theta_b), so its D at another cj is D + (cj - q_cjf):
       the fused Newton update (cond_solve_bt_q) solves the relaxation rows with the
       current cj's D, exactly for the correction it applies (see there); the plain
       solve (cond_solve_raw) is J^-1 of the factorised J. */
    int nq;
    const int *q_off, *q_sz, *q_nch, *q_eo, *q_co, *q_so, *q_src, *q_tgt, *q_ao;
    const double *q_nu, *q_mu;
    double *q_A, *q_dinv, *q_kap, *q_g, *q_dc, *q_kc, *q_gh;
    const int *q_cb, *q_fk, *q_fl, *q_kb, *q_kco, *q_kcol;
    const long long *q_kwo;
    double *q_W;
    const int *q_bk, *q_bl, *q_ucell, *q_ustep;
    double q_cjf;
    double q_rdcj;    /* the cj - q_cjf that q_dc, q_kc hold (NaN: none; set by the solve) */
} kv_cond;


/* the relaxation blocks' limits (MAX_SIZE, MAX_SOURCES in relaxation.py, which checks
   them): unknowns and sources per block */
#define KV_QMAX 72
#define KV_QMAX_SRC 32

#define J_(i, j) ab[(size_t)(kv + (i) - (j)) + (size_t)(j) * (size_t)c->ldab]
#define JC_(i, j) abc[(size_t)(kvc + (i) - (j)) + (size_t)(j) * (size_t)c->ldc]

/* ---- small dense kernels ----
   The KV_INLINE kernels take their sizes as arguments; the callers pass literal sizes
   for the common cases (the rod's 3 x 3 and 4 x 4 kinematic blocks, its 6-unknown
   Kelvin-Voigt cells), so that the compiler emits unrolled fixed-size copies of them
   beside the generic ones. At these sizes the instruction count, not the flops or the
   memory, is the cost: loops of run-time length 6 cost about twice as many. */

/* inv <- a^-1, a (destroyed) and inv (m x m, column-major): in-place Gauss-Jordan with
   partial (row) pivoting, the interchanges implicit: the pivot row p_k of step k is
   the largest among the rows not yet used, no rows move, and the result is gathered
   into place at the end (inv(k, p_j) = a(p_k, j)). So the updates are plain stride-1
   column operations with the multiplier column l (l[p_k] = 0), one element stored
   apart per column, and the pivot search is branch-free (data-dependent branches
   mispredict). l: workspace of m doubles, prow: of 2m ints. Returns 0, or the 1-based
   step whose pivot is zero or not finite. */
KV_INLINE int gj_inverse(int m, double *restrict a, double *restrict inv,
                         double *restrict l, int *restrict prow)
{
    int *used = prow + m;
    for (int i = 0; i < m; ++i) used[i] = 0;
    for (int k = 0; k < m; ++k) {
        double *ak = a + (size_t)k * m;
        int p = 0;
        double big = -1.0;
        for (int i = 0; i < m; ++i) {
            const double v = fabs(ak[i]);
            const int cand = !used[i] & (v > big);
            p = cand ? i : p;
            big = cand ? v : big;
        }
        const double pv = ak[p];
        if (!(big > 0.0) || !isfinite(pv)) return k + 1;      /* zero, inf or NaN */
        used[p] = 1;
        prow[k] = p;
        const double r = 1.0 / pv;
        for (int i = 0; i < m; ++i) l[i] = ak[i];
        l[p] = 0.0;
        for (int i = 0; i < m; ++i) ak[i] = -l[i] * r;
        ak[p] = r;
        for (int j = 0; j < m; ++j) {
            if (j == k) continue;
            double *aj = a + (size_t)j * m;
            const double t = aj[p] * r;
            for (int i = 0; i < m; ++i) aj[i] -= l[i] * t;
            aj[p] = t;
        }
    }
    for (int j = 0; j < m; ++j) {
        const double *aj = a + (size_t)j * m;
        double *o = inv + (size_t)prow[j] * m;
        for (int k = 0; k < m; ++k) o[k] = aj[prow[k]];
    }
    return 0;
}

/* y (m) = y0 + A x (add) or y0 - A x (!add), A (m x k, column-major, leading
   dimension m), x (k); y0 may be y. Two interleaved sets of accumulators halve the
   chains of dependent adds. */
KV_INLINE void mv_acc(int m, int k, const double *restrict A, const double *restrict x,
                      int add, const double *y0, double *y)
{
    if (m == 6) {        /* in registers: no round trips of y through memory */
        double a0 = y0[0], a1 = y0[1], a2 = y0[2], a3 = y0[3], a4 = y0[4], a5 = y0[5];
        double b0 = 0.0, b1 = 0.0, b2 = 0.0, b3 = 0.0, b4 = 0.0, b5 = 0.0;
        int q = 0;
#define KV_MV6(acc0, acc1, acc2, acc3, acc4, acc5, c, t)                                \
        if (add) { acc0 += c[0] * t; acc1 += c[1] * t; acc2 += c[2] * t;                  \
                   acc3 += c[3] * t; acc4 += c[4] * t; acc5 += c[5] * t; }                \
        else { acc0 -= c[0] * t; acc1 -= c[1] * t; acc2 -= c[2] * t;                      \
               acc3 -= c[3] * t; acc4 -= c[4] * t; acc5 -= c[5] * t; }
        for (; q + 1 < k; q += 2) {
            const double *c0 = A + 6 * q, *c1 = c0 + 6, t = x[q], u = x[q + 1];
            KV_MV6(a0, a1, a2, a3, a4, a5, c0, t)
            KV_MV6(b0, b1, b2, b3, b4, b5, c1, u)
        }
        if (q < k) {
            const double *c0 = A + 6 * q, t = x[q];
            KV_MV6(a0, a1, a2, a3, a4, a5, c0, t)
        }
#undef KV_MV6
        y[0] = a0 + b0; y[1] = a1 + b1; y[2] = a2 + b2;
        y[3] = a3 + b3; y[4] = a4 + b4; y[5] = a5 + b5;
        return;
    }
    if (y != y0)
        for (int r = 0; r < m; ++r) y[r] = y0[r];
    for (int q = 0; q < k; ++q) {
        const double t = add ? x[q] : -x[q];
        const double *c = A + (size_t)q * m;
        for (int r = 0; r < m; ++r) y[r] += c[r] * t;
    }
}

/* t (m x ncol, column-major) <- J[the kept rows of a cell, cols[0..ncol)], each column
   copied run by run (a run is contiguous in the band storage's column); 0 outside the
   band. rl > 0: every run has rl rows (a compile-time constant on the fast path: two
   runs of 3, the rod's Kelvin-Voigt cells, whose columns are built in registers and
   stored whole, because the products read them back at once as vectors and a vector
   load of separately stored elements waits for them to reach the cache). */
KV_INLINE void gather_cols(const kv_cond *c, const double *ab, int ncol, const int *cols,
                           int nrun, const int *run, int rl, int m, double *restrict t)
{
    /* J(i, j) = ab[kl + ku + i - j + (j - col0) ldab] = base[i + j (ldab - 1)] with base
       = ab + kl + ku - col0 ldab, in size_t arithmetic (wraps, exact for entries in ab) */
    const size_t st = (size_t)c->ldab - 1;
    const int kl = c->kl, ku = c->ku;
    const size_t base = (size_t)(kl + ku) - (size_t)c->col0 * (size_t)c->ldab;
    if (rl == 3 && nrun == 2) {
        const int i0 = run[0], i1 = run[3];
        const int jlo = i1 + 2 - kl, jhi = i0 + ku;  /* both runs inside the band */
        for (int q = 0; q < ncol; ++q, t += 6) {
            const int j = cols[q];
            const size_t o = base + (size_t)j * st;
            const double *s0 = ab + (o + (size_t)i0), *s1 = ab + (o + (size_t)i1);
            double v0, v1, v2, v3, v4, v5;
            if (j >= jlo && j <= jhi) {
                v0 = s0[0]; v1 = s0[1]; v2 = s0[2]; v3 = s1[0]; v4 = s1[1]; v5 = s1[2];
            } else {
                const int lo = j - ku, hi = j + kl;
                v0 = i0 >= lo && i0 <= hi ? s0[0] : 0.0;
                v1 = i0 + 1 >= lo && i0 + 1 <= hi ? s0[1] : 0.0;
                v2 = i0 + 2 >= lo && i0 + 2 <= hi ? s0[2] : 0.0;
                v3 = i1 >= lo && i1 <= hi ? s1[0] : 0.0;
                v4 = i1 + 1 >= lo && i1 + 1 <= hi ? s1[1] : 0.0;
                v5 = i1 + 2 >= lo && i1 + 2 <= hi ? s1[2] : 0.0;
            }
            t[0] = v0; t[1] = v1; t[2] = v2; t[3] = v3; t[4] = v4; t[5] = v5;
        }
        return;
    }
    for (int q = 0; q < ncol; ++q, t += m) {
        const int j = cols[q], lo = j - ku, hi = j + kl;
        const size_t col = base + (size_t)j * st;
        for (int u = 0; u < nrun; ++u) {
            const int i0 = run[3 * u], len = rl ? rl : run[3 * u + 2];
            const double *src = ab + (col + (size_t)i0);
            double *d = t + run[3 * u + 1];
            if (i0 >= lo && i0 + len - 1 <= hi)
                for (int r = 0; r < len; ++r) d[r] = src[r];
            else
                for (int r = 0; r < len; ++r) d[r] = i0 + r >= lo && i0 + r <= hi ? src[r] : 0.0;
        }
    }
}

/* the offset in ab of J(r0, j) (inside the band) */
KV_INLINE size_t kv_col(const kv_cond *c, int j, int r0)
{
    return (size_t)(j - c->col0) * (size_t)c->ldab + (size_t)(c->kl + c->ku + r0 - j);
}

/* J(i, j), 0 outside the band */
KV_INLINE double kv_at(const kv_cond *c, const double *ab, int i, int j)
{
    return (i - j > c->kl || j - i > c->ku) ? 0.0 : ab[kv_col(c, j, i)];
}

/* D^-1, kappa and E of the relaxation blocks formed at cell k (q_fk); -1 when a D is
   singular (a zero or non-finite diagonal entry). */
static int q_elim_cell(kv_cond *c, const double *ab, int k)
{
    c->q_rdcj = NAN;                            /* q_dc, q_kc are of the D^-1 before */
    for (int l = c->q_fk[k]; l < c->q_fk[k + 1]; ++l) {
        const int q = c->q_fl[l], o = c->q_off[q], sz = c->q_sz[q], nch = c->q_nch[q];
        const int s0 = c->q_so[q], ns = c->q_so[q + 1] - s0;
        double *di = c->q_dinv + c->q_eo[q], *kap = c->q_kap + c->q_eo[q];
        const double *nu = c->q_nu + c->q_eo[q];
        double *E = c->q_A + c->q_ao[q];
        for (int u = 0; u < sz; ++u) {
            const double d = ab[kv_col(c, o + u, o + u)];
            if (!(d != 0.0) || !isfinite(d)) return -1;
            di[u] = 1.0 / d;
            kap[u] = nu[u] * di[u];
        }
        for (int s = 0; s < ns; ++s) {
            const int j = c->q_src[s0 + s];
            double *restrict e = E + (size_t)s * nch;
            if (o - j >= -c->ku && o + nch - 1 - j <= c->kl) {  /* the rows in the band */
                const double *restrict col = ab + kv_col(c, j, o);
                for (int u = 0; u < nch; ++u) e[u] = col[u];
            } else {
                for (int u = 0; u < nch; ++u) e[u] = kv_at(c, ab, o + u, j);
            }
        }
    }
    return 0;
}

/* sum over the terms of the strains of a block: out_k = sum_b a_bk b_bk (c strains, sz
   unknowns, row u = b c + k) */
KV_INLINE void q_strain_sums(int nch, int sz, const double *restrict a,
                             const double *restrict b, double *restrict out)
{
    for (int k = 0; k < nch; ++k) out[k] = a[k] * b[k];
    for (int u = nch; u < sz; u += nch)
        for (int k = 0; k < nch; ++k) out[k] += a[u + k] * b[u + k];
}

/* The relaxation blocks' fill on the gathered columns of cell k (bt_factor_cell: T =
   [L_k | A_k] over the kept columns from condensed column s0, Cu = C_k, W = W_k over
   the eliminated columns from position e0; m rows in nrun runs, rl as gather_cols):
   Wq <- J[kept rows, reference columns], then J[kept rows, x] -= J[kept rows, ref]
   sigma E for every block q that the cell's rows involve, one source column at a
   time. */
KV_INLINE void q_fill_cell(kv_cond *c, const double *ab, int k, int mp, int m, int s0,
                           int e0, int nrun, const int *run, int rl, double *T, double *Cu,
                           double *W)
{
    const int b0 = c->q_kb[2 * k], b1 = c->q_kb[2 * k + 1];
    if (b1 <= b0) return;
    double *Wq = c->q_W + c->q_kwo[k];
    const int co0 = c->q_co[b0];
    gather_cols(c, ab, c->q_kco[k + 1] - c->q_kco[k], c->q_kcol + c->q_kco[k], nrun, run, rl,
                m, Wq);
    for (int q = b0; q < b1; ++q) {
        const int nch = c->q_nch[q], sz = c->q_sz[q], so = c->q_so[q];
        const int ns = c->q_so[q + 1] - so;
        const double *w = Wq + (size_t)(c->q_co[q] - co0) * m, *E = c->q_A + c->q_ao[q];
        double sig[KV_QMAX], a[KV_QMAX];
        q_strain_sums(nch, sz, c->q_mu + c->q_eo[q], c->q_kap + c->q_eo[q], sig);
        for (int s = 0; s < ns; ++s) {
            const int tg = c->q_tgt[so + s];
            double *t;
            if (tg >= 0) {
                const int col = tg - s0;
                t = col < mp + m ? T + (size_t)col * m : Cu + (size_t)(col - mp - m) * m;
            } else {
                t = W + (size_t)(-1 - tg - e0) * m;
            }
            for (int u = 0; u < nch; ++u) a[u] = sig[u] * E[(size_t)s * nch + u];
            mv_acc(m, nch, w, a, 0, t, t);
        }
    }
}

/* q_dc = (D + dcj)^-1 = D^-1 / (1 + dcj D^-1) and q_kc = nu q_dc, D^-1 and kappa of every
   relaxation row at the current cj, dcj = cj - q_cjf != 0, unless they are held for
   this dcj already (the corrector's iterations at one cj): one pass that vectorises */
KV_INLINE void q_current_at(kv_cond *c, double dcj)
{
    if (dcj == c->q_rdcj) return;
    const int nqe = c->q_eo[c->nq - 1] + c->q_sz[c->nq - 1];
    const double *restrict di = c->q_dinv, *restrict nu = c->q_nu;
    double *restrict dc = c->q_dc, *restrict kc = c->q_kc;
    for (int u = 0; u < nqe; ++u) {
        const double v = di[u] / (1.0 + dcj * di[u]);
        dc[u] = v;
        kc[u] = nu[u] * v;
    }
    c->q_rdcj = dcj;
}

/* g_q = D^-1 r_q and gh of the relaxation blocks of cell k; cur: D at the current cj
   (q_dc, q_current_at) */
KV_INLINE void q_g_cell(kv_cond *c, const double *restrict res, int k, int cur)
{
    const int q0 = c->q_cb[k], q1 = c->q_cb[k + 1];
    for (int q = q0; q < q1; ++q) {
        const int o = c->q_off[q], sz = c->q_sz[q];
        const double *restrict di = (cur ? c->q_dc : c->q_dinv) + c->q_eo[q];
        double *restrict g = c->q_g + c->q_eo[q];
        if (c->q_nch[q] == 3) {
            /* the rod's (the hot path; q_strain_sums serves the rest): g and its sums
               gh together, in registers (g read back from memory at once stalled on the
               store forwarding); q_strain_sums' order */
            const double *restrict mu = c->q_mu + c->q_eo[q];
            const double *restrict r = res + o;
            double s0 = 0.0, s1 = 0.0, s2 = 0.0;
            for (int u = 0; u < sz; u += 3) {
                const double g0 = di[u] * r[u], g1 = di[u + 1] * r[u + 1];
                const double g2 = di[u + 2] * r[u + 2];
                g[u] = g0; g[u + 1] = g1; g[u + 2] = g2;
                if (u == 0) {
                    s0 = mu[0] * g0; s1 = mu[1] * g1; s2 = mu[2] * g2;
                } else {
                    s0 += mu[u] * g0; s1 += mu[u + 1] * g1; s2 += mu[u + 2] * g2;
                }
            }
            double *gh = c->q_gh + c->q_co[q];
            gh[0] = s0; gh[1] = s1; gh[2] = s2;
            continue;
        }
        for (int u = 0; u < sz; ++u) g[u] = di[u] * res[o + u];
        q_strain_sums(c->q_nch[q], sz, c->q_mu + c->q_eo[q], g, c->q_gh + c->q_co[q]);
    }
}

/* tmp (the kept residual of cell k, m rows) -= J[kept rows, q] g_q = J[kept rows, ref]
   gh over the blocks the cell's rows involve */
KV_INLINE void q_forward_cell(const kv_cond *c, int k, int m, double *restrict tmp)
{
    const int b0 = c->q_kb[2 * k], b1 = c->q_kb[2 * k + 1];
    if (b1 <= b0) return;
    mv_acc(m, c->q_kco[k + 1] - c->q_kco[k], c->q_W + c->q_kwo[k], c->q_gh + c->q_co[b0], 0,
           tmp, tmp);
}

/* d (sz) = iscale g - kappa (E x), E (nch x ns, column-major), row u = b nch + k; nch a
   literal for the rod's 3. With g and kappa the current cj's (q_g_cell, q_kc) and
   iscale = 1/scale, the scaled correction scale d solves the relaxation rows at the
   current cj for the scaled dx (cond_solve_bt_q). */
KV_INLINE void q_finish_n(int nch, int sz, int ns, const double *restrict E,
                          const double *restrict x, const double *restrict g,
                          const double *restrict kap, double iscale, double *restrict d)
{
    if (nch == 3) {
        /* the rod's: E x in registers, even and odd sources in two sets of sums (the
           product is a chain of dependent adds per strain, ~10 sources long, and this
           runs once per block and Newton iteration) */
        double a0 = 0.0, a1 = 0.0, a2 = 0.0, b0 = 0.0, b1 = 0.0, b2 = 0.0;
        int s = 0;
        for (; s + 1 < ns; s += 2) {
            const double t = x[s], v = x[s + 1];
            const double *restrict a = E + (size_t)s * 3;
            a0 += a[0] * t; a1 += a[1] * t; a2 += a[2] * t;
            b0 += a[3] * v; b1 += a[4] * v; b2 += a[5] * v;
        }
        if (s < ns) {
            const double t = x[s];
            const double *restrict a = E + (size_t)s * 3;
            a0 += a[0] * t; a1 += a[1] * t; a2 += a[2] * t;
        }
        const double e0 = a0 + b0, e1 = a1 + b1, e2 = a2 + b2;
        for (int u = 0; u < sz; u += 3) {
            d[u] = iscale * g[u] - kap[u] * e0;
            d[u + 1] = iscale * g[u + 1] - kap[u + 1] * e1;
            d[u + 2] = iscale * g[u + 2] - kap[u + 2] * e2;
        }
        return;
    }
    double e[KV_QMAX];
    for (int k = 0; k < nch; ++k) e[k] = 0.0;
    for (int s = 0; s < ns; ++s) {
        const double t = x[s];
        const double *restrict a = E + (size_t)s * nch;
        for (int k = 0; k < nch; ++k) e[k] += a[k] * t;
    }
    for (int u = 0; u < sz; u += nch)
        for (int k = 0; k < nch; ++k) d[u + k] = iscale * g[u + k] - kap[u + k] * e[k];
}

/* dq = g_q - A' dx into res, for the blocks finished at backward step k (their sources
   are in res); cur: at the current cj (q_kc), iscale as q_finish_n */
KV_INLINE void q_backward_cell(const kv_cond *c, int k, double *res, int cur,
                               double iscale)
{
    double x[KV_QMAX_SRC];
    for (int l = c->q_bk[k]; l < c->q_bk[k + 1]; ++l) {
        const int q = c->q_bl[l], sz = c->q_sz[q], so = c->q_so[q], nch = c->q_nch[q];
        const int ns = c->q_so[q + 1] - so, eo = c->q_eo[q];
        const double *E = c->q_A + c->q_ao[q], *g = c->q_g + eo;
        const double *kap = (cur ? c->q_kc : c->q_kap) + eo;
        for (int s = 0; s < ns; ++s) x[s] = res[c->q_src[so + s]];
        double *d = res + c->q_off[q];
        if (nch == 3) q_finish_n(3, sz, ns, E, x, g, kap, iscale, d);
        else q_finish_n(nch, sz, ns, E, x, g, kap, iscale, d);
    }
}

/* Minv_b = M_b^-1 (e x e) and G_b = M_b^-1 K_b (e x k) of block b, column-major, at
   16 b; nonzero when M_b is singular. */
KV_INLINE int block_elim_n(kv_cond *c, const double *ab, int b, int es, int ks)
{
    const int e0 = c->e_off[b], r0 = c->r_off[b], k0 = c->k_off[b];
    double *Mi = c->Minv + 16 * b, *G = c->G + 16 * b, M[16], l[4];
    int piv[8];
    /* the block's rows and columns lie in the band (CondensedNewton checks it) */
    for (int q = 0; q < es; ++q) {
        const double *col = ab + kv_col(c, e0 + q, r0);
        for (int i = 0; i < es; ++i) M[q * es + i] = col[i];
    }
    if (gj_inverse(es, M, Mi, l, piv)) return 1;
    for (int m = 0; m < ks; ++m) {
        const double *col = ab + kv_col(c, k0 + m, r0);
        double K[4], *g = G + m * es;
        for (int i = 0; i < es; ++i) { K[i] = col[i]; g[i] = 0.0; }
        for (int q = 0; q < es; ++q)
            for (int i = 0; i < es; ++i) g[i] += Mi[q * es + i] * K[q];
    }
    return 0;
}

/* block_elim_n for a structurally diagonal block: only the diagonals are inverted. Nonzero
   (then the general case runs) when an off-diagonal entry is not zero after all (the
   pattern is sampled, not proven), or a diagonal one is zero. */
static int block_elim_diag(kv_cond *c, const double *ab, int b)
{
    const int es = c->e_sz[b];
    const int e0 = c->e_off[b], r0 = c->r_off[b], k0 = c->k_off[b];
    double *Mi = c->Minv + 16 * b, *G = c->G + 16 * b;
    for (int q = 0; q < es; ++q) {
        const double *cm = ab + kv_col(c, e0 + q, r0), *ck = ab + kv_col(c, k0 + q, r0);
        for (int i = 0; i < es; ++i) {
            if (i == q) continue;
            if (cm[i] != 0.0 || ck[i] != 0.0) return 1;
            Mi[q * es + i] = 0.0;
            G[q * es + i] = 0.0;
        }
        const double d = cm[q];
        if (!(d != 0.0) || !isfinite(d)) return 1;
        Mi[q * es + q] = 1.0 / d;
        G[q * es + q] = ck[q] / d;
    }
    return 0;
}

/* M_b^-1 and G_b of block b (the fixed-size or diagonal variants when they apply);
   nonzero when M_b is singular. */
static int block_elim(kv_cond *c, const double *ab, int b)
{
    const int es = c->e_sz[b], ks = c->k_sz[b];
    if (c->diag && c->diag[b]) {
        c->diag[b] = block_elim_diag(c, ab, b) ? 2 : 1;
        if (c->diag[b] == 1) return 0;
    }
    if (es == 3 && ks == 3) return block_elim_n(c, ab, b, 3, 3);
    if (es == 4 && ks == 3) return block_elim_n(c, ab, b, 4, 3);
    return block_elim_n(c, ab, b, es, ks);
}

/* g (e) <- g_b = M_b^-1 res[R_b]. */
KV_INLINE void block_g_n(const kv_cond *c, int b, int es, const double *restrict res,
                         double *restrict g)
{
    const double *Mi = c->Minv + 16 * b, *r = res + c->r_off[b];
    for (int i = 0; i < es; ++i) g[i] = 0.0;
    for (int q = 0; q < es; ++q)
        for (int i = 0; i < es; ++i) g[i] += Mi[q * es + i] * r[q];
}

/* res[e_b] <- g_b - G_b x: the eliminated unknowns from the kept ones x = d[k_b] (k). */
KV_INLINE void block_back_n(const kv_cond *c, int b, int es, int ks, const double *restrict g,
                            const double *restrict x, double *restrict res)
{
    const double *G = c->G + 16 * b;
    double d[4];
    for (int i = 0; i < es; ++i) d[i] = g[i];
    for (int m = 0; m < ks; ++m)
        for (int i = 0; i < es; ++i) d[i] -= G[m * es + i] * x[m];
    for (int i = 0; i < es; ++i) res[c->e_off[b] + i] = d[i];
}

/* block_g_n and block_back_n of a diagonal block (diag[b] = 1: M_b^-1 and G_b diagonal) */
KV_INLINE void block_g_diag_n(const kv_cond *c, int b, int es, const double *restrict res,
                              double *restrict g)
{
    const double *Mi = c->Minv + 16 * b, *r = res + c->r_off[b];
    for (int i = 0; i < es; ++i) g[i] = Mi[i * es + i] * r[i];
}

KV_INLINE void block_back_diag_n(const kv_cond *c, int b, int es, const double *restrict g,
                                 const double *restrict x, double *restrict res)
{
    const double *G = c->G + 16 * b;
    double *d = res + c->e_off[b];
    for (int i = 0; i < es; ++i) d[i] = g[i] - G[i * es + i] * x[i];
}

static inline void block_g(const kv_cond *c, int b, const double *res, double *g)
{
    const int es = c->e_sz[b];
    if (c->diag && c->diag[b] == 1) {
        if (es == 3) block_g_diag_n(c, b, 3, res, g);
        else block_g_diag_n(c, b, es, res, g);
        return;
    }
    if (es == 3) block_g_n(c, b, 3, res, g);
    else if (es == 4) block_g_n(c, b, 4, res, g);
    else block_g_n(c, b, es, res, g);
}

static inline void block_back(const kv_cond *c, int b, const double *g, const double *x,
                              double *res)
{
    const int es = c->e_sz[b], ks = c->k_sz[b];
    if (c->diag && c->diag[b] == 1) {
        if (es == 3) block_back_diag_n(c, b, 3, g, x, res);
        else block_back_diag_n(c, b, es, g, x, res);
        return;
    }
    if (es == 3 && ks == 3) block_back_n(c, b, 3, 3, g, x, res);
    else if (es == 4 && ks == 3) block_back_n(c, b, 4, 3, g, x, res);
    else block_back_n(c, b, es, ks, g, x, res);
}

/* ---- the band path ---- */

/* Condense J into abc and factorise (LAPACK's info; -1: an M_b singular). */
static int cond_factor_band(kv_cond *c, const double *ab)
{
    const int kv = c->kl + c->ku, kvc = c->klc + c->kuc;
    double *abc = c->abc;
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
        const int es = c->e_sz[b], ks = c->k_sz[b], e0 = c->e_off[b], k0 = c->k_off[b];
        if (block_elim(c, ab, b)) return -1;
        const double *G = c->G + 16 * b;
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
                for (int q = 0; q < es; ++q) s += W[r * es + q] * G[m * es + q];
                if (s != 0.0) JC_(rc0 + r, c->col2c[k0 + m]) -= s;
            }
        }
    }
    return gbtrf_raw(c->nc, c->klc, c->kuc, abc, c->ldc, c->ipiv, c->prof);
}

/* The band path's solve: res <- J^-1 res through the condensed band factors. */
static void cond_solve_band(kv_cond *c, double *res)
{
    for (int b = 0; b < c->nb; ++b) block_g(c, b, res, c->g + 4 * b);
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
    for (int b = 0; b < c->nb; ++b)                     /* d_e = g_b - G_b d_k */
        block_back(c, b, c->g + 4 * b, res + c->k_off[b], res);
}

/* ---- the block tridiagonal path ---- */

/* Row k of cells of Jc and its block LU step (see kv_cond): T (m x (mp + m + mn),
   column-major, columns = the kept unknowns of cells k-1 .. k+1) <- J[kept rows of k,
   those columns], W_k <- J[kept rows of k, eliminated columns of cells k-1 .. k+1],
   T -= W_k G_b on the k_b columns of every block b of those cells (the condensation);
   then T = [L_k | A_k | C_k], D_k = A_k - L_k X_{k-1}, D_k^-1 (over A_k), X_k =
   D_k^-1 C_k. The M_b^-1, G_b of the blocks of cells <= k+1 must be ready. Returns 0,
   or the 1-based condensed index of a failed pivot of D_k. */
KV_INLINE int bt_factor_cell(kv_cond *c, const double *ab, int k, int mp, int m, int mn,
                             int ne3, int rl)
{
    const int kp = k > 0 ? k - 1 : 0, kn = k + 2 < c->ncell ? k + 2 : c->ncell;
    const int s0 = c->cs[kp], e0 = c->ce[kp];
    /* T = [L_k | A_k] lies in F after W_k, so that L_k and D_k^-1 (from A_k in place)
       need no copies; C_k goes to the workspace (the solves do not read it) */
    double *W = c->F + c->fo[k], *T = W + (size_t)m * ne3, *Di = T + (size_t)m * mp;
    double *Cu = c->T;
    const int *run = c->run + 3 * c->rp[k], nrun = c->rp[k + 1] - c->rp[k];
    gather_cols(c, ab, mp + m, c->keep_col + s0, nrun, run, rl, m, T);
    gather_cols(c, ab, mn, c->keep_col + c->cs[k] + m, nrun, run, rl, m, Cu);
    gather_cols(c, ab, ne3, c->ecol + e0, nrun, run, rl, m, W);
    if (c->nq) q_fill_cell(c, ab, k, mp, m, s0, e0, nrun, run, rl, T, Cu, W);
    for (int b = c->cb[kp]; b < c->cb[kn]; ++b) {
        /* kv6 (rl = 3 only there): the blocks of cells k-1 .. k+1 alternate p (4 x 3)
           and v (3 x 3) */
        const int es = rl ? 4 - (b - c->cb[kp]) % 2 : c->e_sz[b], ks = rl ? 3 : c->k_sz[b];
        const double *w = W + (size_t)(c->eo[b] - e0) * m, *G = c->G + 16 * b;
        const int q = c->col2c[c->k_off[b]] - s0;           /* column in [L_k | A_k | C_k] */
        double *t = q < mp + m ? T + (size_t)q * m : Cu + (size_t)(q - mp - m) * m;
        if (c->diag && c->diag[b] == 1) {
            for (int u = 0; u < es; ++u) {
                const double gu = G[u * es + u];
                for (int r = 0; r < m; ++r) t[u * m + r] -= w[u * m + r] * gu;
            }
        } else if (rl && es == 4) {
            for (int mm = 0; mm < 3; ++mm)
                mv_acc(m, 4, w, G + mm * 4, 0, t + (size_t)mm * m, t + (size_t)mm * m);
        } else if (rl) {
            for (int mm = 0; mm < 3; ++mm)
                mv_acc(m, 3, w, G + mm * 3, 0, t + (size_t)mm * m, t + (size_t)mm * m);
        } else {
            for (int mm = 0; mm < ks; ++mm)
                mv_acc(m, es, w, G + mm * es, 0, t + (size_t)mm * m, t + (size_t)mm * m);
        }
    }
    double dbuf[36], lbuf[6];
    double *D = m <= 6 ? dbuf : Cu + (size_t)m * mn, *l = m <= 6 ? lbuf : D + (size_t)m * m;
    int pbuf[12], *prow = m <= 6 ? pbuf : (int *)(l + m);
    if (mp) {
        const double *Xp = c->X + c->xo[k - 1];               /* mp x m */
        for (int j = 0; j < m; ++j)
            mv_acc(m, mp, T, Xp + (size_t)j * mp, 0, Di + (size_t)j * m, D + (size_t)j * m);
    } else {
        memcpy(D, Di, sizeof(double) * (size_t)m * m);
    }
    const int p = gj_inverse(m, D, Di, l, prow);
    if (p) return c->cs[k] + p;
    if (mn) {
        double *Xk = c->X + c->xo[k];
        for (int j = 0; j < mn; ++j) {
            double *x = Xk + (size_t)j * m;
            for (int r = 0; r < m; ++r) x[r] = 0.0;
            mv_acc(m, m, Di, Cu + (size_t)j * m, 1, x, x);
        }
    }
    return 0;
}

/* The sizes of cell k: m_{k-1}, m_k, m_{k+1} (0 beyond the ends), ne3 (see kv_cond). */
#define BT_SIZES(c, k)                                                                  \
    const int mp = (k) > 0 ? (c)->cs[k] - (c)->cs[(k) - 1] : 0;                         \
    const int m = (c)->cs[(k) + 1] - (c)->cs[k];                                        \
    const int mn = (k) + 1 < (c)->ncell ? (c)->cs[(k) + 2] - (c)->cs[(k) + 1] : 0;      \
    const int ne3 = (c)->ce[(k) + 2 < (c)->ncell ? (k) + 2 : (c)->ncell]                \
                    - (c)->ce[(k) > 0 ? (k) - 1 : 0];

/* The block path's factorisation of cells k0 .. k1, in order (the blocks of cell 0 first
   when k0 = 0; cells 0 .. k0-1 must be done): it reads the columns of J of cells k0-1 ..
   k1+1 (from ab's first column, J's column col0). Returns as cond_factor_raw. */
static int cond_factor_bt_cells(kv_cond *c, const double *ab, int k0, int k1)
{
    if (k0 == 0)
        for (int b = c->cb[0]; b < c->cb[1]; ++b)
            if (block_elim(c, ab, b)) return -1;
    for (int k = k0; k <= k1; ++k) {
        if (k + 1 < c->ncell)
            for (int b = c->cb[k + 1]; b < c->cb[k + 2]; ++b)
                if (block_elim(c, ab, b)) return -1;
        if (c->nq && q_elim_cell(c, ab, k)) return -1;
        BT_SIZES(c, k)
        const int info = c->kv6[k] ? bt_factor_cell(c, ab, k, 6, 6, 6, 21, 3)
                                   : bt_factor_cell(c, ab, k, mp, m, mn, ne3, 0);
        if (info) return info;
    }
    return 0;
}

static int cond_factor_bt(kv_cond *c, const double *ab)
{
    return cond_factor_bt_cells(c, ab, 0, c->ncell - 1);
}

/* Forward sweep, cell k: z_k = D_k^-1 (res[kept rows of k] - W_k g - L_k z_{k-1}), in rc
   (z_{k-1} just before it); tmp: m doubles. The g of cells <= k+1 must be in ge. */
KV_INLINE void bt_forward_cell(kv_cond *c, const double *res, int k, int mp, int m, int ne3,
                               double *restrict tmp)
{
    const int e0 = c->ce[k > 0 ? k - 1 : 0];
    const double *W = c->F + c->fo[k], *Lk = W + (size_t)m * ne3, *Di = Lk + (size_t)m * mp;
    const int *kr = c->keep_row + c->cs[k];
    double *z = c->rc + c->cs[k];
    for (int r = 0; r < m; ++r) tmp[r] = res[kr[r]];
    mv_acc(m, ne3, W, c->ge + e0, 0, tmp, tmp);
    if (c->nq) q_forward_cell(c, k, m, tmp);
    mv_acc(m, mp, Lk, z - mp, 0, tmp, tmp);
    for (int r = 0; r < m; ++r) z[r] = 0.0;
    mv_acc(m, m, Di, tmp, 1, z, z);
}

/* Backward sweep, cell k: x_k = z_k - X_k x_{k+1} (in rc), then the full unknowns of
   the cell into res: the kept ones x_k, the eliminated d_e = g_b - G_b x[k_b]. fast: a
   kv6 cell (m = mn = 6; its blocks p, 4 x 3, and v, 3 x 3). */
KV_INLINE void bt_backward_cell(kv_cond *c, double *res, int k, int m, int mn, int fast)
{
    double *x = c->rc + c->cs[k];
    if (mn) mv_acc(m, mn, c->X + c->xo[k], x + m, 0, x, x);
    const int b0 = c->cb[k];
    if (fast) {
        block_back_n(c, b0, 4, 3, c->ge + c->eo[b0], c->rc + c->col2c[c->k_off[b0]], res);
        if (c->diag[b0 + 1] == 1)
            block_back_diag_n(c, b0 + 1, 3, c->ge + c->eo[b0 + 1],
                              c->rc + c->col2c[c->k_off[b0 + 1]], res);
        else
            block_back_n(c, b0 + 1, 3, 3, c->ge + c->eo[b0 + 1],
                         c->rc + c->col2c[c->k_off[b0 + 1]], res);
    } else {
        for (int b = b0; b < c->cb[k + 1]; ++b)
            block_back(c, b, c->ge + c->eo[b], c->rc + c->col2c[c->k_off[b]], res);
    }
    const int *kc = c->keep_col + c->cs[k];
    for (int r = 0; r < m; ++r) res[kc[r]] = x[r];
}

/* g_b of the blocks of cell k (into ge); fast: a kv6 cell, whose blocks are p (4 x 3)
   and v (3 x 3, structurally diagonal), in this order. */
KV_INLINE void bt_g_cell(kv_cond *c, const double *res, int k, int fast)
{
    const int b0 = c->cb[k];
    if (fast) {
        block_g_n(c, b0, 4, res, c->ge + c->eo[b0]);
        if (c->diag[b0 + 1] == 1) block_g_diag_n(c, b0 + 1, 3, res, c->ge + c->eo[b0 + 1]);
        else block_g_n(c, b0 + 1, 3, res, c->ge + c->eo[b0 + 1]);
        return;
    }
    for (int b = b0; b < c->cb[k + 1]; ++b) block_g(c, b, res, c->ge + c->eo[b]);
}

/* newton_update on one cell, with two partial sums (pairs vectorise; the summation
   order differs from newton_update's, by rounding only). */
KV_INLINE double newton_update2(int n, double *restrict res, double scale,
                                const double *restrict ewt, double *restrict ee,
                                double *restrict yy, double *restrict ypw, double cj)
{
    double s0 = 0.0, s1 = 0.0;
    int i = 0;
    for (; i + 1 < n; i += 2) {
        const double d0 = res[i] * scale, d1 = res[i + 1] * scale;
        const double w0 = d0 * ewt[i], w1 = d1 * ewt[i + 1];
        res[i] = d0; res[i + 1] = d1;
        s0 += w0 * w0; s1 += w1 * w1;
        ee[i] -= d0; ee[i + 1] -= d1;
        yy[i] -= d0; yy[i + 1] -= d1;
        ypw[i] -= cj * d0; ypw[i + 1] -= cj * d1;
    }
    if (i < n) {
        const double d0 = res[i] * scale, w0 = d0 * ewt[i];
        res[i] = d0;
        s0 += w0 * w0;
        ee[i] -= d0;
        yy[i] -= d0;
        ypw[i] -= cj * d0;
    }
    return s0 + s1;
}

/* newton_update2 with four partial sums (four-wide vectors; the relaxation path, whose
   cells are long) */
KV_INLINE double newton_update4(int n, double *restrict res, double scale,
                                const double *restrict ewt, double *restrict ee,
                                double *restrict yy, double *restrict ypw, double cj)
{
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    int i = 0;
    for (; i + 3 < n; i += 4)
        for (int l = 0; l < 4; ++l) {
            const double d = res[i + l] * scale, w = d * ewt[i + l];
            res[i + l] = d;
            s[l] += w * w;
            ee[i + l] -= d;
            yy[i + l] -= d;
            ypw[i + l] -= cj * d;
        }
    for (int l = 0; i < n; ++i, ++l) {
        const double d = res[i] * scale, w = d * ewt[i];
        res[i] = d;
        s[l] += w * w;
        ee[i] -= d;
        yy[i] -= d;
        ypw[i] -= cj * d;
    }
    return (s[0] + s[1]) + (s[2] + s[3]);
}

/* cond_solve_bt with relaxation blocks (nq > 0): their g_q formed a cell ahead of the
   forward sweep, their dq in the backward sweep once their sources are known, and the
   cells updated in the order q_ucell (a cell after its last access). */
static double cond_solve_bt_q(kv_cond *c, double *res, int upd, double scale,
                              const double *ewt, double *ee, double *yy, double *ypw,
                              double cj)
{
    double tmp6[6];
    /* the relaxation rows at the current cj (kv_cond.q_cjf) for the correction applied,
       scale d: dq_applied = (r_q - J[q, x] dx_applied) / (D + cj - q_cjf); a plain solve
       (upd = 0) is J^-1 */
    const double dcj = upd ? cj - c->q_cjf : 0.0;
    const double iscale = upd && scale != 1.0 ? 1.0 / scale : 1.0;
    const int cur = dcj != 0.0;
    if (cur) q_current_at(c, dcj);
    bt_g_cell(c, res, 0, 0);
    q_g_cell(c, res, 0, cur);
    for (int k = 0; k < c->ncell; ++k) {
        if (k + 1 < c->ncell) {
            if (c->kv6[k + 1]) bt_g_cell(c, res, k + 1, 1);
            else bt_g_cell(c, res, k + 1, 0);
            q_g_cell(c, res, k + 1, cur);
        }
        BT_SIZES(c, k)
        (void)mn;
        if (c->kv6[k]) bt_forward_cell(c, res, k, 6, 6, 21, tmp6);
        else bt_forward_cell(c, res, k, mp, m, ne3, c->T);
    }
    double s = 0.0;
    int u = 0;
    for (int k = c->ncell - 1; k >= 0; --k) {
        BT_SIZES(c, k)
        (void)mp; (void)ne3;
        if (c->kv6[k]) bt_backward_cell(c, res, k, 6, 6, 1);
        else bt_backward_cell(c, res, k, m, mn, 0);
        q_backward_cell(c, k, res, cur, iscale);
        for (; upd && u < c->ncell && c->q_ustep[u] == k; ++u) {
            const int f0 = c->cf[c->q_ucell[u]], len = c->cf[c->q_ucell[u] + 1] - f0;
            s += newton_update4(len, res + f0, scale, ewt + f0, ee + f0, yy + f0, ypw + f0,
                                cj);
        }
    }
    return s;
}

/* res <- J^-1 res by the block path; with upd, then the corrector update (newton_update)
   cell by cell while the cell is in cache; returns its sum of squares (0 without upd). */
KV_INLINE double cond_solve_bt(kv_cond *c, double *res, int upd, double scale,
                               const double *ewt, double *ee, double *yy, double *ypw,
                               double cj)
{
    if (c->nq) return cond_solve_bt_q(c, res, upd, scale, ewt, ee, yy, ypw, cj);
    double tmp6[6];
    bt_g_cell(c, res, 0, 0);
    for (int k = 0; k < c->ncell; ++k) {
        if (k + 1 < c->ncell) {
            if (c->kv6[k + 1]) bt_g_cell(c, res, k + 1, 1);
            else bt_g_cell(c, res, k + 1, 0);
        }
        BT_SIZES(c, k)
        (void)mn;
        if (c->kv6[k]) bt_forward_cell(c, res, k, 6, 6, 21, tmp6);
        else bt_forward_cell(c, res, k, mp, m, ne3, c->T);
    }
    double s = 0.0;
    for (int k = c->ncell - 1; k >= 0; --k) {
        BT_SIZES(c, k)
        (void)mp; (void)ne3;
        if (c->kv6[k]) bt_backward_cell(c, res, k, 6, 6, 1);
        else bt_backward_cell(c, res, k, m, mn, 0);
        if (upd) {          /* kv6: 6 kept + 7 eliminated state entries */
            const int f0 = c->cf[k], len = c->cf[k + 1] - f0;
            s += c->kv6[k] ? newton_update2(13, res + f0, scale, ewt + f0, ee + f0, yy + f0,
                                            ypw + f0, cj)
                           : newton_update2(len, res + f0, scale, ewt + f0, ee + f0, yy + f0,
                                            ypw + f0, cj);
        }
    }
    return s;
}
#undef BT_SIZES
#undef J_
#undef JC_

/* Condense the full band J (ab, unchanged) and factorise, without touching the
   floating-point mode (for callers inside their own flush-to-zero region, e.g. a C step
   loop that #includes this file). Returns 0; > 0 when Jc is singular (LAPACK's info on
   the band path; on the block path the 1-based condensed index of a zero or non-finite
   pivot of a diagonal block); -1 when a kinematic block M_b is singular. */
int cond_factor_raw(kv_cond *c, const double *ab, double cj)
{
    c->q_cjf = cj;
    return c->bt ? cond_factor_bt(c, ab) : cond_factor_band(c, ab);
}

/* res <- J^-1 res through the condensed factors (J from ab, as factorised); no FTZ
   handling (see cond_factor_raw). */
void cond_solve_raw(kv_cond *c, const double *ab, double *res)
{
    (void)ab;
    if (c->bt) cond_solve_bt(c, res, 0, 0.0, NULL, NULL, NULL, NULL, 0.0);
    else cond_solve_band(c, res);
}

/* kv_newton on the condensed factors, no FTZ handling (see cond_factor_raw): one
   simplified-Newton update, d = scale * J^-1 res (in res), ee -= d, yy -= d,
   ypw -= cj d; returns the weighted RMS norm of d. */
double cond_newton_raw(kv_cond *c, const double *ab, double *res, double scale,
                       const double *ewt, double *ee, double *yy, double *ypw, double cj)
{
    const int n = c->n;
    double s;
    (void)ab;
    if (c->bt) {
        s = cond_solve_bt(c, res, 1, scale, ewt, ee, yy, ypw, cj);
    } else {
        cond_solve_band(c, res);
        s = newton_update(n, res, scale, ewt, ee, yy, ypw, cj);
    }
    return n > 0 ? sqrt(s / n) : 0.0;
}

/* cond_factor_raw with flush-to-zero. */
int kv_cond_factor(kv_cond *c, const double *ab, double cj)
{
    FTZ_ON
    const int info = cond_factor_raw(c, ab, cj);
    FTZ_OFF
    return info;
}

/* cond_solve_raw with flush-to-zero. */
void kv_cond_solve(kv_cond *c, const double *ab, double *res)
{
    FTZ_ON
    cond_solve_raw(c, ab, res);
    FTZ_OFF
}

/* cond_newton_raw with flush-to-zero. */
double kv_cond_newton(kv_cond *c, const double *ab, double *res, double scale,
                      const double *ewt, double *ee, double *yy, double *ypw, double cj)
{
    FTZ_ON
    const double r = cond_newton_raw(c, ab, res, scale, ewt, ee, yy, ypw, cj);
    FTZ_OFF
    return r;
}
