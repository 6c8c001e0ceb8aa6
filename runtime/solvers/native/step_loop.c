/* The IDA-style BDF step loop of runtime/solvers/bdf.py in C (step_loop.py links it): one call integrates up to
   a stop time (an output, a checkpoint, a snapshot), a watched sign change, or a failure,
   with the energy audit and the output samples of every step on the way.

   Why C: at N = 50 a step costs ~20 us of arithmetic (residual, Newton solves, norms);
   the same step driven from Python cost ~75 us, most of it interpreter overhead of the
   ~40 NumPy and ctypes calls a step makes, plus ~70 us per step for the energy audit's
   interpolation and quadrature. The algorithm is the one of bdf.py (the pure-Python path
   kept for machines without a C compiler), statement for statement, so that both take
   the same steps up to rounding (tests/runtime/test_step_loop.py checks that). Function
   names follow IDA's (IDASetCoeffs, IDANls, IDATestError, IDACompleteStep, ...).

   The problem comes as function pointers: the rod's compiled kernels (kvrod_residual,
   kvrod_jacobian_band or, on the condensed block path, kvrod_jacobian_band_cells,
   kvrod_energies on a kvrod_rod struct), or ctypes callbacks into Python for any other
   problem. Loads that change with time are re-applied by a
   callback ("drive") only when t leaves the interval on which they are constant. Steps
   whose interpolant Python observers need at given times (the deformed centreline,
   snapshots) are copied and handed over in batches (replay_step) instead of stopping. */
#define _POSIX_C_SOURCE 200112L     /* clock_gettime, POSIX threads under -std=c99 */
#include <time.h>
#if !defined(_WIN32) && !defined(KV_NO_THREADS)
#define KV_THREADS 1                /* the audit's second thread (audit_async) */
#include <pthread.h>
#include <signal.h>
#endif
#include "band.c"
#include "condensed.c"
#include "blocks.c"
#include "statics.c"

typedef int (*kv_res_fn)(const void *ctx, double t, const double *y, const double *yp,
                         double *res);
typedef int (*kv_jac_fn)(const void *ctx, double t, const double *y, const double *yp,
                         double cy, double cj, int ldab, double *ab);
/* kvrod_jacobian_band_cells: the contributions of elements i0..i1 into band storage
   holding columns col0.. of J; element i adds to the columns of cells i-1..i+1 (the
   cells of the condensation) and zeroes those of cell i+1 first */
typedef int (*kv_jac_cells_fn)(const void *ctx, double t, const double *y, const double *yp,
                               double cy, double cj, int ldab, double *ab, int col0, int i0,
                               int i1);
typedef int (*kv_en_fn)(const void *ctx, int m, const double *ts, const double *ys,
                        const double *yps, double *out);
typedef int (*kv_drive_fn)(double t);
/* the sensitivity residual of parameter ip: out <- F_y s + F_y' s' + F_theta_ip at
   (t, y, y') (runtime/model/native/rod_tangent.c: kvrod_sens_residual) */
typedef int (*kv_sres_fn)(const void *ctx, double t, const double *y, const double *yp,
                          int ip, const double *s, const double *sp, double *out);
/* a system of coupled band blocks (an assembly of rods): J into the blocks' bands and
   the couplings' values (kv_blocks in blocks.c) */
typedef int (*kv_sysjac_fn)(const void *ctx, double t, const double *y, const double *yp,
                            double cj, kv_blocks *B);
/* the largest next step the problem's state allows (s; HUGE_VAL: none), e.g. contact:
   no segment moves toward an obstacle by more than a fraction of its gap */
typedef double (*kv_maxstep_fn)(const void *ctx, double t, const double *y, const double *yp);
/* the state's error weights (contact: looser velocity tolerances near obstacles): w =
   1/(rtol |y| + atol) of the error test changed in place after every accepted step;
   0, or a negative code (a kernel failed) */
typedef int (*kv_errw_fn)(const void *ctx, const double *y, double rtol, const double *atol,
                          double *w);

#define KV_MAXORD 5
#define KV_NH (KV_MAXORD + 2)
#define KV_NEN 5            /* energies of a state: T, W, 2D, P_ext, P_bc (then extras) */
#define KV_MAXEN 2048       /* most values per state the energies may return (nen;
                               protocols.MAX_ENERGIES) */
#define KV_MAXWATCH 8
#define KV_AUDIT_NODES 4    /* the energy audit's polynomial: cubic (order 4) */

/* IDA's constants (bdf.py) */
#define EPS_NEWT 0.33
#define TOL_DEL (1e-4 * EPS_NEWT)
#define RATE_MAX 0.9
#define XRATE 0.25

/* return codes of kv_ida_advance (>= 0: stopped normally) */
enum { KV_TSTOP = 0, KV_WATCH = 1, KV_FINISHED = 2, KV_MAXSTEPS = 3,
       KV_FAIL_CONV = -1, KV_FAIL_ERR = -2, KV_FAIL_STALL = -3, KV_FAIL_HMIN = -4,
       KV_FAIL_FIXED = -5, KV_CALLBACK = -6, KV_NONFINITE = -7 };
enum { NLS_OK = 0, NLS_CONV_FAIL = 1, NLS_ERR_FAIL = 2, NLS_CALLBACK = 3, NLS_NONFINITE = 4 };

/* The solver: problem, arrays (owned by Python), settings, IDA's scalar state, counters,
   audit and sampling. Mirrored field for field by CoreStruct in step_loop.py (checked by
   kv_ida_sizeof at load). */
typedef struct {
    /* problem */
    int n, kl, ku, ldab;
    kv_res_fn res;
    kv_jac_fn jac;
    kv_en_fn en;                /* NULL: no audit in C */
    int nen;                    /* values per state of en: KV_NEN, then extras sampled
                                   with the outputs (e.g. the supports' reactions) */
    const void *ctx;
    kv_drive_fn drive;          /* NULL: loads never change */
    double drive_lo, drive_hi;  /* the loads are constant for t in [lo, hi) (drive writes) */
    double drive_t;             /* time the loads were last driven to */
    kv_cond *cond;              /* NULL: full band LU */
    /* arrays: phi (KV_NH x n, row-major), vectors of n */
    double *phi, *y, *yp, *yy, *ypw, *ee, *res_v, *tmp, *ewt, *ewt_err, *errmask, *atol;
    double *ab;
    int *ipiv, *prof;
    /* settings */
    double rtol, t_bound, direction, hmax_inv, min_step, fixed_step;   /* fixed_step 0: none */
    int max_order, maxcor, max_conv_fails, max_error_fails;
    double stab_hmin[KV_NH];    /* order k is chosen only on steps |h| >= stab_hmin[k]
                                   (zeros: no stability bound; bdf.py explains) */
    /* IDA's state */
    double psi[KV_NH], alpha[KV_NH], beta[KV_NH], sigma[KV_NH], gamma[KV_NH];
    int kk, kused, knew, ns, phase, have_lu;
    double hh, hused, cj, cjold, cjlast, cjratio, ss, oldnrm, rr;
    double t, t_old;
    int started;                /* an accepted step exists (t_old valid) */
    /* counters */
    long long nstep, nfev, njev, nlu, nni, netf, ncfn;
    long long nst0;             /* nstep at the last (re)start: the first step after a
                                   restart is IDA's first step (nstep - nst0 == 0) */
    /* failure report: the component blamed, the counts, the kind of the last failure */
    int fail_index, fail_count, fail_nflag;
    double fail_t;              /* time of the attempted point (non-finite values) */
    /* sign changes that stop the loop: y[idx] crossing 0 in direction dir (<0: from > 0
       to <= 0; > 0: from < 0 to >= 0) */
    int nwatch;
    int watch_idx[KV_MAXWATCH];
    double watch_dir[KV_MAXWATCH], watch_old[KV_MAXWATCH];
    int watch_hit;              /* bit mask of the watches that fired in the last step */
    /* energy audit: 2D and P at the ends of the last KV_AUDIT_NODES steps (since the
       last (re)start), integrated over each step on the polynomial through them */
    int audit, nh;              /* nh: nodes held (0 after a (re)start: push()) */
    double ht[KV_AUDIT_NODES], hg[2 * KV_AUDIT_NODES];   /* times; (2D, P) at each */
    double dissipated, external_work;   /* J, up to t_old + the last step (t) */
    double coef[2 * KV_AUDIT_NODES];    /* the last step's polynomials of 2D and P in
                                           x = (t - t_old) / h: coef[KV_AUDIT_NODES c + r] x^r */
    double *wy, *wyp;           /* work: 2 x n each */
    /* samples on an output grid t_out[0..m_out): rows [t, y[samp_idx]..., T, W, int 2D,
       int P] for t_out[k_out], ... into a buffer of rec_cap rows, rec_n of them filled;
       when it is full, flush() hands them to Python (which empties it: rec_n = 0) */
    int nsamp, m_out, k_out, rec_w, rec_cap, rec_n;
    const int *samp_idx;
    const double *t_out;
    double *rec;                /* rec_cap x rec_w */
    kv_drive_fn flush;          /* called with t (unused) */
    double *sy, *syp;           /* work: n each */
    /* seconds spent in: residual, Jacobian, LU, Newton solves, energies, drive (when
       timing is set; for benchmarks: two clock reads per call) */
    int timing;
    double sec[6];
    int stop;                   /* set by Python (a signal held in a callback): return */
    /* the Jacobian by cells (NULL: none; used with the condensed block path): J is then
       evaluated chunk cells at a time into a window of jwin_cols columns (ldab rows) and
       the cells are factored right behind, while their columns are in cache, instead of
       writing all of J (21 MB at N = 4000) and reading it back */
    kv_jac_cells_fn jac_cells;
    double *jwin;
    int jwin_cols, jchunk;
    /* rows F_i = y_i - g_i(t) of prescribed unknowns (a held end's position and velocity):
       their Newton corrections are taken unscaled, so that they hold to round-off at
       every step (IDA scales the simplified Newton's corrections by 2/(1 + cj/cj_old)
       when cj changed, which would leave them at the Newton tolerance); exact_res holds
       their residuals across the solve */
    int nexact;
    const int *exact;
    double *exact_res;
    /* a system of coupled band blocks (NULL: one band, condensed or not): sysjac fills
       the blocks and the couplings, kv_blocks factors and solves (blocks.c) */
    kv_blocks *blocks;
    kv_sysjac_fn sysjac;
    /* steps kept for Python observers that need a step's interpolant at given times (the
       deformed centreline, snapshots), instead of a stop at each: the first step reaching
       t_rep[k_rep] (direction * (t - t_rep) >= 0, the stop condition) is copied into rep
       as a row [t_old, t, k, psi[0..KV_NH), phi_0 .. phi_k (n each), the sensitivities'
       history (KV_NH nsens n), y at t (n)] (rep_w doubles); rep_flush() hands the rows to
       Python when rep_cap are filled (Python flushes them itself at every stop, so they
       are replayed in step order). A step is kept once, whatever asked for it. */
    int m_rep, k_rep, rep_w, rep_cap, rep_n;
    const double *t_rep;
    double *rep;
    kv_drive_fn rep_flush;      /* called with t (unused) */
    /* NULL, or the state's bound on the next step, applied after every accepted step as
       hmax is (bdf.py: BDF._state_max_step) */
    kv_maxstep_fn maxstep;
    /* forward sensitivities (runtime/solvers/sensitivity.py, the same algorithm: IDAS's
       staggered corrector after the state's; nsens = 0: none). Vectors of ns = nsens n
       values, parameter i's at [i n, (i+1) n); sphi: KV_NH x ns */
    int nsens, errconS, sscaled;
    kv_sres_fn sres;
    const void *sctx;
    double *sphi, *s_y, *s_yp, *s_yy, *s_ypw, *s_ee, *s_ewt, *s_ewt_err, *s_mask, *s_atol;
    double *s_res, *s_delta;
    double ssS;
    long long nfevS, nniS, ncfnS, netfS, nsetupS;
    /* the sensitivities at the output samples: srec row r holds, for the state's row r
       of rec, s_i[samp_idx[j]] at [i nsamp + j] (NULL: not sampled); s_wy, s_wyp: work
       (ns each) */
    double *srec, *s_wy, *s_wyp;
    /* the sensitivities' own Newton system (s_ab NULL: they share the state's): band
       storage, its condensed systems (NULL: band LU), pivots; the cj of its factors, the
       step count when they were made and whether they are regular; lu_stamp: the step
       count at the state's last factorisation */
    double *s_ab;
    kv_cond *s_cond;
    int *s_ipiv, *s_prof;
    double s_cj;
    long long s_stamp, lu_stamp;
    int s_have_lu;
    /* NULL, or the state's change of the error test's weights (ewt_err, then a separate
       array), applied after every accepted step (bdf.py: BDF._state_error_weights) */
    kv_errw_fn errw;
    /* an output grid of whole states (solve's t_eval): after every accepted step, y and
       y' at each t_grid[k_grid] that the step reaches (direction * (t_grid - t) <= 0) are
       interpolated on it into rows k_grid of grid_y, grid_yp (m_grid x n, row-major,
       owned by Python), so that the loop need not return at each output time */
    int m_grid, k_grid;
    const double *t_grid;
    double *grid_y, *grid_yp;
    /* NULL, or en's 2D and powers alone (values 2, 3, 4 of a state, bit for bit those of
       en; the others need not be filled): the audit's nodes need no more */
    kv_en_fn en_audit;
    /* frames of chosen components instead (the deformed centreline, Centreline in
       observers.py): with grid_idx set, rows of grid_y hold y[grid_idx[0..grid_nidx)] and
       grid_yp is not written (grid_wy: work, n); with grid_slack, a time
       up to 1e-12 max(1, |t|) past the step's end counts as reached and is taken at the
       end (forward runs: the Python observer's rule) */
    const int *grid_idx;
    double *grid_wy;
    int grid_nidx, grid_slack;
    /* the energy audit and the output samples on a second thread while the steps go on
       (1: asked for; taken by an advance call only as async_start allows): jobs in a
       ring of async_cap slots of 4 n doubles at async_buf (owned by Python); the values
       are those of the one-thread path bit for bit; async_runs: the calls that ran it */
    int audit_async, async_cap, async_runs;
    double *async_buf;
    /* 1: the energies read nothing of y' (a rod without coupled sections or contact,
       CKernels.energies_read_rates): the audit's and the samples' states are
       interpolated without it (the same y, bit for bit; ~40 % less work) */
    int en_no_yp;
    /* bit mask of the watches whose sign changes are kept as replayed steps (rep, for
       the observer's step hook at the next flush) instead of stopping the loop (a
       return to Python costs ~0.5 ms: the tip's maxima of a vibration); rep_nstep: the
       step last kept (nstep), so that no step is kept twice */
    int watch_rep;
    long long rep_nstep;
} kv_ida;

