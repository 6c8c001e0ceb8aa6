"""Forward-mode (tangent) kernels of the residual's kernels: the exact directional
derivatives that the sensitivities of the integrator need (issue 34; docs/design.md,
section "Sensitivities").

For a kernel ``f(x_1, ..., x_m) -> r`` of :mod:`derive.discrete_rod` or
:mod:`derive.links` whose output ``r`` enters the residual, :func:`tangent` builds
``f_tan(x_1, ..., x_m, d_x_1, ..., d_x_m) -> d_r = sum_k dr/dx_k d_x_k`` from the same
CasADi SX graph (``ca.jtimes``: forward AD, no finite differences). Every input has a
seed: the state's (node positions, quaternions, velocities, their rates) and the
parameters' (the rows of ``SEGMENT_PARAMS``, ``JOINT_PARAMS``, loads, the link and body
tables, relaxation resultants). The C assembly (``runtime/model/native/rod_tangent.c``,
``system_tangent.c``) feeds them the state direction (s, s') and the parameter direction
(the derivative of the rod's arrays with respect to one problem parameter) and gets
``dF = F_y s + F_y' s' + F_p dp`` in one sweep over the elements.

The tangents are generated into their own file pair (``generated/rod_tangent_kernels.c``
/ ``.h``, :func:`derive.codegen_rod.artifacts`), so the residual's own kernels and their
four-lane forms are untouched.
"""

from __future__ import annotations

import casadi as ca

from derive import discrete_rod as dr
from derive import links

#: the kernels whose outputs enter the residual, with the output that does: (kernel,
#: output). The other outputs (Jacobian helpers of the relaxation kernels) are not the
#: residual's.
TANGENT_OF: tuple[tuple[str, str], ...] = (
    ("rod_node_inertia", "r"),
    ("rod_segment_inertia", "r"),
    ("rod_segment_forces", "Q"),
    ("rod_joint_torques", "T"),
    ("rod_rotate", "Rx"),
    ("rod_rotate_transposed", "RTx"),
    ("rod_segment_branch", "dV"),
    ("rod_joint_branch", "dU"),
    ("rod_coupled_inertia", "r"),
    ("rod_coupled_segment_forces", "Q"),
    ("rod_coupled_joint_torques", "T"),
    ("rod_link_forces", "Q"),
    ("rod_body_inertia", "r"),
)

_OPTS = {"cse": True}


def tangent(f: ca.Function, output: str) -> ca.Function:
    """``<name>_tan``: the inputs of ``f`` followed by a seed ``d_<input>`` of each (same
    shapes), returning ``d_<output>``, the forward derivative of ``f``'s ``output`` along
    the seeds (``ca.jtimes`` on ``f``'s SX graph)."""
    names = [f.name_in(i) for i in range(f.n_in())]
    xs = [ca.SX.sym(n, f.sparsity_in(i)) for i, n in enumerate(names)]
    ds = [ca.SX.sym("d_" + n, f.sparsity_in(i)) for i, n in enumerate(names)]
    out = f.call(dict(zip(names, xs, strict=True)))[output]
    x = ca.vertcat(*(ca.vec(v) for v in xs))
    d = ca.vertcat(*(ca.vec(v) for v in ds))
    dout = ca.densify(ca.jtimes(out, x, d))
    return ca.Function(f.name() + "_tan", xs + ds, [dout], names + ["d_" + n for n in names],
                       ["d_" + output], _OPTS)


def tangent_kernels() -> list[ca.Function]:
    """The tangent kernels of :data:`TANGENT_OF`, in that order."""
    by_name = {f.name(): f for f in dr.kernels() + dr.coupled_kernels() + links.kernels()}
    return [tangent(by_name[name], out) for name, out in TANGENT_OF]


def work_defines(fns: list[ca.Function]) -> str:
    """C defines of the largest work sizes of the tangent kernels (appended to their
    header): ``ROD_TAN_MAXARG``, ``ROD_TAN_MAXRES``, ``ROD_TAN_MAXIW``, ``ROD_TAN_MAXW``."""
    sizes = {"MAXARG": max(f.sz_arg() for f in fns), "MAXRES": max(f.sz_res() for f in fns),
             "MAXIW": max(1, max(f.sz_iw() for f in fns)),
             "MAXW": max(1, max(f.sz_w() for f in fns))}
    lines = ["", "/* largest work sizes of the tangent kernels (derive/tangents.py) */"]
    lines += [f"#define ROD_TAN_{k} {v}" for k, v in sizes.items()]
    return "\n".join(lines) + "\n"
