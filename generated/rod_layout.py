# GENERATED FILE - do not edit; regenerate with `kvrod generate`.
# source: derive/templates/rod_layout.py.jinja
# derivation step: discrete_rod
# inputs sha256: ff87e39d64bfe7cddf01f4067b39949fc3ae1f7535d0c94ac59b97cca06995e7
# tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

"""State, parameter and diagnostics layout of the discrete rod (the one place that owns it).

Rendered from ``derive/discrete_rod.py``; imports only the standard library.

Quaternions are stored with the SCALAR PART FIRST: p = (p0, p1, p2, p3).

State vector y (and y'), cell by cell, for a rod with B rod-level relaxation terms
(generalized Maxwell; B = 0 for Kelvin-Voigt), n = n_state(N, B):

* cell 0 (node 0, joint 0): phi(3) v(3) q_joint(3B)
* cell i = 1..N (segment i between nodes i-1 and i, node i, joint i):
  p(4) Omega(3) q_segment(3B) phi(3) v(3) q_joint(3B)

phi: node position (m), v: node velocity (m/s), p: segment quaternion, Omega: material
angular velocity of the segment (rad/s), q_segment / q_joint: the internal strains of the
relaxation terms (term b at 3b: the shear/extension strain of the segment, the curvature
and twist of the joint toward which the term relaxes). Residual rows use the same
layout: the rows of a field hold its equation (p: kinematics p' - 1/2 p*(0,Omega);
Omega: angular momentum balance; q: q' - (strain - q)/theta_b; phi: phi' - v; v: linear
momentum balance, or v - r'(t) for a held node, whose position starts at r(0)). The
constants CELL0_SIZE, CELL_SIZE and the offsets below are those of B = 0; every index
function takes ``branches`` = B.

Per-element data (row-major arrays, one row per element): SEGMENT_PARAMS for segments
1..N, JOINT_PARAMS for joints 0..N (joint j at node j), NODE_LOADS for nodes 0..N,
SEGMENT_LOADS for segments 1..N; global PARAMS.

The Jacobian dF/dy + c dF/dy' is banded with kl sub- and ku super-diagonals,
:func:`bandwidths` (KL, KU for B = 0 and N >= 2); LAPACK band storage (dgbtrf) has
2 kl + ku + 1 rows, element (i, j) at ab[kl + ku + i - j, j].

Static problem (reduced coordinates, rows = force/torque balance):
cell 0: phi(3); cell i: theta(3) phi(3)
(theta: rotation increment, p <- p*exp(theta/2)); bandwidths STATIC_KL, STATIC_KU.

C API (runtime/model/native/rod_assembly.h): kvrod_residual, kvrod_jacobian_band, kvrod_diagnostics,
kvrod_energies, each on a kvrod_rod struct (N, B, the band and pointers to the arrays);
per-element CasADi kernels in generated/rod_kernels.c (contact: rod_contact_kernels.c) and
generated/rod_<kernel>.casadi.
"""

from functools import lru_cache

CELL0_SIZE = 6
CELL_SIZE = 13
CELL0_OFFSETS = {'phi': 0, 'v': 3}
CELL_OFFSETS = {'p': 0, 'Omega': 4, 'phi': 7, 'v': 10}

OFF_P = 0
OFF_OMEGA = 4
OFF_PHI = 7
OFF_V = 10

KL = 19
KU = 15

#: cells for B relaxation terms: (name, size, size per term), in order
CELL0_FIELDS_B = (('phi', 3, 0), ('v', 3, 0), ('q_joint', 0, 3))
CELL_FIELDS_B = (('p', 4, 0), ('Omega', 3, 0), ('q_segment', 0, 3), ('phi', 3, 0), ('v', 3, 0), ('q_joint', 0, 3))
MAX_BRANCHES = 24
#: band widths kl = KL_FORMULA[0][0] + KL_FORMULA[0][1] B (ku likewise) for N >= 2;
#: N = 1 is narrower by N1_DELTA
KL_FORMULA = ((19, 6), (15, 6))
N1_DELTA = (1, 0)

STATIC_CELL0_SIZE = 3
STATIC_CELL_SIZE = 6
STATIC_CELL_OFFSETS = {'theta': 0, 'phi': 3}
STATIC_KL = 8
STATIC_KU = 8

