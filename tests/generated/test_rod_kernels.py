"""The generated rod code: up to date, deterministic, and equal to in-process CasADi."""

from __future__ import annotations

import importlib

import casadi as ca
import numpy as np
import pytest

from derive import codegen_rod
from derive import discrete_rod as dr
from derive import contact, contact_pair, links
from derive.artifacts import generated_dir, render
from generated import rod_layout as L
from runtime.model.casadi_oracle import load_kernels
from tests.rods import rod_model

BCS = [("clamped", "free"), ("pinned", "pinned"), ("clamped", "clamped"), ("free", "pinned")]
LOADS = [{"kind": "force", "vector": [0.05, 0.01, -0.02]},
         {"kind": "moment", "vector": [1e-3, 0, 2e-3]},
         {"kind": "force", "vector": [0.0, 0.01, 0.02], "frame": "follower"},
         {"kind": "gravity", "vector": [0, -9.81, 0]}]


def _model(N, start, end, backend="auto"):
    return rod_model(N, start, end, loads=LOADS, backend=backend, tau_S=0.04, tau_B=0.02,
                     tau=None)


def _state(m, rng):
    y = m.initial_state() + 0.05 * rng.standard_normal(m.n)
    return y, rng.standard_normal(m.n)


def test_committed_rod_files_equal_a_fresh_generation():
    codegen_rod._build.cache_clear()
    fresh = codegen_rod.artifacts()
    codegen_rod._build.cache_clear()
    again = codegen_rod.artifacts()
    assert [a.text for a in fresh] == [a.text for a in again]  # byte-deterministic
    gdir = generated_dir()
    for a in fresh:
        assert a.path.startswith("rod_")
        assert (gdir / a.path).read_text() == render(a), f"{a.path}: run `kvrod generate`"
    c = next(a for a in fresh if a.path == "rod_kernels.c").text
    assert "/tmp" not in c and "/work" not in c


def test_layout_module_renders_the_derive_constants():
    lay = importlib.reload(L)
    assert lay.CELL_SIZE == dr.CELL_SIZE == 13 and lay.CELL0_SIZE == dr.CELL0_SIZE == 6
    assert lay.CELL_OFFSETS == dr.CELL_OFFSETS and lay.PARAM_OFFSETS == dr.PARAM_OFFSETS
    assert lay.N_PARAMS == dr.N_PARAMS
    assert lay.SEGMENT_OFFSETS == dr.SEGMENT_OFFSETS and lay.N_SEGMENT == dr.N_SEGMENT
    assert lay.JOINT_OFFSETS == dr.JOINT_OFFSETS and lay.N_JOINT == dr.N_JOINT
    assert lay.NODE_LOAD_OFFSETS == dr.NODE_LOAD_OFFSETS
    assert lay.SEGMENT_LOAD_OFFSETS == dr.SEGMENT_LOAD_OFFSETS
    assert lay.n_state(10) == 6 + 13 * 10
    for n in (1, 2, 3, 5):
        assert lay.bandwidths(n) == dr.bandwidths(n)
    assert (lay.STATIC_KL, lay.STATIC_KU) == dr.static_bandwidths(4)
    assert set(lay.KERNELS) == {f.name() for f in dr.kernels() + dr.coupled_kernels()
                                + links.kernels() + contact.contact_kernels()
                                + contact_pair.pair_kernels()}
    for n in (1, 2, 3, 5):
        assert lay.bandwidths(n, 0, True) == dr.bandwidths(n, 0, True)
    assert (lay.COUPLED_STATIC_KL, lay.COUPLED_STATIC_KU) == dr.static_bandwidths(4, True)
    assert lay.COUPLED_SEGMENT_OFFSETS == dr.COUPLED_SEGMENT_OFFSETS
    assert lay.COUPLED_JOINT_OFFSETS == dr.COUPLED_JOINT_OFFSETS


def _rel(a, b):
    a, b = np.array(a, dtype=float), np.array(b, dtype=float)
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


