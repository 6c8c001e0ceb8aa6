// GENERATED FILE - do not edit; regenerate with `kvrod generate`.
// source: derive/templates/rod_layout.h.jinja
// derivation step: discrete_rod
// inputs sha256: b850f334c026de4a8d9b1a69e5be703198769e4ee7039030bf58f2d31272dc58
// tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

/*
 * The discrete rod's layout for the C assembly (runtime/model/native/rod_assembly.c): cell
 * sizes, field offsets, band widths, parameter offsets, kernel work sizes. One source of
 * truth: derive/discrete_rod.py's layout tables (generated/rod_layout.py is the same for
 * Python).
 */
#ifndef KVROD_ROD_LAYOUT_H
#define KVROD_ROD_LAYOUT_H

/* cell sizes and field offsets for nb relaxation terms: base + per * nb */
#define CELL0_BASE 6
#define CELL0_PER 3
#define CELL_BASE 13
#define CELL_PER 6
#define CELL0_PHI_BASE 0
#define CELL0_PHI_PER 0
#define CELL0_V_BASE 3
#define CELL0_V_PER 0
#define CELL0_Q_JOINT_BASE 6
#define CELL0_Q_JOINT_PER 0
#define CELL_PHI_BASE 7
#define CELL_PHI_PER 3
#define CELL_V_BASE 10
#define CELL_V_PER 3
#define CELL_P_BASE 0
#define CELL_P_PER 0
#define CELL_OMEGA_BASE 4
#define CELL_OMEGA_PER 0
#define CELL_Q_SEGMENT_BASE 7
#define CELL_Q_SEGMENT_PER 0
#define CELL_Q_JOINT_BASE 13
#define CELL_Q_JOINT_PER 3

/* band widths: kl = KL0 + KL1 nb, ku = KU0 + KU1 nb, narrower by KL_N1, KU_N1 for N = 1 */
#define KL0 19
#define KL1 6
#define KU0 15
#define KU1 6
#define KL_N1 1
#define KU_N1 0

/* band widths of a rod with coupled sections (nb = 0) for N = 1, 2 and N >= 3 */
#define KLC_1 18
#define KUC_1 15
#define KLC_2 25
#define KUC_2 22
#define KLC 25
#define KUC 22
/* coupled sections: parameters per segment and per joint beside NSEG, NJNT */
#define NSEGC 50
#define NJNTC 18
#define SEGC_C_FF 0
#define SEGC_V_FF 9
#define SEGC_C_FM 18
#define SEGC_V_FM 27
#define SEGC_W 36
#define SEGC_RHOJ 38
#define SEGC_E 47
#define JNTC_C_MM 0
#define JNTC_V_MM 9

/* most relaxation terms; parameters per rod, segment, joint, node load, segment load */
#define MAX_NB 24
#define NPAR 43
#define NSEG 14
#define NJNT 10
#define NNL 6
#define NSL 6
/* diagnostics: energies and powers, then the supports' reactions */
#define NDIAG 17
#define NDIAG_E 5

#define PAR_LOAD_SCALE 0
#define PAR_GRAVITY 1
#define PAR_F_DIST 4
#define PAR_FIX_START 7
#define PAR_CLAMP_START 8
#define PAR_FIX_END 9
#define PAR_CLAMP_END 10
#define PAR_R_START 11
#define PAR_V_START 14
#define PAR_A_START 17
#define PAR_P_START 20
#define PAR_OMEGA_START 24
#define PAR_R_END 27
#define PAR_V_END 30
#define PAR_A_END 33
#define PAR_P_END 36
#define PAR_OMEGA_END 40

#define SEG_H 0
#define SEG_C_F 1
#define SEG_V_F 4
#define SEG_V0 7
#define SEG_RHOA 10
#define SEG_RHOI 11

#define JNT_H 0
#define JNT_C_M 1
#define JNT_V_M 4
#define JNT_U0 7

#define NL_F_DEAD 0
#define NL_F_FOLLOWER 3

#define SL_M_DEAD 0
#define SL_M_FOLLOWER 3

/* work memory large enough for every kernel; the largest kernel Jacobian */
#define MAXW 620
#define MAXIW 1
#define MAXARG 14
#define MAXRES 6
#define MAXJAC 495

#endif
