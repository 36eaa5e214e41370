"""The workflow's runtime: what the Snakefile and its job scripts need to run, and nothing a fit computes.

- :mod:`~.job_server`: job scripts run in forks of one process that has imported their libraries;
- :mod:`~.snakemake_sigterm`: Snakemake's SIGTERM handler made safe at any moment;
- :mod:`~.tables`: tidy CSV tables, written atomically, equal numbers as equal bytes.

It imports only the library's file helpers (``dgmm.files``), never the paper's experiments.
"""