enum { SEC_RES, SEC_JAC, SEC_LU, SEC_NEWTON, SEC_EN, SEC_DRIVE };

static double now(const kv_ida *S)
{
    if (!S->timing) return 0.0;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
#define TIC(S) double tic_ = now(S)
#define TOC(S, k) do { if ((S)->timing) (S)->sec[k] += now(S) - tic_; } while (0)

size_t kv_ida_sizeof(void) { return sizeof(kv_ida); }

/* ---- calls into the problem (outside the flush-to-zero mode of the integrator's own
   arithmetic: the kernels see the caller's floating-point environment) -------------- */
#if defined(__x86_64__) || defined(__SSE2__)
#define USER_MODE(S) _mm_setcsr((S)->user_csr_)
#define CORE_MODE(S) _mm_setcsr((S)->user_csr_ | 0x8040u)
#else
#define USER_MODE(S)
#define CORE_MODE(S)
#endif

struct kv_async_s;
/* one advance call (A: the audit's thread, NULL when the audit runs in the loop) */
typedef struct { kv_ida *S; unsigned int user_csr_; struct kv_async_s *A; } kv_run;

static int drive_to(kv_run *R, double t)
{
    kv_ida *S = R->S;
    if (!S->drive || (t >= S->drive_lo && t < S->drive_hi) || t == S->drive_t) return 0;
    TIC(S);
    USER_MODE(R);
    int rc = S->drive(t);
    CORE_MODE(R);
    TOC(S, SEC_DRIVE);
    if (rc == 0) S->drive_t = t;
    return rc;
}

static int call_res(kv_run *R, double t, const double *y, const double *yp, double *out)
{
    kv_ida *S = R->S;
    if (drive_to(R, t)) return 1;
    TIC(S);
    USER_MODE(R);
    int rc = S->res(S->ctx, t, y, yp, out);
    CORE_MODE(R);
    TOC(S, SEC_RES);
    S->nfev++;
    return rc;
}

static int call_jac(kv_run *R, double t, double cj)
{
    kv_ida *S = R->S;
    if (drive_to(R, t)) return 1;
    TIC(S);
    USER_MODE(R);
    int rc = S->jac(S->ctx, t, S->yy, S->ypw, 1.0, cj, S->ldab, S->ab);
    CORE_MODE(R);
    TOC(S, SEC_JAC);
    S->njev++;
    return rc;
}

/* energies of m states (rows of ys, yps) at times ts: one kernel call when the loads are
   constant over all of them, else one per state (as RodModel.energies) */
static int call_en_fn(kv_run *R, kv_en_fn en, int m, const double *ts, const double *ys,
                      const double *yps, double *out)
{
    kv_ida *S = R->S;
    if (drive_to(R, ts[0])) return 1;
    int steady = 1;
    if (S->drive)
        for (int i = 1; i < m; ++i)
            if (!((ts[i] >= S->drive_lo && ts[i] < S->drive_hi) || ts[i] == S->drive_t))
                steady = 0;
    int rc = 0;
    if (steady) {
        TIC(S);
        USER_MODE(R);
        rc = en(S->ctx, m, ts, ys, yps, out);
        CORE_MODE(R);
        TOC(S, SEC_EN);
        return rc;
    }
    for (int i = 0; i < m && rc == 0; ++i) {
        if (drive_to(R, ts[i])) return 1;
        TIC(S);
        USER_MODE(R);
        rc = en(S->ctx, 1, ts + i, ys + (size_t)i * S->n, yps + (size_t)i * S->n,
                out + (size_t)i * S->nen);
        CORE_MODE(R);
        TOC(S, SEC_EN);
    }
    return rc;
}

static int call_en(kv_run *R, int m, const double *ts, const double *ys, const double *yps,
                   double *out)
{
    return call_en_fn(R, R->S->en, m, ts, ys, yps, out);
}

/* ---- vector helpers ---------------------------------------------------------------- */
static int argmax_abs(int n, const double *v, const double *w)
{
    int k = 0;
    double big = -1.0;
    for (int i = 0; i < n; ++i) {
        double a = fabs(w ? v[i] * w[i] : v[i]);
        if (a > big || (a != a && big == big)) { big = a; k = i; }
    }
    return k;
}

static double hmin(const kv_ida *S)
{
    double a = 16.0 * 2.220446049250313e-16 * fabs(S->t);
    double m = S->min_step > a ? S->min_step : a;
    return m > 1e-300 ? m : 1e-300;
}

#define PHI(j) (S->phi + (size_t)(j) * (size_t)S->n)

/* ---- IDA ------------------------------------------------------------------------- */
static double set_coeffs(kv_ida *S)     /* IDASetCoeffs; returns ck */
{
    const int kk = S->kk;
    const double hh = S->hh;
    double *psi = S->psi, *alpha = S->alpha, *beta = S->beta, *sigma = S->sigma,
           *gamma = S->gamma;
    if (hh != S->hused || kk != S->kused) S->ns = 0;
    S->ns = S->ns + 1 < S->kused + 2 ? S->ns + 1 : S->kused + 2;
    const int ns = S->ns;
    if (kk + 1 >= ns) {
        beta[0] = alpha[0] = sigma[0] = 1.0;
        gamma[0] = 0.0;
        double temp1 = hh;
        for (int i = 1; i <= kk; ++i) {
            double temp2 = psi[i - 1];
            psi[i - 1] = temp1;
            beta[i] = beta[i - 1] * psi[i - 1] / temp2;
            temp1 = temp2 + hh;
            alpha[i] = hh / temp1;
            sigma[i] = i * sigma[i - 1] * alpha[i];
            gamma[i] = gamma[i - 1] + alpha[i - 1] / hh;
        }
        psi[kk] = temp1;
    }
    double alphas = 0.0, alpha0 = 0.0;
    for (int i = 0; i < kk; ++i) {
        alphas -= 1.0 / (i + 1);
        alpha0 -= alpha[i];
    }
    S->cjlast = S->cj;
    S->cj = -alphas / hh;
    double ck = fabs(alpha[kk] + alphas - alpha0);
    if (alpha[kk] > ck) ck = alpha[kk];
    /* IDASetCoeffs' rescaling phi_j *= beta_j (j = ns .. kk) is done by predict, in its
       pass over phi */
    return ck;
}

/* IDAPredict, into the Newton iterates: yy = sum_j phi_j, ypw = sum_j gamma_j phi_j,
   summed in j order per component (as bdf.py's _predict) in one pass over memory; with
   ns <= kk first set_coeffs' rescaling phi_j *= beta_j for j = ns .. kk (the same
   products as bdf.py's, in the same pass: at N = 1000 the pass over phi, not the
   arithmetic, is the cost) */
/* The per-step loops over the n components with the order a literal (the switches
   below): the loop over j unrolls and the loop over the components vectorises. Each
   component gets the same operations in the same order as with a variable order, so the
   same bits; at n = 1565 (the Maxwell cantilever) the prediction and the history update
   took ~9 and ~8 us a step as scalar loops. */
#define KV_ORDER_SWITCH(k, CALL) \
    switch (k) { \
    case 1: CALL(1); break; \
    case 2: CALL(2); break; \
    case 3: CALL(3); break; \
    case 4: CALL(4); break; \
    case 5: CALL(5); break; \
    default: CALL(k); break; \
    }

/* y = sum_j phi_j, y' = sum_{j >= 1} gamma_j phi_j (in j's order) */
KV_INLINE void predict_sum(int kk, int n, double *const *ph, const double *g,
                           double *restrict yy, double *restrict ypw)
{
    for (int q = 0; q < n; ++q) {
        double a = ph[0][q], b = 0.0;
        for (int j = 1; j <= kk; ++j) {
            const double v = ph[j][q];
            a += v;
            b += g[j] * v;
        }
        yy[q] = a;
        ypw[q] = b;
    }
}

/* IDAPredict after the history's rows ns..kk are scaled by beta (IDASetCoeffs) */
static void predict_scaled(kv_ida *S, int ns)
{
    const int n = S->n, kk = S->kk;
    double g[KV_NH];
    double *ph[KV_NH];
    for (int j = 0; j <= kk; ++j) { g[j] = S->gamma[j]; ph[j] = PHI(j); }
    if (ns < 1) ns = 1;
    for (int j = ns; j <= kk; ++j) {
        double *restrict p = ph[j];
        const double bj = S->beta[j];
        for (int q = 0; q < n; ++q) p[q] *= bj;
    }
#define KV_PREDICT(K) predict_sum(K, n, ph, g, S->yy, S->ypw)
    KV_ORDER_SWITCH(kk, KV_PREDICT)
#undef KV_PREDICT
}

static void predict(kv_ida *S) { predict_scaled(S, S->kk + 1); }

static void sens_restore(kv_ida *S);

static void restore(kv_ida *S)           /* IDARestore */
{
    const int kk = S->kk, n = S->n;
    for (int j = 1; j <= kk; ++j) S->psi[j - 1] = S->psi[j] - S->hh;
    for (int j = S->ns; j <= kk; ++j) {
        double *p = PHI(j), r = 1.0 / S->beta[j];
        for (int q = 0; q < n; ++q) p[q] *= r;
    }
    if (S->nsens) sens_restore(S);
}

/* J by cells, condensed and factored behind the sweep (kv_ida.jac_cells): the same
   entries, summed in the same order, and the same factorisation as call_jac then
   cond_factor_bt (cell k needs the columns of cells k-1..k+1, final once element k+2 is
   in, and is done then; the window keeps the columns from cell k-1 on, slid to its
   start by a copy). Returns as cond_factor_raw; -2 after a failed Jacobian call. */
static int jac_factor_cells(kv_run *R, double t, double cj)
{
    kv_ida *S = R->S;
    kv_cond *c = S->cond;
    const int ncell = c->ncell, ldab = S->ldab, chunk = S->jchunk;
    const int *cf = c->cf;
    int el = 0, fac = 0, lo = 0, info = 0;
    if (drive_to(R, t)) return -2;
    c->q_cjf = cj;                      /* as cond_factor_raw */
    while (fac < ncell) {
        const int i1 = el + chunk - 1 < ncell - 1 ? el + chunk - 1 : ncell - 1;
        const int hi = i1 + 2 < ncell ? i1 + 2 : ncell;   /* the columns written reach cell i1+1 */
        if (cf[hi] - cf[lo] > S->jwin_cols) { info = -2; break; }
        TIC(S);
        USER_MODE(R);
        const int rc = S->jac_cells(S->ctx, t, S->yy, S->ypw, 1.0, cj, ldab, S->jwin, cf[lo],
                                    el, i1);
        CORE_MODE(R);
        TOC(S, SEC_JAC);
        if (rc) { info = -2; break; }
        el = i1 + 1;
        const int last = el == ncell ? ncell - 1 : el - 3;
        if (last >= fac) {
            TIC(S);
            c->col0 = cf[lo];
            info = cond_factor_bt_cells(c, S->jwin, fac, last);
            c->col0 = 0;
            TOC(S, SEC_LU);
            if (info) break;
            fac = last + 1;
        }
        if (el == ncell) break;
        const int nlo = fac > 0 ? fac - 1 : 0;
        if (nlo > lo) {
            memmove(S->jwin, S->jwin + (size_t)(cf[nlo] - cf[lo]) * (size_t)ldab,
                    sizeof(double) * (size_t)(cf[hi] - cf[nlo]) * (size_t)ldab);
            lo = nlo;
        }
    }
    S->njev++;
    return info;
}

/* J of a system of coupled band blocks into the blocks and couplings, factorised */
static int setup_blocks(kv_run *R, double t)
{
    kv_ida *S = R->S;
    if (drive_to(R, t)) return -2;
    int rc, info;
    {
        TIC(S);
        USER_MODE(R);
        rc = S->sysjac(S->ctx, t, S->yy, S->ypw, S->cj, S->blocks);
        CORE_MODE(R);
        TOC(S, SEC_JAC);
    }
    S->njev++;
    if (rc) return -2;
    {
        TIC(S);
        info = blocks_factor_raw(S->blocks);
        TOC(S, SEC_LU);
    }
    return info;
}

/* evaluate and factorise J at the iterate; 1 ok, 0 singular, -1 callback failure */
static int setup(kv_run *R, double t)
{
    kv_ida *S = R->S;
    int info;
    if (S->blocks) {
        info = setup_blocks(R, t);
        if (info == -2) return -1;
    } else if (S->jac_cells && S->cond && S->cond->bt) {
        info = jac_factor_cells(R, t, S->cj);
        if (info == -2) return -1;
    } else {
        if (call_jac(R, t, S->cj)) return -1;
        TIC(S);
        if (S->cond) info = kv_cond_factor(S->cond, S->ab, S->cj);   /* J stays in ab */
        else info = kv_gbtrf(S->n, S->kl, S->ku, S->ab, S->ldab, S->ipiv, S->prof);
        TOC(S, SEC_LU);
    }
    S->nlu++;
    S->lu_stamp = S->nstep;
    S->cjold = S->cj;
    S->cjratio = 1.0;
    S->ss = 20.0;
    S->ssS = 20.0;
    S->have_lu = info == 0;
    return info == 0;
}

/* the exact rows (see kv_ida.exact): their residuals before the solve, and after it the
   part of their correction that the scale left out, (1 - scale) F_i, so that the
   correction is F_i itself (the rows are identities: the solve gives scale F_i) */
static void exact_rows_keep(kv_ida *S)
{
    for (int k = 0; k < S->nexact; ++k) S->exact_res[k] = S->res_v[S->exact[k]];
}

static void exact_rows_finish(kv_ida *S, double scale)
{
    if (scale == 1.0) return;
    for (int k = 0; k < S->nexact; ++k) {
        const int i = S->exact[k];
        const double d = (1.0 - scale) * S->exact_res[k];
        S->ee[i] -= d;
        S->yy[i] -= d;
        S->ypw[i] -= S->cj * d;
    }
}

static int nls(kv_run *R, double tnew)   /* IDANls: simplified Newton for ee */
{
    kv_ida *S = R->S;
    const int n = S->n;
    int call_setup = 0;
    if (S->nstep == S->nst0 && !S->have_lu) {
        S->cjold = S->cj;
        S->ss = 20.0;
        S->ssS = 20.0;
        call_setup = 1;
    }
    S->cjratio = S->cj / S->cjold;
    const double cj_lo = (1.0 - XRATE) / (1.0 + XRATE), cj_hi = 1.0 / cj_lo;
    if (S->cjratio < cj_lo || S->cjratio > cj_hi || !S->have_lu) call_setup = 1;
    if (S->cj != S->cjlast) { S->ss = 100.0; S->ssS = 100.0; }

    int first = 1;
    for (;;) {
        if (!first) predict(S);
        first = 0;
        memset(S->ee, 0, sizeof(double) * (size_t)n);
        if (call_res(R, tnew, S->yy, S->ypw, S->res_v)) return NLS_CALLBACK;
        int jcur = 0;
        if (call_setup) {
            jcur = 1;
            int ok = setup(R, tnew);
            if (ok < 0) return NLS_CALLBACK;
            if (!ok) {
                S->fail_index = argmax_abs(n, S->res_v, 0);
                return NLS_CONV_FAIL;
            }
        }
        const double cj = S->cj;
        const double scale = S->cjratio != 1.0 ? 2.0 / (1.0 + S->cjratio) : 1.0;
        int m = 0;
        for (;;) {
            double delnrm;
            exact_rows_keep(S);
            TIC(S);
            if (S->blocks)
                delnrm = blocks_newton_raw(S->blocks, S->res_v, scale, S->ewt, S->ee,
                                           S->yy, S->ypw, cj);
            else if (S->cond)
                delnrm = kv_cond_newton(S->cond, S->ab, S->res_v, scale, S->ewt, S->ee,
                                        S->yy, S->ypw, cj);
            else
                delnrm = kv_newton(n, S->kl, S->ku, S->ab, S->ldab, S->ipiv, S->prof,
                                   S->res_v, scale, S->ewt, S->ee, S->yy, S->ypw, cj);
            TOC(S, SEC_NEWTON);
            exact_rows_finish(S, scale);
            if (!isfinite(delnrm)) { S->fail_t = tnew; return NLS_NONFINITE; }
            S->nni++;
            if (m == 0) {
                S->oldnrm = delnrm;
                if (delnrm <= TOL_DEL) return NLS_OK;
            } else {
                double rate = pow(delnrm / S->oldnrm, 1.0 / m);
                if (rate > RATE_MAX) break;
                S->ss = rate / (1.0 - rate);
            }
            if (S->ss * delnrm <= EPS_NEWT) return NLS_OK;
            m += 1;
            if (m >= S->maxcor) break;
            if (call_res(R, tnew, S->yy, S->ypw, S->res_v)) return NLS_CALLBACK;
        }
        S->fail_index = argmax_abs(n, S->res_v, S->ewt);
        if (jcur) return NLS_CONV_FAIL;
        call_setup = 1;
    }
}

/* IDATestError: estimates at orders k, k-1, k-2 (out: err[3]) and the test */
static int test_error(kv_ida *S, double ck, double *err)
{
    const int kk = S->kk, n = S->n;
    const double *sigma = S->sigma, *w = S->ewt_err, *ee = S->ee;
    /* the three weighted norms of ee, phi_k + ee and phi_k-1 + phi_k + ee in one pass
       (each sum in component order, as kv_wrms) */
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    {
        const double *pk = PHI(kk), *pk1 = PHI(kk > 1 ? kk - 1 : kk);
        for (int q = 0; q < n; ++q) {
            const double e = ee[q], wq = w[q];
            double t = e * wq;
            s0 += t * t;
            const double d1 = pk[q] + e;
            t = d1 * wq;
            s1 += t * t;
            t = (d1 + pk1[q]) * wq;
            s2 += t * t;
        }
    }
    double enorm_k = n > 0 ? sqrt(s0 / n) : 0.0;
    err[0] = sigma[kk] * enorm_k;
    double terr_k = (kk + 1) * err[0];
    err[1] = err[2] = 0.0;
    S->knew = kk;
    if (kk > 1) {
        err[1] = sigma[kk - 1] * (n > 0 ? sqrt(s1 / n) : 0.0);
        double terr_km1 = kk * err[1];
        if (kk > 2) {
            err[2] = sigma[kk - 2] * (n > 0 ? sqrt(s2 / n) : 0.0);
            double terr_km2 = (kk - 1) * err[2];
            if ((terr_km1 > terr_km2 ? terr_km1 : terr_km2) <= terr_k) S->knew = kk - 1;
        } else if (terr_km1 <= 0.5 * terr_k) {
            S->knew = kk - 1;
        }
    }
    if (ck * enorm_k > 1.0) {
        S->fail_index = argmax_abs(n, ee, w);
        return NLS_ERR_FAIL;
    }
    return NLS_OK;
}

/* ---- forward sensitivities: runtime/solvers/sensitivity.py statement for statement
   (IDAS's staggered corrector, IDASensNls / IDASensTestError) ---- */
#define SPHI(j) (S->sphi + (size_t)(j) * (size_t)S->nsens * (size_t)S->n)

/* the largest of the sensitivities' weighted RMS norms (IDASensWrmsNorm) */
static double sens_norm(const kv_ida *S, const double *v, const double *w)
{
    double big = 0.0;
    const int n = S->n;
    for (int i = 0; i < S->nsens; ++i) {
        const double a = kv_wrms(n, v + (size_t)i * n, 0, w + (size_t)i * n);
        if (a > big || a != a) big = a;
    }
    return big;
}

static void sens_weights(kv_ida *S)
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    for (size_t q = 0; q < ns; ++q)
        S->s_ewt[q] = 1.0 / (fabs(S->s_y[q]) * S->rtol + S->s_atol[q]);
    if (S->s_mask)
        for (size_t q = 0; q < ns; ++q) S->s_ewt_err[q] = S->s_ewt[q] * S->s_mask[q];
}