#: parameter vector: (name, size, unit, meaning), in order
PARAMS = (
    ("load_scale", 1, "1", "factor on all external loads (load stepping)"),
    ("gravity", 3, "m/s^2", "gravitational acceleration (spatial)"),
    ("f_dist", 3, "N/m", "dead distributed force per length (spatial)"),
    ("fix_start", 1, "1", "1: node 0 held (clamped or pinned, position prescribed), else 0"),
    ("clamp_start", 1, "1", "1: frame clamped at s = 0 (half-length joint), else 0"),
    ("fix_end", 1, "1", "1: node N held, else 0"),
    ("clamp_end", 1, "1", "1: frame clamped at s = L, else 0"),
    ("r_start", 3, "m", "prescribed position of node 0"),
    ("v_start", 3, "m/s", "prescribed velocity of node 0"),
    ("a_start", 3, "m/s^2", "prescribed acceleration of node 0 (its support\u0027s reaction)"),
    ("p_start", 4, "1", "clamp frame quaternion at s = 0 (scalar first)"),
    ("Omega_start", 3, "rad/s", "material angular velocity of the clamp frame at s = 0"),
    ("r_end", 3, "m", "prescribed position of node N"),
    ("v_end", 3, "m/s", "prescribed velocity of node N"),
    ("a_end", 3, "m/s^2", "prescribed acceleration of node N (its support\u0027s reaction)"),
    ("p_end", 4, "1", "clamp frame quaternion at s = L (scalar first)"),
    ("Omega_end", 3, "rad/s", "material angular velocity of the clamp frame at s = L"),
    ("m_dead_start", 3, "N m", "dead point moment applied at node 0 (spatial; also in segment 1\u0027s m_dead): a free end\u0027s condensation of a coupled rod carries it"),
    ("m_follower_start", 3, "N m", "follower point moment applied at node 0 (material; also in segment 1\u0027s m_follower)"),
    ("m_dead_end", 3, "N m", "dead point moment applied at node N (spatial; also in segment N\u0027s m_dead)"),
    ("m_follower_end", 3, "N m", "follower point moment applied at node N (material; also in segment N\u0027s m_follower)"),
)
N_PARAMS = 55
PARAM_OFFSETS = {'load_scale': 0, 'gravity': 1, 'f_dist': 4, 'fix_start': 7, 'clamp_start': 8, 'fix_end': 9, 'clamp_end': 10, 'r_start': 11, 'v_start': 14, 'a_start': 17, 'p_start': 20, 'Omega_start': 24, 'r_end': 27, 'v_end': 30, 'a_end': 33, 'p_end': 36, 'Omega_end': 40, 'm_dead_start': 43, 'm_follower_start': 46, 'm_dead_end': 49, 'm_follower_end': 52}
PARAM_SIZES = {'load_scale': 1, 'gravity': 3, 'f_dist': 3, 'fix_start': 1, 'clamp_start': 1, 'fix_end': 1, 'clamp_end': 1, 'r_start': 3, 'v_start': 3, 'a_start': 3, 'p_start': 4, 'Omega_start': 3, 'r_end': 3, 'v_end': 3, 'a_end': 3, 'p_end': 4, 'Omega_end': 3, 'm_dead_start': 3, 'm_follower_start': 3, 'm_dead_end': 3, 'm_follower_end': 3}

#: per-segment parameters (segment i = 1..N): (name, size, unit, meaning), in order
SEGMENT_PARAMS = (
    ("h", 1, "m", "segment length (reference arc length)"),
    ("C_F", 3, "N", "diagonal of C_F = diag(GA_1, GA_2, EA), eq. (7)"),
    ("V_F", 3, "N s", "diagonal of V_F, eq. (9)"),
    ("V0", 3, "1", "reference shear/extension strain of the segment (material)"),
    ("rhoA", 1, "kg/m", "mass per length rho A"),
    ("rhoI", 3, "kg m", "rotary inertia per length rho diag(I1, I2, I3)"),
)
N_SEGMENT = 14
SEGMENT_OFFSETS = {'h': 0, 'C_F': 1, 'V_F': 4, 'V0': 7, 'rhoA': 10, 'rhoI': 11}

#: per-joint parameters (joint j = 0..N at node j)
JOINT_PARAMS = (
    ("h", 1, "m", "joint length: (h_j + h_j+1)/2 inside, h/2 at a clamp"),
    ("C_M", 3, "N m^2", "diagonal of C_M = diag(EI_1, EI_2, GJ_T), eq. (7)"),
    ("V_M", 3, "N m^2 s", "diagonal of V_M, eq. (9)"),
    ("U0", 3, "1/m", "reference curvature and twist (material)"),
)
N_JOINT = 10
JOINT_OFFSETS = {'h': 0, 'C_M': 1, 'V_M': 4, 'U0': 7}

