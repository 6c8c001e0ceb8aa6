// GENERATED FILE - do not edit; regenerate with `kvrod generate`.
// source: derive.codegen_lanes.header
// derivation step: discrete_rod
// inputs sha256: 6eb00fc027cee9671700c247060ef0799b9dad63cd1710356316451ffa69e5f5
// tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

/* 4 elements per call: arg[4 * i + l] = input i of lane l,
 * res[4 * o + l] = output o of lane l (all valid); 0 on success. Every lane equals
 * the scalar kernel of the same name bit for bit. See derive/codegen_lanes.py. */
#ifndef ROD_KERNELS_X4_H
#define ROD_KERNELS_X4_H
#ifdef __cplusplus
extern "C" {
#endif
int rod_segment_forces_x4(const double* const* arg, double* const* res);
int rod_segment_forces_jac_x4(const double* const* arg, double* const* res);
int rod_joint_torques_x4(const double* const* arg, double* const* res);
int rod_joint_torques_jac_x4(const double* const* arg, double* const* res);
int rod_segment_diagnostics_x4(const double* const* arg, double* const* res);
int rod_joint_diagnostics_x4(const double* const* arg, double* const* res);
int rod_segment_forces_strain_x4(const double* const* arg, double* const* res);
int rod_joint_torques_strain_x4(const double* const* arg, double* const* res);
#ifdef __cplusplus
}
#endif
#endif
