"""The paper's experiments: what the workflow computes to reproduce Keselman & Hebert's tables, figures and claims.

Built on the library (``dgmm``, ``dgmm.registration``, ``dgmm.odometry``, ``dgmm.recording``), which never imports
this package; the workflow's job scripts (``workflow/scripts/``) call these functions, and nothing here imports them.

- :mod:`~.sweep`: the fitting experiments' inputs (``{source}-{representation}``), fits over seeds and their scores;
- :mod:`~.trials`: the registration experiment (Fig 6, Table 1): every method on the same random rigid trials;
- :mod:`~.shared_responsibility`: Fig 2's gap, the price of one responsibility per triangle;
- :mod:`~.checks`: small experiments for the claims the sweeps do not measure;
- :mod:`~.report`: Table 1, the claims with their verdicts and the figures, from the sweep's tables.
"""