#: a rod with coupled sections (full 6x6 stiffness and viscosity, mass centre off the
#: centreline): per-segment and per-joint parameters beside SEGMENT_PARAMS, JOINT_PARAMS
COUPLED_SEGMENT_PARAMS = (
    ("C_FF", 9, "N", "stiffness block (Gamma, Gamma), symmetric"),
    ("V_FF", 9, "N s", "viscosity block (Gamma, Gamma), symmetric"),
    ("C_FM", 9, "N m", "stiffness block (Gamma, K): n += C_FM K, m += C_FM^T Gamma"),
    ("V_FM", 9, "N m s", "viscosity block (Gamma, K)"),
    ("w", 2, "m", "weights of the couplings with the joints at nodes i-1 and i (h/2 each; 0 where the joint is absent: a free end)"),
    ("rhoJ", 9, "kg m", "rotary inertia per length about the mass centre, 3x3 ((I11, -I12, 0), (-I12, I22, 0), (0, 0, I33)) rho"),
    ("e", 3, "m", "mass centre in the material frame (e1, e2, 0)"),
    ("C_FE", 9, "1/m", "a free end\u0027s share of its applied moment M (material) in the resultant: n += C_FE M (1/2 C_FM C_MM^-1 on a free end\u0027s segment, 0 elsewhere; M enters with its sign at s = L, negated at s = 0)"),
)
N_COUPLED_SEGMENT = 59
COUPLED_SEGMENT_OFFSETS = {'C_FF': 0, 'V_FF': 9, 'C_FM': 18, 'V_FM': 27, 'w': 36, 'rhoJ': 38, 'e': 47, 'C_FE': 50}
COUPLED_JOINT_PARAMS = (
    ("C_MM", 9, "N m^2", "stiffness block (K, K), symmetric"),
    ("V_MM", 9, "N m^2 s", "viscosity block (K, K), symmetric"),
)
N_COUPLED_JOINT = 18
COUPLED_JOINT_OFFSETS = {'C_MM': 0, 'V_MM': 9}
#: band widths of a coupled rod for N = 1, 2 and N >= 3; its static band
COUPLED_BANDS = ((18, 15), (25, 22), (25, 22))
COUPLED_STATIC_KL, COUPLED_STATIC_KU = (11, 11)

#: links between two rod points and frames (derive/links.py; each side's frame the sum of
#: two quaternions): parameters per link, the blocks of its forces Q (rod_link_forces)
#: and the columns of rod_link_forces_jac (rows: LINK_FORCES)
LINK_PARAMS = (
    ("K", 36, "N/m | N | N m", "stiffness 6x6, symmetric positive semi-definite: translation block N/m, couplings N, rotation block N m"),
    ("V", 36, "N s/m | N s | N m s", "viscosity 6x6, symmetric positive semi-definite (same blocks times s)"),
    ("d0", 3, "m", "reference offset R(p_a0)^T (phi_b0 - phi_a0) of b from a, P\u0027s frame"),
    ("r0", 4, "1", "reference relative quaternion conj(p_a0) p_b0 of the side sums (scalar first, any norm)"),
)
N_LINK = 79
LINK_OFFSETS = {'K': 0, 'V': 36, 'd0': 72, 'r0': 75}
LINK_FORCES = (('f_a', 3), ('f_b', 3), ('T_a1', 3), ('T_a2', 3), ('T_b1', 3), ('T_b2', 3))
LINK_FORCE_OFFSETS = {'f_a': 0, 'f_b': 3, 'T_a1': 6, 'T_a2': 9, 'T_b1': 12, 'T_b2': 15}
N_LINK_FORCES = 18
LINK_JAC_COLUMNS = (('phi_a', 3), ('phi_b', 3), ('p_a1', 4), ('p_a2', 4), ('p_b1', 4), ('p_b2', 4), ('v_a', 3), ('v_b', 3), ('Omega_a1', 3), ('Omega_a2', 3), ('Omega_b1', 3), ('Omega_b2', 3))
LINK_JAC_OFFSETS = {'phi_a': 0, 'phi_b': 3, 'p_a1': 6, 'p_a2': 10, 'p_b1': 14, 'p_b2': 18, 'v_a': 22, 'v_b': 25, 'Omega_a1': 28, 'Omega_a2': 31, 'Omega_b1': 34, 'Omega_b2': 37}
N_LINK_JAC_COLUMNS = 40
#: rigid bodies welded at nodes: parameters per body, the rows of rod_body_inertia (added
#: to the node's momentum row and the segment's angular momentum row) and the columns of
#: rod_body_inertia_jac
BODY_PARAMS = (
    ("M", 1, "kg", "mass"),
    ("J", 9, "kg m^2", "inertia about the mass centre, material frame, 3x3 row-major, symmetric"),
    ("e", 3, "m", "mass centre offset from the node, material frame"),
)
N_BODY = 13
BODY_OFFSETS = {'M': 0, 'J': 1, 'e': 10}
BODY_ROWS = (('v', 3), ('Omega', 3))
BODY_ROW_OFFSETS = {'v': 0, 'Omega': 3}
BODY_JAC_COLUMNS = (('v', 3), ('p', 4), ('Omega', 3))
BODY_JAC_OFFSETS = {'v': 0, 'p': 3, 'Omega': 7}
N_BODY_JAC_COLUMNS = 10

