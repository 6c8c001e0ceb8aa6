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
