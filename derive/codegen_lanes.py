"""Lane-parallel C of the rod's hottest kernels: four elements per call (GCC vector
extension, one AVX2 register per value), from the SX algorithm of each kernel.

Why by hand: CasADi generates straight-line scalar C per call (``map`` loops over calls,
it does not vectorise across them), and at N = 1000 the joint torques and segment forces
were ~40 % of a residual evaluation. The x4 functions execute the *same* instructions as
CasADi's scalar code (:meth:`casadi.Function.instruction_id` and friends, in order; the
rod is compiled without contraction to FMA), so every lane is bit for bit the scalar
kernel's result (tests/generated/test_rod_kernels.py). Only the operations these kernels
use are emitted; any other raises, so a kernel that grows one fails here, not in C.

Calling convention of ``<name>_x4(arg, res)``: ``arg[4 * i + l]`` is input ``i`` of lane
``l``, ``res[4 * o + l]`` output ``o`` of lane ``l``; every pointer must be valid (no
NULL inputs or outputs, unlike CasADi's calling convention). Without GCC vector
extensions (``__GNUC__`` undefined) each function calls the scalar kernel four times.
"""

from __future__ import annotations

import casadi as ca

LANES = 4

_BINARY = {ca.OP_ADD: "+", ca.OP_SUB: "-", ca.OP_MUL: "*", ca.OP_DIV: "/"}


def _const(x: float) -> str:
    """An exact C literal of x (hexadecimal floating point), as a vector."""
    return f"kv4_splat({float(x).hex()})"


def lane_function(f: ca.Function) -> str:
    """C source of ``<f.name()>_x4``: f's SX algorithm on LANES lanes (see module doc)."""
    if not f.is_a("SXFunction"):
        raise TypeError(f"{f.name()}: lane code needs an SX function, got {f.class_name()}")
    name, n_in, n_out = f.name(), f.n_in(), f.n_out()
    body: list[str] = []
    used: set[int] = set()
    for k in range(f.n_instructions()):
        op, i, o = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_INPUT:
            loads = ", ".join(f"arg[{LANES * i[0] + lane}][{i[1]}]" for lane in range(LANES))
            body.append(f"  w{o[0]} = (kv4){{{loads}}};")
        elif op == ca.OP_OUTPUT:
            body.extend(f"  res[{LANES * o[0] + lane}][{o[1]}] = w{i[0]}[{lane}];"
                        for lane in range(LANES))
        elif op == ca.OP_CONST:
            body.append(f"  w{o[0]} = {_const(f.instruction_constant(k))};")
        elif op in _BINARY:
            body.append(f"  w{o[0]} = w{i[0]} {_BINARY[op]} w{i[1]};")
        elif op == ca.OP_NEG:
            body.append(f"  w{o[0]} = -w{i[0]};")
        elif op == ca.OP_SQ:                       # casadi_sq(x) = x*x
            body.append(f"  w{o[0]} = w{i[0]} * w{i[0]};")
        elif op == ca.OP_TWICE:                    # CasADi's (2.*x)
            body.append(f"  w{o[0]} = 2. * w{i[0]};")
        elif op == ca.OP_ASSIGN:
            body.append(f"  w{o[0]} = w{i[0]};")
        else:
            raise NotImplementedError(f"{name}: SX operation {op} has no lane code")
        if op != ca.OP_OUTPUT:
            used.add(o[0])
    names = [f"w{w}" for w in sorted(used)]
    decl = ";\n  kv4 ".join(", ".join(names[k:k + 12]) for k in range(0, len(names), 12))
    fallback = "\n".join(
        f"    arg1[{i}] = arg[{LANES} * {i} + l];" for i in range(n_in)) + "\n" + "\n".join(
        f"    res1[{o}] = res[{LANES} * {o} + l];" for o in range(n_out))
    sz_iw, sz_w = max(f.sz_iw(), 1), max(f.sz_w(), 1)
    return f"""
int {name}_x4(const double* const* arg, double* const* res) {{
#if KV4_VECTOR
  kv4 {decl};
{chr(10).join(body)}
  return 0;
#else
  const double* arg1[{n_in}];
  double* res1[{n_out}];
  casadi_int iw[{sz_iw}];
  casadi_real w[{sz_w}];
  int l;
  for (l = 0; l < {LANES}; ++l) {{
{fallback}
    if ({name}(arg1, res1, iw, w, 0)) return 1;
  }}
  return 0;
#endif
}}
"""


def source(fns: list[ca.Function]) -> str:
    """The C file of the lane functions of ``fns`` (needs rod_kernels.h)."""
    parts = [f"""/* {LANES} elements per call: see derive/codegen_lanes.py. */
#include "rod_kernels.h"
#include "rod_kernels_x4.h"

#if defined(__GNUC__)
#define KV4_VECTOR 1
typedef double kv4 __attribute__((vector_size({8 * LANES})));
static inline kv4 kv4_splat(double x) {{ return (kv4){{{", ".join(["x"] * LANES)}}}; }}
#else
#define KV4_VECTOR 0
#endif
"""]
    parts.extend(lane_function(f) for f in fns)
    return "".join(parts)


def header(fns: list[ca.Function]) -> str:
    """Prototypes of the lane functions of ``fns``."""
    protos = "\n".join(f"int {f.name()}_x4(const double* const* arg, double* const* res);"
                       for f in fns)
    return f"""/* {LANES} elements per call: arg[{LANES} * i + l] = input i of lane l,
 * res[{LANES} * o + l] = output o of lane l (all valid); 0 on success. Every lane equals
 * the scalar kernel of the same name bit for bit. See derive/codegen_lanes.py. */
#ifndef ROD_KERNELS_X4_H
#define ROD_KERNELS_X4_H
#ifdef __cplusplus
extern "C" {{
#endif
{protos}
#ifdef __cplusplus
}}
#endif
#endif
"""