#: contact (derive/contact.py, derive/contact_pair.py; kernels in rod_contact_kernels.c):
#: NQ quadrature points per segment at QUADRATURE's nodes xi in [0, 1] with its weights
#: (times the segment's h); rod_contact_<kind> for each of OBSTACLE_KINDS; a segment (or a
#: pair) whose bound kernel (rod_contact_<kind>_bound, rod_contact_pair_bound) exceeds
#: CONTACT_CUTOFF delta contributes nothing above round-off
NQ = 3
QUADRATURE = ((0.0, 0.5, 1.0), (0.16666666666666666, 0.6666666666666666, 0.16666666666666666))
OBSTACLE_KINDS = ('plane', 'sphere', 'cylinder', 'pipe')
CONTACT_CUTOFF = 40.0
#: one obstacle's parameters (its current pose first) and one segment's contact with it
OBS_PARAMS = (
    ("c", 3, "m", "position of the obstacle frame\u0027s origin (spatial); the reference point of F_obs, M_obs and of the motion"),
    ("q", 4, "1", "orientation of the obstacle frame (quaternion, scalar first, any norm)"),
    ("v", 3, "m/s", "velocity of the origin c (spatial)"),
    ("w", 3, "rad/s", "angular velocity of the obstacle (spatial)"),
    ("point", 3, "m", "plane: a point of the plane; sphere: its centre; cylinder, pipe: a point on the axis (obstacle frame)"),
    ("axis", 3, "1", "plane: its outward normal; cylinder, pipe: the axis direction (obstacle frame, any length \u003e 0; unused by a sphere)"),
    ("radius", 1, "m", "sphere, cylinder, pipe: the radius (\u003e 0)"),
    ("length", 1, "m", "cylinder, pipe: length from the point along the axis; \u003c= 0: infinite"),
    ("edge", 1, "m", "cylinder: rounding of the rims; pipe: length over which an open end switches the contact off (\u003e 0 when length \u003e 0, else unused)"),
)
N_OBS = 22
OBS_OFFSETS = {'c': 0, 'q': 3, 'v': 7, 'w': 10, 'point': 13, 'axis': 16, 'radius': 19, 'length': 20, 'edge': 21}
CNT_PARAMS = (
    ("k", 1, "N/m^2", "stiffness per length (\u003e 0)"),
    ("delta", 1, "m", "smoothing length of the gap, the penetration tolerance scale (\u003e 0)"),
    ("c", 1, "N s/m^2", "normal damping per length (\u003e= 0)"),
    ("mu", 1, "1", "Coulomb friction coefficient (\u003e= 0)"),
    ("v_s", 1, "m/s", "slip velocity tolerance of the regularised friction (\u003e 0)"),
    ("r", 1, "m", "contact radius of the rod (\u003e= 0)"),
    ("h", 1, "m", "reference length of the segment (the weight of its line integral)"),
)
N_CNT = 7
CNT_OFFSETS = {'k': 0, 'delta': 1, 'c': 2, 'mu': 3, 'v_s': 4, 'r': 5, 'h': 6}
#: blocks of rod_contact_<kind>'s Q, columns of its _jac, columns of its diagnostics'
#: points (NQ rows)
CONTACT_FORCES = (('f_a', 3), ('f_b', 3), ('T', 3))
CONTACT_FORCE_OFFSETS = {'f_a': 0, 'f_b': 3, 'T': 6}
N_CONTACT_FORCES = 9
CONTACT_JAC_COLUMNS = (('phi_a', 3), ('phi_b', 3), ('p', 4), ('v_a', 3), ('v_b', 3), ('Omega', 3))
CONTACT_JAC_OFFSETS = {'phi_a': 0, 'phi_b': 3, 'p': 6, 'v_a': 10, 'v_b': 13, 'Omega': 16}
N_CONTACT_JAC_COLUMNS = 19
CONTACT_POINT_COLUMNS = (('x', 3), ('g', 1))
#: a pair of segments in contact (rod_contact_pair): parameters, blocks of Q, columns of
#: its _jac
PAIR_PARAMS = (
    ("k", 1, "N/m^2", "stiffness per length (\u003e 0)"),
    ("delta", 1, "m", "smoothing length of the gap (\u003e 0)"),
    ("c", 1, "N s/m^2", "normal damping per length (\u003e= 0)"),
    ("mu", 1, "1", "Coulomb friction coefficient (\u003e= 0)"),
    ("v_s", 1, "m/s", "slip velocity tolerance (\u003e 0)"),
    ("r_1", 1, "m", "contact radius of segment 1 (\u003e= 0)"),
    ("r_2", 1, "m", "contact radius of segment 2 (\u003e= 0)"),
    ("l_x", 1, "m", "contact length of a crossing at right angles (\u003e 0; r_1 + r_2 suggested)"),
)
N_PAIR = 8
PAIR_OFFSETS = {'k': 0, 'delta': 1, 'c': 2, 'mu': 3, 'v_s': 4, 'r_1': 5, 'r_2': 6, 'l_x': 7}
PAIR_FORCES = (('f_a', 3), ('f_b', 3), ('T_1', 3), ('f_c', 3), ('f_d', 3), ('T_2', 3))
PAIR_FORCE_OFFSETS = {'f_a': 0, 'f_b': 3, 'T_1': 6, 'f_c': 9, 'f_d': 12, 'T_2': 15}
N_PAIR_FORCES = 18
PAIR_JAC_COLUMNS = (('phi_a', 3), ('phi_b', 3), ('p_1', 4), ('phi_c', 3), ('phi_d', 3), ('p_2', 4), ('v_a', 3), ('v_b', 3), ('Omega_1', 3), ('v_c', 3), ('v_d', 3), ('Omega_2', 3))
PAIR_JAC_OFFSETS = {'phi_a': 0, 'phi_b': 3, 'p_1': 6, 'phi_c': 10, 'phi_d': 13, 'p_2': 16, 'v_a': 20, 'v_b': 23, 'Omega_1': 26, 'v_c': 29, 'v_d': 32, 'Omega_2': 35}
N_PAIR_JAC_COLUMNS = 38

