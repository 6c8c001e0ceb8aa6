"""Generate the discrete rod's C kernels, layout header and module and serialised
CasADi functions (docs/design.md, section 3).

Files (all in ``generated/``):

* ``rod_kernels.c`` / ``rod_kernels.h``: every kernel of :func:`derive.discrete_rod.kernels`,
  :func:`derive.discrete_rod.coupled_kernels` and :func:`derive.links.kernels` (links
  and rigid bodies) through one ``casadi.CodeGenerator`` (size independent of N);
* ``rod_kernels_x4.c`` / ``rod_kernels_x4.h``: the hottest kernels four elements per
  call (:mod:`derive.codegen_lanes`, from their SX algorithms; bit for bit the scalar ones);
* ``rod_contact_kernels.c`` / ``rod_contact_kernels.h``: the contact kernels of
  :func:`derive.contact.contact_kernels` (rod-obstacle) and
  :func:`derive.contact_pair.pair_kernels` (rod-rod) through a CodeGenerator of their
  own (their ~0.9 MB would take rod_kernels.c over its 1 MB bound);
* ``rod_tangent_kernels.c`` / ``rod_tangent_kernels.h``: the forward-mode (tangent)
  kernels of the residual's kernels (:func:`derive.tangents.tangent_kernels`: the
  sensitivities' ``F_y s + F_y' s' + F_p dp``) through a CodeGenerator of their own, the
  header ending with their work sizes;
* ``rod_layout.h``: the layout the C assembly (``runtime/model/native/rod_assembly.c``,
  written by hand) is compiled with: cell sizes, field and parameter offsets, band
  widths, kernel work sizes (``templates/rod_layout.h.jinja``);
* ``rod_layout.py``: the same layout for Python (``templates/rod_layout.py.jinja``);
* ``rod_<kernel>.casadi``: each kernel serialised (in-process fallback, IDAS cross-check).
"""

from __future__ import annotations

import json
import tempfile
from functools import lru_cache
from pathlib import Path

import casadi as ca

from derive import cache, codegen_lanes, contact, contact_pair, links, tangents
from derive import discrete_rod as dr
from derive.artifact import Artifact, sha256_text
from derive.templating import render

STEP = "discrete_rod"
TEMPLATES = Path(__file__).resolve().parent / "templates"
#: CasADi CodeGenerator options (part of every inputs hash)
CODEGEN_OPTIONS = {"with_header": True, "indent": 2, "casadi_int": "long long int"}
#: kernels that also get a four-lane variant (``<name>_x4``): the costliest of the
#: residual, of the Jacobian and of the energies (evaluated three times a step by the
#: energy audit)
X4_KERNELS = ("rod_segment_forces", "rod_joint_torques", "rod_segment_forces_jac",
              "rod_joint_torques_jac", "rod_segment_diagnostics", "rod_joint_diagnostics",
              "rod_segment_forces_strain", "rod_joint_torques_strain")


def _signature(f: ca.Function) -> dict:
    return {
        "inputs": {f.name_in(i): list(f.size_in(i)) for i in range(f.n_in())},
        "outputs": {f.name_out(i): list(f.size_out(i)) for i in range(f.n_out())},
    }


@lru_cache(maxsize=1)
def _build() -> tuple[list[ca.Function], str, str, tuple, tuple]:
    fns = dr.kernels() + dr.coupled_kernels() + links.kernels()
    cg = ca.CodeGenerator("rod_kernels.c", CODEGEN_OPTIONS)
    for f in fns:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + "/")
        c_text = (Path(tmp) / "rod_kernels.c").read_text()
        h_text = (Path(tmp) / "rod_kernels.h").read_text()
    bands = _band_data()
    return fns, c_text, h_text, bands["bands"], bands["static"]


@lru_cache(maxsize=1)
def _build_contact() -> tuple[list[ca.Function], str, str]:
    """The contact kernels and their C source and header (rod_contact_kernels.c/.h)."""
    fns = contact.contact_kernels() + contact_pair.pair_kernels()
    cg = ca.CodeGenerator("rod_contact_kernels.c", CODEGEN_OPTIONS)
    for f in fns:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + "/")
        c_text = (Path(tmp) / "rod_contact_kernels.c").read_text()
        h_text = (Path(tmp) / "rod_contact_kernels.h").read_text()
    return fns, c_text, h_text


