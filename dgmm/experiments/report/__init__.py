"""The reproduction report: Table 1, the paper's claims with verdicts, and the figures, from the sweep's tables.

- :mod:`~.tables`: tables from the tidy CSVs (likelihood means, Fig 2 bars, registration, Table 1);
- :mod:`~.claims`: each claim of the paper checked by an explicit rule;
- :mod:`~.figures`: one function per figure (matplotlib, Agg canvas, no pyplot);
- :mod:`~.document`: Markdown and self-contained HTML from one list of blocks;
- :mod:`~.build`: the table of figures and :func:`build_report`.
"""
from dgmm.experiments.report.build import FIGURES, INPUTS, build_report, figure_names

__all__ = ["FIGURES", "INPUTS", "build_report", "figure_names"]