#: loads per node (0..N) and per segment (1..N), current values
NODE_LOADS = (
    ("f_dead", 3, "N", "dead point force (spatial)"),
    ("f_follower", 3, "N", "follower point force (material frame of the node\u0027s segment)"),
)
N_NODE_LOAD = 6
NODE_LOAD_OFFSETS = {'f_dead': 0, 'f_follower': 3}
SEGMENT_LOADS = (
    ("m_dead", 3, "N m", "dead point moment (spatial)"),
    ("m_follower", 3, "N m", "follower point moment (material)"),
)
N_SEGMENT_LOAD = 6
SEGMENT_LOAD_OFFSETS = {'m_dead': 0, 'm_follower': 3}

#: diagnostics vector: these scalars, then V (3N), F (3N), U (3(N+1)), M (3(N+1));
#: joint j = 0..N sits at node j (j = 0 and j = N are the clamp joints, zero if absent)
DIAG_SCALARS = ('kinetic', 'elastic', 'dissipation_rate', 'external_power', 'boundary_power', 'start_force_x', 'start_force_y', 'start_force_z', 'start_moment_x', 'start_moment_y', 'start_moment_z', 'end_force_x', 'end_force_y', 'end_force_z', 'end_moment_x', 'end_moment_y', 'end_moment_z')
#: the first five: energies and powers; then the supports' reactions (6 per end)
DIAG_ENERGIES = DIAG_SCALARS[:5]
DIAG_REACTIONS = DIAG_SCALARS[5:]