static void sens_scale(kv_ida *S)         /* phi -> phi* (IDASetCoeffs), the state's */
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    for (int j = S->ns; j <= S->kk; ++j) {
        double *p = SPHI(j), b = S->beta[j];
        for (size_t q = 0; q < ns; ++q) p[q] *= b;
    }
    S->sscaled = 1;
}

static void sens_restore(kv_ida *S)       /* IDARestore */
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    if (S->sscaled)
        for (int j = S->ns; j <= S->kk; ++j) {
            double *p = SPHI(j), r = 1.0 / S->beta[j];
            for (size_t q = 0; q < ns; ++q) p[q] *= r;
        }
    S->sscaled = 0;
}

static void sens_rescale_first(kv_ida *S, double f)   /* IDAReset: h s'0 to a new h */
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    double *p = SPHI(1);
    for (size_t q = 0; q < ns; ++q) p[q] *= f;
}

static void sens_predict(kv_ida *S)       /* IDASensPredict, summed in j order */
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    const int kk = S->kk;
    for (size_t q = 0; q < ns; ++q) {
        double a = SPHI(0)[q], b = 0.0;
        for (int j = 1; j <= kk; ++j) {
            const double v = SPHI(j)[q];
            a += v;
            b += v * S->gamma[j];
        }
        S->s_yy[q] = a;
        S->s_ypw[q] = b;
    }
}

