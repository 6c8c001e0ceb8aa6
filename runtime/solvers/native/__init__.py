"""The integrator's compiled code, by role (compiled on first use, cached; else the NumPy
path of :mod:`runtime.solvers.bdf` takes the same steps):

* ``loader.py``: compiles and loads the library (``step_loop.c``, which includes
  ``band.c`` and ``condensed.c``: one unit), declares its functions;
* ``band.py`` / ``band.c``: the band LU and its solves, the fused Newton update, norms,
  the interpolant;
* ``condensed.py`` / ``condensed.c``: the Newton systems condensed by the kinematic rows,
  block tridiagonal in the rod's cells;
* ``step_loop.py`` / ``step_loop.c``: IDA's step loop in C and its link to
  :class:`~runtime.solvers.bdf.BDF`.

Why C here (measured on the 10 s cantilever release, ``bench/integrators.py``):

- Denormals. The Newton correction of a long rod is the solution of a banded system with a
  local right-hand side; it decays exponentially along the rod and reaches subnormal
  numbers (< 2.2e-308) in far cells at N >= ~500. Subnormal arithmetic is ~100x slower on
  x86, in LAPACK's solve and in every NumPy operation on the history arrays afterwards:
  N = 1000 took 40 s instead of ~4 s. These helpers run with flush-to-zero /
  denormals-are-zero set in MXCSR *only for their own duration* (saved and restored, so
  the caller's floating-point mode is untouched); subnormal corrections become 0, which
  is far below any tolerance.
  The weighted norms of the error test are computed here for the same reason: squares
  of tiny (normal) entries underflow.
- Call overhead. One call does the band solve (``dgbtrs`` semantics on ``dgbtrf``'s
  factors), the scaling by 2/(1 + cj ratio), the weighted RMS norm and the updates of the
  correction, y and y' -- nine NumPy/f2py calls of 1-5 us each per Newton iteration
  before. ``kv_gbtrf`` factorises into a preallocated pivot array (no f2py wrapper, no
  allocation, flush-to-zero during the factorisation too) with LAPACK's unblocked
  ``dgbtf2`` algorithm written out in C (what ``dgbtrf`` itself runs for bands narrower
  than its block size 32, i.e. kvrod's). Not calling SciPy's LAPACK keeps
  ``scipy.linalg`` (0.18-0.27 s to import) out of every run.
- Memory traffic. At large N the solves are memory bound (the LU factors are 5.6 MB at
  N = 1000, 11 MB at N = 2000, streamed twice per Newton iteration). ``kv_gbtrf`` records
  the nonzero profile of each factor column (U rarely uses the kl rows of fill-in room
  that partial pivoting reserves) and the solve reads only that: Newton solves -22 % at
  N = 1000, -39 % at N = 2000 (LAPACK's dgbtrs reads the whole band). (Fusing the predictor and
  the history update into C as well was measured and gave nothing at N = 50: a ctypes
  call with many arguments costs about as much as the few NumPy calls it replaces.)
- Condensed Newton systems (``CondensedNewton``, ``kv_cond`` in condensed.c): the
  kinematic rows eliminate v and p, leaving 6 unknowns per cell of the rod, and the
  condensed matrix is block tridiagonal in the cells (nearest-neighbour coupling). Its
  block LU (dense 6 x 6 blocks, pivoting inside them) is assembled per cell straight
  from J, and its solve is two sweeps of fixed-size products with the Newton update
  fused in: at N = 1000 factorisation 1190 -> 480 us, Newton update 205 -> 85 us per
  call (the band LU of the condensed matrix, kept for other structures, needs a cleared
  band storage, an index scatter and a pivoting band elimination). A generalized Maxwell
  rod's internal strains (rows diagonal in them: relaxation.py) are eliminated first, so
  its cells keep the same 6 unknowns and take the same fixed-size kernels (N = 50, 3
  terms: factorisation ~1.0 ms -> ~60 us, Newton solve and update ~26 -> ~11 us).

``load()`` returns None without a C compiler (or with ``KVROD_NO_COMPILER=1``); the BDF
then uses the NumPy/f2py path with the same results up to rounding.
"""