#: per-element CasADi kernels (names, inputs, outputs)
KERNELS = {'rod_segment_forces': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'seg': [14, 1], 'n_q': [3, 1]}, 'outputs': {'Q': [9, 1]}}, 'rod_segment_forces_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'seg': [14, 1], 'n_q': [3, 1]}, 'outputs': {'dQb_dxb': [6, 13]}}, 'rod_joint_torques': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'm_q': [3, 1]}, 'outputs': {'T': [6, 1]}}, 'rod_joint_torques_jac': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'm_q': [3, 1]}, 'outputs': {'dT_dx': [6, 14]}}, 'rod_segment_inertia': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'p_dot': [4, 1], 'Omega_dot': [3, 1], 'seg': [14, 1]}, 'outputs': {'r': [7, 1]}}, 'rod_segment_inertia_jac': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'p_dot': [4, 1], 'Omega_dot': [3, 1], 'seg': [14, 1], 'c_y': [1, 1], 'c_j': [1, 1]}, 'outputs': {'J': [7, 7]}}, 'rod_node_inertia': {'inputs': {'phi': [3, 1], 'v': [3, 1], 'phi_dot': [3, 1], 'v_dot': [3, 1], 'm': [1, 1], 'f': [3, 1], 'held': [1, 1], 'r_held': [3, 1], 'v_held': [3, 1]}, 'outputs': {'r': [6, 1]}}, 'rod_node_inertia_jac': {'inputs': {'phi': [3, 1], 'v': [3, 1], 'phi_dot': [3, 1], 'v_dot': [3, 1], 'm': [1, 1], 'f': [3, 1], 'held': [1, 1], 'r_held': [3, 1], 'v_held': [3, 1], 'c_y': [1, 1], 'c_j': [1, 1]}, 'outputs': {'J': [6, 6]}}, 'rod_rotate': {'inputs': {'p': [4, 1], 'x': [3, 1]}, 'outputs': {'Rx': [3, 1]}}, 'rod_rotate_jac': {'inputs': {'p': [4, 1], 'x': [3, 1]}, 'outputs': {'dRx_dp': [3, 4]}}, 'rod_rotate_transposed': {'inputs': {'p': [4, 1], 'x': [3, 1]}, 'outputs': {'RTx': [3, 1]}}, 'rod_rotate_transposed_jac': {'inputs': {'p': [4, 1], 'x': [3, 1]}, 'outputs': {'dRTx_dp': [3, 4]}}, 'rod_segment_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'seg': [14, 1], 'n_q': [3, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'V': [3, 1], 'F': [3, 1]}}, 'rod_joint_diagnostics': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'm_q': [3, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'U': [3, 1], 'M': [3, 1]}}, 'rod_segment_kinetic': {'inputs': {'Omega': [3, 1], 'seg': [14, 1]}, 'outputs': {'T': [1, 1]}}, 'rod_node_kinetic': {'inputs': {'v': [3, 1], 'm': [1, 1]}, 'outputs': {'T': [1, 1]}}, 'rod_segment_branch': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'seg': [14, 1]}, 'outputs': {'dV': [3, 1], 'dV_dx': [3, 7], 'G': [6, 3]}}, 'rod_joint_branch': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'jnt': [10, 1]}, 'outputs': {'dU': [3, 1], 'dU_dx': [3, 8], 'G': [6, 3]}}, 'rod_segment_forces_strain': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'seg': [14, 1], 'n_q': [3, 1]}, 'outputs': {'Q': [9, 1], 'dV': [3, 1]}}, 'rod_joint_torques_strain': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'm_q': [3, 1]}, 'outputs': {'T': [6, 1], 'dU': [3, 1]}}, 'rod_coupled_segment_forces': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p_a': [4, 1], 'p': [4, 1], 'p_b': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega_a': [3, 1], 'Omega': [3, 1], 'Omega_b': [3, 1], 'seg': [14, 1], 'segc': [59, 1], 'jnt_a': [10, 1], 'jnt_b': [10, 1], 'm_end': [6, 1]}, 'outputs': {'Q': [15, 1]}}, 'rod_coupled_segment_forces_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p_a': [4, 1], 'p': [4, 1], 'p_b': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega_a': [3, 1], 'Omega': [3, 1], 'Omega_b': [3, 1], 'seg': [14, 1], 'segc': [59, 1], 'jnt_a': [10, 1], 'jnt_b': [10, 1], 'm_end': [6, 1]}, 'outputs': {'dQ_dx': [15, 33]}}, 'rod_coupled_segment_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p_a': [4, 1], 'p': [4, 1], 'p_b': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega_a': [3, 1], 'Omega': [3, 1], 'Omega_b': [3, 1], 'seg': [14, 1], 'segc': [59, 1], 'jnt_a': [10, 1], 'jnt_b': [10, 1], 'm_end': [6, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'V': [3, 1], 'F': [3, 1], 'M_a': [3, 1], 'M_b': [3, 1], 'P_M': [1, 1]}}, 'rod_coupled_joint_torques': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'jntc': [18, 1]}, 'outputs': {'T': [6, 1]}}, 'rod_coupled_joint_torques_jac': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'jntc': [18, 1]}, 'outputs': {'dT_dx': [6, 14]}}, 'rod_coupled_joint_diagnostics': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'jnt': [10, 1], 'jntc': [18, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'U': [3, 1], 'M': [3, 1]}}, 'rod_coupled_inertia': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'p_dot': [4, 1], 'Omega_dot': [3, 1], 'v_dot_a': [3, 1], 'v_dot_b': [3, 1], 'seg': [14, 1], 'segc': [59, 1], 'g': [3, 1]}, 'outputs': {'r': [13, 1]}}, 'rod_coupled_inertia_jac': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'p_dot': [4, 1], 'Omega_dot': [3, 1], 'v_dot_a': [3, 1], 'v_dot_b': [3, 1], 'seg': [14, 1], 'segc': [59, 1], 'g': [3, 1], 'c_y': [1, 1], 'c_j': [1, 1]}, 'outputs': {'J': [13, 13]}}, 'rod_coupled_kinetic': {'inputs': {'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'seg': [14, 1], 'segc': [59, 1], 'g': [3, 1]}, 'outputs': {'T': [1, 1], 'P_g': [1, 1]}}, 'rod_link_forces': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p_a1': [4, 1], 'p_a2': [4, 1], 'p_b1': [4, 1], 'p_b2': [4, 1], 'Omega_a1': [3, 1], 'Omega_a2': [3, 1], 'Omega_b1': [3, 1], 'Omega_b2': [3, 1], 'lnk': [79, 1]}, 'outputs': {'Q': [18, 1]}}, 'rod_link_forces_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p_a1': [4, 1], 'p_a2': [4, 1], 'p_b1': [4, 1], 'p_b2': [4, 1], 'Omega_a1': [3, 1], 'Omega_a2': [3, 1], 'Omega_b1': [3, 1], 'Omega_b2': [3, 1], 'lnk': [79, 1]}, 'outputs': {'dQ_dx': [18, 40]}}, 'rod_link_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p_a1': [4, 1], 'p_a2': [4, 1], 'p_b1': [4, 1], 'p_b2': [4, 1], 'Omega_a1': [3, 1], 'Omega_a2': [3, 1], 'Omega_b1': [3, 1], 'Omega_b2': [3, 1], 'lnk': [79, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'e': [6, 1], 's': [6, 1]}}, 'rod_body_inertia': {'inputs': {'v': [3, 1], 'v_dot': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'Omega_dot': [3, 1], 'g': [3, 1], 'bdy': [13, 1]}, 'outputs': {'r': [6, 1]}}, 'rod_body_inertia_jac': {'inputs': {'v': [3, 1], 'v_dot': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'Omega_dot': [3, 1], 'g': [3, 1], 'bdy': [13, 1], 'c_y': [1, 1], 'c_j': [1, 1]}, 'outputs': {'J': [6, 10]}}, 'rod_body_kinetic': {'inputs': {'v': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'g': [3, 1], 'bdy': [13, 1]}, 'outputs': {'T': [1, 1], 'P_g': [1, 1]}}, 'rod_contact_plane': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'Q': [9, 1]}}, 'rod_contact_plane_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'dQ_dx': [9, 19]}}, 'rod_contact_plane_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'E': [1, 1], 'P_diss': [1, 1], 'F_obs': [3, 1], 'M_obs': [3, 1], 'P_obs': [1, 1], 'g_min': [1, 1], 'points': [3, 4], 'P_fric': [1, 1]}}, 'rod_contact_plane_bound': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'g_lb': [1, 1]}}, 'rod_contact_sphere': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'Q': [9, 1]}}, 'rod_contact_sphere_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'dQ_dx': [9, 19]}}, 'rod_contact_sphere_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'E': [1, 1], 'P_diss': [1, 1], 'F_obs': [3, 1], 'M_obs': [3, 1], 'P_obs': [1, 1], 'g_min': [1, 1], 'points': [3, 4], 'P_fric': [1, 1]}}, 'rod_contact_sphere_bound': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'g_lb': [1, 1]}}, 'rod_contact_cylinder': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'Q': [9, 1]}}, 'rod_contact_cylinder_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'dQ_dx': [9, 19]}}, 'rod_contact_cylinder_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'E': [1, 1], 'P_diss': [1, 1], 'F_obs': [3, 1], 'M_obs': [3, 1], 'P_obs': [1, 1], 'g_min': [1, 1], 'points': [3, 4], 'P_fric': [1, 1]}}, 'rod_contact_cylinder_bound': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'g_lb': [1, 1]}}, 'rod_contact_pipe': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'Q': [9, 1]}}, 'rod_contact_pipe_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'dQ_dx': [9, 19]}}, 'rod_contact_pipe_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p': [4, 1], 'Omega': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'E': [1, 1], 'P_diss': [1, 1], 'F_obs': [3, 1], 'M_obs': [3, 1], 'P_obs': [1, 1], 'g_min': [1, 1], 'points': [3, 4], 'P_fric': [1, 1]}}, 'rod_contact_pipe_bound': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'obs': [22, 1], 'cnt': [7, 1]}, 'outputs': {'g_lb': [1, 1]}}, 'rod_contact_pair': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p_1': [4, 1], 'Omega_1': [3, 1], 'phi_c': [3, 1], 'phi_d': [3, 1], 'v_c': [3, 1], 'v_d': [3, 1], 'p_2': [4, 1], 'Omega_2': [3, 1], 'cnt': [8, 1]}, 'outputs': {'Q': [18, 1]}}, 'rod_contact_pair_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p_1': [4, 1], 'Omega_1': [3, 1], 'phi_c': [3, 1], 'phi_d': [3, 1], 'v_c': [3, 1], 'v_d': [3, 1], 'p_2': [4, 1], 'Omega_2': [3, 1], 'cnt': [8, 1]}, 'outputs': {'dQ_dx': [18, 38]}}, 'rod_contact_pair_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'p_1': [4, 1], 'Omega_1': [3, 1], 'phi_c': [3, 1], 'phi_d': [3, 1], 'v_c': [3, 1], 'v_d': [3, 1], 'p_2': [4, 1], 'Omega_2': [3, 1], 'cnt': [8, 1]}, 'outputs': {'E': [1, 1], 'P_diss': [1, 1], 'g_min': [1, 1], 'P_fric': [1, 1], 'st': [2, 1], 'W': [1, 1], 'F_12': [3, 1]}}, 'rod_contact_pair_bound': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'phi_c': [3, 1], 'phi_d': [3, 1], 'cnt': [8, 1]}, 'outputs': {'g_lb': [1, 1]}}}