def test_kernel_closed_forms_equal_casadi_ad_of_the_functionals():
    """Rates, energies, forces/torques and Jacobian blocks evaluated by the kernels equal the
    CasADi AD derivatives of W and D (eqs. (10), (11)) to rounding, for non-unit p."""
    s = dr._symbols()
    seg, jnt = dr.segment_quantities(s), dr.joint_quantities(s)
    sf, jf = dr.segment_functionals(s), dr.joint_functionals(s)
    Qad, Tad = dr.segment_forces_ad(s), dr.joint_torques_ad(s)
    xs = ca.vertcat(s.phi_b, s.p, s.v_b, s.omega)
    xj = ca.vertcat(s.p, s.p_b, s.omega, s.omega_b)
    br = dr.branch_quantities(s)
    ins = [s.phi_a, s.phi_b, s.p, s.v_a, s.v_b, s.omega, s.p_b, s.omega_b, s.sp, s.jp,
           s.n_q, s.m_q]
    pairs = [(seg["Vdot"], sf["Vdot"]), (seg["W"], sf["W"]), (seg["D"], sf["D"]),
             (seg["Q"], Qad), (jnt["Udot"], jf["Udot"]), (jnt["W"], jf["W"]),
             (jnt["D"], jf["D"]), (jnt["T"], Tad),
             (dr.segment_jacobian(s), ca.jacobian(Qad[3:9], xs)),
             (dr.joint_jacobian(s), ca.jacobian(Tad, xj)),
             # what the relaxation terms use: strain derivatives, forces per resultant
             (br["dV_dx"], ca.jacobian(sf["V"], ca.vertcat(s.phi_b, s.p))),
             (br["dU_dx"], ca.jacobian(jf["U"], ca.vertcat(s.p, s.p_b))),
             (br["G_seg"], ca.jacobian(Qad[3:9], s.n_q)),
             (br["G_jnt"], ca.jacobian(Tad, s.m_q))]
    f = ca.Function("f", ins, [x for pair in pairs for x in pair])
    rng = np.random.default_rng(0)
    for _ in range(5):
        args = [rng.standard_normal(k) for k in (3, 3, 4, 3, 3, 3, 4, 3)]
        args[6] = args[2] * 1.2 + 0.3 * rng.standard_normal(4)
        args += [np.abs(rng.standard_normal(dr.N_SEGMENT)) + 0.1,
                 np.abs(rng.standard_normal(dr.N_JOINT)) + 0.1,
                 rng.standard_normal(3), rng.standard_normal(3)]
        out = f(*args)
        for k in range(0, len(out), 2):
            assert _rel(out[k], out[k + 1]) < 1e-11, k


@pytest.mark.parametrize("start,end", BCS)
def test_compiled_kernels_equal_in_process_casadi(start, end):
    mc, mp = _model(6, start, end), _model(6, start, end, backend="casadi")
    if mc.backend != "c":
        pytest.skip("no C compiler")
    rng = np.random.default_rng(1)
    y, yp = _state(mc, rng)
    r1, r2 = np.empty(mc.n), np.empty(mc.n)
    mc.residual(0.0, y, yp, r1)
    mp.residual(0.0, y, yp, r2)
    assert np.abs(r1 - r2).max() <= 1e-12 * np.abs(r1).max()
    for cy, cj in ((1.0, 0.0), (0.0, 1.0), (1.0, 123.0)):
        a1 = np.zeros((mc.ldab, mc.n), order="F")
        a2 = np.zeros((mc.ldab, mc.n), order="F")
        mc.jacobian_band2(0.0, y, yp, cy, cj, a1)
        mp.jacobian_band2(0.0, y, yp, cy, cj, a2)
        assert np.abs(a1 - a2).max() <= 1e-12 * np.abs(a1).max()
    d1, d2 = mc.diagnostics(0.0, y, yp), mp.diagnostics(0.0, y, yp)
    for key in ("kinetic", "elastic", "dissipation_rate", "external_power", "boundary_power"):
        assert d1[key] == pytest.approx(d2[key], rel=1e-12, abs=1e-300)
    for group in ("strains", "resultants"):
        for k, v in d1[group].items():
            assert np.allclose(v, d2[group][k], rtol=1e-12, atol=1e-12 * np.abs(v).max())


def test_serialised_kernels_equal_the_definitions():
    ks = load_kernels()
    for f in dr.kernels():
        g = ks[f.name()]
        args = [np.random.default_rng(4).standard_normal(f.size_in(i)) + 1.0
                for i in range(f.n_in())]
        for a, b in zip(f.call(args), g.call(args), strict=True):
            assert np.array_equal(np.array(a), np.array(b))


def test_generated_c_size_is_independent_of_N():
    gdir = generated_dir()
    size = sum((gdir / f).stat().st_size for f in ("rod_kernels.c", "rod_layout.h"))
    assert size < 1_000_000  # per-element kernels: one file for every N