@lru_cache(maxsize=1)
def _build_tangents() -> tuple[list[ca.Function], str, str]:
    """The tangent kernels and their C source and header (rod_tangent_kernels.c/.h)."""
    fns = tangents.tangent_kernels()
    cg = ca.CodeGenerator("rod_tangent_kernels.c", CODEGEN_OPTIONS)
    for f in fns:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + "/")
        c_text = (Path(tmp) / "rod_tangent_kernels.c").read_text()
        h_text = (Path(tmp) / "rod_tangent_kernels.h").read_text()
    return fns, c_text, h_text + tangents.work_defines(fns)


def _band_data() -> dict:
    """Band widths of the Jacobians for N = 1..4 (static: 1..3), the formula in the number
    of branches and its N = 1 offset, as tuples. Pure functions of discrete_rod's layout
    that take ~1.5 s of Python, so kept in the derivation cache (:func:`derive.cache.memo`,
    keyed by derive/)."""

    def compute() -> dict:
        formula = dr.bandwidth_formula()
        return {"bands": [dr.bandwidths(n) for n in (1, 2, 3, 4)],
                "static": [dr.static_bandwidths(n) for n in (1, 2, 3)],
                "formula": formula, "n1_delta": _n1_delta(formula),
                "coupled": [dr.bandwidths(n, 0, True) for n in (1, 2, 3, 4, 5)],
                "coupled_static": [dr.static_bandwidths(n, True) for n in (1, 2, 3, 4)]}

    d = cache.memo("rod-bands-coupled", compute)
    pairs = lambda rows: tuple(tuple(int(v) for v in r) for r in rows)  # noqa: E731
    return {"bands": pairs(d["bands"]), "static": pairs(d["static"]),
            "coupled": pairs(d["coupled"]), "coupled_static": pairs(d["coupled_static"]),
            "formula": pairs(d["formula"]), "n1_delta": tuple(int(v) for v in d["n1_delta"])}


def _offsets_b(fields) -> dict[str, tuple[int, int]]:
    """{field: (base, per relaxation term)} offsets of a cell's fields."""
    out, a, b = {}, 0, 0
    for name, base, per in fields:
        out[name] = (a, b)
        a, b = a + base, b + per
    return out


def _n1_delta(formula) -> tuple[int, int]:
    """How much narrower the band of N = 1 is than the formula (the same for every B)."""
    (kl0, kl1), (ku0, ku1) = formula
    deltas = {(kl0 + kl1 * B - dr.bandwidths(1, B)[0], ku0 + ku1 * B - dr.bandwidths(1, B)[1])
              for B in range(dr.MAX_BRANCHES + 1)}
    if len(deltas) != 1:
        raise RuntimeError(f"N = 1 band widths are not a fixed offset: {deltas}")
    return deltas.pop()


