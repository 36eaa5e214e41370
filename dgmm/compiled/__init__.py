"""numba kernels of the library's hot loops, each tested against the numpy code it replaces.

- :mod:`~dgmm.compiled.e_step`: a screened fit's E-step and M-step sums in one pass, and the screened
  exponentials of its responsibilities, the far pairs left out (``GaussianMixture(screen=...)``, the odometry
  frames' fits); on the same blocks, scoring's log-normalisers of 3-D primitives (every 3-D ``score``);
- :mod:`~dgmm.compiled.scoring`: scoring's log-normalisers in other dimensions, the far terms left out;
- :mod:`~dgmm.compiled.registration`: the P2D cost and its derivatives for both solvers (``register_p2d``, the
  sweep's registrations), and D2D's for Gauss-Newton (``register_d2d(solver="gauss-newton")``, odometry's);
- :mod:`~dgmm.compiled.visibility`, :mod:`~dgmm.compiled.measured_cut`: the odometry cut rounds' visibility test
  and their cut mixtures.

The library imports them only where they run, so numba's import (about 0.2 s) and the loading of its on-disk cache
(``cache=True``: compiled code beside each module, made by a machine's first run; about 0.15 s for P2D's kernels)
cost nothing to the paper's fits, which stay numpy, until a mixture scores. The sweep's job server loads P2D's
kernels once (:func:`dgmm.registration.p2d.load_p2d_kernels`) for its registration jobs. The kernels import nothing of the library
above them; each module holds everything its kernels call and takes other modules' constants as arguments: numba's
cache checks only the file of the function it compiled.
"""