@pytest.mark.parametrize("start,end", BCS)
@pytest.mark.parametrize("chunk", [1, 2, 5])
def test_jacobian_by_elements_into_a_sliding_window_equals_the_whole_sweep(start, end, chunk):
    """kvrod_jacobian_band_cells, as the C step loop calls it: elements chunk by chunk
    into a window of columns slid along the rod; the columns of cells <= i-1 are final
    after element i, bit for bit those of kvrod_jacobian_band."""
    import ctypes

    m = _model(7, start, end)
    m.at(0.0)
    if m.backend != "c":
        pytest.skip("no C compiler")
    y, yp = _state(m, np.random.default_rng(2))
    full = np.zeros((m.ldab, m.n), order="F")
    m.jacobian_band2(0.0, y, yp, 1.0, 37.0, full)
    cf = np.asarray(m.condensation_cells() + [m.n])
    ncell = len(cf) - 1
    assert ncell == m.N + 1
    lib, P = m._lib, ctypes.c_void_p
    win = np.full((m.ldab, m.n), np.nan, order="F")        # big enough; slid by hand
    got = np.full((m.ldab, m.n), np.nan, order="F")
    lo, el = 0, 0
    while el < ncell:
        i1 = min(el + chunk - 1, ncell - 1)
        rc = lib.kvrod_jacobian_band_cells(m._struct_ptr(), 0.0, P(y.ctypes.data),
                                           P(yp.ctypes.data), 1.0, 37.0, m.ldab,
                                           P(win.ctypes.data), int(cf[lo]), el, i1)
        assert rc == 0
        el = i1 + 1
        done = ncell if el == ncell else el - 1           # cells < done are final
        hi = cf[min(el + 1, ncell)]                         # written up to cell el
        got[:, cf[lo]:cf[done]] = win[:, :cf[done] - cf[lo]]
        nlo = max(done - 1, 0)                              # keep from cell done-1 on
        win[:, :hi - cf[nlo]] = win[:, cf[nlo] - cf[lo]:hi - cf[lo]].copy()
        win[:, hi - cf[nlo]:] = np.nan
        lo = nlo
    band = slice(m.kl, None)                                # rows 0..kl-1: LU workspace
    assert np.array_equal(got[band], full[band])


def test_jacobian_by_elements_rejects_cells_outside_the_rod_or_the_window():
    import ctypes

    m = _model(4, "clamped", "free")
    m.at(0.0)
    if m.backend != "c":
        pytest.skip("no C compiler")
    y, yp = _state(m, np.random.default_rng(3))
    ab = np.zeros((m.ldab, m.n), order="F")
    cf = m.condensation_cells()
    P = ctypes.c_void_p

    def call(col0, i0, i1, ldab=m.ldab):
        return m._lib.kvrod_jacobian_band_cells(m._struct_ptr(), 0.0, P(y.ctypes.data),
                                                P(yp.ctypes.data), 1.0, 1.0, ldab,
                                                P(ab.ctypes.data), col0, i0, i1)

    assert call(0, 0, m.N) == 0
    assert call(cf[2], 3, 3) == 0                  # col0 = first column of cell i0 - 1
    assert call(cf[3], 3, 3) == -4                 # element 3 writes cell 2's columns
    assert call(0, -1, 2) == -4 and call(0, 0, m.N + 1) == -4
    assert call(0, 0, m.N, ldab=m.kl + m.ku + 1) == -2


