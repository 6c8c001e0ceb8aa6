/* The numeric phase of the section's supernodal multifrontal Cholesky
 * (runtime/section/cholesky.py, _factor_block; driven by runtime/section/multifrontal.py).
 *
 * The same fronts as the NumPy loop of _factor_block, assembled in the same order and
 * factored with the same LAPACK and BLAS routines (SciPy's own, handed over as function
 * pointers from scipy.linalg.cython_lapack / cython_blas), on copies laid out as SciPy's
 * wrappers lay them out: the factor is the NumPy loop's bit for bit (tested). Written by
 * hand because that loop spends about two thirds of its time in NumPy's per-call
 * overhead (3301 fronts of median size 39 + 51 on a 20k-element mesh: ~0.5 of 0.74 s),
 * not in the dense work.
 *
 * Front s (supernode positions a = bounds[s] .. b = bounds[s+1] of the node ordering)
 * holds the block's unknowns r0 = start[a] .. r1 = start[b] - 1 (k of them, maybe none)
 * and its update unknowns upd = upd_all[uptr[s] .. uptr[s+1]) (u of them, sorted, all
 * >= r1). F (f = k + u, column-major) gets the upper triangle of A's rows r0 .. r1-1
 * (assigned) and then every child's update matrix (added, children in the order they
 * were finished; only the upper triangle is ever read, so only it is added). With k > 0:
 * U11 = chol(F11) (upper, lower triangle zeroed), X = U11^-T F12, and F22 - X^T X (its
 * upper triangle, dsyrk) goes to the parent; with k = 0 F itself goes to the parent.
 */
#include <stdlib.h>
#include <string.h>

typedef void (*kv_potrf_t)(char *, int *, double *, int *, int *);
typedef void (*kv_trsm_t)(char *, char *, char *, char *, int *, int *, double *, double *,
                          int *, double *, int *);
typedef void (*kv_syrk_t)(char *, char *, int *, int *, double *, double *, int *, double *,
                          double *, int *);

/* Returns 0; 1: a pivot block is not positive definite (err[0] = the front, err[1] =
 * LAPACK's info); 2: A has an entry outside the symbolic factor of its row's front
 * (err[0] = the front); 3: a child's update unknown is not in its parent's front; 4: out
 * of memory. out + off[s]: U11 (k x k), then X (k x u), column-major, of every front
 * with k > 0. loc, stamp: workspaces of n entries (stamp: all -1 on entry). */