def _context() -> dict:
    fns, _, _, bands, sbands = _build()
    fns = fns + _build_contact()[0]
    kl, ku = bands[-1]
    if bands[1] != bands[-1] or bands[2] != bands[-1]:
        raise RuntimeError(f"band widths not constant for N >= 2: {bands}")
    skl, sku = max(b[0] for b in sbands), max(b[1] for b in sbands)
    small = {n: b for n, b in zip((1,), bands[:1], strict=True) if b != (kl, ku)}
    max_jac = max(f.nnz_out(0) for f in fns if f.name().endswith("_jac"))
    formula = _band_data()["formula"]
    if formula != ((kl, formula[0][1]), (ku, formula[1][1])):
        raise RuntimeError(f"band formula {formula} disagrees with the B = 0 band {kl, ku}")
    dkl, dku = _band_data()["n1_delta"]
    cb = _band_data()["coupled"]
    if len(set(cb[2:])) != 1:
        raise RuntimeError(f"coupled band widths not constant for N >= 3: {cb}")
    cs = _band_data()["coupled_static"]
    return {
        "coupled_bands": cb[:3], "coupled_static": (max(b[0] for b in cs),
                                                    max(b[1] for b in cs)),
        "coupled_segment_params": dr.COUPLED_SEGMENT_PARAMS,
        "n_coupled_segment": dr.N_COUPLED_SEGMENT,
        "coupled_segment_offsets": dr.COUPLED_SEGMENT_OFFSETS,
        "coupled_joint_params": dr.COUPLED_JOINT_PARAMS,
        "n_coupled_joint": dr.N_COUPLED_JOINT,
        "coupled_joint_offsets": dr.COUPLED_JOINT_OFFSETS,
        "link_params": links.LINK_PARAMS, "n_link": links.N_LINK,
        "link_offsets": links.LINK_OFFSETS,
        "body_params": links.BODY_PARAMS, "n_body": links.N_BODY,
        "body_offsets": links.BODY_OFFSETS,
        "link_forces": links.LINK_FORCES, "link_force_offsets": links.LINK_FORCE_OFFSETS,
        "n_link_forces": links.N_LINK_FORCES,
        "link_jac_columns": links.LINK_JAC_COLUMNS,
        "link_jac_offsets": links.LINK_JAC_OFFSETS,
        "n_link_jac_columns": links.N_LINK_JAC_COLUMNS,
        "body_rows": links.BODY_ROWS, "body_row_offsets": links.BODY_ROW_OFFSETS,
        "n_body_rows": links.N_BODY_ROWS,
        "body_jac_columns": links.BODY_JAC_COLUMNS,
        "body_jac_offsets": links.BODY_JAC_OFFSETS,
        "n_body_jac_columns": links.N_BODY_JAC_COLUMNS,
        "nq": contact.NQ, "quadrature": contact.QUADRATURE,
        "obstacle_kinds": contact.OBSTACLE_KINDS, "contact_cutoff": contact.CONTACT_CUTOFF,
        "obs_params": contact.OBS_PARAMS, "n_obs": contact.N_OBS,
        "obs_offsets": contact.OBS_OFFSETS,
        "cnt_params": contact.CNT_PARAMS, "n_cnt": contact.N_CNT,
        "cnt_offsets": contact.CNT_OFFSETS,
        "contact_forces": contact.CONTACT_FORCES,
        "contact_force_offsets": contact.CONTACT_FORCE_OFFSETS,
        "n_contact_forces": contact.N_CONTACT_FORCES,
        "contact_jac_columns": contact.CONTACT_JAC_COLUMNS,
        "contact_jac_offsets": contact.CONTACT_JAC_OFFSETS,
        "n_contact_jac_columns": contact.N_CONTACT_JAC_COLUMNS,
        "contact_point_columns": contact.CONTACT_POINT_COLUMNS,
        "pair_params": contact_pair.PAIR_PARAMS, "n_pair": contact_pair.N_PAIR,
        "pair_offsets": contact_pair.PAIR_OFFSETS,
        "pair_forces": contact_pair.PAIR_FORCES,
        "pair_force_offsets": contact_pair.PAIR_FORCE_OFFSETS,
        "n_pair_forces": contact_pair.N_PAIR_FORCES,
        "pair_jac_columns": contact_pair.PAIR_JAC_COLUMNS,
        "pair_jac_offsets": contact_pair.PAIR_JAC_OFFSETS,
        "n_pair_jac_columns": contact_pair.N_PAIR_JAC_COLUMNS,
        "cell0_fields_b": dr.CELL0_FIELDS_B, "cell_fields_b": dr.CELL_FIELDS_B,
        "cell0_offsets_b": _offsets_b(dr.CELL0_FIELDS_B),
        "cell_offsets_b": _offsets_b(dr.CELL_FIELDS_B),
        "cell0_base": sum(f[1] for f in dr.CELL0_FIELDS_B),
        "cell0_per": sum(f[2] for f in dr.CELL0_FIELDS_B),
        "cell_base": sum(f[1] for f in dr.CELL_FIELDS_B),
        "cell_per": sum(f[2] for f in dr.CELL_FIELDS_B),
        "kl_formula": formula, "kl_n1_delta": dkl, "ku_n1_delta": dku,
        "max_branches": dr.MAX_BRANCHES,
        "cell0_fields": dr.CELL0_FIELDS, "cell_fields": dr.CELL_FIELDS,
        "cell0_size": dr.CELL0_SIZE, "cell_size": dr.CELL_SIZE,
        "cell0_offsets": dr.CELL0_OFFSETS, "cell_offsets": dr.CELL_OFFSETS,
        "static_cell0_fields": dr.STATIC_CELL0_FIELDS,
        "static_cell_fields": dr.STATIC_CELL_FIELDS,
        "static_cell0_size": dr.STATIC_CELL0_SIZE,
        "static_cell_size": dr.STATIC_CELL_SIZE,
        "static_cell_offsets": dr.STATIC_CELL_OFFSETS,
        "kl": kl, "ku": ku, "small_bands": small, "static_kl": skl, "static_ku": sku,
        "params": dr.PARAMS, "n_params": dr.N_PARAMS, "param_offsets": dr.PARAM_OFFSETS,
        "param_sizes": dr.PARAM_SIZES, "diag_scalars": dr.DIAG_SCALARS,
        "segment_params": dr.SEGMENT_PARAMS, "n_segment": dr.N_SEGMENT,
        "segment_offsets": dr.SEGMENT_OFFSETS,
        "joint_params": dr.JOINT_PARAMS, "n_joint": dr.N_JOINT,
        "joint_offsets": dr.JOINT_OFFSETS,
        "node_loads": dr.NODE_LOADS, "n_node_load": dr.N_NODE_LOAD,
        "node_load_offsets": dr.NODE_LOAD_OFFSETS,
        "segment_loads": dr.SEGMENT_LOADS, "n_segment_load": dr.N_SEGMENT_LOAD,
        "segment_load_offsets": dr.SEGMENT_LOAD_OFFSETS,
        "n_diag_scalars": len(dr.DIAG_SCALARS), "n_diag_energies": len(dr.DIAG_ENERGIES),
        "kernels": {f.name(): _signature(f) for f in fns},
        "max_w": max(1, max(f.sz_w() for f in fns)),
        "max_iw": max(1, max(f.sz_iw() for f in fns)),
        "max_arg": max(f.sz_arg() for f in fns), "max_res": max(f.sz_res() for f in fns),
        "max_jac": max_jac,
    }