static double newton_solve(kv_ida *S, int own, double *res, double scale,
                           const double *ewt, double *ee, double *yy, double *ypw, double cj)
{
    if (own) {
        if (S->s_cond)
            return kv_cond_newton(S->s_cond, S->s_ab, res, scale, ewt, ee, yy, ypw, cj);
        return kv_newton(S->n, S->kl, S->ku, S->s_ab, S->ldab, S->s_ipiv, S->s_prof, res,
                         scale, ewt, ee, yy, ypw, cj);
    }
    if (S->blocks)
        return blocks_newton_raw(S->blocks, res, scale, ewt, ee, yy, ypw, cj);
    if (S->cond)
        return kv_cond_newton(S->cond, S->ab, res, scale, ewt, ee, yy, ypw, cj);
    return kv_newton(S->n, S->kl, S->ku, S->ab, S->ldab, S->ipiv, S->prof, res, scale, ewt,
                     ee, yy, ypw, cj);
}

/* one Newton iteration of every sensitivity: the largest weighted correction (NAN:
   not finite; -1: a callback failed) */
static double sens_iterate(kv_run *R, double tnew, double scale, double cj, int own)
{
    kv_ida *S = R->S;
    const int n = S->n;
    double worst = 0.0;
    for (int i = 0; i < S->nsens; ++i) {
        const size_t o = (size_t)i * n;
        if (drive_to(R, tnew)) return -1.0;
        int rc;
        {
            TIC(S);
            USER_MODE(R);
            rc = S->sres(S->sctx, tnew, S->yy, S->ypw, i, S->s_yy + o, S->s_ypw + o,
                         S->s_res);
            CORE_MODE(R);
            TOC(S, SEC_RES);
        }
        S->nfevS++;
        if (rc) return -1.0;
        for (int k = 0; k < S->nexact; ++k) S->exact_res[k] = S->s_res[S->exact[k]];
        double d;
        {
            TIC(S);
            d = newton_solve(S, own, S->s_res, scale, S->s_ewt + o, S->s_ee + o,
                             S->s_yy + o, S->s_ypw + o, cj);
            TOC(S, SEC_NEWTON);
        }
        if (scale != 1.0)
            for (int k = 0; k < S->nexact; ++k) {
                const int r = S->exact[k];
                const double dd = (1.0 - scale) * S->exact_res[k];
                S->s_ee[o + r] -= dd;
                S->s_yy[o + r] -= dd;
                S->s_ypw[o + r] -= cj * dd;
            }
        if (!isfinite(d)) return NAN;
        if (d > worst) worst = d;
    }
    return worst;
}

/* J at the converged state into the sensitivities' own Newton system, factorised: 1
   regular, 0 singular, -1 callback failure */
static int sens_setup(kv_run *R, double t)
{
    kv_ida *S = R->S;
    if (drive_to(R, t)) return -1;
    int rc, info;
    {
        TIC(S);
        USER_MODE(R);
        rc = S->jac(S->ctx, t, S->yy, S->ypw, 1.0, S->cj, S->ldab, S->s_ab);
        CORE_MODE(R);
        TOC(S, SEC_JAC);
    }
    if (rc) return -1;
    {
        TIC(S);
        if (S->s_cond) info = kv_cond_factor(S->s_cond, S->s_ab, S->cj);
        else info = kv_gbtrf(S->n, S->kl, S->ku, S->s_ab, S->ldab, S->s_ipiv, S->s_prof);
        TOC(S, SEC_LU);
    }
    S->s_have_lu = info == 0;
    S->s_cj = S->cj;
    S->s_stamp = S->nstep;
    return info == 0;
}

/* IDASensNls: NLS_OK, NLS_CONV_FAIL or NLS_CALLBACK (after the state's corrector and
   error test at tnew) */
