# GENERATED FILE - do not edit; regenerate with `kvrod generate`.
# source: derive/templates/rod_layout.py.jinja
# derivation step: discrete_rod
# inputs sha256: 2aa1d165372b5a8960abe44358dfcee6c105f4d2be5da8ccf84b091604dcbddd
# tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

"""State, parameter and diagnostics layout of the discrete rod (the one place that owns it).

Rendered from ``derive/discrete_rod.py``; imports only the standard library.

Quaternions are stored with the SCALAR PART FIRST: p = (p0, p1, p2, p3).

State vector y (and y'), cell by cell, n = CELL0_SIZE + CELL_SIZE * N:

* cell 0 (node 0): phi(3) v(3)
* cell i = 1..N (segment i between nodes i-1 and i, then node i):
  p(4) Omega(3) phi(3) v(3)

phi: node position (m), v: node velocity (m/s), p: segment quaternion, Omega: material
angular velocity of the segment (rad/s). Residual rows use the same layout: the rows of a
field hold its equation (p: kinematics p' - 1/2 p*(0,Omega); Omega: angular momentum
balance; phi: phi' - v; v: linear momentum balance, or v = 0 for a fixed node).

The Jacobian dF/dy + c dF/dy' is banded with KL sub- and KU super-diagonals for
N >= 2 (see :func:`bandwidths` for N = 1); LAPACK band storage (dgbtrf) has 2*KL+KU+1
rows, element (i, j) at ab[KL + KU + i - j, j].

Static problem (reduced coordinates, rows = force/torque balance):
cell 0: phi(3); cell i: theta(3) phi(3)
(theta: rotation increment, p <- p*exp(theta/2)); bandwidths STATIC_KL, STATIC_KU.

C API (generated/rod_assembly.h): kvrod_residual, kvrod_jacobian_band(2), kvrod_diagnostics;
per-element CasADi kernels in generated/rod_kernels.c and generated/rod_<kernel>.casadi.
"""

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
_BANDWIDTHS_SMALL = {1: (18, 15)}

STATIC_CELL0_SIZE = 3
STATIC_CELL_SIZE = 6
STATIC_CELL_OFFSETS = {'theta': 0, 'phi': 3}
STATIC_KL = 8
STATIC_KU = 8

#: parameter vector: (name, size, unit, meaning), in order
PARAMS = (
    ("h", 1, "m", "element length L/N"),
    ("C_F", 3, "N", "diagonal of C_F = diag(GA_1, GA_2, EA), eq. (7)"),
    ("C_M", 3, "N m^2", "diagonal of C_M = diag(EI_1, EI_2, GJ_T), eq. (7)"),
    ("V_F", 3, "N s", "diagonal of V_F, eq. (9)"),
    ("V_M", 3, "N m^2 s", "diagonal of V_M, eq. (9)"),
    ("U0", 3, "1/m", "reference curvature (material)"),
    ("rhoA", 1, "kg/m", "mass per length rho A"),
    ("rhoI", 3, "kg m", "rotary inertia per length rho diag(I1, I2, I3)"),
    ("gravity", 3, "m/s^2", "gravitational acceleration (spatial)"),
    ("tip_force", 3, "N", "dead force at node N (spatial)"),
    ("tip_moment", 3, "N m", "dead moment on segment N (spatial)"),
    ("load_scale", 1, "1", "factor on all external loads (load stepping)"),
    ("p_start", 4, "1", "clamp frame quaternion at s = 0 (scalar first)"),
    ("p_end", 4, "1", "clamp frame quaternion at s = L (scalar first)"),
    ("fix_start", 1, "1", "1: node 0 position fixed (clamped or pinned), else 0"),
    ("clamp_start", 1, "1", "1: frame clamped at s = 0 (half-length joint), else 0"),
    ("fix_end", 1, "1", "1: node N position fixed, else 0"),
    ("clamp_end", 1, "1", "1: frame clamped at s = L, else 0"),
)
N_PARAMS = 42
PARAM_OFFSETS = {'h': 0, 'C_F': 1, 'C_M': 4, 'V_F': 7, 'V_M': 10, 'U0': 13, 'rhoA': 16, 'rhoI': 17, 'gravity': 20, 'tip_force': 23, 'tip_moment': 26, 'load_scale': 29, 'p_start': 30, 'p_end': 34, 'fix_start': 38, 'clamp_start': 39, 'fix_end': 40, 'clamp_end': 41}
PARAM_SIZES = {'h': 1, 'C_F': 3, 'C_M': 3, 'V_F': 3, 'V_M': 3, 'U0': 3, 'rhoA': 1, 'rhoI': 3, 'gravity': 3, 'tip_force': 3, 'tip_moment': 3, 'load_scale': 1, 'p_start': 4, 'p_end': 4, 'fix_start': 1, 'clamp_start': 1, 'fix_end': 1, 'clamp_end': 1}

