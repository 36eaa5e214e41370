"""Small experiments that settle claims of the paper the fitting and registration sweeps do not measure.

One module per experiment, each a plain function a thin job script calls (``workflow/rules/checks.smk``):

- :mod:`~.convergence`: fits run to 100 iterations (Discussion: convergence speed, the 100-iteration comparison) and
  the "fuller model" numbers of Fig 5 (surface coverage by 2σ ellipsoids, spread of the weights);
- :mod:`~.resampling`: the same mesh with every triangle split in four (§II, invariance to resampling);
- :mod:`~.optimisers`: P2D with CG beside BFGS and a rotation vector beside the quaternion (§VI-A);
- :mod:`~.identities`: the identities the paper states (§III, §V-A, §VII), each side computed independently;
- :mod:`~.timing`: same-run CPU-time ratios of the speed claims by interleaved repeats (:mod:`~.interleaved`), in
  :mod:`~.timing_meshes` (approximation, decimation, sampling), :mod:`~.timing_registration` (D2D's determinant,
  CPD beside P2D) and :mod:`~.timing_odometry` (pixel beside point mixtures, GMM beside ICP odometry).

Their tables are deterministic except the timing tables (``*_seconds``), which the report flags as machine
dependent.
"""