static int sens_nls(kv_run *R, double tnew)
{
    kv_ida *S = R->S;
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    if (!S->sscaled) sens_scale(S);
    int jcur = 0;
    for (;;) {
        sens_predict(S);
        memset(S->s_ee, 0, sizeof(double) * ns);
        const double cj = S->cj;
        const int own = S->s_ab && S->s_have_lu && S->s_stamp >= S->lu_stamp;
        const double ratio = own ? cj / S->s_cj : S->cjratio;
        const double scale = ratio != 1.0 ? 2.0 / (1.0 + ratio) : 1.0;
        int m = 0;
        double oldnrm = 0.0;
        for (;;) {
            const double delnrm = sens_iterate(R, tnew, scale, cj, own);
            if (delnrm == -1.0) return NLS_CALLBACK;
            S->nniS++;
            if (!isfinite(delnrm)) break;
            if (m == 0) {
                oldnrm = delnrm;
                if (delnrm <= TOL_DEL) return NLS_OK;
            } else {
                const double rate = pow(delnrm / oldnrm, 1.0 / m);
                if (rate > RATE_MAX) break;
                S->ssS = rate / (1.0 - rate);
                if (S->ssS * delnrm <= EPS_NEWT) return NLS_OK;
            }
            m += 1;
            if (m >= S->maxcor) break;
        }
        if (jcur) { S->ncfnS++; return NLS_CONV_FAIL; }
        /* J afresh at the converged state: into their own system (the state's else) */
        const int ok = S->s_ab ? sens_setup(R, tnew) : setup(R, tnew);
        if (ok < 0) return NLS_CALLBACK;
        S->nsetupS++;
        if (!ok) { S->ncfnS++; return NLS_CONV_FAIL; }
        S->ssS = 20.0;
        jcur = 1;
    }
}

/* IDASensTestError: raises err[0..2] with the sensitivities' estimates, may lower knew */
static int sens_test_error(kv_ida *S, double ck, double *err)
{
    const int kk = S->kk;
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    const double *sigma = S->sigma, *w = S->s_ewt_err;
    const double enorm = sens_norm(S, S->s_ee, w);
    const double e_k = sigma[kk] * enorm;
    int check = 0;
    if (e_k > err[0]) { err[0] = e_k; check = 1; }
    const double terr_k = (kk + 1) * err[0];
    if (kk > 1) {
        double *d = S->s_delta;
        const double *pk = SPHI(kk);
        for (size_t q = 0; q < ns; ++q) d[q] = pk[q] + S->s_ee[q];
        const double e_km1 = sigma[kk - 1] * sens_norm(S, d, w);
        if (e_km1 > err[1]) { err[1] = e_km1; check = 1; }
        const double terr_km1 = kk * err[1];
        if (S->knew != kk) check = 0;
        if (check) {
            if (kk > 2) {
                const double *pk1 = SPHI(kk - 1);
                for (size_t q = 0; q < ns; ++q) d[q] += pk1[q];
                const double e_km2 = sigma[kk - 2] * sens_norm(S, d, w);
                if (e_km2 > err[2]) err[2] = e_km2;
                const double terr_km2 = (kk - 1) * err[2];
                if ((terr_km1 > terr_km2 ? terr_km1 : terr_km2) <= terr_k) S->knew = kk - 1;
            } else if (terr_km1 <= 0.5 * terr_k) {
                S->knew = kk - 1;
            }
        }
    }
    if (ck * enorm > 1.0) { S->netfS++; return NLS_ERR_FAIL; }
    return NLS_OK;
}

/* the estimate at order k+1 with the sensitivities (IDASensWrmsNormUpdate) */
static double sens_order_norm(kv_ida *S, double enorm)
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    const double *p = SPHI(S->kk + 1);
    for (size_t q = 0; q < ns; ++q) S->s_delta[q] = S->s_ee[q] - p[q];
    const double e = sens_norm(S, S->s_delta, S->s_ewt_err);
    return e > enorm ? e : enorm;
}

/* IDACompleteStep's history update of the sensitivities; accept s, s' */
static void sens_complete(kv_ida *S, int ku)
{
    const size_t ns = (size_t)S->nsens * (size_t)S->n;
    for (size_t q = 0; q < ns; ++q) {
        const double e = S->s_ee[q];
        if (ku < S->max_order) SPHI(ku + 1)[q] = e;
        double v = SPHI(ku)[q] + e;
        SPHI(ku)[q] = v;
        for (int j = ku - 1; j >= 0; --j) {
            v = SPHI(j)[q] + v;
            SPHI(j)[q] = v;
        }
    }
    double *sw = S->s_y; S->s_y = S->s_yy; S->s_yy = sw;
    sw = S->s_yp; S->s_yp = S->s_ypw; S->s_ypw = sw;
    S->sscaled = 0;
    sens_weights(S);
}

/* IDAHandleNFlag: shrink h (and maybe the order); 0 to retry, or a KV_FAIL_ code */
static int handle_failure(kv_ida *S, int nflag, int ncf, int nef, double err_k,
                          double err_km1)
{
    S->phase = 1;
    S->fail_nflag = nflag;
    if (nflag == NLS_CONV_FAIL) {
        S->ncfn++;
        if (S->fixed_step > 0.0) return KV_FAIL_FIXED;
        if (ncf >= S->max_conv_fails) { S->fail_count = ncf; return KV_FAIL_CONV; }
        S->rr = 0.25;
    } else {
        S->netf++;
        if (nef == 1) {
            double err_knew = S->kk == S->knew ? err_k : err_km1;
            S->kk = S->knew;
            double rr = 0.9 * pow(2.0 * err_knew + 1e-4, -1.0 / (S->kk + 1));
            S->rr = rr < 0.25 ? 0.25 : (rr > 0.9 ? 0.9 : rr);
        } else if (nef == 2) {
            S->kk = S->knew;
            S->rr = 0.25;
        } else {
            S->kk = 1;
            S->rr = 0.25;
        }
        if (nef >= S->max_error_fails) { S->fail_count = nef; return KV_FAIL_ERR; }
    }
    S->hh *= S->rr;
    if (fabs(S->hh) < hmin(S)) return KV_FAIL_HMIN;
    return 0;
}

/* 0, or -1 when the state's error weights failed (the step is accepted) */
/* IDACompleteStep's history: phi_ku += ee, then phi_j += phi_j+1 for j = ku-1 .. 0 */
KV_INLINE void history_update(int ku, int n, double *const *ph, const double *restrict ee)
{
    for (int q = 0; q < n; ++q) {
        double v = ph[ku][q] + ee[q];
        ph[ku][q] = v;
        for (int j = ku - 1; j >= 0; --j) {
            v = ph[j][q] + v;
            ph[j][q] = v;
        }
    }
}

static int complete_step(kv_ida *S, double tnew, double err_k, double err_km1)
{
    const int n = S->n;
    int mo = S->max_order;      /* lowered where the step is below an order's stability bound */
    if (S->fixed_step <= 0.0)
        while (mo > 2 && fabs(S->hh) < S->stab_hmin[mo]) --mo;
    S->nstep++;
    const int kk = S->kk;
    const int kdiff = kk - S->kused;
    S->kused = kk;
    S->hused = S->hh;
    double *ee = S->ee;
    if (S->fixed_step > 0.0) {
        if (S->nstep - S->nst0 > 1 && kk < mo) S->kk = kk + 1;
        S->hh = S->direction * S->fixed_step;
    } else {
        if (S->knew == kk - 1 || kk >= mo) S->phase = 1;
        if (S->phase == 0) {
            if (S->nstep - S->nst0 > 1) {
                S->kk = kk + 1;
                double hnew = 2.0 * S->hh;
                double tmp = fabs(hnew) * S->hmax_inv;
                if (tmp > 1.0) hnew /= tmp;
                S->hh = hnew;
            }
        } else {
            int action = 0;
            double err_kp1 = 0.0;
            if (S->knew == kk - 1 || kk > mo) {
                action = -1;
            } else if (kk == mo || kk + 1 >= S->ns || kdiff == 1) {
                action = 0;
            } else {
                const double *pk1 = PHI(kk + 1), *w = S->ewt_err;
                double sq = 0.0;        /* wrms(ee - phi_k+1), without storing it */
                for (int q = 0; q < n; ++q) {
                    const double t = (ee[q] - pk1[q]) * w[q];
                    sq += t * t;
                }
                double enorm = n > 0 ? sqrt(sq / n) : 0.0;
                if (S->nsens && S->errconS) enorm = sens_order_norm(S, enorm);
                err_kp1 = enorm / (kk + 2);
                double terr_k = (kk + 1) * err_k, terr_kp1 = (kk + 2) * err_kp1;
                if (kk == 1) {
                    action = terr_kp1 >= 0.5 * terr_k ? 0 : 1;
                } else {
                    double terr_km1 = kk * err_km1;
                    double mn = terr_k < terr_kp1 ? terr_k : terr_kp1;
                    if (terr_km1 <= mn) action = -1;
                    else if (terr_kp1 >= terr_k) action = 0;
                    else action = 1;
                }
            }
            double err_knew;
            if (action == 1) { S->kk = kk + 1; err_knew = err_kp1; }
            else if (action == -1) { S->kk = kk - 1; err_knew = err_km1; }
            else err_knew = err_k;
            double hnew = S->hh;
            double rr = pow(2.0 * err_knew + 1e-4, -1.0 / (S->kk + 1));
            if (rr >= 2.0) {
                hnew = 2.0 * S->hh;
                double tmp = fabs(hnew) * S->hmax_inv;
                if (tmp > 1.0) hnew /= tmp;
            } else if (rr <= 1.0) {
                rr = rr < 0.5 ? 0.5 : (rr > 0.9 ? 0.9 : rr);
                hnew = S->hh * rr;
            }
            S->hh = hnew;
        }
    }
    /* the history update (phi_ku+1 = ee, phi_ku += ee, phi_j += phi_j+1 downwards) and
       the new weights, in one pass */
    const int ku = S->kused;
    double *sw = S->y; S->y = S->yy; S->yy = sw;       /* accept the iterate: swap */
    sw = S->yp; S->yp = S->ypw; S->ypw = sw;
    const double *restrict y = S->y, *restrict atol = S->atol, rtol = S->rtol;
    double *restrict ewt = S->ewt;
    double *ph[KV_NH];
    for (int j = 0; j <= ku + 1 && j < KV_NH; ++j) ph[j] = PHI(j);
    if (ku < S->max_order) memcpy(ph[ku + 1], ee, sizeof(double) * (size_t)n);
#define KV_HISTORY(K) history_update(K, n, ph, ee)
    KV_ORDER_SWITCH(ku, KV_HISTORY)
#undef KV_HISTORY
    if (S->errmask) {                   /* one pass for both (the same values) */
        const double *restrict mask = S->errmask;
        double *restrict werr = S->ewt_err;
        for (int q = 0; q < n; ++q) {
            const double w = 1.0 / (fabs(y[q]) * rtol + atol[q]);
            ewt[q] = w;
            werr[q] = w * mask[q];
        }
    } else {
        for (int q = 0; q < n; ++q) ewt[q] = 1.0 / (fabs(y[q]) * rtol + atol[q]);
    }
    const int errw_rc = S->errw ? S->errw(S->ctx, S->y, rtol, atol, S->ewt_err) : 0;
    if (S->nsens) sens_complete(S, ku);
    S->t_old = S->t;
    S->t = tnew;
    S->started = 1;
    if (S->maxstep && S->fixed_step <= 0.0) {
        double hb = S->maxstep(S->ctx, S->t, S->y, S->yp);
        const double hm = hmin(S);
        if (hb < hm) hb = hm;
        if (fabs(S->hh) > hb) S->hh = S->direction * hb;
    }
    return errw_rc < 0 ? -1 : 0;
}

