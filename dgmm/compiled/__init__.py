"""numba kernels of the library's hot loops, each tested against the numpy code it replaces.

- :mod:`~dgmm.compiled.e_step`: a screened fit's E-step and M-step sums in one pass, and the screened
  exponentials of its responsibilities, the far pairs left out (``GaussianMixture(screen=...)``, the odometry
  frames' fits);
- :mod:`~dgmm.compiled.registration`: the P2D and D2D costs and their derivatives for the
  Gauss-Newton solver (``register_p2d`` / ``register_d2d(solver="gauss-newton")``, odometry's registrations).

The library imports them only where they run, so numba's import (about half a second) and the loading of its
on-disk cache (``cache=True``: compiled code beside each module, made by a machine's first run) cost nothing to the
paper's fits, scoring and BFGS registrations, which stay numpy. Each module holds everything its kernels call and
takes other modules' constants as arguments: numba's cache checks only the file of the function it compiled.
"""