def _render(template: str, ctx: dict) -> str:
    return render(TEMPLATES, template, **ctx)


def artifacts() -> list[Artifact]:
    """All rod artifacts (bodies without provenance header), deterministic."""
    fns, c_text, h_text, _, _ = _build()
    ctx = _context()
    opts = json.dumps(CODEGEN_OPTIONS, sort_keys=True)
    serial = {f.name(): f.serialize() for f in fns}
    kernels_hash = sha256_text(opts, *(serial[k] for k in sorted(serial)))
    sigs = {f.name(): _signature(f) for f in fns}
    ctx_json = json.dumps(ctx, sort_keys=True, default=str)
    out = [
        Artifact("rod_kernels.c", c_text, "casadi.CodeGenerator(derive.discrete_rod.kernels()"
                 " + coupled_kernels() + derive.links.kernels())", STEP, kernels_hash,
                 {"functions": sigs}),
        Artifact("rod_kernels.h", h_text, "casadi.CodeGenerator (header)", STEP, kernels_hash),
    ]
    x4 = [f for f in fns if f.name() in X4_KERNELS]
    x4_hash = sha256_text(Path(codegen_lanes.__file__).read_text(),
                          *(serial[f.name()] for f in x4))
    out += [Artifact("rod_kernels_x4.c", codegen_lanes.source(x4),
                     "derive.codegen_lanes.source(" + ", ".join(X4_KERNELS) + ")", STEP,
                     x4_hash),
            Artifact("rod_kernels_x4.h", codegen_lanes.header(x4),
                     "derive.codegen_lanes.header", STEP, x4_hash)]
    cfns, cc_text, ch_text = _build_contact()
    cserial = {f.name(): f.serialize() for f in cfns}
    contact_hash = sha256_text(opts, *(cserial[k] for k in sorted(cserial)))
    out += [Artifact("rod_contact_kernels.c", cc_text,
                     "casadi.CodeGenerator(derive.contact.contact_kernels()"
                     " + derive.contact_pair.pair_kernels())", STEP, contact_hash,
                     {"functions": {f.name(): _signature(f) for f in cfns}}),
            Artifact("rod_contact_kernels.h", ch_text, "casadi.CodeGenerator (header)", STEP,
                     contact_hash)]
    serial.update(cserial)
    sigs.update({f.name(): _signature(f) for f in cfns})
    tfns, tc_text, th_text = _build_tangents()
    tserial = [f.serialize() for f in tfns]
    tangent_hash = sha256_text(opts, Path(tangents.__file__).read_text(), *tserial)
    out += [Artifact("rod_tangent_kernels.c", tc_text,
                     "casadi.CodeGenerator(derive.tangents.tangent_kernels())", STEP,
                     tangent_hash, {"functions": {f.name(): _signature(f) for f in tfns}}),
            Artifact("rod_tangent_kernels.h", th_text,
                     "casadi.CodeGenerator (header) + derive.tangents.work_defines", STEP,
                     tangent_hash)]
    for tpl, path in (("rod_layout.h.jinja", "rod_layout.h"),
                      ("rod_layout.py.jinja", "rod_layout.py")):
        text = _render(tpl, ctx)
        out.append(Artifact(path, text, "derive/templates/" + tpl, STEP,
                            sha256_text((TEMPLATES / tpl).read_text(), ctx_json)))
    for name in sorted(serial):
        out.append(Artifact(f"{name}.casadi", serial[name], f"casadi.Function {name}", STEP,
                            sha256_text(serial[name]), {name: sigs[name]}))
    return out