/* one accepted step (bdf.py's _step_impl); 0 or a KV_FAIL_ / KV_CALLBACK / KV_NONFINITE */
static int step(kv_run *R)
{
    kv_ida *S = R->S;
    int ncf = 0, nef = 0;
    const double tn = S->t;
    double tnew, err[3];
    for (;;) {
        const double remaining = S->t_bound - tn;
        if (S->direction * (S->hh - remaining) > -1e-8 * fabs(S->hh)) {
            if (S->nstep == S->nst0) {
                double f = remaining / S->hh, *p = PHI(1);
                for (int q = 0; q < S->n; ++q) p[q] *= f;
                if (S->nsens) sens_rescale_first(S, f);
                S->psi[0] = remaining;
            }
            S->hh = remaining;
        }
        const double hh = S->hh;
        if (fabs(hh) < hmin(S)) {
            S->fail_index = argmax_abs(S->n, S->ee, S->ewt);
            return KV_FAIL_STALL;
        }
        double ck = set_coeffs(S);
        tnew = tn + hh;
        if (hh == remaining) tnew = S->t_bound;
        predict_scaled(S, S->ns);
        int nflag = nls(R, tnew);
        if (nflag == NLS_CALLBACK) return KV_CALLBACK;
        if (nflag == NLS_NONFINITE) return KV_NONFINITE;
        err[0] = err[1] = err[2] = 0.0;
        if (nflag == NLS_OK && S->fixed_step <= 0.0) nflag = test_error(S, ck, err);
        if (nflag == NLS_OK && S->nsens) {          /* IDAS's staggered corrector */
            nflag = sens_nls(R, tnew);
            if (nflag == NLS_CALLBACK) return KV_CALLBACK;
            if (nflag == NLS_OK && S->errconS && S->fixed_step <= 0.0)
                nflag = sens_test_error(S, ck, err);
        }
        if (nflag == NLS_OK) break;
        restore(S);
        if (nflag == NLS_CONV_FAIL) ncf++;
        else nef++;
        int rc = handle_failure(S, nflag, ncf, nef, err[0], err[1]);
        if (rc) return rc;
        if (S->nstep == S->nst0) {    /* IDAReset: rescale h y'0 to the new step */
            S->psi[0] = S->hh;
            double *p = PHI(1);
            for (int q = 0; q < S->n; ++q) p[q] *= S->rr;
            if (S->nsens) sens_rescale_first(S, S->rr);
        }
    }
    if (complete_step(S, tnew, err[0], err[1])) return KV_CALLBACK;
    return 0;
}

/* ---- after a step: energy audit, output samples, watches --------------------------- */
/* the integral over [0, x] of the polynomial p[0] + p[1] x + ... (m coefficients) */
static double kv_audit_integral(int m, const double *p, double x)
{
    double s = 0.0;
    for (int r = m - 1; r >= 0; --r) s = s * x + p[r] / (double)(r + 1);
    return s * x;
}

/* The polynomial through (ht[j], hg[2 j + c]), j < m (the last two: the step's start and
   end), in x = (t - t0) / h: monomial coefficients coef[KV_AUDIT_NODES c + r], from
   Newton's divided differences expanded by Horner's scheme. 2D is never negative: where
   its cubic's mean over the step is (an edge the cubic overshoots: a contact's release,
   2D falling from hundreds of watts to nothing within a few steps), the straight line
   through the step's two ends instead. runtime.simulate.observers.audit_polynomial: the
   same operations. */
static void kv_audit_polynomial(int m, const double *ht, const double *hg, double t0,
                                double h, double *coef)
{
    double x[KV_AUDIT_NODES], d[KV_AUDIT_NODES];
    for (int j = 0; j < m; ++j) x[j] = (ht[j] - t0) / h;
    for (int c = 0; c < 2; ++c) {
        for (int j = 0; j < m; ++j) d[j] = hg[2 * j + c];
        for (int k = 1; k < m; ++k)
            for (int j = m - 1; j >= k; --j) d[j] = (d[j] - d[j - 1]) / (x[j] - x[j - k]);
        double *p = coef + KV_AUDIT_NODES * c;
        for (int r = 0; r < KV_AUDIT_NODES; ++r) p[r] = 0.0;
        p[0] = d[m - 1];
        for (int k = m - 2; k >= 0; --k) {         /* p <- p (x - x_k) + d_k */
            for (int r = m - 1 - k; r >= 1; --r) p[r] = p[r - 1] - x[k] * p[r];
            p[0] = d[k] - x[k] * p[0];
        }
        if (c == 0 && m > 2 && kv_audit_integral(m, p, 1.0) < 0.0) {
            const double g0 = hg[2 * (m - 2)], g1 = hg[2 * (m - 1)];
            for (int r = 0; r < KV_AUDIT_NODES; ++r) p[r] = 0.0;
            p[0] = g0;
            p[1] = g1 - g0;
        }
    }
}

static void interp(const kv_ida *S, int m, const double *ts, double *oy, double *oyp)
{
    const int k = S->kused > 1 ? S->kused : 1;
    kv_interp(k, S->n, m, S->t, S->psi, S->phi, ts, oy, oyp);
}

/* the audit's states at ts (m of them): at the step's end alone and without y' (en_no_yp),
   interp's y at t there, read off the history's first row (kv_interp_at_tn) */
static void audit_states(const kv_ida *S, int m, const double *ts, double *oy, double *oyp)
{
    if (m == 1 && S->en_no_yp && ts[0] == S->t)
        kv_interp_at_tn(S->kused > 1 ? S->kused : 1, S->n, S->psi, S->phi, oy);
    else
        interp(S, m, ts, oy, S->en_no_yp ? NULL : oyp);
}

/* a node of the audit: 2D and P of m states (ys, yps: m rows of n) at ts, the oldest node
   dropped beyond KV_AUDIT_NODES, and the polynomial of the step [t0, t0 + h] through them */
static int audit_node(kv_run *R, int m, const double *ts, const double *ys,
                      const double *yps, double t0, double h)
{
    kv_ida *S = R->S;
    double e[2 * KV_MAXEN];
    if (call_en_fn(R, S->en_audit ? S->en_audit : S->en, m, ts, ys, yps, e)) return 1;
    for (int j = 0; j < m; ++j) {
        if (S->nh == KV_AUDIT_NODES) {          /* the oldest node leaves */
            for (int i = 1; i < KV_AUDIT_NODES; ++i) {
                S->ht[i - 1] = S->ht[i];
                S->hg[2 * i - 2] = S->hg[2 * i];
                S->hg[2 * i - 1] = S->hg[2 * i + 1];
            }
            S->nh--;
        }
        const double *g = e + j * S->nen;
        S->ht[S->nh] = ts[j];
        S->hg[2 * S->nh] = g[2];
        S->hg[2 * S->nh + 1] = g[3] + g[4];
        S->nh++;
    }
    kv_audit_polynomial(S->nh, S->ht, S->hg, t0, h, S->coef);
    return 0;
}

static int audit_step(kv_run *R)
{
    /* 2D and P once per step, at its end on its interpolant (at a (re)start also at its
       start), and their integral over the step on the polynomial through the last
       KV_AUDIT_NODES ends: a variable-step Adams-Moulton rule of order 4 (3 evaluations
       a step on Gauss-Legendre nodes cost 30 % of simulate's loop; the two agree to the
       integrator's tolerance, tests/runtime/test_energy_audit.py).
       runtime.simulate.observers.audit_polynomial is the same arithmetic in Python. */
    kv_ida *S = R->S;
    const double t0 = S->t_old, t1 = S->t, h = t1 - t0;
    if (h == 0.0) return 0;
    const int first = S->nh == 0, m = first ? 2 : 1;
    double tq[2] = {t0, t1};
    audit_states(S, m, first ? tq : tq + 1, S->wy, S->wyp);
    return audit_node(R, m, first ? tq : tq + 1, S->wy, S->wyp, t0, h);
}

/* the audit's integrals over [t0, t] of the step [t0, t1] */
static void partial(const kv_ida *S, double t0, double t1, double t, double *d, double *w)
{
    const double h = t1 - t0;
    if (h == 0.0) { *d = *w = 0.0; return; }
    const double x = (t - t0) / h;
    *d = kv_audit_integral(S->nh, S->coef, x) * h;
    *w = kv_audit_integral(S->nh, S->coef + KV_AUDIT_NODES, x) * h;
}

/* the sample row at ts of the step [t0, t1] (state y, y' there) into row `row` of rec */
static int sample_row(kv_run *R, double ts, const double *y, const double *yp, double t0,
                      double t1, int row)
{
    kv_ida *S = R->S;
    double e[KV_MAXEN], d, w;
    if (call_en(R, 1, &ts, y, yp, e)) return 1;
    partial(S, t0, t1, ts, &d, &w);
    double *r = S->rec + (size_t)row * (size_t)S->rec_w;
    r[0] = ts;
    for (int i = 0; i < S->nsamp; ++i) r[1 + i] = y[S->samp_idx[i]];
    r[1 + S->nsamp] = e[0];
    r[2 + S->nsamp] = e[1];
    r[3 + S->nsamp] = S->dissipated + d;
    r[4 + S->nsamp] = S->external_work + w;
    for (int k = KV_NEN; k < S->nen; ++k) r[k + S->nsamp] = e[k];
    return 0;
}