int kv_mf_factor(int ns, const long long *bounds, const long long *start,
                 const long long *upd_all, const long long *uptr, const long long *parent,
                 const long long *indptr, const long long *indices, const double *data,
                 const long long *off, double *out, long long *loc, long long *stamp,
                 void *potrf_p, void *trsm_p, void *syrk_p, long long *err)
{
    kv_potrf_t potrf = (kv_potrf_t)potrf_p;
    kv_trsm_t trsm = (kv_trsm_t)trsm_p;
    kv_syrk_t syrk = (kv_syrk_t)syrk_p;
    /* the update matrices waiting for their parent: per parent a list in finishing order */
    double **pend = calloc((size_t)ns, sizeof(double *));
    long long *first = malloc(sizeof(long long) * (size_t)ns);
    long long *last = malloc(sizeof(long long) * (size_t)ns);
    long long *next = malloc(sizeof(long long) * (size_t)ns);
    int rc = 0;
    if (!pend || !first || !last || !next) { rc = 4; goto done; }
    for (int s = 0; s < ns; ++s) first[s] = last[s] = next[s] = -1;
    for (int s = 0; s < ns && rc == 0; ++s) {
        const long long *upd = upd_all + uptr[s];
        const long long u = uptr[s + 1] - uptr[s];
        const long long r0 = start[bounds[s]], r1 = start[bounds[s + 1]], k = r1 - r0;
        if (k == 0 && first[s] < 0) continue;
        const long long f = k + u;
        for (long long i = 0; i < k; ++i) { loc[r0 + i] = i; stamp[r0 + i] = s; }
        for (long long i = 0; i < u; ++i) { loc[upd[i]] = k + i; stamp[upd[i]] = s; }
        double *F = calloc((size_t)(f * f > 0 ? f * f : 1), sizeof(double));
        if (!F) { rc = 4; break; }
        for (long long r = r0; r < r1 && rc == 0; ++r)
            for (long long p = indptr[r]; p < indptr[r + 1]; ++p) {
                const long long c = indices[p];
                if (stamp[c] != s) { rc = 2; err[0] = s; break; }
                F[(r - r0) + loc[c] * f] = data[p];
            }
        for (long long c = first[s]; c >= 0 && rc == 0; c = next[c]) {
            const long long *cu = upd_all + uptr[c];
            const long long cn = uptr[c + 1] - uptr[c];
            const double *U = pend[c];
            for (long long i = 0; i < cn; ++i)
                if (stamp[cu[i]] != s) { rc = 3; err[0] = s; break; }
            if (rc) break;
            for (long long j = 0; j < cn; ++j) {
                double *Fj = F + loc[cu[j]] * f;
                const double *Uj = U + j * cn;
                for (long long i = 0; i <= j; ++i) Fj[loc[cu[i]]] += Uj[i];
            }
        }
        for (long long c = first[s]; c >= 0; c = next[c]) { free(pend[c]); pend[c] = NULL; }
        if (rc) { free(F); break; }
        double *pass = NULL;
        if (k == 0) {
            pass = F;                       /* nothing of this block to eliminate here */
        } else {
            double *U11 = out + off[s], *X = U11 + k * k;
            for (long long j = 0; j < k; ++j)
                memcpy(U11 + j * k, F + j * f, sizeof(double) * (size_t)k);
            int ki = (int)k, info = 0;
            char up = 'U';
            potrf(&up, &ki, U11, &ki, &info);
            if (info != 0) { rc = 1; err[0] = s; err[1] = info; free(F); break; }
            for (long long j = 0; j < k; ++j)       /* clean: the lower triangle zeroed */
                for (long long i = j + 1; i < k; ++i) U11[i + j * k] = 0.0;
            if (u > 0) {
                int ui = (int)u;
                double one = 1.0, minus = -1.0;
                char side = 'L', tr = 'T', nd = 'N';
                for (long long j = 0; j < u; ++j)
                    memcpy(X + j * k, F + (k + j) * f, sizeof(double) * (size_t)k);
                trsm(&side, &up, &tr, &nd, &ki, &ui, &one, U11, &ki, X, &ki);
                pass = malloc(sizeof(double) * (size_t)(u * u));
                if (!pass) { rc = 4; free(F); break; }
                for (long long j = 0; j < u; ++j)
                    memcpy(pass + j * u, F + k + (k + j) * f, sizeof(double) * (size_t)u);
                syrk(&up, &tr, &ui, &ki, &minus, X, &ki, &one, pass, &ui);
            }
            free(F);
        }
        const long long p = parent[s];
        if (pass && p >= 0 && p < ns) {
            pend[s] = pass;
            if (last[p] < 0) first[p] = s; else next[last[p]] = s;
            last[p] = s;
        } else {
            free(pass);
        }
    }
done:
    if (pend)
        for (int s = 0; s < ns; ++s) free(pend[s]);
    free(pend); free(first); free(last); free(next);
    return rc;
}

/* ---- The symbolic phase's supernodes (cholesky._supernodes_python, bit for bit) ----
 * Integer bookkeeping only, written in C because its Python loops (one iteration per
 * fundamental supernode and per child: 21,199 supernodes on the 20k-element laminate's
 * node graph of 41,531 nodes) cost ~70 ms a factorization there. The node factor L (m columns, CSC, sorted, diagonal first) in
 * elimination order: fundamental supernodes (chains j -> j + 1 whose column counts drop
 * by one), then each child merged into its parent (children in increasing order) while
 * the merged front has at most small_nodes columns or its explicit zeros are at most the
 * limit of the first size class nz_size[i] >= its columns; the kept children of a merged
 * child become its host's. Output: the merged tree's postorder (the same traversal as the
 * Python stack), order (m: the columns, each supernode's sorted), bounds (at most m + 1),
 * tops (the last original column of each). Returns the number of supernodes, or -1 when
 * out of memory. */