#: diagnostics vector: these scalars, then V (3N), F (3N), U (3(N+1)), M (3(N+1));
#: joint j = 0..N sits at node j (j = 0 and j = N are the clamp joints, zero if absent)
DIAG_SCALARS = ('kinetic', 'elastic', 'dissipation_rate', 'external_power')

#: per-element CasADi kernels (names, inputs, outputs)
KERNELS = {'rod_segment_forces': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'par': [42, 1]}, 'outputs': {'Q': [9, 1]}}, 'rod_segment_forces_jac': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'par': [42, 1]}, 'outputs': {'dQb_dxb': [6, 13]}}, 'rod_joint_torques': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'h_j': [1, 1], 'par': [42, 1]}, 'outputs': {'T': [6, 1]}}, 'rod_joint_torques_jac': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'h_j': [1, 1], 'par': [42, 1]}, 'outputs': {'dT_dx': [6, 14]}}, 'rod_segment_inertia': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'p_dot': [4, 1], 'Omega_dot': [3, 1], 'par': [42, 1]}, 'outputs': {'r': [7, 1]}}, 'rod_segment_inertia_jac': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'p_dot': [4, 1], 'Omega_dot': [3, 1], 'par': [42, 1], 'c_y': [1, 1], 'c_j': [1, 1]}, 'outputs': {'J': [7, 7]}}, 'rod_tip_moment': {'inputs': {'p': [4, 1], 'par': [42, 1]}, 'outputs': {'T': [3, 1]}}, 'rod_tip_moment_jac': {'inputs': {'p': [4, 1], 'par': [42, 1]}, 'outputs': {'dT_dp': [3, 4]}}, 'rod_node_inertia': {'inputs': {'phi': [3, 1], 'v': [3, 1], 'phi_dot': [3, 1], 'v_dot': [3, 1], 'm': [1, 1], 'tip': [1, 1], 'fixed': [1, 1], 'par': [42, 1]}, 'outputs': {'r': [6, 1]}}, 'rod_node_inertia_jac': {'inputs': {'phi': [3, 1], 'v': [3, 1], 'phi_dot': [3, 1], 'v_dot': [3, 1], 'm': [1, 1], 'tip': [1, 1], 'fixed': [1, 1], 'par': [42, 1], 'c_y': [1, 1], 'c_j': [1, 1]}, 'outputs': {'J': [6, 6]}}, 'rod_segment_diagnostics': {'inputs': {'phi_a': [3, 1], 'phi_b': [3, 1], 'p': [4, 1], 'v_a': [3, 1], 'v_b': [3, 1], 'Omega': [3, 1], 'par': [42, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'V': [3, 1], 'F': [3, 1]}}, 'rod_joint_diagnostics': {'inputs': {'p_a': [4, 1], 'p_b': [4, 1], 'Omega_a': [3, 1], 'Omega_b': [3, 1], 'h_j': [1, 1], 'par': [42, 1]}, 'outputs': {'W': [1, 1], 'D': [1, 1], 'U': [3, 1], 'M': [3, 1]}}, 'rod_segment_kinetic': {'inputs': {'p': [4, 1], 'Omega': [3, 1], 'tip': [1, 1], 'par': [42, 1]}, 'outputs': {'T': [1, 1], 'P_ext': [1, 1]}}, 'rod_node_kinetic': {'inputs': {'v': [3, 1], 'm': [1, 1], 'tip': [1, 1], 'par': [42, 1]}, 'outputs': {'T': [1, 1], 'P_ext': [1, 1]}}}


def n_state(n_elements: int) -> int:
    """Length of y for N elements."""
    return CELL0_SIZE + CELL_SIZE * n_elements


def n_static(n_elements: int) -> int:
    """Length of the static unknown vector for N elements."""
    return STATIC_CELL0_SIZE + STATIC_CELL_SIZE * n_elements


def cell_start(i: int) -> int:
    """Index of the first unknown of cell i in y."""
    return 0 if i == 0 else CELL0_SIZE + CELL_SIZE * (i - 1)


def static_cell_start(i: int) -> int:
    """Index of the first static unknown of cell i (cell 0: node 0's phi)."""
    return 0 if i == 0 else STATIC_CELL0_SIZE + STATIC_CELL_SIZE * (i - 1)


def static_theta(i: int) -> int:
    """Index of the rotation increment theta of segment i >= 1 in the static vector."""
    return static_cell_start(i) + STATIC_CELL_OFFSETS["theta"]


def static_phi(i: int) -> int:
    """Index of node i's position in the static vector."""
    return 0 if i == 0 else static_cell_start(i) + STATIC_CELL_OFFSETS["phi"]


def bandwidths(n_elements: int) -> tuple[int, int]:
    """Exact (kl, ku) of the dynamic Jacobian for N elements."""
    return _BANDWIDTHS_SMALL.get(n_elements, (KL, KU))


def diagnostics_size(n_elements: int) -> int:
    """Length of the diagnostics vector written by kvrod_diagnostics."""
    return len(DIAG_SCALARS) + 6 * n_elements + 6 * (n_elements + 1)