/* the audit's whole step [t0, t0 + h] (x = 1) */
static void audit_step_end(kv_ida *S, double h)
{
    S->dissipated += kv_audit_integral(S->nh, S->coef, 1.0) * h;
    S->external_work += kv_audit_integral(S->nh, S->coef + KV_AUDIT_NODES, 1.0) * h;
}

/* the next output time this step reaches, taken at the step's end if up to 1e-12 past
   it; 0 when there is none */
static int next_output(const kv_ida *S, double *ts)
{
    const double t1 = S->t, slack = 1e-12 * (fabs(t1) > 1.0 ? fabs(t1) : 1.0);
    if (S->k_out >= S->m_out || S->t_out[S->k_out] > t1 + slack) return 0;
    *ts = S->t_out[S->k_out] < t1 ? S->t_out[S->k_out] : t1;
    return 1;
}

#ifdef KV_THREADS
struct kv_async_s;
static int async_drain(struct kv_async_s *A);
#endif

/* before a call into Python: the audit's thread done (Python may read its rows or move
   the loads); nonzero: it failed */
static int python_ready(kv_run *R)
{
#ifdef KV_THREADS
    if (R->A) return async_drain(R->A);
#endif
    (void)R;
    return 0;
}

/* the sample rows to Python when the buffer is full; nonzero: a failure */
static int flush_if_full(kv_run *R, double ts)
{
    kv_ida *S = R->S;
    if (S->rec_n < S->rec_cap) return 0;
    if (python_ready(R)) return 1;
    USER_MODE(R);
    const int rc = S->flush(ts);
    CORE_MODE(R);
    return rc || S->rec_n == S->rec_cap;
}

static int sample_step(kv_run *R)
{
    kv_ida *S = R->S;
    double ts;
    while (next_output(S, &ts)) {
        interp(S, 1, &ts, S->sy, S->en_no_yp ? NULL : S->syp);
        if (flush_if_full(R, ts)) return 1;
        if (sample_row(R, ts, S->sy, S->syp, S->t_old, S->t, S->rec_n)) return 1;
        if (S->nsens && S->srec) {      /* the sensitivities of the sampled components */
            const int k = S->kused > 1 ? S->kused : 1, n = S->n;
            kv_interp(k, S->nsens * n, 1, S->t, S->psi, S->sphi, &ts, S->s_wy, NULL);
            double *srow = S->srec + (size_t)S->rec_n * (size_t)S->nsens * (size_t)S->nsamp;
            for (int i = 0; i < S->nsens; ++i)
                for (int j = 0; j < S->nsamp; ++j)
                    srow[i * S->nsamp + j] = S->s_wy[(size_t)i * n + S->samp_idx[j]];
        }
        S->rec_n++;
        S->k_out++;
    }
    return 0;
}

/* ---- the audit's second thread ------------------------------------------------------
   Why: the audit's node a step and the samples' full energies are a quarter of a
   simulate's loop at N = 50 (~5000 evaluations of ~3.5 us), and they feed nothing back
   into the steps. With audit_async the loop interpolates the states (from the history,
   which the next step overwrites) into a ring of slots and goes on; a worker evaluates
   the energies, the audit's nodes and polynomials, the step integrals and the sample
   rows in the loop's order, with the same functions, so every value is the one-thread
   value bit for bit. The worker owns nh, ht, hg, coef, dissipated, external_work and
   the rows it is given until the ring is drained: before any call or return to Python
   (python_ready: a flush of samples or of replayed steps; the end of the advance
   call), so Python never sees a half-done audit. It runs only while the loads cannot
   move (async_start). It is woken once per KV_ASYNC_BATCH jobs, not per job (a futex
   wake costs as much as a small job). An error of the energies fails the run at the next step the loop takes
   (KV_CALLBACK), with the audit up to the failing job. */
#ifdef KV_THREADS
#define KV_ASYNC_BATCH 32
#define KV_ASYNC_TAKE 16    /* jobs the worker takes per visit to the lock */
/* the worker starts once the run has taken KV_ASYNC_WORK / n steps (at least
   KV_ASYNC_MIN): the audit's work per step grows with the state's length n, the
   thread's cost (~1 ms of CPU) does not, so a short run of a small rod (a sweep's tiny
   point: n = 58, ~60 steps) keeps its audit on the loop's thread, and the paper's
   cantilever (n = 656) hands it over after 18 steps instead of 200 (~1.7 ms of
   audit off the loop's thread) */
#define KV_ASYNC_WORK 12000
#define KV_ASYNC_MIN 16
static long long async_after(const kv_ida *S)
{
    const long long k = KV_ASYNC_WORK / (S->n > 0 ? S->n : 1);
    return k > KV_ASYNC_MIN ? k : KV_ASYNC_MIN;
}
enum { JOB_AUDIT, JOB_SAMPLE, JOB_STEP };
typedef struct { int kind, m, row; double ts[2], t0, t1; } kv_job;
typedef struct kv_async_s {
    kv_ida *S;
    unsigned int user_csr_;
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t wake, done;
    kv_job *jobs;               /* async_cap of them; job k's slot: async_buf + (k % cap) 4n */
    long long head, tail;       /* next job of the worker, next free slot (under mu) */
    int quit, err, sleeping, waiting, primed;
    int bad_row;                /* the first sample row not written (after a failure), -1 */
} kv_async;

static double *async_slot_at(const kv_async *A, long long k)
{
    const kv_ida *S = A->S;
    return S->async_buf + (size_t)(k % S->async_cap) * 4u * (size_t)S->n;
}

static int async_run_job(kv_run *R, const kv_job *J, const double *slot)
{
    kv_ida *S = R->S;
    const size_t n = (size_t)S->n;
    switch (J->kind) {
    case JOB_AUDIT:
        return audit_node(R, J->m, J->ts, slot, slot + 2 * n, J->t0, J->t1 - J->t0);
    case JOB_SAMPLE:
        return sample_row(R, J->ts[0], slot, slot + 2 * n, J->t0, J->t1, J->row);
    default:
        audit_step_end(S, J->t1 - J->t0);
        return 0;
    }
}

static void *async_worker(void *arg)
{
    kv_async *A = (kv_async *)arg;
    kv_run R = {A->S, A->user_csr_, NULL};
    CORE_MODE(&R);          /* as the loop: the audit's own arithmetic flushes to zero */
    pthread_mutex_lock(&A->mu);
    for (;;) {
        while (A->head == A->tail && !A->quit) {
            A->sleeping = 1;
            pthread_cond_wait(&A->wake, &A->mu);
            A->sleeping = 0;
        }
        if (A->head == A->tail) break;                 /* told to quit, nothing left */
        /* up to KV_ASYNC_TAKE jobs per visit to the lock: a lock taken per job met the
           loop's pushes so often (a Maxwell rod's jobs are longer) that the two threads
           woke each other through the kernel hundreds of times a run; the jobs before
           tail and their slots are the loop's no more until head passes them */
        const long long k0 = A->head;
        const long long k1 = A->tail - k0 > KV_ASYNC_TAKE ? k0 + KV_ASYNC_TAKE : A->tail;
        int failed = A->err, bad = -1;
        pthread_mutex_unlock(&A->mu);
        for (long long k = k0; k < k1; ++k) {
            const kv_job J = A->jobs[k % A->S->async_cap];
            /* a failed job and every later one are not done */
            failed = failed || async_run_job(&R, &J, async_slot_at(A, k));
            if (failed && J.kind == JOB_SAMPLE && (bad < 0 || J.row < bad)) bad = J.row;
        }
        pthread_mutex_lock(&A->mu);
        if (failed) {
            A->err = 1;
            if (bad >= 0 && (A->bad_row < 0 || bad < A->bad_row)) A->bad_row = bad;
        }
        A->head = k1;
        if (A->waiting) {           /* as async_push: signalled outside the lock */
            pthread_mutex_unlock(&A->mu);
            pthread_cond_signal(&A->done);
            pthread_mutex_lock(&A->mu);
        }
    }
    pthread_mutex_unlock(&A->mu);
    return NULL;
}

/* the slot of the next job (waits while the ring is full) */
static double *async_slot(kv_async *A)
{
    pthread_mutex_lock(&A->mu);
    while (A->tail - A->head == A->S->async_cap) {
        A->waiting = 1;
        if (A->sleeping) pthread_cond_signal(&A->wake);
        pthread_cond_wait(&A->done, &A->mu);
        A->waiting = 0;
    }
    double *slot = async_slot_at(A, A->tail);
    pthread_mutex_unlock(&A->mu);
    return slot;
}

/* hand the job of the slot async_slot gave over; nonzero: the worker has failed. The
   worker is woken once (sleeping cleared here), after the lock is released: woken
   under it, it would wake only to wait for the lock (two trips through the kernel) */
static int async_push(kv_async *A, const kv_job *J)
{
    pthread_mutex_lock(&A->mu);
    A->jobs[A->tail % A->S->async_cap] = *J;
    A->tail++;
    const int wake = A->sleeping && A->tail - A->head >= KV_ASYNC_BATCH;
    if (wake) A->sleeping = 0;
    const int err = A->err;
    pthread_mutex_unlock(&A->mu);
    if (wake) pthread_cond_signal(&A->wake);
    return err;
}

/* wait until every job is done; nonzero: one failed */
static int async_drain(struct kv_async_s *A)
{
    pthread_mutex_lock(&A->mu);
    while (A->head != A->tail) {
        A->waiting = 1;
        if (A->sleeping) pthread_cond_signal(&A->wake);
        pthread_cond_wait(&A->done, &A->mu);
        A->waiting = 0;
    }
    const int err = A->err;
    pthread_mutex_unlock(&A->mu);
    return err;
}