static int kv_cmp_ll(const void *a, const void *b)
{
    const long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

long long kv_mf_supernodes(long long m, const long long *indptr, const long long *indices,
                           long long small_nodes, int nclass, const double *nz_size,
                           const double *nz_limit, long long *order, long long *bounds,
                           long long *tops)
{
    long long rc = -1, ns = 0, nout = 0, pos = 0;
    long long *parent = malloc(sizeof(long long) * (size_t)(m > 0 ? m : 1));
    long long *starts = malloc(sizeof(long long) * (size_t)(m + 1));
    long long *owner = malloc(sizeof(long long) * (size_t)(m > 0 ? m : 1));
    long long *sparent = NULL, *ncols = NULL, *nupd = NULL, *truec = NULL, *cptr = NULL,
              *clist = NULL, *kid_head = NULL, *kid_tail = NULL, *kid_next = NULL,
              *mem_head = NULL, *mem_tail = NULL, *mem_next = NULL, *stack = NULL,
              *ranges = NULL;
    if (!parent || !starts || !owner) goto done;
    for (long long j = 0; j < m; ++j) {
        const long long cnt = indptr[j + 1] - indptr[j];
        parent[j] = cnt > 1 ? indices[indptr[j] + 1] : -1;
    }
    for (long long j = 0; j < m; ++j) {
        /* column j continues the chain of j - 1 */
        const int chain = j > 0 && parent[j - 1] == j
                          && indptr[j] - indptr[j - 1] == indptr[j + 1] - indptr[j] + 1;
        if (!chain) starts[ns++] = j;
        owner[j] = ns - 1;
    }
    starts[ns] = m;
    const size_t sz = sizeof(long long) * (size_t)(ns > 0 ? ns : 1);
    sparent = malloc(sz); ncols = malloc(sz); nupd = malloc(sz); truec = malloc(sz);
    cptr = calloc((size_t)ns + 2, sizeof(long long)); clist = malloc(sz);
    kid_head = malloc(sz); kid_tail = malloc(sz); kid_next = malloc(sz);
    mem_head = malloc(sz); mem_tail = malloc(sz); mem_next = malloc(sz);
    /* every supernode is on the stack at most twice (to expand, to emit) */
    stack = malloc(2 * sz + sizeof(long long)); ranges = malloc(sz);
    if (!sparent || !ncols || !nupd || !truec || !cptr || !clist || !kid_head || !kid_tail
        || !kid_next || !mem_head || !mem_tail || !mem_next || !stack || !ranges)
        goto done;
    for (long long g = 0; g < ns; ++g) {
        const long long top = starts[g + 1] - 1, p = parent[top];
        sparent[g] = p >= 0 ? owner[p] : -1;
        ncols[g] = starts[g + 1] - starts[g];
        nupd[g] = indptr[top + 1] - indptr[top] - 1;
        truec[g] = ncols[g] * (ncols[g] + 1) / 2 + ncols[g] * nupd[g];
        kid_head[g] = kid_tail[g] = kid_next[g] = -1;
        mem_head[g] = mem_tail[g] = g;
        mem_next[g] = -1;
        if (sparent[g] >= 0) cptr[sparent[g] + 2]++;
    }
    for (long long g = 0; g < ns; ++g) cptr[g + 2] += cptr[g + 1];
    for (long long g = 0; g < ns; ++g)              /* children in increasing order */
        if (sparent[g] >= 0) clist[cptr[sparent[g] + 1]++] = g;
    for (long long p = 0; p < ns; ++p)
        for (long long i = cptr[p]; i < cptr[p + 1]; ++i) {
            const long long c = clist[i], k = ncols[p] + ncols[c];
            const long long dense = k * (k + 1) / 2 + k * nupd[p];
            const double zeros = 1.0 - (double)(truec[p] + truec[c]) / (double)dense;
            double limit = nz_limit[nclass - 1];
            for (int q = 0; q < nclass; ++q)
                if ((double)k <= nz_size[q]) { limit = nz_limit[q]; break; }
            if (k <= small_nodes || zeros <= limit) {
                ncols[p] = k;
                truec[p] += truec[c];
                mem_next[mem_tail[c]] = mem_head[p];      /* members[c] + members[p] */
                mem_head[p] = mem_head[c];
                if (kid_head[c] >= 0) {                    /* kids[p].extend(kids[c]) */
                    if (kid_head[p] >= 0) kid_next[kid_tail[p]] = kid_head[c];
                    else kid_head[p] = kid_head[c];
                    kid_tail[p] = kid_tail[c];
                }
            } else {                                       /* kids[p].append(c) */
                kid_next[c] = -1;
                if (kid_head[p] >= 0) kid_next[kid_tail[p]] = c;
                else kid_head[p] = c;
                kid_tail[p] = c;
            }
        }
    /* postorder: the roots in increasing order, each node's kids in their list's order;
       a stack entry is g (to expand) or -1 - g (to emit) */
    long long sp = 0;
    for (long long g = ns - 1; g >= 0; --g)
        if (sparent[g] < 0) stack[sp++] = g;
    while (sp > 0) {
        const long long e = stack[--sp];
        if (e < 0) {
            const long long g = -1 - e;
            long long nr = 0;
            for (long long h = mem_head[g]; h >= 0; h = mem_next[h]) ranges[nr++] = starts[h];
            qsort(ranges, (size_t)nr, sizeof(long long), kv_cmp_ll);
            for (long long r = 0; r < nr; ++r) {
                const long long h = owner[ranges[r]];
                for (long long j = starts[h]; j < starts[h + 1]; ++j) order[pos++] = j;
            }
            bounds[nout] = pos;
            tops[nout] = starts[g + 1] - 1;
            nout++;
            continue;
        }
        long long nk = 0;
        for (long long c = kid_head[e]; c >= 0; c = kid_next[c]) nk++;
        stack[sp++] = -1 - e;
        long long at = sp + nk;
        for (long long c = kid_head[e]; c >= 0; c = kid_next[c]) stack[--at] = c;
        sp += nk;
    }
    /* bounds[0] = 0, then the end of each supernode */
    for (long long g = nout; g > 0; --g) bounds[g] = bounds[g - 1];
    bounds[0] = 0;
    rc = nout;
done:
    free(parent); free(starts); free(owner); free(sparent); free(ncols); free(nupd);
    free(truec); free(cptr); free(clist); free(kid_head); free(kid_tail); free(kid_next);
    free(mem_head); free(mem_tail); free(mem_next); free(stack); free(ranges);
    return rc;
}

/* ---- The solve with the factor (cholesky.CholeskyFactor.solve, bit for bit) ----
 * Written by hand for the same reason as kv_mf_factor: the Python loop over the fronts
 * (two sweeps of 3307 fronts on the 20k-element laminate: a dtrsm, a gather, a product
 * and a scatter each) spends half its ~0.1 s a call in per-call overhead. Forward, per
 * front in order: y[r0:r1] <- U11^-T y[r0:r1], then y[upd] -= X^T y[r0:r1]; backward, in
 * reverse order: y[r0:r1] <- U11^-1 (y[r0:r1] - X y[upd]). The triangular solves are
 * SciPy's dtrsm on a contiguous copy, as its wrapper makes one. The products are formed
 * as NumPy's matmul forms `X.T @ yo` and `X @ y[upd]` (y[upd] a C-ordered gather) with
 * the same BLAS operation on the same memory layout: a row-major product is the
 * column-major one of the transposes (dgemm), a one-row operand makes it a dgemv, an
 * inner dimension of 1 exact products; the same operation in the same layout gives the
 * same bits (SciPy's and NumPy's OpenBLAS take the same kernels; checked, not assumed:
 * the tests compare this solve with the Python loop). y: the block's right-hand sides in
 * its elimination order, n x k (k >= 2), column-major. Fronts: r0, kf, off (U11 at
 * out + off, X after it), their un[g] update unknowns upd_all[ulo[g] ..]. Returns 0, or 4
 * when out of memory (y untouched). */
typedef void (*kv_gemm_t)(char *, char *, int *, int *, int *, double *, double *, int *,
                          double *, int *, double *, double *, int *);
typedef void (*kv_gemv_t)(char *, int *, int *, double *, double *, int *, double *, int *,
                          double *, double *, int *);

int kv_mf_solve(long long nf, const long long *r0, const long long *kf,
                const long long *off, const long long *upd_all, const long long *ulo,
                const long long *un, const double *out, double *y, long long n, long long k,
                void *trsm_p, void *gemm_p, void *gemv_p)
{
    kv_trsm_t trsm = (kv_trsm_t)trsm_p;
    kv_gemm_t gemm = (kv_gemm_t)gemm_p;
    kv_gemv_t gemv = (kv_gemv_t)gemv_p;
    long long umax = 0, kmax = 0;
    for (long long g = 0; g < nf; ++g) {
        if (un[g] > umax) umax = un[g];
        if (kf[g] > kmax) kmax = kf[g];
    }
    const long long wmax = (umax > kmax ? umax : kmax) * k;
    double *w = malloc(sizeof(double) * (size_t)(wmax > 0 ? wmax : 1));
    double *t = malloc(sizeof(double) * (size_t)(wmax > 0 ? wmax : 1));
    if (!w || !t) { free(w); free(t); return 4; }
    char side = 'L', up = 'U', tr = 'T', nt = 'N', nd = 'N';
    double one = 1.0, zero = 0.0;
    int ki = (int)k, inc = 1;
    for (long long g = 0; g < nf; ++g) {             /* L y = b */
        const long long a = r0[g], m = kf[g], u = un[g];
        const long long *upd = upd_all + ulo[g];
        const double *U11 = out + off[g], *X = U11 + m * m;
        int mi = (int)m, ui = (int)u;
        for (long long j = 0; j < k; ++j)
            memcpy(w + j * m, y + a + j * n, sizeof(double) * (size_t)m);
        trsm(&side, &up, &tr, &nd, &mi, &ki, &one, (double *)U11, &mi, w, &mi);
        for (long long j = 0; j < k; ++j)
            memcpy(y + a + j * n, w + j * m, sizeof(double) * (size_t)m);
        if (u == 0) continue;
        if (u == 1)            /* X.T @ yo with one row: t = yo^T x */
            gemv(&tr, &mi, &ki, &one, w, &mi, (double *)X, &inc, &zero, t, &inc);
        else                   /* row-major (u x k) = its transpose (k x u) column-major */
            gemm(&tr, &nt, &ki, &ui, &mi, &one, w, &mi, (double *)X, &mi, &zero, t, &ki);
        for (long long i = 0; i < u; ++i)
            for (long long j = 0; j < k; ++j) y[upd[i] + j * n] -= t[j + i * k];
    }
    for (long long g = nf - 1; g >= 0; --g) {         /* L^T x = y */
        const long long a = r0[g], m = kf[g], u = un[g];
        const long long *upd = upd_all + ulo[g];
        const double *U11 = out + off[g], *X = U11 + m * m;
        int mi = (int)m, ui = (int)u;
        if (u > 0) {
            for (long long i = 0; i < u; ++i)        /* y[upd], row-major (k x u col-major) */
                for (long long j = 0; j < k; ++j) w[j + i * k] = y[upd[i] + j * n];
            if (m == 1)        /* X @ y[upd] with one row: t = y[upd]^T x */
                gemv(&nt, &ki, &ui, &one, w, &ki, (double *)X, &inc, &zero, t, &inc);
            else
                gemm(&nt, &tr, &ki, &mi, &ui, &one, w, &ki, (double *)X, &mi, &zero, t, &ki);
            for (long long j = 0; j < k; ++j)
                for (long long i = 0; i < m; ++i)
                    w[i + j * m] = y[a + i + j * n] - t[j + i * k];
        } else {
            for (long long j = 0; j < k; ++j)
                memcpy(w + j * m, y + a + j * n, sizeof(double) * (size_t)m);
        }
        trsm(&side, &up, &nt, &nd, &mi, &ki, &one, (double *)U11, &mi, w, &mi);
        for (long long j = 0; j < k; ++j)
            memcpy(y + a + j * n, w + j * m, sizeof(double) * (size_t)m);
    }
    free(w); free(t);
    return 0;
}
