"""numba kernels of the library's hot loops, each tested against the numpy code it replaces.

- :mod:`~dgmm.compiled.e_step`: a screened fit's E-step and M-step sums in one pass, and the screened
  exponentials of its responsibilities, the far pairs left out (``GaussianMixture(screen=...)``, the odometry
  frames' fits);
- :mod:`~dgmm.compiled.registration`: the P2D cost and its derivatives for both solvers (``register_p2d``, the
  sweep's registrations), and D2D's for Gauss-Newton (``register_d2d(solver="gauss-newton")``, odometry's).

The library imports them only where they run, so numba's import (about 0.2 s) and the loading of its on-disk cache
(``cache=True``: compiled code beside each module, made by a machine's first run; about 0.15 s for P2D's kernels)
cost nothing to the paper's fits and scoring, which stay numpy. The sweep's job server loads P2D's kernels once
(:func:`load_p2d_kernels`) for its registration jobs. Each module holds everything its kernels call and takes other
modules' constants as arguments: numba's cache checks only the file of the function it compiled.
"""
import numpy as np


def load_p2d_kernels():
    """Load P2D's kernels from numba's cache (compiling them where there is none) by registering four points once
    with each solver: forks of a process that called this, the job server's registration jobs, run them at once."""
    from dgmm.registration import register_p2d
    from dgmm.registration.fitted import FittedMixture

    means = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    mixture = FittedMixture(np.full(2, 0.5), means, np.repeat(np.eye(3)[None], 2, axis=0),
                            np.repeat(np.eye(3)[None], 2, axis=0))
    points = np.array([[0.1, 0.0, 0.0], [0.9, 0.1, 0.0], [0.0, 0.1, 0.1], [1.0, 0.0, 0.1]])
    for solver in ("bfgs", "gauss-newton"):
        register_p2d(points, mixture, solver=solver)