def _check_branches(branches: int) -> int:
    if not 0 <= branches <= MAX_BRANCHES:
        raise ValueError(f"branches = {branches!r} is outside the allowed range: "
                         f"0..{MAX_BRANCHES}")
    return branches


# the index functions below run once per node or element while a model is built: the
# offsets and sizes of each B are worked out once per process
@lru_cache(maxsize=None)
def _offsets(branches: int, first: bool) -> tuple[tuple[str, int], ...]:
    B = _check_branches(branches)
    out, k = [], 0
    for name, size, per in (CELL0_FIELDS_B if first else CELL_FIELDS_B):
        out.append((name, k))
        k += size + per * B
    return tuple(out)


def cell_offsets(branches: int = 0, first: bool = False) -> dict[str, int]:
    """Offsets of the fields of a cell (``first``: cell 0) for B = ``branches`` terms."""
    return dict(_offsets(branches, bool(first)))


@lru_cache(maxsize=None)
def cell_sizes(branches: int = 0) -> tuple[int, int]:
    """(size of cell 0, size of cell i >= 1) for B = ``branches`` terms."""
    B = _check_branches(branches)
    return (sum(a + b * B for _, a, b in CELL0_FIELDS_B),
            sum(a + b * B for _, a, b in CELL_FIELDS_B))


