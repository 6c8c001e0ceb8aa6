// GENERATED FILE - do not edit; regenerate with `kvrod generate`.
// source: derive/templates/rod_layout.h.jinja
// derivation step: discrete_rod
// inputs sha256: 25df1564f3a0d773f3a7ae1e3e39ae5f91c53c454787a0c96f858d6488be6c5f
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
#define NSEGC 59
#define NJNTC 18
#define SEGC_C_FF 0
#define SEGC_V_FF 9
#define SEGC_C_FM 18
#define SEGC_V_FM 27
#define SEGC_W 36
#define SEGC_RHOJ 38
#define SEGC_E 47
#define SEGC_C_FE 50
#define JNTC_C_MM 0
#define JNTC_V_MM 9

/* links (derive/links.py): parameters per link; the blocks of Q (rod_link_forces); the
 * columns of rod_link_forces_jac (NLNKQ x NLNKJ, dense, column-major) */
#define NLNK 79
#define LNK_K 0
#define LNK_V 36
#define LNK_D0 72
#define LNK_R0 75
#define NLNKQ 18
#define LNKQ_F_A 0
#define LNKQ_F_B 3
#define LNKQ_T_A1 6
#define LNKQ_T_A2 9
#define LNKQ_T_B1 12
#define LNKQ_T_B2 15
#define NLNKJ 40
#define LNKJ_PHI_A 0
#define LNKJ_PHI_B 3
#define LNKJ_P_A1 6
#define LNKJ_P_A2 10
#define LNKJ_P_B1 14
#define LNKJ_P_B2 18
#define LNKJ_V_A 22
#define LNKJ_V_B 25
#define LNKJ_OMEGA_A1 28
#define LNKJ_OMEGA_A2 31
#define LNKJ_OMEGA_B1 34
#define LNKJ_OMEGA_B2 37
/* rigid bodies at nodes: parameters per body; the rows of rod_body_inertia; the columns
 * of rod_body_inertia_jac (NBDYR x NBDYJ, dense, column-major) */
#define NBDY 13
#define BDY_M 0
#define BDY_J 1
#define BDY_E 10
#define NBDYR 6
#define BDYR_V 0
#define BDYR_OMEGA 3
#define NBDYJ 10
#define BDYJ_V 0
#define BDYJ_P 3
#define BDYJ_OMEGA 7

/* contact (derive/contact.py, contact_pair.py; kernels in rod_contact_kernels.c):
 * quadrature points per segment; a segment or pair whose bound kernel
 * (rod_contact_<kind>_bound, rod_contact_pair_bound) exceeds CONTACT_CUTOFF delta
 * contributes nothing above round-off */
#define NQ 3
#define CONTACT_CUTOFF 40.0
/* parameters per obstacle (its current pose first) and per segment's contact with it */
#define NOBS 22
#define OBS_C 0
#define OBS_Q 3
#define OBS_V 7
#define OBS_W 10
#define OBS_POINT 13
#define OBS_AXIS 16
#define OBS_RADIUS 19
#define OBS_LENGTH 20
#define OBS_EDGE 21
#define NCNT 7
#define CNT_K 0
#define CNT_DELTA 1
#define CNT_C 2
#define CNT_MU 3
#define CNT_V_S 4
#define CNT_R 5
#define CNT_H 6
/* the blocks of rod_contact_<kind>'s Q; the columns of its _jac (NCNTQ x NCNTJ, dense,
 * column-major) */
#define NCNTQ 9
#define CNTQ_F_A 0
#define CNTQ_F_B 3
#define CNTQ_T 6
#define NCNTJ 19
#define CNTJ_PHI_A 0
#define CNTJ_PHI_B 3
#define CNTJ_P 6
#define CNTJ_V_A 10
#define CNTJ_V_B 13
#define CNTJ_OMEGA 16
/* a pair of segments (rod_contact_pair): parameters, blocks of Q, columns of its _jac
 * (NPAIRQ x NPAIRJ, dense, column-major) */
#define NPAIR 8
#define PAIR_K 0
#define PAIR_DELTA 1
#define PAIR_C 2
#define PAIR_MU 3
#define PAIR_V_S 4
#define PAIR_R_1 5
#define PAIR_R_2 6
#define PAIR_L_X 7
#define NPAIRQ 18
#define PAIRQ_F_A 0
#define PAIRQ_F_B 3
#define PAIRQ_T_1 6
#define PAIRQ_F_C 9
#define PAIRQ_F_D 12
#define PAIRQ_T_2 15
#define NPAIRJ 38
#define PAIRJ_PHI_A 0
#define PAIRJ_PHI_B 3
#define PAIRJ_P_1 6
#define PAIRJ_PHI_C 10
#define PAIRJ_PHI_D 13
#define PAIRJ_P_2 16
#define PAIRJ_V_A 20
#define PAIRJ_V_B 23
#define PAIRJ_OMEGA_1 26
#define PAIRJ_V_C 29
#define PAIRJ_V_D 32
#define PAIRJ_OMEGA_2 35

/* most relaxation terms; parameters per rod, segment, joint, node load, segment load */
#define MAX_NB 24
#define NPAR 55
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
#define PAR_M_DEAD_START 43
#define PAR_M_FOLLOWER_START 46
#define PAR_M_DEAD_END 49
#define PAR_M_FOLLOWER_END 52

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
#define MAXW 694
#define MAXIW 1
#define MAXARG 15
#define MAXRES 8
#define MAXJAC 720

#endif
