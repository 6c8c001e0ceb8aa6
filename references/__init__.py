"""Independent reference solutions for validating kvrod (written without any kvrod code).

- :mod:`.reissner`: static planar large deflection of a clamped-free rod under a dead tip
  force (extensible, shearable Simo-Reissner rod by shooting; inextensible Euler elastica in
  closed form through elliptic integrals).
- :mod:`.beams`: linear cantilever frequencies (Euler-Bernoulli, Timoshenko, axial,
  torsional), small-deflection static tip, linear Kelvin-Voigt modal damping.

Only NumPy and SciPy are used, so the references share no code with the simulator.
"""