def n_state(n_elements: int, branches: int = 0) -> int:
    """Length of y for N elements and B relaxation terms."""
    c0, c = cell_sizes(branches)
    return c0 + c * n_elements


def n_static(n_elements: int) -> int:
    """Length of the static unknown vector for N elements."""
    return STATIC_CELL0_SIZE + STATIC_CELL_SIZE * n_elements


def cell_start(i: int, branches: int = 0) -> int:
    """Index of the first unknown of cell i in y."""
    c0, c = cell_sizes(branches)
    return 0 if i == 0 else c0 + c * (i - 1)


@lru_cache(maxsize=None)
def _offset(name: str, branches: int, first: bool) -> int:
    return dict(_offsets(branches, first))[name]


def _at(i: int, name: str, branches: int) -> int:
    return cell_start(i, branches) + _offset(name, branches, i == 0)


def node_phi(i: int, branches: int = 0) -> int:
    """Index of node i's position phi (3) in y."""
    return _at(i, "phi", branches)


def node_v(i: int, branches: int = 0) -> int:
    """Index of node i's velocity v (3) in y."""
    return _at(i, "v", branches)


def segment_p(i: int, branches: int = 0) -> int:
    """Index of segment i's quaternion p (4) in y (i = 1..N)."""
    return _at(i, "p", branches)


def segment_omega(i: int, branches: int = 0) -> int:
    """Index of segment i's angular velocity Omega (3) in y (i = 1..N)."""
    return _at(i, "Omega", branches)


def segment_q(i: int, branches: int) -> int:
    """Index of segment i's internal strains (3B, term b at 3b) in y (i = 1..N)."""
    return _at(i, "q_segment", branches)


def joint_q(j: int, branches: int) -> int:
    """Index of joint j's internal strains (3B, term b at 3b) in y (j = 0..N)."""
    return _at(j, "q_joint", branches)


def describe_index(n_elements: int, index: int, branches: int = 0) -> str:
    """Human-readable name of state/residual component ``index`` (e.g. for failures)."""
    if index < 0 or index >= n_state(n_elements, branches):
        return f"state index {index}"
    c0, c = cell_sizes(branches)
    if index < c0:
        cell, local, offs = 0, index, cell_offsets(branches, first=True)
    else:
        cell, local = divmod(index - c0, c)
        cell, offs = cell + 1, cell_offsets(branches)
    for name, start in sorted(offs.items(), key=lambda kv: -kv[1]):
        if local >= start:
            where = {"p": "segment", "Omega": "segment", "q_segment": "segment",
                     "q_joint": "joint"}.get(name, "node")
            return f"{where} {cell} {name}[{local - start}] (state index {index})"
    return f"state index {index}"  # pragma: no cover


def static_cell_start(i: int) -> int:
    """Index of the first static unknown of cell i (cell 0: node 0's phi)."""
    return 0 if i == 0 else STATIC_CELL0_SIZE + STATIC_CELL_SIZE * (i - 1)


def static_theta(i: int) -> int:
    """Index of the rotation increment theta of segment i >= 1 in the static vector."""
    return static_cell_start(i) + STATIC_CELL_OFFSETS["theta"]


def static_phi(i: int) -> int:
    """Index of node i's position in the static vector."""
    return 0 if i == 0 else static_cell_start(i) + STATIC_CELL_OFFSETS["phi"]


def bandwidths(n_elements: int, branches: int = 0, coupled: bool = False
               ) -> tuple[int, int]:
    """Exact (kl, ku) of the dynamic Jacobian for N elements and B relaxation terms
    (``coupled``: a rod with coupled sections, B = 0)."""
    B = _check_branches(branches)
    if coupled:
        if B:
            raise ValueError("coupled sections with relaxation terms are not supported")
        return COUPLED_BANDS[min(n_elements, 3) - 1]
    (kl0, kl1), (ku0, ku1) = KL_FORMULA
    kl, ku = kl0 + kl1 * B, ku0 + ku1 * B
    if n_elements == 1:
        return kl - N1_DELTA[0], ku - N1_DELTA[1]
    return kl, ku


def diagnostics_size(n_elements: int) -> int:
    """Length of the diagnostics vector written by kvrod_diagnostics."""
    return len(DIAG_SCALARS) + 6 * n_elements + 6 * (n_elements + 1)
