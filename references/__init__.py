"""Independent reference solutions for validating kvrod (written without any kvrod code).

- :mod:`.reissner`: static planar large deflection of a clamped-free rod under a dead tip
  force (extensible, shearable Simo-Reissner rod by shooting; inextensible Euler elastica in
  closed form through elliptic integrals).
- :mod:`.beams`: linear cantilever frequencies (Euler-Bernoulli, Timoshenko, axial,
  torsional), small-deflection static tip, linear Kelvin-Voigt modal damping.
- :mod:`.viscoelastic_beam`: complex eigenvalues of the cantilever (Euler-Bernoulli,
  Timoshenko), bar and shaft with frequency-dependent moduli ``E(s)``, ``G(s)``; steady
  base-excitation transmissibility of the cantilever.
- :mod:`.viscoelastic_material`: 3-D generalized Maxwell relaxation (uniaxial stress, pure
  shear) in the time domain and by inverse Laplace transform; exact uniaxial response and
  complex modulus of the 3-D Kelvin-Voigt solid.
- :mod:`.pendulum`: rigid compound pendulum released from rest (Jacobi elliptic functions).
- :mod:`.sections`: section constants (rectangle, circle, ellipse, tube) with Saint-Venant
  torsion constants and Cowper's shear factors.
- :mod:`.cosserat_bvp`: general static 3-D Simo-Reissner rod (intrinsic curvature/twist,
  dead end and distributed loads, free or clamped far end) by shooting.
- :mod:`.bend45`: the Bathe-Bolourchi 45-degree bend, converged tip positions.
- :mod:`.rollup`: roll-up of a straight cantilever by an end moment (closed form).
- :mod:`.helix`: axial stiffness of a helical spring (classical and end-point loads).
- :mod:`.clamped`: rod clamped at both ends, linear Timoshenko deflections.
- :mod:`.supported`: simply supported (pinned-pinned) and free-free beams: linear
  Timoshenko midspan sag, natural frequencies (closed-form and transfer-matrix frequency
  equations), bars and shafts.
- :mod:`.assemblies`: rod assemblies: cantilever with a tip body (mass and rotary
  inertia; Euler-Bernoulli frequency equation and Timoshenko transfer matrix), L-frame
  with a rigid corner (tip compliance by the unit-load method), propped cantilever and
  two-span continuous beam (Timoshenko-exact reactions), hinged double pendulum of rigid
  bars, free circular ring (Hoppe, Michell, and the linear Cosserat ring by Fourier modes).
- :mod:`.contact`: rods against rigid bodies: heavy rod lifted off a table (Euler-Bernoulli
  and Timoshenko rigid-contact solutions), incline with Coulomb friction (sliding, rolling),
  capstan, flat drop, heavy cable draped over a cylinder (with friction), push force
  through a bend (capstan limit, frictionless configurational force).

Only NumPy and SciPy are used, so the references share no code with the simulator.
"""