@pytest.mark.parametrize("name", codegen_rod.X4_KERNELS)
def test_four_lane_kernels_equal_the_scalar_kernel_bit_for_bit(name):
    """<name>_x4 (derive/codegen_lanes.py) runs the scalar kernel's SX instructions on
    four elements at once: every lane must be the scalar result exactly."""
    import ctypes

    m = _model(3, "clamped", "free")
    if m.backend != "c":
        pytest.skip("no C compiler")
    f = next(k for k in dr.kernels() if k.name() == name)
    rng = np.random.default_rng(4)
    lanes = [[rng.uniform(0.5, 1.5, f.nnz_in(i)) * rng.choice([-1, 1], f.nnz_in(i))
              for i in range(f.n_in())] for _ in range(4)]
    outs = [[np.full(f.nnz_out(o), np.nan) for o in range(f.n_out())] for _ in range(5)]
    P = ctypes.c_void_p
    arg = (P * (4 * f.n_in()))(*[lanes[lane][i].ctypes.data for i in range(f.n_in())
                                 for lane in range(4)])
    res = (P * (4 * f.n_out()))(*[outs[lane][o].ctypes.data for o in range(f.n_out())
                                  for lane in range(4)])
    assert getattr(m._lib, name + "_x4")(arg, res) == 0
    scalar = getattr(m._lib, name)
    for lane in range(4):
        a1 = (P * f.n_in())(*[x.ctypes.data for x in lanes[lane]])
        r1 = (P * f.n_out())(*[outs[4][o].ctypes.data for o in range(f.n_out())])
        assert scalar(a1, r1, None, (ctypes.c_double * max(f.sz_w(), 1))(), 0) == 0
        for o in range(f.n_out()):
            assert np.array_equal(outs[lane][o], outs[4][o]), (lane, o)
    # and the numbers are the function's (in-process CasADi, to rounding)
    for lane in range(4):
        ref = f(*lanes[lane])
        ref = [ref] if f.n_out() == 1 else ref
        for o in range(f.n_out()):
            want = np.asarray(ref[o]).ravel(order="F")
            assert np.allclose(outs[lane][o], want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("combined, forces, strain", [
    ("rod_segment_forces_strain", "rod_segment_forces", "rod_segment_branch"),
    ("rod_joint_torques_strain", "rod_joint_torques", "rod_joint_branch"),
])
def test_the_combined_maxwell_kernels_are_the_separate_ones_bit_for_bit(combined, forces,
                                                                         strain):
    """A generalized Maxwell rod's residual takes forces and relaxation strains from one
    kernel (rod_assembly.c, residual_own): both outputs must be, bit for bit, what the
    force kernel gives and the strain the branch kernel (the Jacobian's) gives (compiled
    C, random inputs)."""
    import ctypes

    m = _model(3, "clamped", "free")
    if m.backend != "c":
        pytest.skip("no C compiler")
    fns = {k.name(): k for k in dr.kernels()}
    f, g, h = fns[combined], fns[forces], fns[strain]
    P = ctypes.c_void_p
    rng = np.random.default_rng(7)

    def call(fn, inputs):
        outs = [np.full(fn.nnz_out(o), np.nan) for o in range(fn.n_out())]
        a = (P * fn.n_in())(*[x.ctypes.data for x in inputs])
        r = (P * fn.n_out())(*[o.ctypes.data for o in outs])
        w = (ctypes.c_double * max(fn.sz_w(), 1))()
        assert getattr(m._lib, fn.name())(a, r, None, w, 0) == 0
        return outs

    for _ in range(20):
        ins = {f.name_in(i): rng.uniform(0.5, 1.5, f.nnz_in(i)) * rng.choice([-1, 1],
                                                                           f.nnz_in(i))
               for i in range(f.n_in())}
        both = call(f, [ins[f.name_in(i)] for i in range(f.n_in())])
        alone = call(g, [ins[g.name_in(i)] for i in range(g.n_in())])
        strains = call(h, [ins[h.name_in(i)] for i in range(h.n_in())])
        assert np.array_equal(both[0], alone[0]) and np.array_equal(both[1], strains[0])


def test_coupled_kernel_closed_forms_equal_casadi_ad_of_the_functionals():
    """The coupled segment's forces and torques (closed form through its resultant and
    its joints' moments) and the coupled joint's torques equal the CasADi AD of their W
    and D (the definitions) to rounding, for random non-unit quaternions and random,
    non-symmetric-looking blocks (the quadratic forms take their symmetric parts)."""
    c = dr._csymbols()
    ins = [c.phi_a, c.phi_b, c.p_a, c.p, c.p_b, c.v_a, c.v_b, c.omega_a, c.omega, c.omega_b,
           c.sp, c.sc, c.ja, c.jb, c.m_end]
    f = ca.Function("f", ins, [dr.coupled_segment_quantities(c)["Q"],
                               dr.coupled_segment_forces_ad(c)])
    s = dr._symbols()
    jc = ca.SX.sym("jc", dr.N_COUPLED_JOINT)
    jins = [s.p, s.p_b, s.omega, s.omega_b, s.jp, jc]
    g = ca.Function("g", jins, [dr.coupled_joint_quantities(s, jc)["T"],
                                dr.coupled_joint_torques_ad(s, jc)])
    rng = np.random.default_rng(5)
    for _ in range(3):
        vals = [rng.standard_normal(x.numel()) for x in ins]
        for k in (2, 3, 4):
            vals[k][0] += 2.5                       # frames not far apart, |p| != 1
        vals[10][0] = 0.3                           # h
        vals[12][0], vals[13][0] = 0.25, 0.35       # joint lengths
        a, b = f(*vals)
        assert _rel(a, b) < 1e-12
        jv = [rng.standard_normal(x.numel()) for x in jins]
        jv[0][0] += 2.5
        jv[1][0] += 2.5
        jv[4][0] = 0.3
        a, b = g(*jv)
        assert _rel(a, b) < 1e-12