/* audit_step and sample_step as jobs for the worker */
static int async_after_step(kv_run *R)
{
    kv_ida *S = R->S;
    kv_async *A = R->A;
    const size_t n = (size_t)S->n;
    const double t0 = S->t_old, t1 = S->t, h = t1 - t0;
    if (h != 0.0) {
        const int m = A->primed ? 1 : 2;
        kv_job J = {JOB_AUDIT, m, -1, {m == 2 ? t0 : t1, t1}, t0, t1};
        double *slot = async_slot(A);
        audit_states(S, m, J.ts, slot, slot + 2 * n);
        if (async_push(A, &J)) return 1;
        A->primed = 1;
    }
    double ts;
    while (next_output(S, &ts)) {
        if (flush_if_full(R, ts)) return 1;
        kv_job J = {JOB_SAMPLE, 1, S->rec_n, {ts, ts}, t0, t1};
        double *slot = async_slot(A);
        interp(S, 1, &ts, slot, S->en_no_yp ? NULL : slot + 2 * n);
        if (async_push(A, &J)) return 1;
        S->rec_n++;
        S->k_out++;
    }
    if (h != 0.0) {             /* a slot of its own (unused): jobs and slots go one to one */
        kv_job J = {JOB_STEP, 0, -1, {t1, t1}, t0, t1};
        async_slot(A);
        if (async_push(A, &J)) return 1;
    }
    return 0;
}

/* the worker for one advance call (0 and A->S NULL: none, the audit stays in the loop) */
static int async_start(kv_run *R, kv_async *A)
{
    kv_ida *S = R->S;
    A->S = NULL;
    /* the loads must stay as they are for the whole call: no drive, or one whose
       constant interval covers everything up to t_bound (a release: step_loop.py,
       CoreLink.advance), so that the energies never see the loads move under them */
    const int steady = !S->drive || (S->direction > 0
        ? S->t >= S->drive_lo && S->t_bound < S->drive_hi
        : S->t < S->drive_hi && S->drive_lo == -HUGE_VAL);
    if (!(S->audit && S->audit_async && S->async_cap >= 2 && S->async_buf && steady
          && !S->nsens))
        return 0;
    A->jobs = (kv_job *)malloc(sizeof(kv_job) * (size_t)S->async_cap);
    if (!A->jobs) return 0;
    A->S = S;
    A->user_csr_ = R->user_csr_;
    A->head = A->tail = 0;
    A->quit = A->err = A->sleeping = A->waiting = 0;
    A->bad_row = -1;
    A->primed = S->nh > 0;
    const int made = (pthread_mutex_init(&A->mu, NULL) == 0)
        + (pthread_cond_init(&A->wake, NULL) == 0) + (pthread_cond_init(&A->done, NULL) == 0);
    /* the worker blocks every signal (it inherits the mask it is created with): Ctrl-C
       and SIGTERM reach the loop's thread, as without it */
    sigset_t all, mine;
    sigfillset(&all);
    int created = 0;
    if (made == 3 && pthread_sigmask(SIG_SETMASK, &all, &mine) == 0) {
        created = pthread_create(&A->thread, NULL, async_worker, A) == 0;
        pthread_sigmask(SIG_SETMASK, &mine, NULL);
    }
    if (created) {
        R->A = A;
        S->async_runs++;
        return 1;
    }
    /* no thread (resources): the audit stays in the loop */
    if (made == 3) {
        pthread_cond_destroy(&A->done);
        pthread_cond_destroy(&A->wake);
        pthread_mutex_destroy(&A->mu);
    }
    free(A->jobs);
    A->S = NULL;
    return 0;
}

/* drain, stop and join the worker; nonzero: a job failed */
static int async_stop(kv_run *R)
{
    kv_async *A = R->A;
    if (!A) return 0;
    const int err = async_drain(A);
    pthread_mutex_lock(&A->mu);
    A->quit = 1;
    pthread_cond_signal(&A->wake);
    pthread_mutex_unlock(&A->mu);
    pthread_join(A->thread, NULL);
    if (err && A->bad_row >= 0 && A->bad_row < A->S->rec_n)
        A->S->rec_n = A->bad_row;       /* the rows reserved for jobs not done */
    pthread_cond_destroy(&A->done);
    pthread_cond_destroy(&A->wake);
    pthread_mutex_destroy(&A->mu);
    free(A->jobs);
    R->A = NULL;
    return err;
}
#endif

/* the step just taken as a row of rep (once), the buffer handed to Python first when
   full; 1 when that failed */
static int replay_keep(kv_run *R)
{
    kv_ida *S = R->S;
    if (S->rep_nstep == S->nstep) return 0;
    if (S->rep_n == S->rep_cap) {
        /* Python may move the loads (a snapshot's diagnostics drive the model to its
           time): the audit's thread must not evaluate meanwhile */
        if (python_ready(R)) return 1;
        USER_MODE(R);
        int rc = S->rep_flush(S->t);
        CORE_MODE(R);
        if (rc || S->rep_n == S->rep_cap) return 1;
    }
    double *row = S->rep + (size_t)S->rep_n++ * (size_t)S->rep_w;
    const int k = S->kused > 1 ? S->kused : 1;      /* the interpolant's order (interp) */
    row[0] = S->t_old;
    row[1] = S->t;
    row[2] = k;
    for (int j = 0; j < KV_NH; ++j) row[3 + j] = S->psi[j];
    memcpy(row + 3 + KV_NH, S->phi, sizeof(double) * (size_t)(k + 1) * (size_t)S->n);
    if (S->nsens)          /* and the sensitivities' history, after the state's rows */
        memcpy(row + 3 + KV_NH + (size_t)KV_NH * S->n, S->sphi,
               sizeof(double) * (size_t)(k + 1) * (size_t)S->nsens * (size_t)S->n);
    memcpy(row + 3 + KV_NH + (size_t)KV_NH * (size_t)S->n * (size_t)(1 + S->nsens), S->y,
           sizeof(double) * (size_t)S->n);
    S->rep_nstep = S->nstep;
    return 0;
}

/* the step, kept if it reaches the next of the replay times */
static int replay_step(kv_run *R)
{
    kv_ida *S = R->S;
    if (S->direction * (S->t - S->t_rep[S->k_rep]) < 0.0) return 0;
    while (S->k_rep < S->m_rep && S->direction * (S->t - S->t_rep[S->k_rep]) >= 0.0)
        S->k_rep++;
    return replay_keep(R);
}

/* the outputs of the grid that this step reaches, on its interpolant (IDAGetDky; what
   BDFDenseOutput.values computes from the same history) */
static void grid_step(kv_ida *S)
{
    const size_t n = (size_t)S->n;
    if (S->grid_idx) {                  /* frames of chosen components */
        const double t1 = S->t;
        const double reach = S->grid_slack ? t1 + 1e-12 * (fabs(t1) > 1.0 ? fabs(t1) : 1.0)
                                           : t1;
        while (S->k_grid < S->m_grid && S->t_grid[S->k_grid] <= reach) {
            const size_t k = (size_t)S->k_grid++;
            const double t = S->t_grid[k] < t1 ? S->t_grid[k] : t1;
            interp(S, 1, &t, S->grid_wy, NULL);          /* rows of y only */
            double *row = S->grid_y + k * (size_t)S->grid_nidx;
            for (int j = 0; j < S->grid_nidx; ++j) row[j] = S->grid_wy[S->grid_idx[j]];
        }
        return;
    }
    while (S->k_grid < S->m_grid && S->direction * (S->t_grid[S->k_grid] - S->t) <= 0.0) {
        const size_t k = (size_t)S->k_grid++;
        interp(S, 1, S->t_grid + k, S->grid_y + k * n, S->grid_yp + k * n);
    }
}

static int after_step(kv_run *R)
{
    kv_ida *S = R->S;
    if (S->k_grid < S->m_grid) grid_step(S);
    if (S->k_rep < S->m_rep && replay_step(R)) return 1;
#ifdef KV_THREADS
    if (R->A) {
        if (async_after_step(R)) return 1;
    } else
#endif
    if (S->audit) {
        if (audit_step(R)) return 1;
        if (S->m_out > S->k_out && sample_step(R)) return 1;
        if (S->t != S->t_old) audit_step_end(S, S->t - S->t_old);   /* the whole step */
    }
    S->watch_hit = 0;
    for (int k = 0; k < S->nwatch; ++k) {
        const double v_new = S->y[S->watch_idx[k]], v_old = S->watch_old[k];
        if ((S->watch_dir[k] < 0 && v_old > 0.0 && v_new <= 0.0) ||
            (S->watch_dir[k] > 0 && v_old < 0.0 && v_new >= 0.0))
            S->watch_hit |= 1 << k;
        S->watch_old[k] = v_new;
    }
    if ((S->watch_hit & S->watch_rep) && S->rep_cap > 0) {   /* kept, not a stop */
        if (replay_keep(R)) return 1;
        S->watch_hit &= ~S->watch_rep;
    }
    return 0;
}

/* Integrate until t reaches t_stop (in the direction of integration) or t_bound, a
   watched sign change, max_steps steps, or a failure; the step that reaches t_stop is
   completed (t may pass t_stop: interpolate back). Returns a KV_ code. */
int kv_ida_advance(kv_ida *S, double t_stop, long long max_steps)
{
    kv_run R = {S, 0, NULL};
#if defined(__x86_64__) || defined(__SSE2__)
    R.user_csr_ = _mm_getcsr();
    CORE_MODE(&R);
#endif
#ifdef KV_THREADS
    kv_async A;
    A.S = NULL;
    const long long after = async_after(S);
    if (S->nstep >= after) async_start(&R, &A);
#endif
    int rc = KV_MAXSTEPS;
    for (long long k = 0; k < max_steps; ++k) {
        if (S->t == S->t_bound) { rc = KV_FINISHED; break; }
        int r = step(&R);
        if (r) { rc = r; break; }
        if (after_step(&R)) { rc = KV_CALLBACK; break; }
#ifdef KV_THREADS
        if (!R.A && S->nstep == after) async_start(&R, &A);
#endif
        if (S->direction * (S->t - S->t_bound) >= 0.0) { rc = KV_FINISHED; break; }
        if (S->watch_hit) { rc = KV_WATCH; break; }
        if (S->direction * (S->t - t_stop) >= 0.0) { rc = KV_TSTOP; break; }
        if (S->stop) break;
    }
#ifdef KV_THREADS
    if (async_stop(&R) && rc >= 0) rc = KV_CALLBACK;
#endif
    USER_MODE(&R);
    return rc;
}

/* the watched components' current values (call after setting the watches) */
void kv_ida_watch_reset(kv_ida *S)
{
    for (int k = 0; k < S->nwatch; ++k) S->watch_old[k] = S->y[S->watch_idx[k]];
}
