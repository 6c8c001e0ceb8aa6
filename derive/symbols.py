"""The SymPy symbols of the derivation: one place, one meaning each.

Names follow the paper (Linn, Lang, Tuganov 2013). Physical moduli, viscosities, times and
section constants are positive; Poisson's ratio ``nu`` is real (-1 < nu <= 1/2 is a
modelling range, not a SymPy assumption). Material strain components ``V1..U3`` and their
rates ``dV1..dU3`` are real. Reference values: ``V0 = e3`` (no initial shear, arc-length
parametrisation) and ``U0 = (U01, U02, U03)``.
"""

from __future__ import annotations

import sympy as sp

_pos = {"positive": True}
_real = {"real": True}

# material (Sect. 3.3, 4.1) -------------------------------------------------------------
E, G, K, eta, zeta = sp.symbols("E G K eta zeta", **_pos)
lam, mu = sp.symbols("lambda mu", **_pos)          # Lame constants (mu = G)
nu = sp.Symbol("nu", **_real)
tau_S, tau_B, tau_E = sp.symbols("tau_S tau_B tau_E", **_pos)
eta_E = sp.Symbol("eta_E", **_pos)

# cross section (Sect. 3.1) -------------------------------------------------------------
A, I1, I2, I3 = sp.symbols("A I1 I2 I3", **_pos)
kappa_1, kappa_2, kappa_3 = sp.symbols("kappa_1 kappa_2 kappa_3", **_pos)
xi1, xi2 = sp.symbols("xi1 xi2", **_real)
s, t = sp.symbols("s t", **_real)
rho = sp.Symbol("rho", **_pos)

# rod strains, their reference values and rates (Sect. 2.1, (17), (31)) ----------------
V1, V2, V3, U1, U2, U3 = sp.symbols("V1 V2 V3 U1 U2 U3", **_real)
U01, U02, U03 = sp.symbols("U01 U02 U03", **_real)
dV1, dV2, dV3, dU1, dU2, dU3 = sp.symbols("dV1 dV2 dV3 dU1 dU2 dU3", **_real)
Om1, Om2, Om3 = sp.symbols("Omega1 Omega2 Omega3", **_real)     # material angular velocity
dphi1, dphi2, dphi3 = sp.symbols("dphi1 dphi2 dphi3", **_real)  # material centreline velocity

# abstract strain vector H and its rate, and the reference volume factor J0 ---------------
H1, H2, H3 = sp.symbols("H1 H2 H3", **_real)
dH1, dH2, dH3 = sp.symbols("dH1 dH2 dH3", **_real)
J0 = sp.Symbol("J_0", **_pos)

V = sp.Matrix([V1, V2, V3])
U = sp.Matrix([U1, U2, U3])
U0 = sp.Matrix([U01, U02, U03])
dV = sp.Matrix([dV1, dV2, dV3])
dU = sp.Matrix([dU1, dU2, dU3])
Hvec = sp.Matrix([H1, H2, H3])
dHvec = sp.Matrix([dH1, dH2, dH3])
e1, e2, e3 = (sp.Matrix([1, 0, 0]), sp.Matrix([0, 1, 0]), sp.Matrix([0, 0, 1]))
I_3 = sp.eye(3)

# generalized Maxwell solid, Laplace domain (steps maxwell_material, maxwell_rod) ---------
#: Laplace variable [1/s]; complex, so no assumptions (the arc-length ``s`` above is real)
s_lap = sp.Symbol("s")
omega = sp.Symbol("omega", **_pos)                        # angular frequency [1/s]
G_inf, K_inf = sp.symbols("G_inf K_inf", **_pos)          # equilibrium moduli [Pa]
G_j, K_j, tau_j = sp.symbols("G_j K_j tau_j", **_pos)     # one branch: moduli [Pa], time [s]
eta_j, zeta_j = sp.symbols("eta_j zeta_j", **_pos)        # branch viscosities G_j tau_j, K_j tau_j
E_inf = sp.Symbol("E_inf", **_pos)
j_idx = sp.Symbol("j", integer=True, positive=True)       # branch index 1..M
M_br = sp.Symbol("M", integer=True, nonnegative=True)     # number of branches
G_br, K_br = sp.IndexedBase("G", **_pos), sp.IndexedBase("K", **_pos)
tau_br = sp.IndexedBase("tau", **_pos)
eta_br, zeta_br = sp.IndexedBase("eta", **_pos), sp.IndexedBase("zeta", **_pos)
#: Laplace-domain moduli G(s), K(s), E(s) and lateral ratio nu(s) as undetermined functions
G_of, K_of, E_of, nu_of = (sp.Function(n) for n in ("G", "K", "E", "nu"))
