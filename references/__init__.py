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

Only NumPy and SciPy are used, so the references share no code with the simulator.
"""
